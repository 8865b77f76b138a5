/*
 * Tests of link v2 (attitude/link2.h): CRC-32C check value, the frame
 * layout byte for byte (SYN, its ACK, a DATA frame of packed codes), in-order
 * exactly-once delivery with duplicates suppressed, go-back after a lost
 * frame, back-pressure (nothing delivered beyond the room, window update),
 * a rebooted receiver (NOSESSION, new session, no record lost), garbage
 * before a frame, configuration checks, and the end-to-end simulation
 * through the channel model at BER 1e-3 and 1e-2.
 */
#include <string.h>

#include "att_test.h"
#include "attitude/link2.h"
#include "link2_sim.h"

typedef struct {
    att_link2_sender a;
    att_link2_receiver b;
    uint8_t ring[16 * 6];
    uint8_t out[ATT_LINK2_OUT_MAX];
    uint8_t got[4096];
    int n_got;
    uint16_t t;
    int drop_a_frame; /* drop the k-th frame A sends (1-based; 0 none) */
    int a_frames;
} rig;

static void rig_init(rig *r, uint8_t ring_size, uint16_t room)
{
    att_link2_sender_config c;
    memset(r, 0, sizeof(*r));
    att_link2_sender_config_init(&c, ring_size);
    c.max_samples = 4;
    CHECK_EQ_INT(att_link2_sender_init(&r->a, &c, r->ring), ATT_OK);
    CHECK_EQ_INT(att_link2_receiver_init(&r->b, r->out), ATT_OK);
    att_link2_receiver_set_room(&r->b, room);
}

/* One byte time: each end hands out one byte, which arrives at once. */
static void rig_step(rig *r)
{
    uint8_t byte;
    int st;
    do {
        st = att_link2_sender_poll(&r->a, r->t, &byte);
    } while (st == ATT_LINK2_TIMEOUT);
    if (st == ATT_LINK2_SEND) {
        int dropped = r->drop_a_frame != 0 && r->a_frames + 1 == r->drop_a_frame;
        if (byte == 0 && r->a.tx == 0) {
            r->a_frames++; /* the delimiter that ends a frame */
        }
        if (!dropped) {
            st = att_link2_receiver_sink(&r->b, byte);
            if (st == ATT_LINK2_DELIVERED) {
                memcpy(r->got + 6 * r->n_got, r->out, (size_t)r->b.n_out * 6u);
                r->n_got += r->b.n_out;
            }
        }
    }
    if (att_link2_receiver_poll(&r->b, &byte) == ATT_LINK2_SEND) {
        (void)att_link2_sender_sink(&r->a, byte, r->t);
    }
    r->t++;
}

static void sample(uint16_t i, uint8_t *rec)
{
    uint16_t c[3];
    int k;
    c[0] = (uint16_t)(i * 7u & 0xFFFu);
    c[1] = (uint16_t)(4095u - (i & 0xFFFu));
    c[2] = (uint16_t)((i * 2654u + 11u) & 0xFFFu);
    for (k = 0; k < 3; k++) {
        rec[2 * k] = (uint8_t)(c[k] >> 8);
        rec[2 * k + 1] = (uint8_t)c[k];
    }
}

static void test_crc(void)
{
    const uint8_t check[9] = { '1', '2', '3', '4', '5', '6', '7', '8', '9' };
    CHECK_EQ_INT(att_link2_crc(check, 9), 0xE3069283ul); /* CRC-32C check value (RFC 3720 family) */
    CHECK_EQ_INT(att_link2_crc(NULL, 3), 0);
}

/* The first bytes A sends: 0x00 (idle line), then SYN at seq 0 rCOBS-encoded, 0x00. */
static void test_syn_bytes(void)
{
    rig r;
    uint8_t byte, want[8];
    uint32_t crc;
    uint8_t syn[6] = { 0x80, 0x00, 0, 0, 0, 0 };
    int i;
    rig_init(&r, 16, 100);
    crc = att_link2_crc(syn, 2);
    syn[2] = (uint8_t)(crc >> 24);
    syn[3] = (uint8_t)(crc >> 16);
    syn[4] = (uint8_t)(crc >> 8);
    syn[5] = (uint8_t)crc;
    /* rCOBS by hand: 0x80, code for the zero (1 byte before it: 2), then the CRC (no zero in it), final code */
    want[0] = 0x00;
    want[1] = 0x80;
    want[2] = 0x02;
    for (i = 0; i < 4; i++) {
        want[3 + i] = syn[2 + i];
    }
    CHECK(syn[2] && syn[3] && syn[4] && syn[5]); /* true of this CRC: the hand encoding assumes it */
    want[7] = 5;
    for (i = 0; i < 8; i++) {
        CHECK_EQ_INT(att_link2_sender_poll(&r.a, 0, &byte), ATT_LINK2_SEND);
        CHECK_EQ_INT(byte, want[i]);
    }
    CHECK_EQ_INT(att_link2_sender_poll(&r.a, 0, &byte), ATT_LINK2_SEND);
    CHECK_EQ_INT(byte, 0x00);
    CHECK_EQ_INT(att_link2_sender_poll(&r.a, 0, &byte), ATT_LINK2_NONE); /* waits for SYNACK */
    CHECK_EQ_INT(att_link2_sender_ticks_left(&r.a, 0), 201);             /* rto 200 from the frame end */
}

static void run(rig *r, int steps)
{
    int i;
    for (i = 0; i < steps; i++) {
        rig_step(r);
    }
}

static void test_stream(void)
{
    rig r;
    uint8_t rec[6];
    uint16_t i, pushed = 0;
    rig_init(&r, 16, 1000);
    while (pushed < 100) {
        while (pushed < 100 && att_link2_sender_room(&r.a) > 0) {
            sample(pushed, rec);
            if (pushed == 50) {
                rec[0] = 0xFE; /* a report travels RAW */
                rec[1] = 3;
            }
            CHECK_EQ_INT(att_link2_sender_push(&r.a, rec), ATT_OK);
            pushed++;
        }
        rig_step(&r);
    }
    run(&r, 400);
    CHECK_EQ_INT(r.n_got, 100);
    for (i = 0; i < 100; i++) {
        sample(i, rec);
        if (i == 50) {
            rec[0] = 0xFE;
            rec[1] = 3;
        }
        CHECK(memcmp(r.got + 6 * i, rec, 6) == 0);
    }
    CHECK_EQ_INT(att_link2_sender_pending(&r.a), 0);
    CHECK_EQ_INT(r.b.stats.duplicates, 0);
    CHECK_EQ_INT(r.a.stats.resent, 0);
    CHECK_EQ_INT(att_link2_sender_poll(&r.a, r.t, rec), ATT_LINK2_IDLE);
    CHECK_EQ_INT(att_link2_sender_ticks_left(&r.a, r.t), ATT_LINK2_NO_TIMER);
}

/* att_link2_sender_tail: the slot the next push fills, NULL when the ring
 * is full; a record built there and pushed travels like a copied one. */
static void test_tail(void)
{
    rig r;
    uint8_t rec[6];
    uint8_t *slot;
    uint16_t i;
    rig_init(&r, 4, 1000);
    for (i = 0; i < 4; i++) {
        slot = att_link2_sender_tail(&r.a);
        CHECK(slot == r.ring + 6 * i);
        sample(i, slot);
        CHECK_EQ_INT(att_link2_sender_push(&r.a, slot), ATT_OK);
    }
    CHECK(att_link2_sender_tail(&r.a) == NULL);
    CHECK(att_link2_sender_tail(NULL) == NULL);
    run(&r, 200);
    CHECK_EQ_INT(r.n_got, 4);
    for (i = 0; i < 4; i++) {
        sample(i, rec);
        CHECK(memcmp(r.got + 6 * i, rec, 6) == 0);
    }
    CHECK(att_link2_sender_tail(&r.a) == r.ring); /* all acknowledged: the ring wrapped */
}

/* Frame 3 (the second DATA frame) is lost: B reports the gap, A goes back, all arrive once. */
static void test_lost_frame(void)
{
    rig r;
    uint8_t rec[6];
    uint16_t i;
    rig_init(&r, 16, 1000);
    r.drop_a_frame = 3;
    for (i = 0; i < 16; i++) {
        sample(i, rec);
        CHECK_EQ_INT(att_link2_sender_push(&r.a, rec), ATT_OK);
    }
    CHECK_EQ_INT(att_link2_sender_push(&r.a, rec), ATT_LINK2_E_FULL);
    run(&r, 600);
    CHECK_EQ_INT(r.n_got, 16);
    for (i = 0; i < 16; i++) {
        sample(i, rec);
        CHECK(memcmp(r.got + 6 * i, rec, 6) == 0);
    }
    CHECK(r.b.stats.gaps >= 1);
    CHECK_EQ_INT(r.a.stats.gobacks, 1);
    CHECK(r.a.stats.resent >= 4);
    CHECK_EQ_INT(att_link2_sender_pending(&r.a), 0);
}

/* Room 5: B delivers 5, refuses the rest, A stops at B's limit; room again: the rest. */
static void test_back_pressure(void)
{
    rig r;
    uint8_t rec[6];
    uint16_t i;
    rig_init(&r, 16, 5);
    for (i = 0; i < 12; i++) {
        sample(i, rec);
        CHECK_EQ_INT(att_link2_sender_push(&r.a, rec), ATT_OK);
    }
    run(&r, 3000);
    CHECK_EQ_INT(r.n_got, 5);
    CHECK_EQ_INT(r.b.room, 0);
    CHECK_EQ_INT(att_link2_sender_pending(&r.a), 7);
    CHECK_EQ_INT(r.b.stats.records, 5);
    att_link2_receiver_set_room(&r.b, 100);
    run(&r, 600);
    CHECK_EQ_INT(r.n_got, 12);
    for (i = 0; i < 12; i++) {
        sample(i, rec);
        CHECK(memcmp(r.got + 6 * i, rec, 6) == 0);
    }
    CHECK_EQ_INT(att_link2_sender_pending(&r.a), 0);
}

/* B reboots with records in flight: A re-SYNs at its base, nothing lost. */
static void test_receiver_reboot(void)
{
    rig r;
    uint8_t rec[6];
    uint16_t i, pushed = 0;
    rig_init(&r, 16, 1000);
    while (pushed < 40 || att_link2_sender_pending(&r.a) != 0) {
        while (pushed < 40 && att_link2_sender_room(&r.a) > 0) {
            sample(pushed, rec);
            CHECK_EQ_INT(att_link2_sender_push(&r.a, rec), ATT_OK);
            pushed++;
        }
        if (r.t == 200) {
            att_link2_receiver_reset(&r.b);
        }
        rig_step(&r);
        if (r.t > 20000) {
            break;
        }
    }
    CHECK_EQ_INT(r.n_got, 40);
    for (i = 0; i < 40 && i < r.n_got; i++) {
        sample(i, rec);
        CHECK(memcmp(r.got + 6 * i, rec, 6) == 0);
    }
    CHECK(r.a.stats.syns >= 2); /* one more per NOSESSION answer to a frame sent before the new SYN */
    CHECK(r.b.stats.no_session >= 1);
}

/* Garbage and a half frame before a SYN: the SYN is still taken. */
static void test_garbage(void)
{
    att_link2_receiver b;
    uint8_t out[ATT_LINK2_OUT_MAX], f[6] = { 0x80, 7, 0, 0, 0, 0 }, byte;
    uint32_t crc = att_link2_crc(f, 2);
    const uint8_t junk[5] = { 0x13, 0xFF, 0x80, 0x02, 0x44 };
    int i, st = 0;
    CHECK_EQ_INT(att_link2_receiver_init(&b, out), ATT_OK);
    for (i = 0; i < 5; i++) {
        CHECK_EQ_INT(att_link2_receiver_sink(&b, junk[i]), ATT_LINK2_NONE);
    }
    CHECK_EQ_INT(att_link2_receiver_sink(&b, 0x00), ATT_LINK2_BAD_FRAME);
    f[2] = (uint8_t)(crc >> 24);
    f[3] = (uint8_t)(crc >> 16);
    f[4] = (uint8_t)(crc >> 8);
    f[5] = (uint8_t)crc;
    /* seq 7 has no zero; the CRC bytes may: encode by rule */
    {
        uint8_t run = 0;
        for (i = 0; i < 6; i++) {
            if (f[i] == 0) {
                st = att_link2_receiver_sink(&b, (uint8_t)(run + 1));
                run = 0;
            } else {
                st = att_link2_receiver_sink(&b, f[i]);
                run++;
            }
            CHECK_EQ_INT(st, ATT_LINK2_NONE);
        }
        CHECK_EQ_INT(att_link2_receiver_sink(&b, (uint8_t)(run + 1)), ATT_LINK2_NONE);
    }
    CHECK_EQ_INT(att_link2_receiver_sink(&b, 0x00), ATT_LINK2_FRAME);
    CHECK_EQ_INT(b.synced, 1);
    CHECK_EQ_INT(b.expected, 7);
    CHECK_EQ_INT(att_link2_receiver_poll(&b, &byte), ATT_LINK2_SEND);
    CHECK_EQ_INT(byte, 0x00);
    /* an over-long frame is skipped to its delimiter */
    for (i = 0; i < ATT_LINK2_WIRE_MAX; i++) {
        CHECK_EQ_INT(att_link2_receiver_sink(&b, 0x55), ATT_LINK2_NONE);
    }
    CHECK_EQ_INT(att_link2_receiver_sink(&b, 0x55), ATT_LINK2_DISCARDED);
    CHECK_EQ_INT(att_link2_receiver_sink(&b, 0x55), ATT_LINK2_DISCARDED);
    CHECK_EQ_INT(att_link2_receiver_sink(&b, 0x00), ATT_LINK2_BAD_FRAME);
    CHECK_EQ_INT(b.stats.bytes_discarded, ATT_LINK2_WIRE_MAX + 2);
}

static void test_config(void)
{
    att_link2_sender a;
    att_link2_sender_config c;
    uint8_t ring[6 * 8], byte = 0;
    att_link2_sender_config_init(&c, 8);
    CHECK_EQ_INT(att_link2_sender_init(NULL, &c, ring), ATT_LINK2_E_NULL);
    CHECK_EQ_INT(att_link2_sender_init(&a, NULL, ring), ATT_LINK2_E_NULL);
    CHECK_EQ_INT(att_link2_sender_init(&a, &c, NULL), ATT_LINK2_E_NULL);
    c.ring_size = 6;
    CHECK_EQ_INT(att_link2_sender_init(&a, &c, ring), ATT_LINK2_E_CONFIG);
    CHECK_EQ_INT(att_link2_sender_poll(&a, 0, &byte), ATT_LINK2_E_STATE);
    CHECK_EQ_INT(att_link2_sender_push(&a, ring), ATT_LINK2_E_STATE);
    CHECK_EQ_INT(att_link2_sender_sink(&a, 0, 0), ATT_LINK2_E_STATE);
    CHECK_EQ_INT(att_link2_sender_room(&a), 0);
    c.ring_size = 8;
    c.max_samples = 0;
    CHECK_EQ_INT(att_link2_sender_init(&a, &c, ring), ATT_LINK2_E_CONFIG);
    c.max_samples = ATT_LINK2_SAMPLES_MAX + 1;
    CHECK_EQ_INT(att_link2_sender_init(&a, &c, ring), ATT_LINK2_E_CONFIG);
    c.max_samples = ATT_LINK2_SAMPLES_MAX;
    c.rto = 0;
    CHECK_EQ_INT(att_link2_sender_init(&a, &c, ring), ATT_LINK2_E_CONFIG);
    c.rto = ATT_LINK2_TIMEOUT_MAX + 1;
    CHECK_EQ_INT(att_link2_sender_init(&a, &c, ring), ATT_LINK2_E_CONFIG);
    c.rto = ATT_LINK2_TIMEOUT_MAX;
    CHECK_EQ_INT(att_link2_sender_init(&a, &c, ring), ATT_OK);
    CHECK_EQ_INT(att_link2_sender_poll(NULL, 0, &byte), ATT_LINK2_E_NULL);
    CHECK_EQ_INT(att_link2_sender_poll(&a, 0, NULL), ATT_LINK2_E_NULL);
    CHECK_EQ_INT(att_link2_sender_push(&a, NULL), ATT_LINK2_E_NULL);
    CHECK_EQ_INT(att_link2_sender_sink(NULL, 0, 0), ATT_LINK2_E_NULL);
    CHECK_EQ_INT(att_link2_receiver_init(NULL, ring), ATT_LINK2_E_NULL);
    CHECK_EQ_INT(att_link2_receiver_sink(NULL, 0), ATT_LINK2_E_NULL);
    CHECK_EQ_INT(att_link2_receiver_poll(NULL, &byte), ATT_LINK2_E_NULL);
}

/* The channel model end to end: exactly once, in order, unaltered. */
static void test_sim(double ber, double drop, uint64_t n)
{
    att_link_channel ch;
    att_link_channel_config cc;
    att_link2_sim_config c;
    att_link2_sim_result r;
    memset(&cc, 0, sizeof(cc));
    memset(&c, 0, sizeof(c));
    cc.a_to_b.ber = cc.b_to_a.ber = ber;
    cc.a_to_b.p_drop = cc.b_to_a.p_drop = drop;
    cc.a_to_b.p_insert = cc.b_to_a.p_insert = drop;
    cc.seed = 7;
    CHECK_EQ_INT(att_link_channel_init(&ch, &cc), ATT_OK);
    att_link2_sender_config_init(&c.sender, 32);
    c.sender.rto = 600; /* bit times: 62.5 ms at 9600 baud */
    c.ticks_per_byte = 10;
    c.n_records = n;
    c.report_every = 37;
    c.queue = 200;
    c.consume_period = 40;
    CHECK_EQ_INT(att_link2_sim_run(&c, &ch, &r), ATT_OK);
    CHECK_EQ_INT(r.delivered, n);
    CHECK_EQ_INT(r.in_order, n);
    CHECK_EQ_INT(r.corrupt, 0);
    CHECK_EQ_INT(r.duplicates, 0);
    CHECK_EQ_INT(r.lost, 0);
    CHECK_EQ_INT(r.acked, n);
}

int main(void)
{
    test_crc();
    test_syn_bytes();
    test_stream();
    test_tail();
    test_lost_frame();
    test_back_pressure();
    test_receiver_reboot();
    test_garbage();
    test_config();
    test_sim(1e-3, 0.0, 20000);
    test_sim(1e-2, 0.0, 500);
    test_sim(1e-4, 1e-3, 20000);
    return ATT_TEST_REPORT();
}
