/*
 * Tests of the link sender A and receiver B (attitude/link.h): byte-exact
 * transcripts of the paper's handshake in the normal case and under each
 * fault, timeouts with 16-bit tick wrap-around, configuration checks.
 *
 * A tiny lock-step driver connects the two ends: one tick per byte time,
 * each end hands out at most one byte per tick, a byte handed out at tick
 * t arrives at t+1. Faults are applied to the
 * k-th byte of a direction (drop, or XOR with a mask).
 */
#include <string.h>

#include "att_test.h"
#include "attitude/link.h"

#define MAXLOG 512

typedef struct {
    att_link_sender a;
    att_link_receiver b;
    uint8_t rxbuf[ATT_LINK_BLOCK_MAX];
    /* wire logs (what each end handed out, before faults) */
    uint8_t a_log[MAXLOG];
    int a_n;
    uint8_t b_log[MAXLOG];
    int b_n;
    /* faults: index of the byte in each direction, -1 = none */
    int a_drop, a_flip_at, a_flip2_at;
    uint8_t a_flip, a_flip2;
    int b_drop;
    /* bytes in flight (one per direction per tick at most, plus queue) */
    uint8_t a_q[MAXLOG];
    int a_qn;
    uint8_t b_q[MAXLOG];
    int b_qn;
    int accepted, rejected, a_timeouts, b_timeouts, gave_up, a_accepted;
    uint8_t last_block[ATT_LINK_BLOCK_MAX];
} rig;

static void rig_init(rig *r, uint8_t n, uint16_t syn_to, uint16_t ans_to, uint16_t gap, uint8_t attempts)
{
    att_link_sender_config sc;
    att_link_receiver_config rc;
    memset(r, 0, sizeof(*r));
    att_link_sender_config_init(&sc, n);
    sc.syn_timeout = syn_to;
    sc.answer_timeout = ans_to;
    sc.max_attempts = attempts;
    att_link_receiver_config_init(&rc, n);
    rc.gap_timeout = gap;
    CHECK_EQ_INT(att_link_sender_init(&r->a, &sc), ATT_OK);
    CHECK_EQ_INT(att_link_receiver_init(&r->b, &rc, r->rxbuf), ATT_OK);
    r->a_drop = r->a_flip_at = r->a_flip2_at = r->b_drop = -1;
}

/* One tick: deliver queued bytes, then poll both ends. */
static void rig_tick(rig *r, uint16_t t)
{
    int i;
    uint8_t out;
    att_link_result res;
    /* deliver everything queued during the previous tick */
    for (i = 0; i < r->a_qn; i++) {
        res = att_link_receiver_sink(&r->b, r->a_q[i], t);
        CHECK(res >= 0);
        if (res == ATT_LINK_ACCEPTED) {
            r->accepted++;
            memcpy(r->last_block, r->rxbuf, r->b.cfg.block_size);
        } else if (res == ATT_LINK_REJECTED) {
            r->rejected++;
        }
    }
    r->a_qn = 0;
    for (i = 0; i < r->b_qn; i++) {
        res = att_link_sender_sink(&r->a, r->b_q[i], t);
        CHECK(res >= 0);
        if (res == ATT_LINK_ACCEPTED) {
            r->a_accepted++;
        }
    }
    r->b_qn = 0;
    while ((res = att_link_sender_poll(&r->a, t, &out)) != ATT_LINK_NONE && res != ATT_LINK_IDLE) {
        CHECK(res >= 0);
        if (res < 0) {
            break;
        }
        if (res == ATT_LINK_SEND) {
            int k = r->a_n;
            if (r->a_n < MAXLOG) {
                r->a_log[r->a_n++] = out;
            }
            if (k == r->a_flip_at) {
                out = (uint8_t)(out ^ r->a_flip);
            }
            if (k == r->a_flip2_at) {
                out = (uint8_t)(out ^ r->a_flip2);
            }
            if (k != r->a_drop) {
                r->a_q[r->a_qn++] = out;
            }
            break; /* one byte per tick: the line is paced */
        } else if (res == ATT_LINK_TIMEOUT) {
            r->a_timeouts++;
        } else if (res == ATT_LINK_GAVE_UP) {
            r->gave_up++;
        }
    }
    while ((res = att_link_receiver_poll(&r->b, t, &out)) != ATT_LINK_NONE && res != ATT_LINK_IDLE) {
        CHECK(res >= 0);
        if (res < 0) {
            break;
        }
        if (res == ATT_LINK_SEND) {
            int k = r->b_n;
            if (r->b_n < MAXLOG) {
                r->b_log[r->b_n++] = out;
            }
            if (k != r->b_drop) {
                r->b_q[r->b_qn++] = out;
            }
            break;
        } else if (res == ATT_LINK_TIMEOUT) {
            r->b_timeouts++;
        }
    }
}

/* Run until A is idle again (or `limit` ticks), starting at tick t0. */
static uint16_t rig_run(rig *r, uint16_t t0, int limit)
{
    uint16_t t = t0;
    int i;
    for (i = 0; i < limit; i++) {
        rig_tick(r, t);
        t++;
        /* idle sender = no timer and nothing to hand out */
        if (att_link_sender_ticks_left(&r->a, t) == ATT_LINK_NO_TIMER && r->a_qn == 0 && r->b_qn == 0) {
            break;
        }
    }
    CHECK(i < limit);
    return t;
}

static uint16_t rig_send(rig *r, const uint8_t *block, uint16_t t0, int limit)
{
    CHECK_EQ_INT(att_link_sender_start(&r->a, block, t0), ATT_OK);
    return rig_run(r, t0, limit);
}

static int same(const uint8_t *a, int na, const uint8_t *b, int nb)
{
    return na == nb && memcmp(a, b, (size_t)na) == 0;
}

static const uint8_t BLK[6] = { 0x12, 0x34, 0x56, 0x78, 0x9A, 0xBC };
/* checksum = 0x12+0x34+0x56+0x78+0x9A+0xBC = 0x26A -> 0x6A */

static void test_checksum(void)
{
    CHECK_EQ_INT(att_link_checksum(BLK, 6), 0x6A);
    CHECK_EQ_INT(att_link_checksum(BLK, 0), 0);
    CHECK_EQ_INT(att_link_checksum(NULL, 3), 0);
}

static void test_config(void)
{
    att_link_sender s;
    att_link_sender_config sc;
    att_link_receiver r;
    att_link_receiver_config rc;
    uint8_t buf[ATT_LINK_BLOCK_MAX];
    att_link_sender_config_init(&sc, 6);
    CHECK_EQ_INT(sc.block_size, 6);
    CHECK_EQ_INT(sc.syn_timeout, 50);
    CHECK_EQ_INT(att_link_sender_init(NULL, &sc), ATT_LINK_E_NULL);
    CHECK_EQ_INT(att_link_sender_init(&s, NULL), ATT_LINK_E_NULL);
    sc.block_size = 0;
    CHECK_EQ_INT(att_link_sender_init(&s, &sc), ATT_LINK_E_CONFIG);
    sc.block_size = 65;
    CHECK_EQ_INT(att_link_sender_init(&s, &sc), ATT_LINK_E_CONFIG);
    /* a sender whose init failed refuses to work instead of misbehaving */
    CHECK_EQ_INT(att_link_sender_poll(&s, 0, buf), ATT_LINK_E_STATE);
    CHECK_EQ_INT(att_link_sender_sink(&s, 0xBB, 0), ATT_LINK_E_STATE);
    CHECK_EQ_INT(att_link_sender_start(&s, BLK, 0), ATT_LINK_E_BUSY);
    sc.block_size = 64;
    CHECK_EQ_INT(att_link_sender_init(&s, &sc), ATT_OK);
    sc.max_attempts = 0;
    CHECK_EQ_INT(att_link_sender_init(&s, &sc), ATT_LINK_E_CONFIG);
    sc.max_attempts = 1;
    sc.syn_timeout = 0;
    CHECK_EQ_INT(att_link_sender_init(&s, &sc), ATT_LINK_E_CONFIG);
    sc.syn_timeout = 32768;
    CHECK_EQ_INT(att_link_sender_init(&s, &sc), ATT_LINK_E_CONFIG);
    sc.syn_timeout = 32767;
    sc.answer_timeout = 0;
    CHECK_EQ_INT(att_link_sender_init(&s, &sc), ATT_LINK_E_CONFIG);
    att_link_receiver_config_init(&rc, 6);
    CHECK_EQ_INT(rc.gap_timeout, 20);
    CHECK_EQ_INT(att_link_receiver_init(&r, &rc, NULL), ATT_LINK_E_NULL);
    rc.gap_timeout = 0;
    CHECK_EQ_INT(att_link_receiver_init(&r, &rc, buf), ATT_LINK_E_CONFIG);
    rc.gap_timeout = 20;
    rc.block_size = 0;
    CHECK_EQ_INT(att_link_receiver_init(&r, &rc, buf), ATT_LINK_E_CONFIG);
    rc.block_size = 6;
    CHECK_EQ_INT(att_link_receiver_init(&r, &rc, buf), ATT_OK);
    /* NULL pointers on the byte functions are errors, never crashes */
    CHECK_EQ_INT(att_link_sender_sink(NULL, 0, 0), ATT_LINK_E_NULL);
    CHECK_EQ_INT(att_link_sender_poll(NULL, 0, buf), ATT_LINK_E_NULL);
    CHECK_EQ_INT(att_link_receiver_sink(NULL, 0, 0), ATT_LINK_E_NULL);
    CHECK_EQ_INT(att_link_receiver_poll(&r, 0, NULL), ATT_LINK_E_NULL);
    /* start while busy */
    sc.max_attempts = 3;
    sc.syn_timeout = 10;
    sc.answer_timeout = 10;
    sc.block_size = 6;
    CHECK_EQ_INT(att_link_sender_init(&s, &sc), ATT_OK);
    CHECK_EQ_INT(att_link_sender_start(&s, NULL, 0), ATT_LINK_E_NULL);
    CHECK_EQ_INT(att_link_sender_start(&s, BLK, 0), ATT_OK);
    CHECK_EQ_INT(att_link_sender_start(&s, BLK, 0), ATT_LINK_E_BUSY);
    /* corrupted state is reported, not followed */
    s.state = 200;
    CHECK_EQ_INT(att_link_sender_poll(&s, 0, buf), ATT_LINK_E_STATE);
    r.state = 200;
    CHECK_EQ_INT(att_link_receiver_sink(&r, 0xAA, 0), ATT_LINK_E_STATE);
}

static void test_normal(void)
{
    rig r;
    static const uint8_t want_a[] = { 0xAA, 0x12, 0x34, 0x56, 0x78, 0x9A, 0xBC, 0x6A };
    static const uint8_t want_b[] = { 0xBB, 0x00 };
    rig_init(&r, 6, 20, 20, 5, 3);
    rig_send(&r, BLK, 0, 100);
    CHECK(same(r.a_log, r.a_n, want_a, sizeof want_a));
    CHECK(same(r.b_log, r.b_n, want_b, sizeof want_b));
    CHECK_EQ_INT(r.accepted, 1);
    CHECK_EQ_INT(r.a_accepted, 1);
    CHECK(memcmp(r.last_block, BLK, 6) == 0);
    CHECK_EQ_INT(r.a.stats.blocks_sent, 1);
    CHECK_EQ_INT(r.a.stats.blocks_accepted, 1);
    CHECK_EQ_INT(r.a.stats.naks + r.a.stats.timeouts + r.a.stats.gave_up + r.a.stats.bytes_discarded, 0);
    CHECK_EQ_INT(r.b.stats.syns, 1);
    CHECK_EQ_INT(r.b.stats.blocks_accepted, 1);
    CHECK_EQ_INT(r.b.stats.naks + r.b.stats.timeouts + r.b.stats.resyncs + r.b.stats.bytes_discarded, 0);
}

static void test_corrupted_block(void)
{
    rig r;
    /* data byte 3 (wire index 3) corrupted once: B answers 0xFF, A resends from 0xAA */
    static const uint8_t want_a[] = { 0xAA, 0x12, 0x34, 0x56, 0x78, 0x9A, 0xBC, 0x6A,
                                      0xAA, 0x12, 0x34, 0x56, 0x78, 0x9A, 0xBC, 0x6A };
    static const uint8_t want_b[] = { 0xBB, 0xFF, 0xBB, 0x00 };
    rig_init(&r, 6, 20, 20, 5, 3);
    r.a_flip_at = 3;
    r.a_flip = 0x01;
    rig_send(&r, BLK, 0, 200);
    CHECK(same(r.a_log, r.a_n, want_a, sizeof want_a));
    CHECK(same(r.b_log, r.b_n, want_b, sizeof want_b));
    CHECK_EQ_INT(r.rejected, 1);
    CHECK_EQ_INT(r.accepted, 1);
    CHECK_EQ_INT(r.a.stats.naks, 1);
    CHECK_EQ_INT(r.a.stats.blocks_sent, 2);
    CHECK_EQ_INT(r.b.stats.naks, 1);
    CHECK(memcmp(r.last_block, BLK, 6) == 0);
}

static void test_two_bit_error_undetected(void)
{
    rig r;
    /* bit 1 flipped in 0x12 (-> 0x10, -2) and in 0x34 (-> 0x36, +2): the sum
     * is unchanged and B accepts a wrong block -- the 8-bit sum's weakness */
    static const uint8_t wrong[6] = { 0x10, 0x36, 0x56, 0x78, 0x9A, 0xBC };
    rig_init(&r, 6, 20, 20, 5, 3);
    r.a_flip_at = 1;
    r.a_flip = 0x02;
    r.a_flip2_at = 2;
    r.a_flip2 = 0x02;
    rig_send(&r, BLK, 0, 100);
    CHECK_EQ_INT(r.accepted, 1);
    CHECK_EQ_INT(r.a_accepted, 1);
    CHECK(memcmp(r.last_block, wrong, 6) == 0);
}

static void test_lost_syn_ack(void)
{
    rig r;
    static const uint8_t want_a[] = { 0xAA, 0xAA, 0x12, 0x34, 0x56, 0x78, 0x9A, 0xBC, 0x6A };
    static const uint8_t want_b[] = { 0xBB, 0xBB, 0x00 };
    rig_init(&r, 6, 20, 20, 5, 3);
    r.b_drop = 0; /* the first 0xBB is lost */
    rig_send(&r, BLK, 0, 200);
    CHECK(same(r.a_log, r.a_n, want_a, sizeof want_a));
    CHECK(same(r.b_log, r.b_n, want_b, sizeof want_b));
    CHECK_EQ_INT(r.a.stats.timeouts, 1);
    CHECK_EQ_INT(r.a_timeouts, 1);
    CHECK_EQ_INT(r.b.stats.timeouts, 1); /* B gave up on the block it had opened */
    CHECK_EQ_INT(r.b_timeouts, 1);
    CHECK_EQ_INT(r.b.stats.syns, 2);
    CHECK_EQ_INT(r.accepted, 1);
}

static void test_lost_answer_duplicates(void)
{
    rig r;
    static const uint8_t want_b[] = { 0xBB, 0x00, 0xBB, 0x00 };
    rig_init(&r, 6, 20, 20, 5, 3);
    r.b_drop = 1; /* the first 0x00 is lost: A resends a block B already has */
    rig_send(&r, BLK, 0, 200);
    CHECK(same(r.b_log, r.b_n, want_b, sizeof want_b));
    CHECK_EQ_INT(r.accepted, 2); /* the duplicate the protocol cannot detect */
    CHECK_EQ_INT(r.a_accepted, 1);
    CHECK_EQ_INT(r.a.stats.timeouts, 1);
    CHECK_EQ_INT(r.a.stats.blocks_sent, 2);
}

static void test_garbage_before_syn(void)
{
    rig r;
    static const uint8_t want_b[] = { 0xBB, 0x00 };
    uint16_t t;
    rig_init(&r, 6, 20, 20, 5, 3);
    /* noise on the line before A starts: B discards it */
    CHECK_EQ_INT(att_link_receiver_sink(&r.b, 0x00, 0), ATT_LINK_DISCARDED);
    CHECK_EQ_INT(att_link_receiver_sink(&r.b, 0xBB, 0), ATT_LINK_DISCARDED);
    CHECK_EQ_INT(att_link_receiver_sink(&r.b, 0x55, 1), ATT_LINK_DISCARDED);
    t = rig_send(&r, BLK, 2, 100);
    (void)t;
    CHECK(same(r.b_log, r.b_n, want_b, sizeof want_b));
    CHECK_EQ_INT(r.b.stats.bytes_discarded, 3);
    CHECK_EQ_INT(r.b.stats.resyncs, 1);
    CHECK_EQ_INT(r.accepted, 1);
    /* garbage at A while idle or waiting is discarded and counted */
    CHECK_EQ_INT(att_link_sender_sink(&r.a, 0x42, 50), ATT_LINK_DISCARDED);
    CHECK_EQ_INT(r.a.stats.bytes_discarded, 1);
}

static void test_syn_inside_data(void)
{
    rig r;
    static const uint8_t blk[6] = { 0xAA, 0xAA, 0x00, 0xAA, 0xFF, 0xBB };
    rig_init(&r, 6, 20, 20, 5, 3);
    rig_send(&r, blk, 0, 100);
    CHECK_EQ_INT(r.accepted, 1);
    CHECK(memcmp(r.last_block, blk, 6) == 0);
    CHECK_EQ_INT(r.b.stats.syns, 1);
    /* checksum 0xAA*3 + 0xFF + 0xBB = 0x3B8 -> 0xB8 */
    CHECK_EQ_INT(r.a_log[7], 0xB8);
}

static void test_truncated_block(void)
{
    att_link_receiver b;
    att_link_receiver_config rc;
    uint8_t buf[6];
    uint8_t out = 0;
    att_link_receiver_config_init(&rc, 6);
    rc.gap_timeout = 5;
    CHECK_EQ_INT(att_link_receiver_init(&b, &rc, buf), ATT_OK);
    CHECK_EQ_INT(att_link_receiver_sink(&b, 0xAA, 100), ATT_LINK_SYN_RX);
    CHECK_EQ_INT(att_link_receiver_poll(&b, 100, &out), ATT_LINK_SEND);
    CHECK_EQ_INT(out, 0xBB);
    CHECK_EQ_INT(att_link_receiver_ticks_left(&b, 100), 6);
    CHECK_EQ_INT(att_link_receiver_sink(&b, 0x01, 101), ATT_LINK_DATA_RX);
    CHECK_EQ_INT(att_link_receiver_sink(&b, 0x02, 102), ATT_LINK_DATA_RX);
    CHECK_EQ_INT(att_link_receiver_poll(&b, 107, &out), ATT_LINK_NONE); /* gap 5: not yet */
    CHECK_EQ_INT(att_link_receiver_ticks_left(&b, 107), 1);
    CHECK_EQ_INT(att_link_receiver_poll(&b, 108, &out), ATT_LINK_TIMEOUT);
    CHECK_EQ_INT(att_link_receiver_poll(&b, 108, &out), ATT_LINK_IDLE);
    CHECK_EQ_INT(b.stats.timeouts, 1);
    CHECK_EQ_INT(b.stats.bytes_discarded, 2);
    /* a new handshake works at once */
    CHECK_EQ_INT(att_link_receiver_sink(&b, 0xAA, 110), ATT_LINK_SYN_RX);
    /* gap detected by sink when poll was not called: the late byte is
       handled as if B were idle (here: 0xAA starts a new handshake) */
    CHECK_EQ_INT(att_link_receiver_poll(&b, 110, &out), ATT_LINK_SEND);
    CHECK_EQ_INT(att_link_receiver_sink(&b, 0x07, 111), ATT_LINK_DATA_RX);
    CHECK_EQ_INT(att_link_receiver_sink(&b, 0xAA, 200), ATT_LINK_SYN_RX);
    CHECK_EQ_INT(att_link_receiver_poll(&b, 200, &out), ATT_LINK_TIMEOUT);
    CHECK_EQ_INT(att_link_receiver_poll(&b, 200, &out), ATT_LINK_SEND);
    CHECK_EQ_INT(out, 0xBB);
    CHECK_EQ_INT(b.stats.timeouts, 2);
    CHECK_EQ_INT(b.stats.syns, 3);
}

static void test_reboot_mid_block(void)
{
    rig r;
    static const uint8_t blk2[6] = { 1, 2, 3, 4, 5, 6 };
    uint16_t t;
    rig_init(&r, 6, 20, 20, 5, 3);
    /* A sends 0xAA and three data bytes, then reboots */
    CHECK_EQ_INT(att_link_sender_start(&r.a, BLK, 0), ATT_OK);
    for (t = 0; t < 5; t++) {
        rig_tick(&r, t);
    }
    CHECK(r.a_n >= 3);
    att_link_sender_reset(&r.a);
    r.a_qn = 0;
    /* after the reboot A starts a fresh block; B has dropped the partial one */
    t = rig_send(&r, blk2, 20, 100);
    CHECK_EQ_INT(r.accepted, 1);
    CHECK(memcmp(r.last_block, blk2, 6) == 0);
    CHECK_EQ_INT(r.b.stats.timeouts, 1);
    /* reboot of B mid-block: A's answer timer expires, A resends, B accepts */
    CHECK_EQ_INT(att_link_sender_start(&r.a, BLK, t), ATT_OK);
    rig_tick(&r, t);
    rig_tick(&r, (uint16_t)(t + 1));
    rig_tick(&r, (uint16_t)(t + 2));
    rig_tick(&r, (uint16_t)(t + 3));
    att_link_receiver_reset(&r.b);
    rig_run(&r, (uint16_t)(t + 4), 200);
    CHECK_EQ_INT(r.accepted, 2);
    CHECK_EQ_INT(r.a_accepted, 2);
    CHECK(memcmp(r.last_block, BLK, 6) == 0);
    CHECK_EQ_INT(r.a.stats.timeouts, 1);
    CHECK(r.b.stats.bytes_discarded > 0); /* the tail of the interrupted block */
}

static void test_give_up(void)
{
    rig r;
    uint16_t t;
    rig_init(&r, 6, 10, 10, 5, 3);
    r.b_drop = -1;
    /* B never answers: the receiver is not connected (drop everything A sends) */
    CHECK_EQ_INT(att_link_sender_start(&r.a, BLK, 65500), ATT_OK); /* across the 16-bit wrap */
    for (t = 65500; r.gave_up == 0 && t != 200; t++) {
        rig_tick(&r, t);
        r.a_qn = 0;
    }
    CHECK_EQ_INT(r.gave_up, 1);
    CHECK_EQ_INT(r.a_timeouts, 3);
    CHECK_EQ_INT(r.a.stats.timeouts, 3);
    CHECK_EQ_INT(r.a.stats.gave_up, 1);
    CHECK_EQ_INT(r.a_n, 3); /* three 0xAA, nothing else */
    /* 3 attempts x (timeout 10 -> expires after 11 ticks) = 33 ticks, wrapped */
    CHECK_EQ_INT((uint16_t)(t - 65500), 34);
    CHECK_EQ_INT(att_link_sender_ticks_left(&r.a, t), ATT_LINK_NO_TIMER);
}

static void test_ticks_left_and_late_byte(void)
{
    att_link_sender s;
    att_link_sender_config sc;
    uint8_t out;
    att_link_sender_config_init(&sc, 6);
    sc.syn_timeout = 10;
    CHECK_EQ_INT(att_link_sender_init(&s, &sc), ATT_OK);
    CHECK_EQ_INT(att_link_sender_ticks_left(&s, 0), ATT_LINK_NO_TIMER);
    CHECK_EQ_INT(att_link_sender_poll(&s, 0, &out), ATT_LINK_IDLE);
    CHECK_EQ_INT(att_link_sender_start(&s, BLK, 65530), ATT_OK);
    CHECK_EQ_INT(att_link_sender_ticks_left(&s, 65530), 0);
    CHECK_EQ_INT(att_link_sender_poll(&s, 65530, &out), ATT_LINK_SEND);
    CHECK_EQ_INT(out, 0xAA);
    CHECK_EQ_INT(att_link_sender_ticks_left(&s, 65530), 11);
    CHECK_EQ_INT(att_link_sender_ticks_left(&s, 4), 1);
    CHECK_EQ_INT(att_link_sender_poll(&s, 4, &out), ATT_LINK_NONE);
    /* a 0xBB arriving after the timer expired is late: discarded, and the
       timeout is reported by the next poll */
    CHECK_EQ_INT(att_link_sender_sink(&s, 0xBB, 5), ATT_LINK_DISCARDED);
    CHECK_EQ_INT(att_link_sender_poll(&s, 5, &out), ATT_LINK_TIMEOUT);
    CHECK_EQ_INT(att_link_sender_poll(&s, 5, &out), ATT_LINK_SEND);
    CHECK_EQ_INT(out, 0xAA);
    CHECK_EQ_INT(s.stats.timeouts, 1);
    CHECK_EQ_INT(s.stats.bytes_discarded, 1);
}

static void test_block_sizes(void)
{
    uint8_t blk[ATT_LINK_BLOCK_MAX];
    int n, i;
    for (i = 0; i < ATT_LINK_BLOCK_MAX; i++) {
        blk[i] = (uint8_t)(i * 37 + 0xA5);
    }
    for (n = 1; n <= ATT_LINK_BLOCK_MAX; n += 7) {
        rig r;
        rig_init(&r, (uint8_t)n, 200, 200, 100, 3);
        rig_send(&r, blk, 0, 400);
        CHECK_EQ_INT(r.accepted, 1);
        CHECK_EQ_INT(r.a_n, n + 2);
        CHECK(memcmp(r.last_block, blk, (size_t)n) == 0);
    }
}

int main(void)
{
    test_checksum();
    test_config();
    test_normal();
    test_corrupted_block();
    test_two_bit_error_undetected();
    test_lost_syn_ack();
    test_lost_answer_duplicates();
    test_garbage_before_syn();
    test_syn_inside_data();
    test_truncated_block();
    test_reboot_mid_block();
    test_give_up();
    test_ticks_left_and_late_byte();
    test_block_sizes();
    return ATT_TEST_REPORT();
}
