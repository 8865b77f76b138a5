/*
 * libFuzzer target: link v2 (attitude/link2.h), both ends.
 *
 * Mode 0 (first byte even): sender A and receiver B through a channel the
 * fuzzer drives: it decides when each direction delivers, drops, corrupts,
 * duplicates a byte or inserts one, when time jumps (16-bit wrap crossed),
 * when records are pushed, how much room B's caller has, when A reboots.
 * What a corruption or an insertion puts on the line comes from a fixed
 * PRNG, not from the fuzzer, and the records' contents are a hash of their
 * number: the fuzzer can choose where faults hit, never forge a valid
 * frame (a CRC-32C pass by chance: 2^-32). Oracle: B hands its caller the
 * pushed records in order, each once, never more than the room it was
 * given (after an A reboot the stream may skip forward once: A lost its
 * window; the old A's last frame may still be completed by the new A's
 * leading delimiter; never backward); and once the line is clean and B has room, everything
 * A holds is delivered and acknowledged within a bounded time (never stuck).
 * ticks_left is checked by polling copies of A one tick before and at the
 * reported time.
 *
 * Mode 1: arbitrary bytes into B, then into A (ACKs the fuzzer may forge):
 * no out-of-bounds access (ASan), B delivers at most its room and at most
 * one frame's records, A's window bookkeeping stays consistent, and after
 * it all a fresh exchange still works (B takes a SYN and a DATA frame).
 */
#include <stdint.h>
#include <string.h>

#include "attitude/link2.h"

#define CHECK(c)              \
    do {                      \
        if (!(c)) {           \
            __builtin_trap(); \
        }                     \
    } while (0)

static uint64_t rng_state;

static uint8_t rng_byte(void)
{
    uint64_t z = (rng_state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return (uint8_t)(z ^ (z >> 31));
}

static void record(uint32_t i, uint8_t *rec)
{
    uint32_t h = (i + 1u) * 2654435761u;
    if (i % 29u == 28u) { /* a report: RAW frame */
        rec[0] = 0xFE;
        rec[1] = 3;
        rec[2] = (uint8_t)(i >> 8);
        rec[3] = (uint8_t)i;
        rec[4] = (uint8_t)(h >> 24);
        rec[5] = (uint8_t)(h >> 16);
        return;
    }
    rec[0] = (uint8_t)((h >> 28) & 0x0Fu);
    rec[1] = (uint8_t)(h >> 20);
    rec[2] = (uint8_t)((h >> 16) & 0x0Fu);
    rec[3] = (uint8_t)(h >> 8);
    rec[4] = (uint8_t)(h & 0x0Fu);
    rec[5] = (uint8_t)(h ^ (h >> 13));
}

typedef struct {
    att_link2_sender a;
    att_link2_receiver b;
    uint8_t ring[ATT_LINK2_RING_MAX * 6];
    uint8_t out[ATT_LINK2_OUT_MAX];
    uint8_t a_line[4], b_line[4]; /* byte handed out, not yet delivered (one per direction) */
    int a_full, b_full;
    uint32_t pushed, delivered;
    int may_skip;              /* A rebooted since the last delivery: the stream may jump forward */
    uint32_t pushed_at_reboot; /* records pushed before A's last reboot (those A held are lost) */
    uint16_t t;
} rig;

static void deliver_to_b(rig *r, uint8_t byte)
{
    uint8_t want[6];
    uint16_t room = r->b.room;
    int i, st = att_link2_receiver_sink(&r->b, byte);
    CHECK(st >= 0);
    if (st != ATT_LINK2_DELIVERED) {
        CHECK(r->b.n_out == 0);
        return;
    }
    CHECK(r->b.n_out >= 1 && r->b.n_out <= ATT_LINK2_SAMPLES_MAX && r->b.n_out <= room);
    CHECK(r->b.room == room - r->b.n_out);
    for (i = 0; i < r->b.n_out; i++) {
        record(r->delivered, want);
        if (memcmp(want, r->out + 6 * i, 6) != 0) {
            uint32_t k;
            CHECK(r->may_skip); /* only a rebooted A loses records: find the one delivered */
            for (k = r->delivered + 1; k < r->pushed; k++) {
                record(k, want);
                if (memcmp(want, r->out + 6 * i, 6) == 0) {
                    break;
                }
            }
            CHECK(k < r->pushed);
            r->delivered = k;
        }
        if (r->delivered >= r->pushed_at_reboot) {
            r->may_skip = 0; /* a record of the new session: no more skipping */
        }
        r->delivered++;
        CHECK(r->delivered <= r->pushed);
    }
}

/* ticks_left(now) = k: a copy polled at now + k - 1 does nothing on the clock, one at now + k does. */
static void check_ticks_left(const att_link2_sender *a, uint16_t now)
{
    att_link2_sender c;
    uint8_t byte;
    uint16_t k = att_link2_sender_ticks_left(a, now);
    int st;
    if (k == ATT_LINK2_NO_TIMER) {
        c = *a;
        st = att_link2_sender_poll(&c, (uint16_t)(now + 30000u), &byte);
        CHECK(st == ATT_LINK2_IDLE || st == ATT_LINK2_NONE);
        return;
    }
    if (k == 0) {
        c = *a;
        st = att_link2_sender_poll(&c, now, &byte);
        CHECK(st == ATT_LINK2_SEND || st == ATT_LINK2_TIMEOUT);
        return;
    }
    CHECK(k <= a->cfg.rto + 1u);
    c = *a;
    st = att_link2_sender_poll(&c, (uint16_t)(now + k - 1u), &byte);
    CHECK(st == ATT_LINK2_NONE || st == ATT_LINK2_IDLE);
    c = *a;
    st = att_link2_sender_poll(&c, (uint16_t)(now + k), &byte);
    CHECK(st == ATT_LINK2_SEND || st == ATT_LINK2_TIMEOUT);
}

static void sender_invariants(const att_link2_sender *a)
{
    uint8_t pend = (uint8_t)(a->head - a->base);
    CHECK(pend <= a->cfg.ring_size);
    CHECK((uint8_t)(a->hi - a->base) <= pend);
    CHECK((uint8_t)(a->next - a->base) <= (uint8_t)(a->hi - a->base) || a->next == a->hi);
    CHECK(a->cur >= 1 && a->cur <= a->cfg.max_samples);
    CHECK(att_link2_sender_room(a) <= a->cfg.ring_size);
}

/* One byte time: A and B hand out a byte each if their line is free. */
static void hand_out(rig *r)
{
    uint8_t byte;
    int st;
    if (!r->a_full) {
        do {
            st = att_link2_sender_poll(&r->a, r->t, &byte);
        } while (st == ATT_LINK2_TIMEOUT);
        CHECK(st >= 0);
        if (st == ATT_LINK2_SEND) {
            r->a_line[0] = byte;
            r->a_full = 1;
        }
    }
    if (!r->b_full) {
        st = att_link2_receiver_poll(&r->b, &byte);
        CHECK(st >= 0);
        if (st == ATT_LINK2_SEND) {
            r->b_line[0] = byte;
            r->b_full = 1;
        }
    }
}

static void push_all(rig *r, int n)
{
    uint8_t rec[6];
    while (n-- > 0 && att_link2_sender_room(&r->a) > 0) {
        record(r->pushed, rec);
        CHECK(att_link2_sender_push(&r->a, rec) == ATT_OK);
        r->pushed++;
    }
}

static void mode_link(const uint8_t *data, size_t size)
{
    static rig r; /* large; one at a time */
    att_link2_sender_config cfg;
    size_t i;
    int steps;
    memset(&r, 0, sizeof(r));
    rng_state = 0x1234;
    att_link2_sender_config_init(&cfg, (uint8_t)(1u << (((data[0] >> 1) & 7u) % 7u)));
    cfg.max_samples = (uint8_t)(1u + data[0] % ATT_LINK2_SAMPLES_MAX);
    cfg.rto = (uint16_t)(20u + (data[0] >> 4) * 7u);
    r.t = (uint16_t)(data[0] * 257u);
    CHECK(att_link2_sender_init(&r.a, &cfg, r.ring) == ATT_OK);
    CHECK(att_link2_receiver_init(&r.b, r.out) == ATT_OK);
    att_link2_receiver_set_room(&r.b, 30);
    for (i = 1; i < size; i++) {
        uint8_t op = data[i];
        check_ticks_left(&r.a, r.t);
        sender_invariants(&r.a);
        switch (op & 0x0Fu) {
        case 0:
        case 1:
        case 2:
        case 3: /* a byte time: each direction delivers what is on its line */
            if (r.a_full) {
                deliver_to_b(&r, r.a_line[0]);
                r.a_full = 0;
            }
            if (r.b_full) {
                CHECK(att_link2_sender_sink(&r.a, r.b_line[0], r.t) >= 0);
                r.b_full = 0;
            }
            r.t++;
            hand_out(&r);
            break;
        case 4: /* drop the byte on a line */
            if (op & 0x10u)
                r.a_full = 0;
            else
                r.b_full = 0;
            hand_out(&r);
            break;
        case 5: /* corrupt it (PRNG mask, never 0) */
            if (op & 0x10u)
                r.a_line[0] ^= (uint8_t)(rng_byte() | 1u);
            else
                r.b_line[0] ^= (uint8_t)(rng_byte() | 1u);
            break;
        case 6: /* insert a PRNG byte before it */
            if (op & 0x10u)
                deliver_to_b(&r, rng_byte());
            else
                CHECK(att_link2_sender_sink(&r.a, rng_byte(), r.t) >= 0);
            break;
        case 7: /* duplicate it */
            if ((op & 0x10u) && r.a_full)
                deliver_to_b(&r, r.a_line[0]);
            if (!(op & 0x10u) && r.b_full)
                CHECK(att_link2_sender_sink(&r.a, r.b_line[0], r.t) >= 0);
            break;
        case 8:
        case 9: /* records */
            push_all(&r, 1 + (op >> 4));
            break;
        case 10: /* room */
            att_link2_receiver_set_room(&r.b, (uint16_t)(op >> 4) * 3u);
            break;
        case 11: /* time jumps */
            r.t = (uint16_t)(r.t + (uint16_t)(op >> 4) * 97u);
            break;
        case 12:
            r.t = (uint16_t)(r.t + 32767u);
            hand_out(&r);
            break;
        case 13: /* A reboots: its window is lost */
            if ((op >> 4) == 5u) {
                att_link2_sender_reset(&r.a);
                r.a_full = 0;
                r.may_skip = 1;
                r.pushed_at_reboot = r.pushed;
            }
            break;
        default: /* poll both, nothing delivered */
            hand_out(&r);
            break;
        }
    }
    /* the line recovers: everything A holds reaches B, once, in order */
    att_link2_receiver_set_room(&r.b, 0xFFFFu);
    for (steps = 0; steps < 200000 && (att_link2_sender_pending(&r.a) != 0 || r.a_full || r.b_full);
         steps++) {
        if (r.a_full) {
            deliver_to_b(&r, r.a_line[0]);
            r.a_full = 0;
        }
        if (r.b_full) {
            CHECK(att_link2_sender_sink(&r.a, r.b_line[0], r.t) >= 0);
            r.b_full = 0;
        }
        r.t++;
        hand_out(&r);
    }
    CHECK(att_link2_sender_pending(&r.a) == 0);
    CHECK(r.delivered == r.pushed || (r.pushed == r.pushed_at_reboot && r.delivered <= r.pushed));
}

static void mode_raw(const uint8_t *data, size_t size)
{
    att_link2_receiver b;
    att_link2_sender a;
    att_link2_sender_config cfg;
    uint8_t out[ATT_LINK2_OUT_MAX], ring[8 * 6], rec[6], byte, f[12];
    uint8_t expected;
    uint32_t crc;
    size_t i, half = size / 2;
    uint16_t t = 0;
    int st, k;
    CHECK(att_link2_receiver_init(&b, out) == ATT_OK);
    att_link2_receiver_set_room(&b, data[0]);
    for (i = 1; i < half; i++) {
        uint16_t room = b.room;
        expected = b.expected;
        st = att_link2_receiver_sink(&b, data[i]);
        CHECK(st >= 0);
        if (st == ATT_LINK2_DELIVERED) {
            CHECK(b.n_out >= 1 && b.n_out <= room && b.n_out <= ATT_LINK2_SAMPLES_MAX);
            CHECK((uint8_t)(b.expected - expected) == b.n_out);
        } else {
            CHECK(b.expected == expected || st == ATT_LINK2_FRAME);
        }
        if (data[i] & 1u) {
            while (att_link2_receiver_poll(&b, &byte) == ATT_LINK2_SEND) {
            }
        }
    }
    /* B is never stuck: a delimiter, a SYN at 7 and a one-sample DATA frame are taken */
    att_link2_receiver_set_room(&b, 4);
    f[0] = 0x80;
    f[1] = 7;
    for (k = 0; k < 2; k++) {
        uint8_t len = k == 0 ? 2 : 7, j, run = 0;
        if (k == 1) {
            f[0] = 0x01;
            f[2] = 0x12;
            f[3] = 0x34;
            f[4] = 0x56;
            f[5] = 0x78;
            f[6] = 0x90;
        }
        crc = att_link2_crc(f, len);
        f[len] = (uint8_t)(crc >> 24);
        f[len + 1] = (uint8_t)(crc >> 16);
        f[len + 2] = (uint8_t)(crc >> 8);
        f[len + 3] = (uint8_t)crc;
        (void)att_link2_receiver_sink(&b, 0);
        for (j = 0; j < len + 4u; j++) {
            if (f[j] == 0) {
                CHECK(att_link2_receiver_sink(&b, (uint8_t)(run + 1u)) == ATT_LINK2_NONE);
                run = 0;
            } else {
                CHECK(att_link2_receiver_sink(&b, f[j]) == ATT_LINK2_NONE);
                run++;
            }
        }
        CHECK(att_link2_receiver_sink(&b, (uint8_t)(run + 1u)) == ATT_LINK2_NONE);
        st = att_link2_receiver_sink(&b, 0);
        CHECK(st == (k == 0 ? ATT_LINK2_FRAME : ATT_LINK2_DELIVERED));
    }
    CHECK(b.n_out == 1 && out[0] == 0x01 && out[1] == 0x23 && out[4] == 0x07 && out[5] == 0x89);

    /* A: any bytes (forged ACKs included) at any times: its bookkeeping holds */
    att_link2_sender_config_init(&cfg, 8);
    cfg.max_samples = 3;
    cfg.rto = 50;
    CHECK(att_link2_sender_init(&a, &cfg, ring) == ATT_OK);
    for (i = half; i < size; i++) {
        if ((data[i] & 3u) == 0u) {
            memset(rec, data[i], 6);
            (void)att_link2_sender_push(&a, rec);
        }
        st = att_link2_sender_sink(&a, data[i], t);
        CHECK(st >= 0);
        t = (uint16_t)(t + (data[i] >> 2));
        check_ticks_left(&a, t);
        while ((st = att_link2_sender_poll(&a, t, &byte)) == ATT_LINK2_SEND || st == ATT_LINK2_TIMEOUT) {
        }
        CHECK(st >= 0);
        sender_invariants(&a);
    }
    /* NULLs and a corrupted state */
    CHECK(att_link2_receiver_sink(NULL, 0) == ATT_LINK2_E_NULL);
    b.len = 200;
    CHECK(att_link2_receiver_sink(&b, 1) == ATT_LINK2_E_STATE);
    a.tx = 9;
    CHECK(att_link2_sender_poll(&a, 0, &byte) == ATT_LINK2_E_STATE);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 2) {
        return 0;
    }
    if (data[0] & 1u) {
        mode_raw(data + 1, size - 1);
    } else {
        mode_link(data + 1, size - 1);
    }
    return 0;
}
