/*
 * libattitude host-only: link v2 (attitude/link2.h) end to end in simulated
 * line time: a producer pushes numbered records into the C sender A, the
 * bytes cross the seeded channel model of link_sim.h in both directions
 * (full duplex: each direction carries one byte per byte time), the C
 * receiver B delivers into a consumer queue that drains at a set rate,
 * and every delivered record is checked against the record it should be
 * (in order, exactly once, unaltered). Not for the 8051 (64-bit counters).
 */
#ifndef ATTITUDE_LINK2_SIM_H
#define ATTITUDE_LINK2_SIM_H

#include "attitude/link2.h"
#include "link_sim.h"

typedef struct {
    att_link2_sender_config sender; /* rto in ticks (bit times) */
    uint16_t ticks_per_byte;        /* 10: 8N1 in bit times */
    uint64_t n_records;             /* records the producer offers */
    uint32_t period;                /* ticks between records offered (0: whenever the ring has room) */
    uint32_t report_every;          /* every k-th record is a report (RAW frame); 0: none */
    uint32_t queue;                 /* consumer queue (records; 0: unbounded room) */
    uint32_t consume_period;        /* ticks per record the consumer takes (0: at once) */
    uint64_t reboot_sender_tick;    /* 0: none; else A restarts (new session) at that tick */
    uint64_t reboot_receiver_tick;  /* 0: none; else B restarts (session forgotten) */
    uint64_t max_ticks;             /* stop there (0: when every record is acknowledged) */
} att_link2_sim_config;

typedef struct {
    uint64_t ticks;        /* simulated time at the end */
    uint64_t offered;      /* records pushed into A */
    uint64_t dropped_full; /* records the producer could not push (A's ring full: the source's loss) */
    uint64_t delivered;    /* records B handed out */
    uint64_t in_order;     /* of them: exactly the next record, unaltered */
    uint64_t corrupt;      /* delivered records that are no record offered near that place */
    uint64_t duplicates;   /* delivered records that repeat an earlier one */
    uint64_t lost;         /* records skipped by a delivery (offered, never delivered before a later one) */
    uint64_t acked;        /* records A saw acknowledged (A's base advanced over them) */
    uint64_t unacked_end;  /* records still pending in A at the end */
    uint64_t last_delivery_tick;
    uint64_t s_frames, s_records, s_resent, s_acks, s_bad_frames, s_timeouts, s_gobacks, s_syns;
    att_link2_receiver_stats receiver;
} att_link2_sim_result;

/* The record number i pushed into A (the i-th record A took) (6 bytes at rec): a sample
 * whose codes are a hash of i (0..4095), or every report_every-th an
 * OVERRUN-shaped report carrying i. */
void att_link2_sim_record(uint64_t i, uint32_t report_every, uint8_t *rec);

/* Run; ATT_OK or a negative status (config errors from the sender's init). */
int att_link2_sim_run(const att_link2_sim_config *cfg, att_link_channel *ch, att_link2_sim_result *res);

#endif
