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
 * Mode 1 (first byte & 3 == 1): arbitrary bytes into B, then into A (ACKs the fuzzer may forge):
 * no out-of-bounds access (ASan), B delivers at most its room and at most
 * one frame's records, A's window bookkeeping stays consistent, and after
 * it all a fresh exchange still works (B takes a SYN and a DATA frame).
 */
#include <stdint.h>
#include <string.h>

#include "attitude/link2.h"
#include "fuzz_harness.h"

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
    FUZZ_CHECK(st >= 0);
    if (st != ATT_LINK2_DELIVERED) {
        FUZZ_CHECK(r->b.n_out == 0);
        return;
    }
    FUZZ_CHECK(r->b.n_out >= 1 && r->b.n_out <= ATT_LINK2_SAMPLES_MAX && r->b.n_out <= room);
    FUZZ_CHECK(r->b.room == room - r->b.n_out);
    for (i = 0; i < r->b.n_out; i++) {
        record(r->delivered, want);
        if (memcmp(want, r->out + 6 * i, 6) != 0) {
            uint32_t k;
            FUZZ_CHECK(r->may_skip); /* only a rebooted A loses records: find the one delivered */
            for (k = r->delivered + 1; k < r->pushed; k++) {
                record(k, want);
                if (memcmp(want, r->out + 6 * i, 6) == 0) {
                    break;
                }
            }
            FUZZ_CHECK(k < r->pushed);
            r->delivered = k;
        }
        if (r->delivered >= r->pushed_at_reboot) {
            r->may_skip = 0; /* a record of the new session: no more skipping */
        }
        r->delivered++;
        FUZZ_CHECK(r->delivered <= r->pushed);
    }
}

#define QUIET(st) ((st) == ATT_LINK2_NONE || (st) == ATT_LINK2_IDLE)
#define FIRES(st) ((st) == ATT_LINK2_SEND || (st) == ATT_LINK2_TIMEOUT)

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
        FUZZ_CHECK(st == ATT_LINK2_IDLE || st == ATT_LINK2_NONE);
        return;
    }
    if (k == 0) {
        c = *a;
        st = att_link2_sender_poll(&c, now, &byte);
        FUZZ_CHECK(st == ATT_LINK2_SEND || st == ATT_LINK2_TIMEOUT);
        return;
    }
    FUZZ_CHECK(k <= a->cfg.rto + 1u);
    FUZZ_TIMER_ORACLE(att_link2_sender, a, now, k, att_link2_sender_poll, QUIET, FIRES);
}

static void sender_invariants(const att_link2_sender *a)
{
    uint8_t pend = (uint8_t)(a->head - a->base);
    FUZZ_CHECK(pend <= a->cfg.ring_size);
    FUZZ_CHECK((uint8_t)(a->hi - a->base) <= pend);
    FUZZ_CHECK((uint8_t)(a->next - a->base) <= (uint8_t)(a->hi - a->base) || a->next == a->hi);
    FUZZ_CHECK(a->cur >= 1 && a->cur <= a->cfg.max_samples);
    FUZZ_CHECK(att_link2_sender_room(a) <= a->cfg.ring_size);
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
        FUZZ_CHECK(st >= 0);
        if (st == ATT_LINK2_SEND) {
            r->a_line[0] = byte;
            r->a_full = 1;
        }
    }
    if (!r->b_full) {
        st = att_link2_receiver_poll(&r->b, &byte);
        FUZZ_CHECK(st >= 0);
        if (st == ATT_LINK2_SEND) {
            r->b_line[0] = byte;
            r->b_full = 1;
        }
    }
}

/* A byte time on the channel: each direction delivers what is on its line, the clock
   ticks, and both ends hand out their next byte. */
static void byte_time(rig *r)
{
    if (r->a_full) {
        deliver_to_b(r, r->a_line[0]);
        r->a_full = 0;
    }
    if (r->b_full) {
        FUZZ_CHECK(att_link2_sender_sink(&r->a, r->b_line[0], r->t) >= 0);
        r->b_full = 0;
    }
    r->t++;
    hand_out(r);
}

/* Every other record is built in the ring slot tail() hands out (the 8051's way). */
static void push_all(rig *r, int n)
{
    uint8_t rec[6];
    uint8_t *slot;
    while (n-- > 0 && att_link2_sender_room(&r->a) > 0) {
        slot = att_link2_sender_tail(&r->a);
        FUZZ_CHECK(slot != NULL);
        if (r->pushed & 1u) {
            record(r->pushed, slot);
            FUZZ_CHECK(att_link2_sender_push(&r->a, slot) == ATT_OK);
        } else {
            record(r->pushed, rec);
            FUZZ_CHECK(att_link2_sender_push(&r->a, rec) == ATT_OK);
        }
        r->pushed++;
    }
    if (att_link2_sender_room(&r->a) == 0) {
        FUZZ_CHECK(att_link2_sender_tail(&r->a) == NULL);
        record(r->pushed, rec);
        FUZZ_CHECK(att_link2_sender_push(&r->a, rec) == ATT_LINK2_E_FULL);
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
    FUZZ_CHECK(att_link2_sender_init(&r.a, &cfg, r.ring) == ATT_OK);
    FUZZ_CHECK(att_link2_receiver_init(&r.b, r.out) == ATT_OK);
    att_link2_receiver_set_room(&r.b, 30);
    for (i = 1; i < size; i++) {
        uint8_t op = data[i];
        check_ticks_left(&r.a, r.t);
        sender_invariants(&r.a);
        switch (op & 0x0Fu) {
        case 0:
        case 1:
        case 2:
        case 3: /* a byte time */
            byte_time(&r);
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
                FUZZ_CHECK(att_link2_sender_sink(&r.a, rng_byte(), r.t) >= 0);
            break;
        case 7: /* duplicate it */
            if ((op & 0x10u) && r.a_full)
                deliver_to_b(&r, r.a_line[0]);
            if (!(op & 0x10u) && r.b_full)
                FUZZ_CHECK(att_link2_sender_sink(&r.a, r.b_line[0], r.t) >= 0);
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
    for (steps = 0; steps < 200000 && (att_link2_sender_pending(&r.a) != 0 || r.a_full || r.b_full); steps++)
        byte_time(&r);
    FUZZ_CHECK(att_link2_sender_pending(&r.a) == 0);
    FUZZ_CHECK(r.delivered == r.pushed || (r.pushed == r.pushed_at_reboot && r.delivered <= r.pushed));
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
    FUZZ_CHECK(att_link2_receiver_init(&b, out) == ATT_OK);
    att_link2_receiver_set_room(&b, data[0]);
    for (i = 1; i < half; i++) {
        uint16_t room = b.room;
        expected = b.expected;
        st = att_link2_receiver_sink(&b, data[i]);
        FUZZ_CHECK(st >= 0);
        if (st == ATT_LINK2_DELIVERED) {
            FUZZ_CHECK(b.n_out >= 1 && b.n_out <= room && b.n_out <= ATT_LINK2_SAMPLES_MAX);
            FUZZ_CHECK((uint8_t)(b.expected - expected) == b.n_out);
        } else {
            FUZZ_CHECK(b.expected == expected || st == ATT_LINK2_FRAME);
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
                FUZZ_CHECK(att_link2_receiver_sink(&b, (uint8_t)(run + 1u)) == ATT_LINK2_NONE);
                run = 0;
            } else {
                FUZZ_CHECK(att_link2_receiver_sink(&b, f[j]) == ATT_LINK2_NONE);
                run++;
            }
        }
        FUZZ_CHECK(att_link2_receiver_sink(&b, (uint8_t)(run + 1u)) == ATT_LINK2_NONE);
        st = att_link2_receiver_sink(&b, 0);
        FUZZ_CHECK(st == (k == 0 ? ATT_LINK2_FRAME : ATT_LINK2_DELIVERED));
    }
    FUZZ_CHECK(b.n_out == 1 && out[0] == 0x01 && out[1] == 0x23 && out[4] == 0x07 && out[5] == 0x89);

    /* A: any bytes (forged ACKs included) at any times: its bookkeeping holds */
    att_link2_sender_config_init(&cfg, 8);
    cfg.max_samples = 3;
    cfg.rto = 50;
    FUZZ_CHECK(att_link2_sender_init(&a, &cfg, ring) == ATT_OK);
    for (i = half; i < size; i++) {
        if ((data[i] & 3u) == 0u) {
            memset(rec, data[i], 6);
            (void)att_link2_sender_push(&a, rec);
        }
        st = att_link2_sender_sink(&a, data[i], t);
        FUZZ_CHECK(st >= 0);
        t = (uint16_t)(t + (data[i] >> 2));
        check_ticks_left(&a, t);
        while ((st = att_link2_sender_poll(&a, t, &byte)) == ATT_LINK2_SEND || st == ATT_LINK2_TIMEOUT) {
        }
        FUZZ_CHECK(st >= 0);
        sender_invariants(&a);
    }
    /* NULLs and a corrupted state */
    FUZZ_CHECK(att_link2_receiver_sink(NULL, 0) == ATT_LINK2_E_NULL);
    b.len = 200;
    FUZZ_CHECK(att_link2_receiver_sink(&b, 1) == ATT_LINK2_E_STATE);
    a.tx = 9;
    FUZZ_CHECK(att_link2_sender_poll(&a, 0, &byte) == ATT_LINK2_E_STATE);
}

/* -- mode 3: well-formed frames and ACKs (valid CRC, fuzzer-chosen fields) -- */

/* rCOBS, from docs/link.md: every 0 becomes the count of bytes since the
 * previous 0 (or the start) plus one, and that count for the tail follows
 * the last byte. n + 1 bytes out, none 0. */
static size_t rcobs(const uint8_t *in, size_t n, uint8_t *out)
{
    size_t i;
    uint8_t run = 0;
    for (i = 0; i < n; i++) {
        out[i] = in[i] != 0 ? in[i] : (uint8_t)(run + 1u);
        run = in[i] != 0 ? (uint8_t)(run + 1u) : 0u;
    }
    out[n] = (uint8_t)(run + 1u);
    return n + 1;
}

/* f[0..n) followed by its CRC-32C, most significant byte first: returns n + 4. */
static size_t with_crc(uint8_t *f, size_t n)
{
    uint32_t crc = att_link2_crc(f, (uint16_t)n);
    f[n] = (uint8_t)(crc >> 24);
    f[n + 1] = (uint8_t)(crc >> 16);
    f[n + 2] = (uint8_t)(crc >> 8);
    f[n + 3] = (uint8_t)crc;
    return n + 4;
}

/* Code m of a DATA payload: nibbles 3m, 3m + 1, 3m + 2 of the nibble stream
 * (high nibble of each byte first), as the spec packs them. */
static uint16_t code_at(const uint8_t *payload, unsigned m)
{
    uint16_t v = 0;
    unsigned j;
    for (j = 3 * m; j < 3 * m + 3; j++) {
        v = (uint16_t)((v << 4) | ((j & 1u) ? (payload[j / 2] & 0x0Fu) : (payload[j / 2] >> 4)));
    }
    return v;
}

/* The receiver as the spec describes it (docs/link.md), for mode 3's oracle. */
typedef struct {
    int synced;
    uint8_t expected, last_limit;
    uint16_t room;
} rx_model;

/* B polled: the ACK the model expects (flags given), or IDLE (flags < 0). */
static void expect_ack(att_link2_receiver *b, rx_model *m, int flags)
{
    uint8_t d[8], want[10], byte;
    size_t n, i;
    if (flags < 0) {
        FUZZ_CHECK(att_link2_receiver_poll(b, &byte) == ATT_LINK2_IDLE);
        return;
    }
    d[0] = (uint8_t)(ATT_LINK2_T_ACK | flags);
    d[1] = m->synced ? m->expected : 0u;
    d[2] = m->synced ? (uint8_t)(m->expected + (m->room > 127u ? 127u : m->room)) : 0u;
    want[0] = 0;
    n = rcobs(d, with_crc(d, 3), want + 1);
    FUZZ_CHECK(n == 8);
    want[9] = 0;
    for (i = 0; i < 10; i++) {
        FUZZ_CHECK(att_link2_receiver_poll(b, &byte) == ATT_LINK2_SEND && byte == want[i]);
    }
    FUZZ_CHECK(att_link2_receiver_poll(b, &byte) == ATT_LINK2_IDLE);
    m->last_limit = d[2];
}

/* Frame f[0..len) (CRC appended here) into B: result, delivery and ACK as the model says. */
static void frame_to_b(att_link2_receiver *b, rx_model *m, const uint8_t *out, uint8_t *f, size_t len)
{
    uint8_t wire[ATT_LINK2_WIRE_MAX + 8];
    uint8_t h = f[0], seq = f[1], off;
    size_t n, i;
    unsigned cnt = 0, k, c;
    int valid, st, flags;
    n = rcobs(f, with_crc(f, len), wire);
    FUZZ_CHECK(att_link2_receiver_sink(b, 0) == ATT_LINK2_NONE);
    for (i = 0; i < n; i++) {
        st = att_link2_receiver_sink(b, wire[i]);
        FUZZ_CHECK(st == (i < ATT_LINK2_WIRE_MAX ? ATT_LINK2_NONE : ATT_LINK2_DISCARDED));
    }
    st = att_link2_receiver_sink(b, 0);
    switch (h & 0xC0u) {
    case ATT_LINK2_T_DATA:
        cnt = h & 0x1Fu;
        valid = len >= 2 && cnt <= ATT_LINK2_SAMPLES_MAX && len == 2 + (9 * cnt + 1) / 2
                && !((cnt & 1u) && (f[len - 1] & 0x0Fu) != 0);
        break;
    case ATT_LINK2_T_RAW:
        cnt = 1;
        valid = (h & ~ATT_LINK2_E_BIT) == ATT_LINK2_T_RAW && len == 2 + ATT_LINK2_RECORD;
        break;
    case ATT_LINK2_T_SYN:
        valid = h == ATT_LINK2_T_SYN && len == 2;
        break;
    default:
        valid = 0;
        break;
    }
    if (!valid || len < 2) {
        FUZZ_CHECK(st == ATT_LINK2_BAD_FRAME);
        expect_ack(b, m, -1);
        return;
    }
    if (h == ATT_LINK2_T_SYN) {
        FUZZ_CHECK(st == ATT_LINK2_FRAME);
        m->synced = 1;
        m->expected = seq;
        expect_ack(b, m, ATT_LINK2_F_SYNACK);
        return;
    }
    flags = (h & ATT_LINK2_E_BIT) ? ATT_LINK2_F_EPOCH : 0;
    off = (uint8_t)(m->expected - seq);
    if (!m->synced || off > 127u) {
        FUZZ_CHECK(st == ATT_LINK2_FRAME);
        expect_ack(b, m, m->synced ? (ATT_LINK2_F_GAP | flags) : ATT_LINK2_F_NOSESSION);
        return;
    }
    k = off >= cnt ? 0u : cnt - off;
    if (k > m->room) {
        k = m->room;
    }
    if (k == 0) {
        FUZZ_CHECK(st == ATT_LINK2_FRAME);
    } else {
        FUZZ_CHECK(st == ATT_LINK2_DELIVERED && b->n_out == k);
        for (i = 0; i < k; i++) {
            for (c = 0; c < 3; c++) {
                uint16_t v = (h & ATT_LINK2_T_RAW) ? (uint16_t)((f[2 + 2 * c] << 8) | f[3 + 2 * c])
                                                   : code_at(f + 2, 3 * (off + (unsigned)i) + c);
                FUZZ_CHECK(out[6 * i + 2 * c] == (uint8_t)(v >> 8) && out[6 * i + 2 * c + 1] == (uint8_t)v);
            }
        }
        m->expected = (uint8_t)(m->expected + k);
        m->room = (uint16_t)(m->room - k);
    }
    expect_ack(b, m, flags);
}

/* A valid ACK (flags, ack, limit) into A: it never acknowledges what was never sent. */
static void ack_to_a(att_link2_sender *a, uint8_t flags, uint8_t ack, uint8_t limit, uint16_t t)
{
    uint8_t d[8], wire[8];
    uint8_t base = a->base, hi = a->hi, head = a->head, next = a->next;
    size_t i;
    int st;
    d[0] = (uint8_t)(ATT_LINK2_T_ACK | (flags & 0x0Fu));
    d[1] = ack;
    d[2] = limit;
    FUZZ_CHECK(rcobs(d, with_crc(d, 3), wire) == 8);
    FUZZ_CHECK(att_link2_sender_sink(a, 0, t) == ATT_LINK2_NONE);
    for (i = 0; i < 8; i++) {
        FUZZ_CHECK(att_link2_sender_sink(a, wire[i], t) == ATT_LINK2_NONE);
    }
    st = att_link2_sender_sink(a, 0, t);
    FUZZ_CHECK(st == ATT_LINK2_FRAME || st == ATT_LINK2_BAD_FRAME);
    FUZZ_CHECK(a->head == head);
    if (st == ATT_LINK2_BAD_FRAME) { /* acknowledges records never sent: ignored */
        FUZZ_CHECK((uint8_t)(ack - base) > (uint8_t)(hi - base) && a->base == base && a->hi == hi
                   && a->next == next);
        return;
    }
    if (flags & ATT_LINK2_F_NOSESSION) { /* B lost the session: SYN again at base, ring kept */
        FUZZ_CHECK(a->base == base && att_link2_sender_ticks_left(a, t) == 0);
        return;
    }
    FUZZ_CHECK(a->base == base || (a->base == ack && (uint8_t)(ack - base) <= (uint8_t)(hi - base)));
}

/* The calls every unusable or absent sender / receiver must refuse. */
static void refusals(void)
{
    att_link2_sender a;
    att_link2_sender_config cfg;
    att_link2_receiver b;
    uint8_t ring[6], out[ATT_LINK2_OUT_MAX], byte = 0;
    att_link2_sender_config_init(NULL, 4);
    att_link2_sender_reset(NULL);
    att_link2_receiver_reset(NULL);
    att_link2_receiver_set_room(NULL, 3);
    FUZZ_CHECK(att_link2_crc(NULL, 3) == 0);
    FUZZ_CHECK(att_link2_sender_ticks_left(NULL, 0) == ATT_LINK2_NO_TIMER);
    FUZZ_CHECK(att_link2_sender_room(NULL) == 0 && att_link2_sender_pending(NULL) == 0);
    FUZZ_CHECK(att_link2_sender_tail(NULL) == NULL);
    FUZZ_CHECK(att_link2_sender_push(NULL, ring) == ATT_LINK2_E_NULL);
    FUZZ_CHECK(att_link2_sender_sink(NULL, 1, 0) == ATT_LINK2_E_NULL);
    FUZZ_CHECK(att_link2_sender_poll(NULL, 0, &byte) == ATT_LINK2_E_NULL);
    att_link2_sender_config_init(&cfg, 1);
    FUZZ_CHECK(att_link2_sender_init(NULL, &cfg, ring) == ATT_LINK2_E_NULL);
    FUZZ_CHECK(att_link2_sender_init(&a, NULL, ring) == ATT_LINK2_E_NULL);
    FUZZ_CHECK(att_link2_sender_init(&a, &cfg, NULL) == ATT_LINK2_E_NULL);
    FUZZ_CHECK(att_link2_sender_init(&a, &cfg, ring) == ATT_OK);
    FUZZ_CHECK(att_link2_sender_push(&a, NULL) == ATT_LINK2_E_NULL);
    FUZZ_CHECK(att_link2_sender_poll(&a, 0, NULL) == ATT_LINK2_E_NULL);
    FUZZ_CHECK(att_link2_receiver_init(NULL, out) == ATT_LINK2_E_NULL);
    FUZZ_CHECK(att_link2_receiver_init(&b, NULL) == ATT_LINK2_E_NULL);
    FUZZ_CHECK(att_link2_receiver_poll(NULL, &byte) == ATT_LINK2_E_NULL);
    FUZZ_CHECK(att_link2_receiver_init(&b, out) == ATT_OK);
    FUZZ_CHECK(att_link2_receiver_poll(&b, NULL) == ATT_LINK2_E_NULL);
    b.tx_pos = 3; /* past tx_len: corrupted */
    FUZZ_CHECK(att_link2_receiver_poll(&b, &byte) == ATT_LINK2_E_STATE);
    b.tx_pos = 0;
    b.tx_len = 11; /* longer than tx */
    FUZZ_CHECK(att_link2_receiver_poll(&b, &byte) == ATT_LINK2_E_STATE);
}

/* Mode 3: d[0..3] configure A (any values: out of range ones must be refused
 * and leave A refusing every call); then ops drive B with well-formed frames
 * (valid CRC; fields, types and lengths the fuzzer's) checked against a model
 * of the spec (result, records delivered, the exact ACK), and A with valid
 * ACKs carrying any flags, ack and limit. */
static void mode_frames(const uint8_t *data, size_t size)
{
    static uint8_t ring[ATT_LINK2_RING_MAX * 6];
    att_link2_sender a;
    att_link2_sender_config cfg;
    att_link2_receiver b;
    rx_model m;
    uint8_t out[ATT_LINK2_OUT_MAX], f[ATT_LINK2_FRAME_MAX + 8], rec[6], byte;
    size_t i = 4, j, len;
    uint16_t t = 0, room;
    int a_ok, st;
    memset(f, 0, sizeof(f));
    refusals();
    if (size < 4) {
        return;
    }
    att_link2_sender_config_init(&cfg, data[3]);
    FUZZ_CHECK(cfg.ring_size == data[3] && cfg.rto == 200 && cfg.max_samples == ATT_LINK2_SAMPLES_DEFAULT);
    if (data[2] & 0x80u) { /* otherwise the defaults */
        cfg.rto = (uint16_t)((data[0] << 8) | data[1]);
        cfg.max_samples = (uint8_t)(data[2] & 0x7Fu);
    }
    a_ok = cfg.ring_size >= 1 && cfg.ring_size <= ATT_LINK2_RING_MAX
           && (cfg.ring_size & (cfg.ring_size - 1)) == 0 && cfg.max_samples >= 1
           && cfg.max_samples <= ATT_LINK2_SAMPLES_MAX && cfg.rto >= 1 && cfg.rto <= ATT_LINK2_TIMEOUT_MAX;
    st = att_link2_sender_init(&a, &cfg, ring);
    FUZZ_CHECK(st == (a_ok ? ATT_OK : ATT_LINK2_E_CONFIG));
    if (!a_ok) {
        memset(rec, 0, sizeof(rec));
        FUZZ_CHECK(att_link2_sender_room(&a) == 0 && att_link2_sender_pending(&a) == 0);
        FUZZ_CHECK(att_link2_sender_tail(&a) == NULL);
        FUZZ_CHECK(att_link2_sender_push(&a, rec) == ATT_LINK2_E_STATE);
        FUZZ_CHECK(att_link2_sender_sink(&a, 0, 0) == ATT_LINK2_E_STATE);
        FUZZ_CHECK(att_link2_sender_poll(&a, 0, &byte) == ATT_LINK2_E_STATE);
        FUZZ_CHECK(att_link2_sender_ticks_left(&a, 0) == ATT_LINK2_NO_TIMER);
    }
    FUZZ_CHECK(att_link2_receiver_init(&b, out) == ATT_OK);
    memset(&m, 0, sizeof(m));
    while (i < size) {
        uint8_t op = data[i++];
        uint8_t x = i < size ? data[i] : 0u, y = i + 1 < size ? data[i + 1] : 0u;
        switch (op & 7u) {
        case 0: /* a frame of x % 111 bytes (before its CRC): those that follow */
            len = x % (ATT_LINK2_FRAME_MAX - 3u);
            i++;
            for (j = 0; j < len; j++) {
                f[j] = i < size ? data[i++] : 0u;
            }
            if (len >= 2 && (op & 0x08u) && (f[0] & 0xC0u) == ATT_LINK2_T_DATA
                && (f[0] & 0x1Fu) <= ATT_LINK2_SAMPLES_MAX) {
                f[0] = (uint8_t)(f[0] & 0x3Fu); /* a well-sized DATA frame, more often than by chance */
                len = 2 + (9u * (f[0] & 0x1Fu) + 1u) / 2u;
                for (; j < len; j++) {
                    f[j] = i < size ? data[i++] : 0u;
                }
                if (f[0] & 1u) {
                    f[len - 1] &= 0xF0u;
                }
            }
            frame_to_b(&b, &m, out, f, len);
            break;
        case 1: /* room: a window update when it opens a window narrower than a frame */
            room = (uint16_t)((op >> 3) * x);
            i++;
            {
                uint8_t old = (uint8_t)(m.last_limit - m.expected);
                uint8_t w = room > 127u ? 127u : (uint8_t)room;
                att_link2_receiver_set_room(&b, room);
                m.room = room;
                expect_ack(&b, &m, (m.synced && old < ATT_LINK2_SAMPLES_MAX && w > old) ? 0 : -1);
            }
            break;
        case 2: /* B reboots */
            att_link2_receiver_reset(&b);
            m.synced = 0;
            m.expected = 0;
            m.last_limit = 0;
            expect_ack(&b, &m, -1);
            break;
        case 3: /* a stray byte and a delimiter: a bad frame, nothing answered */
            FUZZ_CHECK(att_link2_receiver_sink(&b, (uint8_t)(op | 1u)) == ATT_LINK2_NONE);
            FUZZ_CHECK(att_link2_receiver_sink(&b, 0) == ATT_LINK2_BAD_FRAME);
            expect_ack(&b, &m, -1);
            break;
        default:
            if (!a_ok) {
                break;
            }
            switch (op & 7u) {
            case 4: /* push (ring full: refused) */
                memset(rec, x, sizeof(rec));
                rec[0] = (uint8_t)(op >> 4);
                i++;
                room = att_link2_sender_room(&a);
                FUZZ_CHECK((att_link2_sender_tail(&a) == NULL) == (room == 0));
                FUZZ_CHECK(att_link2_sender_push(&a, rec) == (room != 0 ? ATT_OK : ATT_LINK2_E_FULL));
                break;
            case 5: /* A sends (to nowhere) */
                for (j = 0; j < 2000
                            && ((st = att_link2_sender_poll(&a, t, &byte)) == ATT_LINK2_SEND
                                || st == ATT_LINK2_TIMEOUT);
                     j++) {
                }
                FUZZ_CHECK(st >= 0);
                break;
            case 6: /* a valid ACK */
                ack_to_a(&a, (uint8_t)(op >> 4), x, y, t);
                i += 2;
                break;
            default: /* time passes */
                t = (uint16_t)(t + (uint16_t)((op >> 3) + 1u) * x);
                i++;
                break;
            }
            check_ticks_left(&a, t);
            sender_invariants(&a);
            break;
        }
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 2) {
        return 0;
    }
    if ((data[0] & 3u) == 3u) {
        mode_frames(data + 1, size - 1);
    } else if (data[0] & 1u) {
        mode_raw(data + 1, size - 1);
    } else {
        mode_link(data + 1, size - 1);
    }
    return 0;
}
