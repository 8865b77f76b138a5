/*
 * libattitude — link v2 sender A (see attitude/link2.h and docs/link.md).
 *
 * Portable C99 that SDCC compiles for the AT89S51 (small model): 8/16-bit
 * arithmetic, no float, no function pointers, no library calls. The
 * frame being sent is never built in memory: each decoded byte is made
 * from the ring when it is due (frame_byte), the CRC follows it, and the
 * rCOBS encoder streams (no look-ahead), so the sender needs no frame
 * buffer. What a firmware can do without (config_init, ticks_left,
 * att_link2_crc) is in link2_sender_aux.c (SDCC links whole modules).
 */
#include "attitude/link2.h"

#include "link2_private.h"

uint32_t att_link2_crc_byte(uint32_t reg, uint8_t byte)
{
    uint8_t i;
    reg ^= byte;
    for (i = 0; i < 8u; i++) {
        if (reg & 1u) {
            reg = (reg >> 1) ^ 0x82F63B78ul; /* 0x1EDC6F41 reflected */
        } else {
            reg >>= 1;
        }
    }
    return reg;
}

/* -- ring ------------------------------------------------------------ */

static uint8_t ATT_LINK_MEM *slot(const att_link2_sender ATT_LINK_MEM *s, uint8_t seq)
{
    uint16_t i = (uint8_t)(seq & (uint8_t)(s->cfg.ring_size - 1u));
    return s->ring + (uint16_t)((uint16_t)(i << 2) + (uint16_t)(i << 1)); /* 6 i: no multiply on the 8051 */
}

/* A sample record whose three codes fit 12 bits travels packed. */
static uint8_t packable(const uint8_t ATT_LINK_MEM *rec)
{
    return (uint8_t)(rec[0] < 16u && rec[2] < 16u && rec[4] < 16u);
}

/* Does B's limit let A send record `seq`? (limit - seq in 1..127) */
static uint8_t window_open(const att_link2_sender ATT_LINK_MEM *s, uint8_t seq)
{
    return (uint8_t)((uint8_t)((uint8_t)(s->limit - seq) - 1u) < (uint8_t)ATT_LINK2_WINDOW_MAX);
}

int att_link2_sender_init(att_link2_sender ATT_LINK_MEM *s, const att_link2_sender_config *cfg,
                          uint8_t ATT_LINK_MEM *ring)
{
    uint8_t ATT_LINK_MEM *p;
    uint8_t n;
    if (s == NULL || cfg == NULL || ring == NULL) {
        return ATT_LINK2_E_NULL;
    }
    s->cfg = *cfg;
    s->ring = ring;
    p = (uint8_t ATT_LINK_MEM *)&s->stats;
    n = (uint8_t)sizeof(s->stats);
    do {
        *p++ = 0;
    } while (--n != 0);
    att_link2_sender_reset(s);
    n = s->cfg.ring_size;
    if (n == 0u || n > (uint8_t)ATT_LINK2_RING_MAX || (uint8_t)(n & (uint8_t)(n - 1u)) != 0u
        || (uint8_t)(s->cfg.max_samples - 1u) >= (uint8_t)ATT_LINK2_SAMPLES_MAX
        || (uint16_t)(s->cfg.rto - 1u) >= (uint16_t)ATT_LINK2_TIMEOUT_MAX) {
        s->session = (uint8_t)SES_BAD; /* unusable: every call reports an error */
        return ATT_LINK2_E_CONFIG;
    }
    return ATT_OK;
}

void att_link2_sender_reset(att_link2_sender ATT_LINK_MEM *s)
{
    if (s == NULL) {
        return;
    }
    s->head = 0;
    s->base = 0;
    s->next = 0;
    s->hi = 0;
    s->limit = 0;
    s->t0 = 0;
    s->crc = 0;
    s->cur = s->cfg.max_samples;
    s->session = (uint8_t)SES_SYN_SEND;
    s->tx = (uint8_t)TX_IDLE;
    s->flags = (uint8_t)FL_LINE_IDLE;
    s->f_head = 0;
    s->f_seq = 0;
    s->f_len = 0;
    s->f_pos = 0;
    s->run = 0;
    s->rx_len = 0;
}

/* Records whose slots are in use: from base, or from the frame being sent
 * when B acknowledged some of its records meanwhile (its bytes are still read
 * from the ring). */
static uint8_t used(const att_link2_sender ATT_LINK_MEM *s)
{
    uint8_t n = (uint8_t)(s->head - s->base);
    if (s->tx != (uint8_t)TX_IDLE && (uint8_t)(s->head - s->f_seq) > n) {
        n = (uint8_t)(s->head - s->f_seq);
    }
    return n;
}

uint8_t att_link2_sender_pending(const att_link2_sender ATT_LINK_MEM *s)
{
    return s == NULL ? 0u : (uint8_t)(s->head - s->base);
}

uint8_t att_link2_sender_room(const att_link2_sender ATT_LINK_MEM *s)
{
    if (s == NULL || s->session >= (uint8_t)SES_BAD) {
        return 0;
    }
    return (uint8_t)(s->cfg.ring_size - used(s));
}

int att_link2_sender_push(att_link2_sender ATT_LINK_MEM *s, const uint8_t ATT_LINK_MEM *record)
{
    uint8_t ATT_LINK_MEM *d;
    uint8_t i;
    if (s == NULL || record == NULL) {
        return ATT_LINK2_E_NULL;
    }
    if (s->session >= (uint8_t)SES_BAD) {
        return ATT_LINK2_E_STATE;
    }
    if (used(s) >= s->cfg.ring_size) {
        return ATT_LINK2_E_FULL;
    }
    d = slot(s, s->head);
    for (i = 0; i < (uint8_t)ATT_LINK2_RECORD; i++) {
        d[i] = record[i];
    }
    s->head++;
    return ATT_OK;
}

/* -- sink: ACK frames from B ----------------------------------------- */

/* Apply a valid ACK: d[0] = 0xC0 | flags, d[1] = ack, d[2] = limit. */
static att_link2_result apply_ack(att_link2_sender ATT_LINK_MEM *s, const uint8_t ATT_LINK_MEM *d,
                                  uint16_t tick)
{
    uint8_t fl = (uint8_t)(d[0] & 0x0Fu);
    uint8_t a = d[1];
    uint8_t adv = (uint8_t)(a - s->base);
    s->stats.acks++;
    if (fl & (uint8_t)ATT_LINK2_F_NOSESSION) { /* B rebooted: new session from base, ring kept */
        s->session = (uint8_t)SES_SYN_SEND;
        s->next = s->base;
        s->hi = s->base;
        s->limit = s->base;
        return ATT_LINK2_FRAME;
    }
    if (s->session == (uint8_t)SES_SYN_WAIT) {
        if ((fl & (uint8_t)ATT_LINK2_F_SYNACK) == 0u || adv != 0u) {
            return ATT_LINK2_FRAME; /* not the answer to our SYN */
        }
        s->session = (uint8_t)SES_RUN;
        s->t0 = tick;
    } else if (s->session != (uint8_t)SES_RUN) {
        return ATT_LINK2_FRAME; /* SYN not sent yet: nothing to acknowledge */
    }
    if (adv > (uint8_t)(s->hi - s->base)) {
        s->stats.bad_frames++; /* acknowledges records never sent */
        return ATT_LINK2_BAD_FRAME;
    }
    if (adv != 0u) {
        if ((uint8_t)(s->next - s->base) < adv) {
            s->next = a; /* B already had what was being sent again */
        }
        s->base = a;
        s->t0 = tick;
        if (s->cur < s->cfg.max_samples) {
            s->cur++; /* progress: longer frames again */
        }
    }
    if ((uint8_t)(d[2] - a) <= (uint8_t)ATT_LINK2_WINDOW_MAX) {
        s->limit = d[2];
    }
    if ((fl & (uint8_t)ATT_LINK2_F_GAP) && s->hi != s->base
        && (uint8_t)((fl & (uint8_t)ATT_LINK2_F_EPOCH) ? FL_EPOCH : 0u) == (uint8_t)(s->flags & FL_EPOCH)) {
        /* a gap in what was sent since the last go-back: go back to the first record B lacks */
        s->next = s->base;
        s->cur = (uint8_t)((uint8_t)(s->cur + 1u) >> 1); /* and shorter frames */
        s->flags ^= (uint8_t)FL_EPOCH;
        s->stats.gobacks++;
        s->t0 = tick;
    }
    return ATT_LINK2_FRAME;
}

/* Decode the 8 encoded bytes in s->rx (rCOBS, backwards) into the 7 bytes
 * of an ACK and check it. */
static att_link2_result ack_frame(att_link2_sender ATT_LINK_MEM *s, uint16_t tick)
{
    uint8_t d[7];
    uint8_t p = 8;
    uint8_t q = 7;
    uint8_t code;
    uint8_t first = 1;
    uint32_t crc;
    while (p != 0u) {
        code = s->rx[p - 1u];
        if (code > p || code == 0xFFu || (uint8_t)(code - 1u + (first ^ 1u)) > q) {
            goto bad;
        }
        p--;
        if (!first) {
            d[--q] = 0;
        }
        first = 0;
        while (--code != 0u) {
            d[--q] = s->rx[--p];
        }
    }
    if (q != 0u || (uint8_t)(d[0] & 0xF0u) != (uint8_t)ATT_LINK2_T_ACK) {
        goto bad;
    }
    crc = 0xFFFFFFFFul;
    for (q = 0; q < 3u; q++) {
        crc = att_link2_crc_byte(crc, d[q]);
    }
    crc = ~crc;
    if (d[3] != (uint8_t)(crc >> 24) || d[4] != (uint8_t)(crc >> 16) || d[5] != (uint8_t)(crc >> 8)
        || d[6] != (uint8_t)crc) {
        goto bad;
    }
    return apply_ack(s, d, tick);
bad:
    s->stats.bad_frames++;
    return ATT_LINK2_BAD_FRAME;
}

att_link2_result att_link2_sender_sink(att_link2_sender ATT_LINK_MEM *s, uint8_t byte, uint16_t tick)
{
    uint8_t n;
    if (s == NULL) {
        return ATT_LINK2_E_NULL;
    }
    if (s->session >= (uint8_t)SES_BAD) {
        return ATT_LINK2_E_STATE;
    }
    n = s->rx_len;
    if (byte != (uint8_t)ATT_LINK2_DELIM) {
        if (n >= (uint8_t)sizeof(s->rx)) {
            s->rx_len = 0xFFu; /* longer than an ACK: skip to the delimiter */
            return ATT_LINK2_DISCARDED;
        }
        s->rx[n] = byte;
        s->rx_len = (uint8_t)(n + 1u);
        return ATT_LINK2_NONE;
    }
    s->rx_len = 0;
    if (n == 0u) {
        return ATT_LINK2_NONE; /* idle delimiter */
    }
    if (n != (uint8_t)sizeof(s->rx)) {
        s->stats.bad_frames++;
        return ATT_LINK2_BAD_FRAME;
    }
    return ack_frame(s, tick);
}

/* -- poll: the emitter, one function per state ----------------------- */

/* Code m (0..3n-1) of the DATA frame being sent: sample m / 3, channel m % 3. */
static uint16_t code_at(const att_link2_sender ATT_LINK_MEM *s, uint8_t m)
{
    uint8_t k = (uint8_t)(m / (uint8_t)3); /* 8-bit division: DIV AB on the 8051 */
    uint8_t c = (uint8_t)(m - (uint8_t)(k + (uint8_t)(k << 1)));
    const uint8_t ATT_LINK_MEM *r = slot(s, (uint8_t)(s->f_seq + k)) + (uint8_t)(c << 1);
    return (uint16_t)((uint16_t)((uint16_t)r[0] << 8) | r[1]);
}

/* Byte j of the packed codes: pair j / 3 of codes, byte j % 3 of it. */
static uint8_t packed_byte(const att_link2_sender ATT_LINK_MEM *s, uint8_t j)
{
    uint8_t p = (uint8_t)(j / (uint8_t)3);
    uint8_t r = (uint8_t)(j - (uint8_t)(p + (uint8_t)(p << 1)));
    uint8_t m = (uint8_t)(p << 1);
    uint8_t n = (uint8_t)(s->f_head & 0x1Fu);
    uint8_t ncodes = (uint8_t)(n + (uint8_t)(n << 1));
    if (r == 0u) {
        return (uint8_t)(code_at(s, m) >> 4);
    }
    if (r == 2u) {
        return (uint8_t)code_at(s, (uint8_t)(m + 1u));
    }
    r = (uint8_t)(code_at(s, m) << 4);
    if ((uint8_t)(m + 1u) < ncodes) {
        r |= (uint8_t)(code_at(s, (uint8_t)(m + 1u)) >> 8);
    }
    return r;
}

/* Decoded byte i of the frame being sent (the CRC bytes once every byte before them went out). */
static uint8_t frame_byte(const att_link2_sender ATT_LINK_MEM *s, uint8_t i)
{
    uint8_t tail = (uint8_t)(s->f_len - 4u);
    uint32_t v;
    if (i == 0u) {
        return s->f_head;
    }
    if (i == 1u) {
        return s->f_seq;
    }
    if (i < tail) {
        i = (uint8_t)(i - 2u);
        if (s->f_head & (uint8_t)ATT_LINK2_T_RAW) {
            return slot(s, s->f_seq)[i];
        }
        return packed_byte(s, i);
    }
    v = ~s->crc; /* the CRC, most significant byte first */
    i = (uint8_t)(i - tail);
    if (i == 0u) {
        return (uint8_t)(v >> 24);
    }
    if (i == 1u) {
        return (uint8_t)(v >> 16);
    }
    return i == 2u ? (uint8_t)(v >> 8) : (uint8_t)v;
}

static att_link2_result poll_body(att_link2_sender ATT_LINK_MEM *s, uint8_t ATT_LINK_MEM *out)
{
    uint8_t b;
    if (s->run == 254u) { /* 254 bytes without a zero: a code that stands for none */
        s->run = 0;
        *out = 0xFFu;
        return ATT_LINK2_SEND;
    }
    if (s->f_pos >= s->f_len) { /* final code, then the delimiter */
        *out = (uint8_t)(s->run + 1u);
        s->tx = (uint8_t)TX_DELIM;
        return ATT_LINK2_SEND;
    }
    b = frame_byte(s, s->f_pos);
    if (s->f_pos < (uint8_t)(s->f_len - 4u)) {
        s->crc = att_link2_crc_byte(s->crc, b);
    }
    s->f_pos++;
    if (b == 0u) {
        b = (uint8_t)(s->run + 1u);
        s->run = 0;
    } else {
        s->run++;
    }
    *out = b;
    return ATT_LINK2_SEND;
}

static att_link2_result poll_lead(att_link2_sender ATT_LINK_MEM *s, uint8_t ATT_LINK_MEM *out)
{
    s->tx = (uint8_t)TX_BODY;
    *out = (uint8_t)ATT_LINK2_DELIM;
    return ATT_LINK2_SEND;
}

static att_link2_result poll_delim(att_link2_sender ATT_LINK_MEM *s, uint16_t tick, uint8_t ATT_LINK_MEM *out)
{
    s->tx = (uint8_t)TX_IDLE;
    s->t0 = tick; /* the timer counts from the end of the last frame */
    *out = (uint8_t)ATT_LINK2_DELIM;
    return ATT_LINK2_SEND;
}

static att_link2_result start_frame(att_link2_sender ATT_LINK_MEM *s, uint8_t head, uint8_t seq, uint8_t len,
                                    uint8_t ATT_LINK_MEM *out)
{
    s->f_head = head;
    s->f_seq = seq;
    s->f_len = len;
    s->f_pos = 0;
    s->run = 0;
    s->crc = 0xFFFFFFFFul;
    s->stats.frames++;
    if (s->flags & (uint8_t)FL_LINE_IDLE) {
        s->flags &= (uint8_t)~FL_LINE_IDLE;
        return poll_lead(s, out);
    }
    s->tx = (uint8_t)TX_BODY;
    return poll_body(s, out);
}

/* The next data frame from record `next`: one RAW record, or up to
 * max_samples packable samples below head and B's limit. */
static att_link2_result start_data(att_link2_sender ATT_LINK_MEM *s, uint8_t ATT_LINK_MEM *out)
{
    uint8_t seq = s->next;
    uint8_t n = 1;
    uint8_t old;
    uint8_t head;
    uint8_t len;
    if (!packable(slot(s, seq))) {
        head = (uint8_t)(ATT_LINK2_T_RAW | (s->flags & FL_EPOCH));
        len = (uint8_t)(6u + (uint8_t)ATT_LINK2_RECORD);
    } else {
        while (n < s->cur && (uint8_t)(seq + n) != s->head && window_open(s, (uint8_t)(seq + n))
               && packable(slot(s, (uint8_t)(seq + n)))) {
            n++;
        }
        head = (uint8_t)(n | (s->flags & FL_EPOCH));
        len = (uint8_t)(6u + (uint8_t)((uint8_t)(9u * n + 1u) >> 1));
    }
    /* records below hi were sent before: they count as resent */
    old = (uint8_t)(s->next - s->base) < (uint8_t)(s->hi - s->base) ? (uint8_t)(s->hi - s->next) : 0u;
    if (old >= n) {
        s->stats.resent += n;
    } else {
        s->stats.resent += old;
        s->stats.records += (uint8_t)(n - old);
        s->hi = (uint8_t)(seq + n);
    }
    s->next = (uint8_t)(seq + n);
    return start_frame(s, head, seq, len, out);
}

static att_link2_result poll_idle(att_link2_sender ATT_LINK_MEM *s, uint16_t tick, uint8_t ATT_LINK_MEM *out)
{
    uint8_t waiting;
    if (s->session == (uint8_t)SES_SYN_SEND) {
        s->session = (uint8_t)SES_SYN_WAIT;
        s->stats.syns++;
        return start_frame(s, (uint8_t)ATT_LINK2_T_SYN, s->base, 6u, out);
    }
    waiting = (uint8_t)(s->session == (uint8_t)SES_SYN_WAIT || s->hi != s->base
                        || (s->next != s->head && !window_open(s, s->next)));
    if (waiting && (uint16_t)(tick - s->t0) > s->cfg.rto) {
        s->stats.timeouts++;
        s->t0 = tick;
        if (s->session == (uint8_t)SES_SYN_WAIT) {
            s->session = (uint8_t)SES_SYN_SEND;
            return ATT_LINK2_TIMEOUT;
        }
        if (s->hi != s->base) {
            s->next = s->base; /* no progress: go back to the first unacknowledged record */
            s->cur = (uint8_t)((uint8_t)(s->cur + 1u) >> 1);
            s->flags ^= (uint8_t)FL_EPOCH;
        }
        if (window_open(s, s->next)) {
            return ATT_LINK2_TIMEOUT; /* the next poll sends again */
        }
        /* B's limit blocks A (or A missed the ACK that opened it): ask with an empty frame */
        return start_frame(s, (uint8_t)(ATT_LINK2_T_DATA | (s->flags & FL_EPOCH)), s->next, 6u,
                           out); /* probe */
    }
    if (s->session == (uint8_t)SES_RUN && s->next != s->head && window_open(s, s->next)) {
        return start_data(s, out);
    }
    s->flags |= (uint8_t)FL_LINE_IDLE;
    return (s->session == (uint8_t)SES_RUN && s->head == s->base) ? ATT_LINK2_IDLE : ATT_LINK2_NONE;
}

att_link2_result att_link2_sender_poll(att_link2_sender ATT_LINK_MEM *s, uint16_t tick,
                                       uint8_t ATT_LINK_MEM *out_byte)
{
    if (s == NULL || out_byte == NULL) {
        return ATT_LINK2_E_NULL;
    }
    if (s->session >= (uint8_t)SES_BAD) {
        return ATT_LINK2_E_STATE;
    }
    switch (s->tx) {
    case TX_IDLE:
        return poll_idle(s, tick, out_byte);
    case TX_LEAD:
        return poll_lead(s, out_byte);
    case TX_BODY:
        return poll_body(s, out_byte);
    case TX_DELIM:
        return poll_delim(s, tick, out_byte);
    default:
        return ATT_LINK2_E_STATE;
    }
}
