/*
 * libattitude — serial link protocol of the paper (sec. 3.3), both ends.
 *
 * Sender A (the acquisition board) and receiver B (the Linux computer)
 * are non-blocking, byte-at-a-time state machines in the heatshrink style:
 * the caller feeds every received byte with `..._sink(byte, tick)` and
 * calls `..._poll(tick, &out)` to get the next byte to transmit and the
 * timeout events. No malloc, no I/O, no global state: all state lives in
 * caller-owned structs, the data block in a caller-owned buffer. The
 * sender compiles for the AT89S51 with SDCC (small model): 8/16-bit
 * arithmetic only, no float, no function pointers.
 *
 * Wire protocol (docs/link.md):
 *   A: 0xAA            B: 0xBB (when idle)
 *   A: N data bytes, then sum(data) mod 256
 *   B: 0x00 if its running sum equals the checksum (block accepted), else 0xFF
 *   A: on 0xFF or no answer in time, start again at 0xAA with the same
 *      block; after max_attempts attempts report "gave up" and move on.
 *
 * Ticks: the caller chooses the unit (e.g. 1 ms timer interrupts on the
 * 8051, CLOCK_MONOTONIC milliseconds on Linux, bit times in the simulator)
 * and passes a free-running 16-bit counter; all comparisons are
 * wrap-safe (elapsed = (uint16_t)(now - start)). A timer expires when
 * more than `timeout` ticks have elapsed. Timeouts must be 1..32767 and
 * the machine must be polled at least once every 32768 ticks.
 * The `..._config_init` functions fill defaults for 1 ms ticks at 9600
 * baud (justified in docs/link.md); scale them for other tick units.
 */
#ifndef ATTITUDE_LINK_H
#define ATTITUDE_LINK_H

#include "attitude/common.h"

ATT_API_BEGIN

/* Memory space of the sender's state, block and output byte: on the
 * 8051 (SDCC) they live in internal RAM (the small model's default), so
 * 1-byte __data pointers replace 3-byte generic ones -- this divides the
 * sender's code size by about three. Empty everywhere else. */
#if defined(__SDCC_mcs51) && !defined(ATT_CDEF)
#define ATT_LINK_MEM __data
#else
#define ATT_LINK_MEM
#endif

/* Protocol constants. */
enum {
    ATT_LINK_SYN = 0xAA,          /* A -> B: request to send a block */
    ATT_LINK_SYN_ACK = 0xBB,      /* B -> A: ready, send the block */
    ATT_LINK_ACK = 0x00,          /* B -> A: checksum matched, block accepted */
    ATT_LINK_NAK = 0xFF,          /* B -> A: checksum mismatch, send again */
    ATT_LINK_BLOCK_MIN = 1,       /* smallest block size N (bytes) */
    ATT_LINK_BLOCK_MAX = 64,      /* largest block size N (bytes) */
    ATT_LINK_BLOCK_DEFAULT = 6,   /* X, Y, Z as 16-bit big-endian ADC codes */
    ATT_LINK_TIMEOUT_MAX = 32767, /* largest timeout in ticks (wrap-safe limit) */
    ATT_LINK_NO_TIMER = 0xFFFF    /* ..._ticks_left(): no timer running */
};

/* What one sink or poll call did. Negative values are errors. */
typedef enum {
    ATT_LINK_NONE = 0,      /* poll: nothing to do now (waiting for the peer or the clock) */
    ATT_LINK_IDLE = 1,      /* poll: machine idle (sender: ready for att_link_sender_start) */
    ATT_LINK_SEND = 2,      /* poll: *out_byte is the next byte to transmit */
    ATT_LINK_DISCARDED = 3, /* sink: byte not expected in this state, ignored and counted */
    ATT_LINK_SYN_RX = 4,    /* sink: B got 0xAA while idle (0xBB queued) / A got 0xBB (data follows) */
    ATT_LINK_DATA_RX = 5,   /* sink: B stored a data byte */
    ATT_LINK_ACCEPTED = 6,  /* sink: B: block good, in the buffer, 0x00 queued / A: got 0x00, now idle */
    ATT_LINK_REJECTED = 7,  /* sink: B: checksum mismatch, 0xFF queued / A: got 0xFF, will retry or give up */
    ATT_LINK_TIMEOUT = 8,   /* poll: A: no 0xBB or no answer in time, will retry or give up /
                               B: gap inside a block too long, partial block dropped */
    ATT_LINK_GAVE_UP = 9,   /* poll: A: max_attempts used, block dropped, now idle */
    ATT_LINK_E_NULL = -60,  /* a required pointer is NULL */
    ATT_LINK_E_CONFIG = -61, /* configuration out of range */
    ATT_LINK_E_BUSY = -62,   /* sender: start while a block is still in progress */
    ATT_LINK_E_STATE = -63   /* internal state corrupted (struct overwritten?) */
} att_link_result;

/* ------------------------------------------------------------------ */
/* Sender A                                                           */
/* ------------------------------------------------------------------ */

typedef struct {
    uint16_t syn_timeout;    /* ticks A waits for 0xBB after handing out 0xAA (1..32767) */
    uint16_t answer_timeout; /* ticks A waits for 0x00/0xFF after handing out the checksum (1..32767) */
    uint8_t block_size;      /* N, data bytes per block (1..64); both ends must agree */
    uint8_t max_attempts;    /* attempts per block before giving up (1..255) */
} att_link_sender_config;

/* Counters wrap modulo 2^16 (8051 RAM). Retries (restarts from 0xAA
 * for the same block) = naks + timeouts - gave_up. */
typedef struct {
    uint16_t blocks_sent;     /* data blocks transmitted (every attempt that reached the checksum) */
    uint16_t blocks_accepted; /* 0x00 answers received */
    uint16_t naks;            /* 0xFF answers received */
    uint16_t timeouts;        /* waits for 0xBB or for the answer that expired */
    uint16_t gave_up;         /* blocks abandoned after max_attempts */
    uint16_t bytes_discarded; /* received bytes not expected in the current state */
} att_link_sender_stats;

typedef struct {
    att_link_sender_config cfg;
    att_link_sender_stats stats;
    const uint8_t ATT_LINK_MEM *block; /* caller's block (cfg.block_size bytes) */
    uint16_t t0;                       /* tick at which the running timer started */
    uint8_t state;                     /* private state (enum in link_sender.c) */
    uint8_t index;                     /* next data byte to send */
    uint8_t attempts;                  /* attempts started for the current block */
} att_link_sender;

/* Defaults for 1 ms ticks at 9600 baud: N = block_size, syn and answer
 * timeouts 50 ms, 5 attempts. */
void att_link_sender_config_init(att_link_sender_config *cfg, uint8_t block_size);

/* Copy and check cfg, zero the statistics, go idle. ATT_OK,
 * ATT_LINK_E_NULL or ATT_LINK_E_CONFIG. */
int att_link_sender_init(att_link_sender ATT_LINK_MEM *s, const att_link_sender_config *cfg);

/* Back to idle without touching the statistics (e.g. after a reboot of
 * the peer); a block in progress is dropped silently. */
void att_link_sender_reset(att_link_sender ATT_LINK_MEM *s);

/* Start sending `block` (cfg.block_size bytes, caller-owned, must stay
 * unchanged until poll reports ATT_LINK_IDLE again). Only when idle:
 * ATT_OK, ATT_LINK_E_NULL or ATT_LINK_E_BUSY. */
int att_link_sender_start(att_link_sender ATT_LINK_MEM *s, const uint8_t ATT_LINK_MEM *block, uint16_t tick);

/* A byte arrived from B at `tick`. Returns ATT_LINK_SYN_RX, ATT_LINK_ACCEPTED,
 * ATT_LINK_REJECTED, ATT_LINK_DISCARDED or an error. A byte arriving after
 * the running timer expired is handled after the timeout (so it is
 * discarded); the timeout is then reported by the next poll. */
att_link_result att_link_sender_sink(att_link_sender ATT_LINK_MEM *s, uint8_t byte, uint16_t tick);

/* Advance the machine at `tick`. Returns ATT_LINK_SEND (transmit
 * *out_byte), ATT_LINK_TIMEOUT, ATT_LINK_GAVE_UP, ATT_LINK_NONE (waiting),
 * ATT_LINK_IDLE (no block) or an error. Call it repeatedly until it
 * returns NONE or IDLE; call it only when the transmitter can take a byte
 * (the timer for an answer starts when the byte is handed out). */
att_link_result att_link_sender_poll(att_link_sender ATT_LINK_MEM *s, uint16_t tick,
                                     uint8_t ATT_LINK_MEM *out_byte);

/* Ticks after `now` at which poll will act on a timer (0: poll now),
 * ATT_LINK_NO_TIMER if no timer runs. Lets a caller sleep. */
uint16_t att_link_sender_ticks_left(const att_link_sender ATT_LINK_MEM *s, uint16_t now);

/* ------------------------------------------------------------------ */
/* Receiver B                                                         */
/* ------------------------------------------------------------------ */

typedef struct {
    uint16_t gap_timeout; /* ticks B waits for the next byte inside a block (after 0xBB is
                             handed out, and between data bytes) before dropping it (1..32767) */
    uint8_t block_size;   /* N (1..64); both ends must agree */
} att_link_receiver_config;

typedef struct {
    uint32_t syns;            /* 0xAA received while idle (answered 0xBB) */
    uint32_t blocks_accepted; /* blocks whose checksum matched (answered 0x00) */
    uint32_t naks;            /* blocks whose checksum did not match (answered 0xFF) */
    uint32_t timeouts;        /* partial blocks dropped after a gap longer than gap_timeout */
    uint32_t resyncs;         /* handshakes found after discarding bytes while idle */
    uint32_t bytes_discarded; /* bytes ignored while idle plus bytes of dropped partial blocks */
} att_link_receiver_stats;

typedef struct {
    att_link_receiver_config cfg;
    att_link_receiver_stats stats;
    uint8_t *block;  /* caller's buffer, cfg.block_size bytes */
    uint16_t t_last; /* tick of the last byte received (or 0xBB handed out) in a block */
    uint8_t state;   /* private receive state (enum in link_receiver.c) */
    uint8_t pending; /* private: what the next poll reports (enum in link_receiver.c) */
    uint8_t index;   /* data bytes stored so far */
    uint8_t sum;     /* running sum of the data bytes mod 256 */
} att_link_receiver;

/* Defaults for 1 ms ticks at 9600 baud: N = block_size, gap 20 ms. */
void att_link_receiver_config_init(att_link_receiver_config *cfg, uint8_t block_size);

/* Copy and check cfg, attach `block` (cfg->block_size bytes), zero the
 * statistics, go idle. ATT_OK, ATT_LINK_E_NULL or ATT_LINK_E_CONFIG. */
int att_link_receiver_init(att_link_receiver *r, const att_link_receiver_config *cfg, uint8_t *block);

/* Back to idle (partial block dropped, pending output cleared), statistics kept. */
void att_link_receiver_reset(att_link_receiver *r);

/* A byte arrived from A at `tick`. Returns ATT_LINK_SYN_RX, ATT_LINK_DATA_RX,
 * ATT_LINK_ACCEPTED (the block is in the buffer until the next block's
 * first data byte), ATT_LINK_REJECTED, ATT_LINK_DISCARDED or an error. If
 * the gap before this byte was too long, the partial block is dropped
 * first (reported as ATT_LINK_TIMEOUT by the next poll) and the byte is
 * handled as if B were idle. */
att_link_result att_link_receiver_sink(att_link_receiver *r, uint8_t byte, uint16_t tick);

/* Advance at `tick`: ATT_LINK_TIMEOUT (partial block dropped),
 * ATT_LINK_SEND (*out_byte = 0xBB, 0x00 or 0xFF), ATT_LINK_NONE (inside a
 * block), ATT_LINK_IDLE, or an error. Call until NONE or IDLE. */
att_link_result att_link_receiver_poll(att_link_receiver *r, uint16_t tick, uint8_t *out_byte);

/* Ticks after `now` at which poll will act on the gap timer (0: poll
 * now), ATT_LINK_NO_TIMER if none runs. */
uint16_t att_link_receiver_ticks_left(const att_link_receiver *r, uint16_t now);

/* Sum of n bytes modulo 256 (the protocol's checksum). */
uint8_t att_link_checksum(const uint8_t *data, uint8_t n);

ATT_API_END

#endif /* ATTITUDE_LINK_H */
