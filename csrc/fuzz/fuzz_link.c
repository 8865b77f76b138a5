/*
 * libFuzzer target for the link machines (attitude/link.h): sender A and
 * receiver B talking through a channel the fuzzer controls, built with
 * AddressSanitizer + UndefinedBehaviorSanitizer (`invoke fuzz`).
 *
 * Input: a 10-byte header (block size, attempts, gap / syn / answer
 * timeouts, the start tick: a run starts anywhere on the 16-bit clock, so
 * it crosses the wrap), then operations, one byte each (some take the next
 * byte as argument): deliver 1..4 bytes A -> B or B -> A; let 0..128 ticks
 * pass; jump up to 32767 ticks (the longest wait the contract allows, so
 * every timer expires and the clock wraps); inject a byte into B or A;
 * drop or corrupt a byte in flight; reset either end; start A while busy.
 * After an operation both ends are polled at the current tick, until they
 * have nothing more to do (A's transmitter is free), unless its bit 7 says
 * not to (a busy transmitter, a busy host): then the next byte's sink finds
 * an expired timer before any poll does, and B may take a byte before
 * handing out its answer to the previous one. Both ends are polled at
 * least every 32767 ticks, as the contract asks.
 *
 * Oracles (abort() on a violation):
 *  - A's every sink and poll result and every byte it hands out are those
 *    of a model of the protocol written from docs/link.md: 0xAA first,
 *    data only after 0xBB arrived, the exact block and its checksum, a
 *    timer that expires when more than its timeout has elapsed (wrap-safe),
 *    a retry after 0xFF or a timeout, at most max_attempts attempts, then
 *    GAVE_UP; A's statistics equal the model's counts.
 *  - B likewise, against a model of B: 0xAA starts a block only when
 *    idle, N data bytes and the checksum, 0xBB / 0x00 / 0xFF handed out as
 *    the answer to the last byte taken, a gap timer restarted by each byte
 *    and by 0xBB leaving, a block dropped when it expires (a 0xBB not yet
 *    handed out with it), reported once; every statistic. A block it
 *    accepts has the checksum it got; its index stays within the block.
 *  - att_link_*_ticks_left(now) = k: polling a copy of the machine at
 *    now + k - 1 fires no timer, at now + k it fires (0: poll acts now,
 *    ATT_LINK_NO_TIMER: no timer runs).
 *  - at the end, at most N + 1 bytes or one gap timeout bring B back to idle.
 *  - every documented error: NULL pointers, bad configurations (a sender
 *    whose init failed answers every call with an error), a corrupted state.
 */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "attitude/link.h"
#include "fuzz_harness.h"

/* ---- a byte FIFO per direction ---- */

enum {
    FIFO_CAP = 1024
};

typedef struct {
    uint8_t b[FIFO_CAP];
    size_t head, n;
} fifo;

static void fifo_put(fifo *f, uint8_t v)
{
    if (f->n < FIFO_CAP) { /* a full line loses the byte */
        f->b[(f->head + f->n) % FIFO_CAP] = v;
        f->n++;
    }
}

static int fifo_get(fifo *f, uint8_t *v)
{
    if (f->n == 0) {
        return 0;
    }
    *v = f->b[f->head];
    f->head = (f->head + 1) % FIFO_CAP;
    f->n--;
    return 1;
}

/* ---- model of sender A (docs/link.md) ---- */

typedef enum {
    M_IDLE,
    M_SEND_SYN,
    M_WAIT_SYN,
    M_DATA,
    M_CHECKSUM,
    M_WAIT_ANSWER,
    M_TIMED_OUT,
    M_GAVE_UP
} m_state;

typedef struct {
    att_link_sender_config cfg;
    m_state st;
    const uint8_t *blk;
    unsigned idx, attempts;
    uint16_t t0;
    unsigned long sent, accepted, naks, timeouts, gave_up, discarded;
} amodel;

static int m_waiting(const amodel *m)
{
    return m->st == M_WAIT_SYN || m->st == M_WAIT_ANSWER;
}

static int m_expired(const amodel *m, uint16_t t)
{
    uint16_t limit = m->st == M_WAIT_SYN ? m->cfg.syn_timeout : m->cfg.answer_timeout;
    return (uint16_t)(t - m->t0) > limit;
}

static void m_failed(amodel *m)
{
    m->st = m->attempts < m->cfg.max_attempts ? M_SEND_SYN : M_GAVE_UP;
}

static uint8_t m_sum(const amodel *m)
{
    unsigned i, s = 0;
    for (i = 0; i < m->cfg.block_size; i++) {
        s += m->blk[i];
    }
    return (uint8_t)s;
}

/* A got `byte` at t: the result the protocol asks for. */
static att_link_result m_sink(amodel *m, uint8_t byte, uint16_t t)
{
    if (m_waiting(m) && m_expired(m, t)) { /* a late byte: the timeout comes first */
        m->timeouts++;
        m->st = M_TIMED_OUT;
    }
    if (m->st == M_WAIT_SYN && byte == (uint8_t)ATT_LINK_SYN_ACK) {
        m->st = M_DATA;
        m->idx = 0;
        return ATT_LINK_SYN_RX;
    }
    if (m->st == M_WAIT_ANSWER && byte == (uint8_t)ATT_LINK_ACK) {
        m->accepted++;
        m->st = M_IDLE;
        return ATT_LINK_ACCEPTED;
    }
    if (m->st == M_WAIT_ANSWER && byte == (uint8_t)ATT_LINK_NAK) {
        m->naks++;
        m_failed(m);
        return ATT_LINK_REJECTED;
    }
    m->discarded++;
    return ATT_LINK_DISCARDED;
}

/* A polled at t: the result (and *out for SEND) the protocol asks for. */
static att_link_result m_poll(amodel *m, uint16_t t, uint8_t *out)
{
    switch (m->st) {
    case M_IDLE:
        return ATT_LINK_IDLE;
    case M_SEND_SYN:
        m->attempts++;
        FUZZ_CHECK(m->attempts <= m->cfg.max_attempts); /* at most the configured attempts */
        m->t0 = t;
        m->st = M_WAIT_SYN;
        *out = (uint8_t)ATT_LINK_SYN;
        return ATT_LINK_SEND;
    case M_WAIT_SYN:
    case M_WAIT_ANSWER:
        if (!m_expired(m, t)) {
            return ATT_LINK_NONE;
        }
        m->timeouts++;
        m_failed(m);
        return ATT_LINK_TIMEOUT;
    case M_DATA: /* only after 0xBB: the block, byte for byte */
        *out = m->blk[m->idx++];
        if (m->idx == m->cfg.block_size) {
            m->st = M_CHECKSUM;
        }
        return ATT_LINK_SEND;
    case M_CHECKSUM:
        *out = m_sum(m);
        m->sent++;
        m->t0 = t;
        m->st = M_WAIT_ANSWER;
        return ATT_LINK_SEND;
    case M_TIMED_OUT:
        m_failed(m);
        return ATT_LINK_TIMEOUT;
    default: /* M_GAVE_UP */
        FUZZ_CHECK(m->attempts == m->cfg.max_attempts);
        m->gave_up++;
        m->st = M_IDLE;
        return ATT_LINK_GAVE_UP;
    }
}

/* What ticks_left must say for the model at t. */
static uint16_t m_ticks_left(const amodel *m, uint16_t t)
{
    uint16_t limit, el;
    if (m->st == M_IDLE) {
        return (uint16_t)ATT_LINK_NO_TIMER;
    }
    if (!m_waiting(m)) {
        return 0;
    }
    limit = m->st == M_WAIT_SYN ? m->cfg.syn_timeout : m->cfg.answer_timeout;
    el = (uint16_t)(t - m->t0);
    return el > limit ? 0 : (uint16_t)(limit - el + 1u);
}

/* ---- model of receiver B (docs/link.md) ---- */

typedef enum {
    B_IDLE,
    B_DATA,
    B_CHECKSUM
} b_state;

typedef struct {
    att_link_receiver_config cfg;
    b_state st;
    unsigned idx;
    uint8_t sum;
    uint16_t t_last;
    int out;             /* byte waiting to be handed out, -1: none */
    int timeout_pending; /* a sink dropped a partial block: the next poll says so */
    int discarded;       /* bytes discarded while idle since the last handshake */
    unsigned long syns, accepted, naks, timeouts, resyncs, bytes_discarded;
} bmodel;

static int b_expired(const bmodel *m, uint16_t t)
{
    return m->st != B_IDLE && (uint16_t)(t - m->t_last) > m->cfg.gap_timeout;
}

/* The gap timer expired inside a block: drop it; a 0xBB not handed out yet is void. */
static void b_drop(bmodel *m)
{
    m->timeouts++;
    m->bytes_discarded += m->idx;
    if (m->out == (int)ATT_LINK_SYN_ACK) {
        m->out = -1;
    }
    m->st = B_IDLE;
    m->idx = 0;
    m->sum = 0;
}

static att_link_result b_sink(bmodel *m, uint8_t byte, uint16_t t)
{
    if (b_expired(m, t)) { /* a late byte: handled as if B were idle */
        b_drop(m);
        m->timeout_pending = 1;
    }
    if (m->st == B_IDLE) {
        if (byte != (uint8_t)ATT_LINK_SYN) {
            m->bytes_discarded++;
            m->discarded = 1;
            return ATT_LINK_DISCARDED;
        }
        m->syns++;
        m->resyncs += (unsigned long)m->discarded;
        m->discarded = 0;
        m->st = B_DATA;
        m->idx = 0;
        m->sum = 0;
        m->t_last = t;
        m->out = ATT_LINK_SYN_ACK;
        return ATT_LINK_SYN_RX;
    }
    if (m->st == B_DATA) {
        m->idx++;
        m->sum = (uint8_t)(m->sum + byte);
        m->t_last = t;
        if (m->idx == m->cfg.block_size) {
            m->st = B_CHECKSUM;
        }
        return ATT_LINK_DATA_RX;
    }
    m->st = B_IDLE; /* the checksum */
    m->idx = 0;
    if (byte == m->sum) {
        m->accepted++;
        m->out = ATT_LINK_ACK;
        return ATT_LINK_ACCEPTED;
    }
    m->naks++;
    m->out = ATT_LINK_NAK;
    return ATT_LINK_REJECTED;
}

static att_link_result b_poll(bmodel *m, uint16_t t, uint8_t *out)
{
    if (b_expired(m, t)) {
        b_drop(m);
        return ATT_LINK_TIMEOUT;
    }
    if (m->timeout_pending) {
        m->timeout_pending = 0;
        return ATT_LINK_TIMEOUT;
    }
    if (m->out >= 0) {
        if (m->out == (int)ATT_LINK_SYN_ACK && m->st == B_DATA && m->idx == 0) {
            m->t_last = t; /* the gap timer counts from 0xBB leaving */
        }
        *out = (uint8_t)m->out;
        m->out = -1;
        return ATT_LINK_SEND;
    }
    return m->st == B_IDLE ? ATT_LINK_IDLE : ATT_LINK_NONE;
}

static uint16_t b_ticks_left(const bmodel *m, uint16_t t)
{
    uint16_t el = (uint16_t)(t - m->t_last);
    if (m->out >= 0 || m->timeout_pending) {
        return 0;
    }
    if (m->st == B_IDLE) {
        return (uint16_t)ATT_LINK_NO_TIMER;
    }
    return el > m->cfg.gap_timeout ? 0 : (uint16_t)(m->cfg.gap_timeout - el + 1u);
}

/* ---- the session ---- */

typedef struct {
    att_link_sender s;
    amodel m;
    att_link_receiver r;
    uint8_t rbuf[ATT_LINK_BLOCK_MAX];
    uint8_t blk[ATT_LINK_BLOCK_MAX]; /* A's current block (unchanged until A is idle) */
    const uint8_t *data;
    size_t size;
    unsigned blocks; /* blocks started */
    fifo ab, ba;
    uint16_t tick;
    bmodel bm;
    uint16_t since_poll; /* ticks since both ends were last polled */
} session;

static void next_block(session *x)
{
    unsigned i;
    for (i = 0; i < x->m.cfg.block_size; i++) {
        x->blk[i] = (uint8_t)(x->data[(x->blocks * 7u + i) % x->size] ^ x->blocks);
    }
    x->blocks++;
}

#define IS_NONE(st)    ((st) == ATT_LINK_NONE)
#define IS_TIMEOUT(st) ((st) == ATT_LINK_TIMEOUT)

/* ticks_left of both ends against the model, and by polling copies around it. */
static void check_timers(const session *x)
{
    uint16_t k = att_link_sender_ticks_left(&x->s, x->tick);
    FUZZ_CHECK(k == m_ticks_left(&x->m, x->tick));
    if (k != 0 && k != (uint16_t)ATT_LINK_NO_TIMER) {
        FUZZ_TIMER_ORACLE(att_link_sender, &x->s, x->tick, k, att_link_sender_poll, IS_NONE, IS_TIMEOUT);
    }
    k = att_link_receiver_ticks_left(&x->r, x->tick);
    FUZZ_CHECK(k == b_ticks_left(&x->bm, x->tick));
    if (k != 0 && k != (uint16_t)ATT_LINK_NO_TIMER) {
        FUZZ_TIMER_ORACLE(att_link_receiver, &x->r, x->tick, k, att_link_receiver_poll, IS_NONE, IS_TIMEOUT);
    }
}

static void drain_b(session *x)
{
    int guard = 0;
    for (;;) {
        uint8_t out = 0, want = 0;
        att_link_result exp = b_poll(&x->bm, x->tick, &want);
        att_link_result res = att_link_receiver_poll(&x->r, x->tick, &out);
        FUZZ_CHECK(res == exp && ++guard < 8);
        if (res == ATT_LINK_NONE || res == ATT_LINK_IDLE) {
            return;
        }
        if (res == ATT_LINK_SEND) { /* only the answer to the last byte B took */
            FUZZ_CHECK(out == want);
            fifo_put(&x->ba, out);
        }
    }
}

static void drain_a(session *x)
{
    int guard = 0;
    for (;;) {
        uint8_t out = 0, want = 0;
        att_link_result exp = m_poll(&x->m, x->tick, &want);
        att_link_result res = att_link_sender_poll(&x->s, x->tick, &out);
        FUZZ_CHECK(res == exp);
        FUZZ_CHECK(++guard < 2 * ATT_LINK_BLOCK_MAX + 16);
        if (res == ATT_LINK_SEND) {
            FUZZ_CHECK(out == want);
            fifo_put(&x->ab, out);
        } else if (res == ATT_LINK_IDLE) {
            next_block(x);
            FUZZ_CHECK(att_link_sender_start(&x->s, x->blk, x->tick) == ATT_OK);
            x->m.st = M_SEND_SYN;
            x->m.blk = x->blk;
            x->m.attempts = 0;
            x->m.idx = 0;
        } else if (res == ATT_LINK_NONE) {
            return;
        }
        FUZZ_CHECK(x->s.index <= x->s.cfg.block_size);
    }
}

/* B takes a byte; with answer, it hands out its answer at once (attitude-rx does). */
static void to_b(session *x, uint8_t byte, int answer)
{
    att_link_result res = att_link_receiver_sink(&x->r, byte, x->tick);
    FUZZ_CHECK(res == b_sink(&x->bm, byte, x->tick));
    FUZZ_CHECK(x->r.index <= x->r.cfg.block_size);
    if (res == ATT_LINK_ACCEPTED || res == ATT_LINK_REJECTED) { /* the block B holds */
        FUZZ_CHECK((att_link_checksum(x->rbuf, x->r.cfg.block_size) == byte) == (res == ATT_LINK_ACCEPTED));
    }
    if (answer) {
        drain_b(x);
    }
}

/* Both ends do what they have to do now. */
static void poll_both(session *x)
{
    drain_b(x);
    drain_a(x);
    x->since_poll = 0;
}

/* Time passes; both ends are polled before 32768 ticks go by unpolled. */
static void advance(session *x, uint16_t ticks)
{
    if ((uint32_t)x->since_poll + ticks > ATT_LINK_TIMEOUT_MAX) {
        poll_both(x);
    }
    x->tick = (uint16_t)(x->tick + ticks);
    x->since_poll = (uint16_t)(x->since_poll + ticks);
}

static void to_a(session *x, uint8_t byte)
{
    att_link_result exp = m_sink(&x->m, byte, x->tick);
    FUZZ_CHECK(att_link_sender_sink(&x->s, byte, x->tick) == exp);
}

/* Every documented error once: NULL pointers, bad configurations, corrupted state. */
static void misuse(const session *x)
{
    att_link_sender s;
    att_link_sender_config sc;
    att_link_receiver r;
    att_link_receiver_config rc;
    uint8_t b[ATT_LINK_BLOCK_MAX] = { 0 }, out;

    att_link_sender_config_init(NULL, 6);
    att_link_receiver_config_init(NULL, 6);
    att_link_sender_reset(NULL);
    att_link_receiver_reset(NULL);
    FUZZ_CHECK(att_link_checksum(NULL, 3) == 0);
    att_link_sender_config_init(&sc, 6);
    att_link_receiver_config_init(&rc, 6);
    FUZZ_CHECK(att_link_sender_init(NULL, &sc) == ATT_LINK_E_NULL
               && att_link_sender_init(&s, NULL) == ATT_LINK_E_NULL);
    FUZZ_CHECK(att_link_receiver_init(NULL, &rc, b) == ATT_LINK_E_NULL
               && att_link_receiver_init(&r, NULL, b) == ATT_LINK_E_NULL
               && att_link_receiver_init(&r, &rc, NULL) == ATT_LINK_E_NULL);
    FUZZ_CHECK(att_link_sender_start(NULL, b, 0) == ATT_LINK_E_NULL
               && att_link_sender_sink(NULL, 0, 0) == ATT_LINK_E_NULL);
    FUZZ_CHECK(att_link_sender_poll(NULL, 0, &out) == ATT_LINK_E_NULL
               && att_link_receiver_sink(NULL, 0, 0) == ATT_LINK_E_NULL);
    FUZZ_CHECK(att_link_receiver_poll(NULL, 0, &out) == ATT_LINK_E_NULL);
    FUZZ_CHECK(att_link_sender_ticks_left(NULL, 0) == (uint16_t)ATT_LINK_NO_TIMER);
    FUZZ_CHECK(att_link_receiver_ticks_left(NULL, 0) == (uint16_t)ATT_LINK_NO_TIMER);
    FUZZ_CHECK(att_link_sender_init(&s, &sc) == ATT_OK
               && att_link_sender_start(&s, NULL, 0) == ATT_LINK_E_NULL);
    FUZZ_CHECK(att_link_sender_poll(&s, 0, NULL) == ATT_LINK_E_NULL);
    FUZZ_CHECK(att_link_receiver_init(&r, &rc, b) == ATT_OK
               && att_link_receiver_poll(&r, 0, NULL) == ATT_LINK_E_NULL);
    /* a state no machine reaches: a struct overwritten */
    s = x->s;
    s.state = 0xEE;
    FUZZ_CHECK(att_link_sender_sink(&s, 0xBB, 0) == ATT_LINK_E_STATE
               && att_link_sender_poll(&s, 0, &out) == ATT_LINK_E_STATE);
    FUZZ_CHECK(att_link_sender_ticks_left(&s, 0) == (uint16_t)ATT_LINK_NO_TIMER);
    r = x->r;
    r.state = 0xEE;
    FUZZ_CHECK(att_link_receiver_sink(&r, 0xAA, 0) == ATT_LINK_E_STATE
               && att_link_receiver_poll(&r, 0, &out) == ATT_LINK_E_STATE);
    FUZZ_CHECK(att_link_receiver_ticks_left(&r, 0) == (uint16_t)ATT_LINK_NO_TIMER);
    r = x->r;
    r.block = NULL;
    FUZZ_CHECK(att_link_receiver_sink(&r, 0xAA, 0) == ATT_LINK_E_NULL);
}

/* Header byte 1 bit 7 set: the raw values of the header as configuration,
 * valid or not; init must accept exactly the valid ones, and a sender it
 * refused answers every call with an error. */
static int raw_config(const uint8_t *data)
{
    att_link_sender s;
    att_link_sender_config sc;
    att_link_receiver r;
    att_link_receiver_config rc;
    uint8_t b[ATT_LINK_BLOCK_MAX] = { 0 }, out;
    uint8_t n = data[0], attempts = (uint8_t)(data[1] & 0x7F);
    uint16_t gap = fuzz_be16(data + 2), syn = fuzz_be16(data + 4), answer = fuzz_be16(data + 6);
    int sender_ok = n >= 1 && n <= ATT_LINK_BLOCK_MAX && attempts >= 1 && syn >= 1
                    && syn <= ATT_LINK_TIMEOUT_MAX && answer >= 1 && answer <= ATT_LINK_TIMEOUT_MAX;
    int receiver_ok = n >= 1 && n <= ATT_LINK_BLOCK_MAX && gap >= 1 && gap <= ATT_LINK_TIMEOUT_MAX;
    sc.block_size = n;
    sc.max_attempts = attempts;
    sc.syn_timeout = syn;
    sc.answer_timeout = answer;
    rc.block_size = n;
    rc.gap_timeout = gap;
    FUZZ_CHECK(att_link_sender_init(&s, &sc) == (sender_ok ? ATT_OK : ATT_LINK_E_CONFIG));
    FUZZ_CHECK(att_link_receiver_init(&r, &rc, b) == (receiver_ok ? ATT_OK : ATT_LINK_E_CONFIG));
    if (!sender_ok) {
        FUZZ_CHECK(att_link_sender_poll(&s, 0, &out) < 0 && att_link_sender_sink(&s, 0xBB, 0) < 0);
        FUZZ_CHECK(att_link_sender_ticks_left(&s, 0) == (uint16_t)ATT_LINK_NO_TIMER);
    }
    return sender_ok && receiver_ok;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static session x;
    att_link_receiver_config rc;
    size_t i;
    int k;
    uint8_t out;
    if (size < 11) {
        return 0;
    }
    memset(&x, 0, sizeof x);
    if ((data[1] & 0x80) && !raw_config(data)) {
        return 0;
    }
    x.data = data;
    x.size = size;
    /* small timeouts are the interesting ones (timers expire between operations); the
     * 0x40 bit of byte 1 lets them take the whole range */
    att_link_sender_config_init(&x.m.cfg, (uint8_t)(data[0] % ATT_LINK_BLOCK_MAX + 1));
    x.m.cfg.max_attempts = (uint8_t)(data[1] % 8 + 1);
    {
        uint16_t span = (data[1] & 0x40) ? (uint16_t)ATT_LINK_TIMEOUT_MAX : 64;
        rc.gap_timeout = (uint16_t)(fuzz_be16(data + 2) % span + 1);
        x.m.cfg.syn_timeout = (uint16_t)(fuzz_be16(data + 4) % span + 1);
        x.m.cfg.answer_timeout = (uint16_t)(fuzz_be16(data + 6) % span + 1);
    }
    rc.block_size = x.m.cfg.block_size;
    x.bm.cfg = rc;
    x.bm.out = -1;
    x.tick = fuzz_be16(data + 8);
    FUZZ_CHECK(att_link_sender_init(&x.s, &x.m.cfg) == ATT_OK);
    FUZZ_CHECK(att_link_receiver_init(&x.r, &rc, x.rbuf) == ATT_OK);
    if (data[10] == 0xA5) {
        misuse(&x);
    }
    poll_both(&x);
    for (i = 10; i < size; i++) {
        uint8_t op = data[i], arg = (uint8_t)((op >> 3) & 15), v = i + 1 < size ? data[i + 1] : 0;
        int answer = !(op & 0x80);
        uint8_t b;
        check_timers(&x);
        switch (op & 7) {
        case 0: /* A's bytes reach B */
            for (k = 0; k <= arg % 4 && fifo_get(&x.ab, &b); k++) {
                to_b(&x, b, answer);
            }
            break;
        case 1: /* B's bytes reach A */
            for (k = 0; k <= arg % 4 && fifo_get(&x.ba, &b); k++) {
                to_a(&x, b);
            }
            break;
        case 2: /* time passes: 0..7 or 16..128 ticks */
            advance(&x, (uint16_t)(arg < 8 ? arg : (arg - 7) * 16));
            break;
        case 3: /* a long silence: up to the longest the contract allows (every timer expires) */
            advance(&x, (uint16_t)((v + 1u) * 128u - (v == 255u)));
            i++;
            break;
        case 4: /* garbage into B */
            to_b(&x, v, answer);
            i++;
            break;
        case 5: /* garbage into A */
            to_a(&x, v);
            i++;
            break;
        case 6: /* a byte lost on the line, or a reboot, or a start while busy */
            switch (arg % 5) {
            case 0:
                (void)fifo_get(&x.ab, &b);
                break;
            case 1:
                (void)fifo_get(&x.ba, &b);
                break;
            case 2: /* A reboots: its block in progress is dropped */
                att_link_sender_reset(&x.s);
                x.m.st = M_IDLE;
                break;
            case 3: /* B reboots: a partial block and a pending answer are dropped */
                att_link_receiver_reset(&x.r);
                x.bm.st = B_IDLE;
                x.bm.idx = 0;
                x.bm.sum = 0;
                x.bm.out = -1;
                x.bm.timeout_pending = 0;
                x.bm.discarded = 0;
                x.bm.t_last = 0;
                break;
            default:
                FUZZ_CHECK(att_link_sender_start(&x.s, x.blk, x.tick)
                           == (x.m.st == M_IDLE ? ATT_OK : ATT_LINK_E_BUSY));
                if (x.m.st == M_IDLE) {
                    x.m.st = M_SEND_SYN;
                    x.m.attempts = 0;
                }
                break;
            }
            break;
        default: /* a byte in flight corrupted */
            if (v != 0) {
                fifo *f = (arg & 1) ? &x.ba : &x.ab;
                if (f->n > 0) {
                    f->b[f->head] ^= v;
                }
            }
            i++;
            break;
        }
        if (answer) {
            poll_both(&x);
        }
    }
    poll_both(&x);
    check_timers(&x);
    /* A's statistics are the model's counts (16-bit, wrapping) */
    FUZZ_CHECK(x.s.stats.blocks_sent == (uint16_t)x.m.sent
               && x.s.stats.blocks_accepted == (uint16_t)x.m.accepted);
    FUZZ_CHECK(x.s.stats.naks == (uint16_t)x.m.naks && x.s.stats.timeouts == (uint16_t)x.m.timeouts);
    FUZZ_CHECK(x.s.stats.gave_up == (uint16_t)x.m.gave_up
               && x.s.stats.bytes_discarded == (uint16_t)x.m.discarded);
    /* B's statistics are the model's counts */
    FUZZ_CHECK(x.r.stats.syns == x.bm.syns && x.r.stats.blocks_accepted == x.bm.accepted
               && x.r.stats.naks == x.bm.naks);
    FUZZ_CHECK(x.r.stats.timeouts == x.bm.timeouts && x.r.stats.resyncs == x.bm.resyncs);
    FUZZ_CHECK(x.r.stats.bytes_discarded == x.bm.bytes_discarded);
    /* bounded return to idle: at most N + 1 more bytes (no 0xAA) end any block */
    for (k = 0; k <= x.r.cfg.block_size; k++) {
        FUZZ_CHECK(att_link_receiver_sink(&x.r, 0x00, x.tick) >= 0);
        while (att_link_receiver_poll(&x.r, x.tick, &out) > ATT_LINK_IDLE) {
        }
    }
    FUZZ_CHECK(att_link_receiver_poll(&x.r, x.tick, &out) == ATT_LINK_IDLE);
    /* and silence longer than the gap timeout always ends a block too */
    FUZZ_CHECK(att_link_receiver_sink(&x.r, 0xAA, x.tick) == ATT_LINK_SYN_RX);
    FUZZ_CHECK(att_link_receiver_poll(&x.r, x.tick, &out) == ATT_LINK_SEND && out == 0xBB);
    FUZZ_CHECK(att_link_receiver_poll(&x.r, (uint16_t)(x.tick + rc.gap_timeout + 1u), &out)
               == ATT_LINK_TIMEOUT);
    FUZZ_CHECK(att_link_receiver_poll(&x.r, (uint16_t)(x.tick + rc.gap_timeout + 1u), &out) == ATT_LINK_IDLE);
    return 0;
}
