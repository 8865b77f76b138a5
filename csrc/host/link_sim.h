/*
 * libattitude host-only: a seeded model of a bad serial line between the
 * link sender A and receiver B, and a fast event-driven simulation of
 * both C ends talking through it in simulated line time (docs/link.md).
 *
 * Time is in ticks of the caller's choice (attitude_c.link uses one bit
 * time, 1/baud s, so one 8N1 byte lasts 10 ticks); the line carries one
 * byte at a time, a byte started at tick t arrives at t + ticks_per_byte.
 * Not for the 8051: uses 64-bit integers and double.
 */
#ifndef ATTITUDE_LINK_SIM_H
#define ATTITUDE_LINK_SIM_H

#include "attitude/link.h"

enum {
    ATT_LINK_SIM_MAX_DEAD = 4,    /* dead-line windows in a channel config */
    ATT_LINK_SIM_MAX_REBOOTS = 8, /* scheduled reboots in a sim config */
    ATT_LINK_SIM_MAX_OUT = 3,     /* bytes one transmitted byte can turn into */
    ATT_LINK_DIR_A_TO_B = 0,
    ATT_LINK_DIR_B_TO_A = 1,
    ATT_LINK_REBOOT_SENDER = 0,
    ATT_LINK_REBOOT_RECEIVER = 1
};

/* Fate of each block A was given (att_link_sim_run's `outcome`). */
enum {
    ATT_LINK_OUTCOME_PENDING = 0,    /* not finished when the run stopped */
    ATT_LINK_OUTCOME_ACKED = 1,      /* A received 0x00 */
    ATT_LINK_OUTCOME_GAVE_UP = 2,    /* A used max_attempts */
    ATT_LINK_OUTCOME_LOST_REBOOT = 3 /* A rebooted while sending it */
};

/* Fault rates of one direction of the line (probabilities, 0..1). */
typedef struct {
    double ber;         /* each of the 8 data bits flipped independently */
    double p_drop;      /* byte lost */
    double p_insert;    /* a random garbage byte arrives just before the byte */
    double p_duplicate; /* the byte arrives twice */
} att_link_fault_rates;

typedef struct {
    att_link_fault_rates a_to_b;
    att_link_fault_rates b_to_a;
    /* dead line windows (4 = ATT_LINK_SIM_MAX_DEAD, a literal for cffi), in ticks: the line
     * loses every byte started in [start, start + length), both directions */
    uint64_t dead_start[4];
    uint64_t dead_length[4];
    uint32_t n_dead;
    uint64_t seed;
} att_link_channel_config;

typedef struct {
    uint64_t bytes;      /* bytes offered to the line */
    uint64_t bit_flips;  /* data bits flipped */
    uint64_t corrupted;  /* bytes with at least one flipped bit */
    uint64_t dropped;    /* bytes lost (p_drop) */
    uint64_t dead;       /* bytes lost because the line was dead */
    uint64_t inserted;   /* garbage bytes inserted */
    uint64_t duplicated; /* bytes delivered twice */
} att_link_channel_stats;

typedef struct {
    att_link_channel_config cfg;
    att_link_channel_stats stats[2]; /* per direction */
    uint64_t rng;                    /* splitmix64 state */
    uint64_t skip[2];                /* error-free bits before the next flipped bit */
} att_link_channel;

/* ATT_OK, ATT_E_NULL, ATT_E_ARG (a rate outside [0, 1], NaN, n_dead too big). */
int att_link_channel_init(att_link_channel *ch, const att_link_channel_config *cfg);

/* A byte starts on the line in direction `dir` at tick t. Writes the
 * bytes that will arrive (in order) to out[0..2]; returns their count
 * (0: lost), or a negative status. */
int att_link_channel_transmit(att_link_channel *ch, int dir, uint8_t byte, uint64_t t, uint8_t *out);

typedef struct {
    att_link_sender_config sender;     /* timeouts in ticks */
    att_link_receiver_config receiver; /* gap timeout in ticks */
    uint16_t ticks_per_byte;           /* line time of one byte (10 for 8N1 in bit times) */
    uint64_t reboot_tick[8];           /* 8 = ATT_LINK_SIM_MAX_REBOOTS (literal for cffi) */
    uint8_t reboot_who[8];             /* ATT_LINK_REBOOT_SENDER / _RECEIVER */
    uint32_t n_reboots;
    uint64_t max_ticks; /* stop at this simulated time (0: no limit) */
} att_link_sim_config;

typedef struct {
    uint64_t ticks;         /* simulated time when the run stopped */
    uint64_t s_blocks_sent; /* sender statistics, extended to 64 bits */
    uint64_t s_blocks_accepted;
    uint64_t s_naks;
    uint64_t s_timeouts;
    uint64_t s_gave_up;
    uint64_t s_bytes_discarded;
    att_link_receiver_stats receiver;
    uint32_t n_accepted;     /* blocks B accepted (recorded: min(n_accepted, capacity)) */
    uint32_t blocks_started; /* blocks A took up */
} att_link_sim_result;

/* Push n_blocks blocks (n_blocks x N bytes) through C sender -> channel ->
 * C receiver. For every block B accepts, records its bytes in
 * acc_data[m*N..], the index of the block A was sending when it sent the
 * checksum in acc_index[m] and the tick in acc_tick[m] (up to
 * acc_capacity blocks; any pointer may be NULL if capacity is 0).
 * outcome[i] (may be NULL) gets ATT_LINK_OUTCOME_*. ATT_OK or a negative
 * status (config errors come from the ends' init). */
int att_link_sim_run(const att_link_sim_config *cfg, att_link_channel *ch, const uint8_t *blocks,
                     uint32_t n_blocks, uint8_t *acc_data, int64_t *acc_index, uint64_t *acc_tick,
                     uint32_t acc_capacity, uint8_t *outcome, att_link_sim_result *res);

#endif /* ATTITUDE_LINK_SIM_H */
