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

/* The two builds of one source (attitude/link2.h, ATT_LINK2_ONE): the
 * library's (caller-owned state passed as `s`, run-time configuration,
 * statistics) and the 8051 firmware's single instance (the state is the
 * firmware's att_link2_one, reached by direct addressing instead of
 * through a pointer; configuration fixed at compile time; no statistics;
 * no NULL or configuration checks: nothing can be NULL or misconfigured). */
#if ATT_LINK2_ONE
#define S     (&att_link2_one)
#define SELF  void
#define CSELF void
#define SELF_
#define ARG
#define ARG_
#define API(name)   att_link2_sender1_##name
#define RING_SIZE   ((uint8_t)ATT_LINK2_ONE_RING)
#define MAX_SAMPLES ((uint8_t)ATT_LINK2_ONE_SAMPLES)
#define RTO         ((uint16_t)ATT_LINK2_ONE_RTO)
#define STAT_INC(name)
#define STAT_ADD(name, n)
#define CHECK_NULL(action)
#define CHECK_BAD(action)
#define CUR MAX_SAMPLES /* frames always as long as the records allow */
#define CUR_RESET()
#define CUR_GROW()
#define CUR_HALVE()
#if ATT_LINK2_ONE_RING_IDATA
#define RING ((uint8_t ATT_LINK_MEM *)att_link2_one_ring) /* reached through @R0/@R1 only */
#else
#define RING (S->ring)
#endif
#if ATT_LINK2_ONE_BATCH /* hold a DATA frame back for more records (attitude/link2.h) */
#define AND_READY(tick)                                             \
    &&((uint8_t)(S->head - S->next) >= (uint8_t)ATT_LINK2_ONE_BATCH \
       || (uint16_t)((tick)-S->t0) > (uint16_t)ATT_LINK2_ONE_HOLD)
#else
#define AND_READY(tick)
#endif
#else
#define S                 s
#define SELF              att_link2_sender ATT_LINK_MEM *s
#define CSELF             const att_link2_sender ATT_LINK_MEM *s
#define SELF_             att_link2_sender ATT_LINK_MEM *s,
#define ARG               s
#define ARG_              s,
#define API(name)         att_link2_sender_##name
#define RING_SIZE         (s->cfg.ring_size)
#define MAX_SAMPLES       (s->cfg.max_samples)
#define RTO               (s->cfg.rto)
#define STAT_INC(name)    (s->stats.name++)
#define STAT_ADD(name, n) (s->stats.name = (uint16_t)(s->stats.name + (n)))
#define CHECK_NULL(action) \
    if (s == NULL) {       \
        action;            \
    }
#define CHECK_BAD(action)                 \
    if (s->session >= (uint8_t)SES_BAD) { \
        action;                           \
    }
#define CUR         (s->cur) /* samples per frame now: halved on a loss, +1 per progress */
#define CUR_RESET() (s->cur = MAX_SAMPLES)
#define CUR_GROW()              \
    if (s->cur < MAX_SAMPLES) { \
        s->cur++;               \
    }
#define CUR_HALVE()     (s->cur = (uint8_t)((uint8_t)(s->cur + 1u) >> 1))
#define RING            (s->ring)
#define AND_READY(tick) /* the library's sender frames at once */
#endif

#if defined(__SDCC_mcs51) && ATT_LINK2_CRC_TABLE
/* The 8051 build with room for a table (the aided AT89S52 image: 8 KB of
 * flash; -DATT_LINK2_CRC_TABLE=1): CRC-32C a byte at a time from a
 * 256-entry table of the reflected polynomial's remainders, kept as four
 * byte planes in code memory (att_link2_crc_t0..t3: byte 0..3 of entry i;
 * 1 KB, defined by the firmware build: toolchain/firmware.py generates
 * them from the polynomial). reg' = (reg >> 8) ^ T[(reg ^ byte) & 0xFF]:
 * four MOVC lookups, about 45 machine cycles instead of the bitwise loop's
 * 230. Same calling convention and registers as the bitwise version below
 * (R7 saved; DPL, DPH, B, A in and out; the top byte in the parameter's
 * cell); checked in s51 against the check value and the host's frames
 * (tests/test_firmware_aided.py). */
extern __code const uint8_t att_link2_crc_t0[256];
extern __code const uint8_t att_link2_crc_t1[256];
extern __code const uint8_t att_link2_crc_t2[256];
extern __code const uint8_t att_link2_crc_t3[256];
uint32_t att_link2_crc_byte(uint32_t reg, uint8_t byte) __naked
{
    (void)reg;
    (void)byte;
    /* clang-format off */
    __asm
        xch a, _att_link2_crc_byte_PARM_2
        xrl a, dpl
        push ar7
        mov r7, a
        push dph
        mov dptr, #_att_link2_crc_t1
        movc a, @a+dptr
        xrl a, b
        push acc
        mov a, r7
        mov dptr, #_att_link2_crc_t2
        movc a, @a+dptr
        xrl a, _att_link2_crc_byte_PARM_2
        mov b, a
        mov a, r7
        mov dptr, #_att_link2_crc_t3
        movc a, @a+dptr
        mov _att_link2_crc_byte_PARM_2, a
        mov a, r7
        mov dptr, #_att_link2_crc_t0
        movc a, @a+dptr
        pop dph
        pop dpl
        xrl dpl, a
        pop ar7
        mov a, _att_link2_crc_byte_PARM_2
        ret
    __endasm;
    /* clang-format on */
}
#elif defined(__SDCC_mcs51)
/* The 8051 build: the same bitwise CRC-32C in assembly. SDCC's 32-bit
 * shift and xor in C cost about 2000 machine cycles per byte; this loop
 * about 230 (8 steps of a 4-byte right shift through the carry and, when a
 * 1 falls out, an xor of the reflected polynomial), in fewer bytes of code.
 * SDCC's calling convention: reg arrives in DPL, DPH, B, A (least
 * significant first), byte in the static parameter, the result leaves in
 * DPL, DPH, B, A. SDCC assumes that a function defined above its callers
 * uses only the registers its C body used, so this one touches no R0-R7
 * but R7, which it saves on the stack (1 byte); its top byte lives in the
 * parameter's cell once the byte is folded in. Checked in s51 against the
 * check value and the host's frames (tests/test_firmware_link2.py). */
uint32_t att_link2_crc_byte(uint32_t reg, uint8_t byte) __naked
{
    (void)reg;
    (void)byte;
    /* clang-format off */
    __asm
        xch a, _att_link2_crc_byte_PARM_2
        xrl dpl, a
        push ar7
        mov r7, #8
    00001$:
        clr c
        mov a, _att_link2_crc_byte_PARM_2
        rrc a
        mov _att_link2_crc_byte_PARM_2, a
        mov a, b
        rrc a
        mov b, a
        mov a, dph
        rrc a
        mov dph, a
        mov a, dpl
        rrc a
        mov dpl, a
        jnc 00002$
        xrl dpl, #0x78
        xrl dph, #0x3B
        xrl b, #0xF6
        xrl _att_link2_crc_byte_PARM_2, #0x82
    00002$:
        djnz r7, 00001$
        pop ar7
        mov a, _att_link2_crc_byte_PARM_2
        ret
    __endasm;
    /* clang-format on */
}
#else
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
#endif

/* -- ring ------------------------------------------------------------ */

static uint8_t ATT_LINK_MEM *slot(SELF_ uint8_t seq)
{
    uint16_t i = (uint8_t)(seq & (uint8_t)(RING_SIZE - 1u));
    return RING + (uint16_t)((uint16_t)(i << 2) + (uint16_t)(i << 1)); /* 6 i: no multiply on the 8051 */
}

/* A sample record whose three codes fit 12 bits travels packed. */
static uint8_t packable(const uint8_t ATT_LINK_MEM *rec)
{
    return (uint8_t)(rec[0] < 16u && rec[2] < 16u && rec[4] < 16u);
}

/* Does B's limit let A send record `seq`? (limit - seq in 1..127) */
static uint8_t window_open(SELF_ uint8_t seq)
{
    return (uint8_t)((uint8_t)((uint8_t)(S->limit - seq) - 1u) < (uint8_t)ATT_LINK2_WINDOW_MAX);
}

#if ATT_LINK2_ONE
void API(init)(void)
{
    API(reset)();
}
#else
int API(init)(SELF_ const att_link2_sender_config *cfg, uint8_t ATT_LINK_MEM *ring)
{
    uint8_t ATT_LINK_MEM *p;
    uint8_t n;
    if (s == NULL || cfg == NULL || ring == NULL) {
        return ATT_LINK2_E_NULL;
    }
    S->cfg = *cfg;
    S->ring = ring;
    p = (uint8_t ATT_LINK_MEM *)&S->stats;
    n = (uint8_t)sizeof(S->stats);
    do {
        *p++ = 0;
    } while (--n != 0);
    API(reset)(ARG);
    n = RING_SIZE;
    if (n == 0u || n > (uint8_t)ATT_LINK2_RING_MAX || (uint8_t)(n & (uint8_t)(n - 1u)) != 0u
        || (uint8_t)(MAX_SAMPLES - 1u) >= (uint8_t)ATT_LINK2_SAMPLES_MAX
        || (uint16_t)(RTO - 1u) >= (uint16_t)ATT_LINK2_TIMEOUT_MAX) {
        S->session = (uint8_t)SES_BAD; /* unusable: every call reports an error */
        return ATT_LINK2_E_CONFIG;
    }
    return ATT_OK;
}
#endif

void API(reset)(SELF)
{
    CHECK_NULL(return );
    S->head = 0;
    S->base = 0;
    S->next = 0;
    S->hi = 0;
    S->limit = 0;
    S->t0 = 0;
    CUR_RESET();
    S->session = (uint8_t)SES_SYN_SEND;
    S->tx = (uint8_t)TX_IDLE;
    S->flags = (uint8_t)FL_LINE_IDLE;
    S->rx_len = 0;
}

/* Records whose slots are in use: from base, or from the frame being sent
 * when B acknowledged some of its records meanwhile (its bytes are still read
 * from the ring). */
static uint8_t used(CSELF)
{
    uint8_t n = (uint8_t)(S->head - S->base);
    if (S->tx != (uint8_t)TX_IDLE && (uint8_t)(S->head - S->f_seq) > n) {
        n = (uint8_t)(S->head - S->f_seq);
    }
    return n;
}

uint8_t API(pending)(CSELF)
{
    CHECK_NULL(return 0);
    return (uint8_t)(S->head - S->base);
}

uint8_t API(room)(CSELF)
{
    CHECK_NULL(return 0);
    CHECK_BAD(return 0);
    return (uint8_t)(RING_SIZE - used(ARG));
}

uint8_t ATT_LINK_MEM *API(tail)(SELF)
{
    CHECK_NULL(return NULL);
    CHECK_BAD(return NULL);
    return used(ARG) >= RING_SIZE ? (uint8_t ATT_LINK_MEM *)NULL : slot(ARG_ S->head);
}

int API(push)(SELF_ const uint8_t ATT_LINK_MEM *record)
{
    uint8_t ATT_LINK_MEM *d;
    uint8_t i;
    CHECK_NULL(return ATT_LINK2_E_NULL);
    if (record == NULL) {
        return ATT_LINK2_E_NULL;
    }
    CHECK_BAD(return ATT_LINK2_E_STATE);
    if (used(ARG) >= RING_SIZE) {
        return ATT_LINK2_E_FULL;
    }
    d = slot(ARG_ S->head);
    for (i = 0; i < (uint8_t)ATT_LINK2_RECORD; i++) {
        d[i] = record[i];
    }
    S->head++;
    return ATT_OK;
}

/* -- sink: ACK frames from B ----------------------------------------- */

/* Apply the valid ACK decoded in place in rx[1..7] (d[0] = 0xC0 | flags,
 * d[1] = ack, d[2] = limit). */
static att_link2_result apply_ack(SELF_ uint16_t tick)
{
    const uint8_t ATT_LINK_MEM *d = S->rx + 1;
    uint8_t fl = (uint8_t)(d[0] & 0x0Fu);
    uint8_t a = d[1];
    uint8_t adv = (uint8_t)(a - S->base);
    STAT_INC(acks);
    if (fl & (uint8_t)ATT_LINK2_F_NOSESSION) { /* B rebooted: new session from base, ring kept */
        S->session = (uint8_t)SES_SYN_SEND;
        S->next = S->base;
        S->hi = S->base;
        S->limit = S->base;
        return ATT_LINK2_FRAME;
    }
    if (S->session == (uint8_t)SES_SYN_WAIT) {
        if ((fl & (uint8_t)ATT_LINK2_F_SYNACK) == 0u || adv != 0u) {
            return ATT_LINK2_FRAME; /* not the answer to our SYN */
        }
        S->session = (uint8_t)SES_RUN;
        S->t0 = tick;
    } else if (S->session != (uint8_t)SES_RUN) {
        return ATT_LINK2_FRAME; /* SYN not sent yet: nothing to acknowledge */
    }
    if (adv > (uint8_t)(S->hi - S->base)) {
        STAT_INC(bad_frames); /* acknowledges records never sent */
        return ATT_LINK2_BAD_FRAME;
    }
    if (adv != 0u) {
        if ((uint8_t)(S->next - S->base) < adv) {
            S->next = a; /* B already had what was being sent again */
        }
        S->base = a;
        S->t0 = tick;
        CUR_GROW(); /* progress: longer frames again */
    }
    if ((uint8_t)(d[2] - a) <= (uint8_t)ATT_LINK2_WINDOW_MAX) {
        S->limit = d[2];
    }
    if ((fl & (uint8_t)ATT_LINK2_F_GAP) && S->hi != S->base
        && (uint8_t)((uint8_t)((uint8_t)(fl << 2) ^ S->flags) & FL_EPOCH)
               == 0u) { /* F_EPOCH << 2 = FL_EPOCH */
        /* a gap in what was sent since the last go-back: go back to the first record B lacks */
        S->next = S->base;
        CUR_HALVE(); /* and shorter frames */
        S->flags ^= (uint8_t)FL_EPOCH;
        STAT_INC(gobacks);
        S->t0 = tick;
    }
    return ATT_LINK2_FRAME;
}

att_link2_result API(sink)(SELF_ uint8_t byte, uint16_t tick)
{
    uint8_t p;
    uint8_t q;
    uint8_t code;
    uint8_t first;
    uint32_t crc;
    CHECK_NULL(return ATT_LINK2_E_NULL);
    CHECK_BAD(return ATT_LINK2_E_STATE);
    p = S->rx_len;
    if (byte != (uint8_t)ATT_LINK2_DELIM) {
        if (p >= (uint8_t)sizeof(S->rx)) {
            S->rx_len = 0xFFu; /* longer than an ACK: skip to the delimiter */
            return ATT_LINK2_DISCARDED;
        }
        S->rx[p] = byte;
        S->rx_len = (uint8_t)(p + 1u);
        return ATT_LINK2_NONE;
    }
    S->rx_len = 0;
    if (p == 0u) {
        return ATT_LINK2_NONE; /* idle delimiter */
    }
    if (p != (uint8_t)sizeof(S->rx)) {
        goto bad;
    }
    /* Decode the 8 encoded bytes (rCOBS, backwards) into the 7 bytes of an
     * ACK, in place: decoded byte q lands in rx[q + 1], at or above the byte
     * read last, so nothing is overwritten before it is read. */
    q = 7;
    first = 1;
    while (p != 0u) {
        code = S->rx[p - 1u];
        if (code > p || code == 0xFFu || (uint8_t)(code - 1u + (first ^ 1u)) > q) {
            goto bad;
        }
        p--;
        if (!first) {
            S->rx[q--] = 0;
        }
        first = 0;
        while (--code != 0u) {
            S->rx[q--] = S->rx[--p];
        }
    }
    if (q != 0u || (uint8_t)(S->rx[1] & 0xF0u) != (uint8_t)ATT_LINK2_T_ACK) {
        goto bad;
    }
    crc = 0xFFFFFFFFul;
    for (q = 1; q < 4u; q++) {
        crc = att_link2_crc_byte(crc, S->rx[q]);
    }
    crc = ~crc;
    if (S->rx[4] != (uint8_t)(crc >> 24) || S->rx[5] != (uint8_t)(crc >> 16)
        || S->rx[6] != (uint8_t)(crc >> 8) || S->rx[7] != (uint8_t)crc) {
        goto bad;
    }
    return apply_ack(ARG_ tick);
bad:
    STAT_INC(bad_frames);
    return ATT_LINK2_BAD_FRAME;
}

/* -- poll: the emitter ----------------------------------------------- */

#if ATT_LINK2_CURSOR
/* Decoded byte i of the frame being sent, i < f_len - 4 (the bytes the CRC
 * covers), asked for in order. Its data bytes come through the cursor f_ptr:
 * a RAW frame's record byte by byte; a DATA frame's codes (big-endian 16-bit
 * words, record after record, so the frame's codes are consecutive words of
 * the ring, wrapping at its end) two by two in three bytes: hi0 lo0 -> byte 0
 * = code 0 >> 4; byte 1 = (code 0 & 15) << 4 | hi1 (0: the padding of an odd
 * number of codes, its last byte); byte 2 = lo1. A word never straddles the
 * ring's end, so the cursor wraps only after a low byte. */
static uint8_t frame_byte(SELF_ uint8_t i)
{
    uint8_t ATT_LINK_MEM *p = S->f_ptr;
    uint8_t b;
    if (i < 2u) {
        return i == 0u ? S->f_head : S->f_seq;
    }
    if (S->f_head & (uint8_t)ATT_LINK2_T_RAW) {
        S->f_ptr = p + 1;
        return *p;
    }
    if (S->f_ph == 1u) {
        S->f_ph = 2;
        if ((uint8_t)(i + 5u) == S->f_len) {
            return S->f_nib; /* the odd last code: its low nibble and 4 bits of padding */
        }
        S->f_ptr = p + 1;
        return (uint8_t)(S->f_nib | *p);
    }
    if (S->f_ph == 0u) {
        b = p[1];
        S->f_nib = (uint8_t)(b << 4);
        b = (uint8_t)((uint8_t)(*p << 4) | (uint8_t)(b >> 4));
        p += 2;
        S->f_ph = 1;
    } else {
        b = *p++;
        S->f_ph = 0;
    }
    if (p == RING + (uint16_t)((uint16_t)((uint16_t)RING_SIZE << 2) + (uint16_t)((uint16_t)RING_SIZE << 1))) {
        p = RING;
    }
    S->f_ptr = p;
    return b;
}
#else
/* Nibble k of the packed codes of the DATA frame being sent (0 past the
 * last code): sample k / 9, nibble k % 9 of its three 12-bit codes, which
 * is the low (0) or high (0x80) nibble of byte nib_at[k % 9] & 7 of the record. */
static const uint8_t nib_at[9] = { 0, 0x81, 1, 2, 0x83, 3, 4, 0x85, 5 };

static uint8_t nibble(SELF_ uint8_t k)
{
    uint8_t smp = (uint8_t)(k / (uint8_t)9); /* 8-bit division: DIV AB on the 8051 */
    uint8_t w = nib_at[(uint8_t)(k - (uint8_t)(smp * (uint8_t)9))];
    uint8_t b;
    if (smp >= (uint8_t)(S->f_head & 0x1Fu)) {
        return 0; /* the padding of an odd number of codes */
    }
    b = slot(ARG_(uint8_t)(S->f_seq + smp))[w & 7u];
    return (uint8_t)((w & 0x80u) ? (uint8_t)(b >> 4) : (uint8_t)(b & 0x0Fu));
}

/* Decoded byte i of the frame being sent, i < f_len - 4 (the bytes the CRC covers). */
static uint8_t frame_byte(SELF_ uint8_t i)
{
    if (i == 0u) {
        return S->f_head;
    }
    if (i == 1u) {
        return S->f_seq;
    }
    i = (uint8_t)(i - 2u);
    if (S->f_head & (uint8_t)ATT_LINK2_T_RAW) {
        return slot(ARG_ S->f_seq)[i];
    }
    /* byte i of the packed codes: nibbles 2i and 2i + 1 */
    i = (uint8_t)(i << 1);
    return (uint8_t)((uint8_t)(nibble(ARG_ i) << 4) | nibble(ARG_(uint8_t)(i + 1u)));
}

#endif

/* The next encoded byte of the frame being sent (tx = TX_BODY). */
static uint8_t body_byte(SELF)
{
    uint8_t b;
    uint8_t i = S->f_pos;
    uint8_t tail = (uint8_t)(S->f_len - 4u);
    if (S->run == 254u) { /* 254 bytes without a zero: a code that stands for none */
        S->run = 0;
        return 0xFFu;
    }
    if (i >= S->f_len) { /* final code, then the delimiter */
        S->tx = (uint8_t)TX_DELIM;
        return (uint8_t)(S->run + 1u);
    }
    if (i < tail) {
        b = frame_byte(ARG_ i);
        S->crc = att_link2_crc_byte(S->crc, b);
    } else { /* the CRC, most significant byte first */
        if (i == tail) {
            S->crc = ~S->crc;
        }
        b = (uint8_t)(S->crc >> 24);
        S->crc <<= 8;
    }
    S->f_pos = (uint8_t)(i + 1u);
    if (b == 0u) {
        b = (uint8_t)(S->run + 1u);
        S->run = 0;
    } else {
        S->run++;
    }
    return b;
}

/* Start the frame whose f_head, f_seq and f_len are set: its first byte
 * goes out at this poll (after a 0x00 if the line was idle). */
static void start_frame(SELF)
{
    S->f_pos = 0;
    S->run = 0;
    S->crc = 0xFFFFFFFFul;
    STAT_INC(frames);
    if (S->flags & (uint8_t)FL_LINE_IDLE) {
        S->flags &= (uint8_t)~FL_LINE_IDLE;
        S->tx = (uint8_t)TX_LEAD;
    } else {
        S->tx = (uint8_t)TX_BODY;
    }
}

/* The next data frame from record `next`: one RAW record, or up to
 * max_samples packable samples below head and B's limit. */
static void start_data(SELF)
{
    uint8_t seq = S->next;
    uint8_t n = 1;
    uint8_t old;
    if (!packable(slot(ARG_ seq))) {
        S->f_head = (uint8_t)(ATT_LINK2_T_RAW | (S->flags & FL_EPOCH));
        S->f_len = (uint8_t)(6u + (uint8_t)ATT_LINK2_RECORD);
    } else {
        while (n < CUR && (uint8_t)(seq + n) != S->head && window_open(ARG_(uint8_t)(seq + n))
               && packable(slot(ARG_(uint8_t)(seq + n)))) {
            n++;
        }
        S->f_head = (uint8_t)(n | (S->flags & FL_EPOCH));
        S->f_len = (uint8_t)(6u + (uint8_t)((uint8_t)(9u * n + 1u) >> 1));
    }
    S->f_seq = seq;
#if ATT_LINK2_CURSOR
    S->f_ptr = slot(ARG_ seq);
    S->f_ph = 0;
#endif
    /* records below hi were sent before: they count as resent */
    old = (uint8_t)(seq - S->base) < (uint8_t)(S->hi - S->base) ? (uint8_t)(S->hi - seq) : 0u;
    if (old >= n) {
        STAT_ADD(resent, n);
    } else {
        STAT_ADD(resent, old);
        STAT_ADD(records, (uint8_t)(n - old));
        S->hi = (uint8_t)(seq + n);
    }
    S->next = (uint8_t)(seq + n);
    start_frame(ARG);
}

/* Between frames: start one (tx leaves TX_IDLE), or say why not. */
static att_link2_result poll_idle(SELF_ uint16_t tick)
{
    if (S->session == (uint8_t)SES_SYN_SEND) {
        S->session = (uint8_t)SES_SYN_WAIT;
        STAT_INC(syns);
        S->f_head = (uint8_t)ATT_LINK2_T_SYN;
        goto empty_frame; /* SYN at base */
    }
    if ((S->session == (uint8_t)SES_SYN_WAIT || S->hi != S->base
         || (S->next != S->head && !window_open(ARG_ S->next)))
        && (uint16_t)(tick - S->t0) > RTO) {
        STAT_INC(timeouts);
        S->t0 = tick;
        if (S->session == (uint8_t)SES_SYN_WAIT) {
            S->session = (uint8_t)SES_SYN_SEND;
            return ATT_LINK2_TIMEOUT;
        }
        if (S->hi != S->base) {
            S->next = S->base; /* no progress: go back to the first unacknowledged record */
            CUR_HALVE();
            S->flags ^= (uint8_t)FL_EPOCH;
        }
        if (window_open(ARG_ S->next)) {
            return ATT_LINK2_TIMEOUT; /* the next poll sends again */
        }
        /* B's limit blocks A (or A missed the ACK that opened it): ask with an empty frame */
        S->f_head = (uint8_t)(ATT_LINK2_T_DATA | (S->flags & FL_EPOCH)); /* probe at next */
        goto empty_frame;
    }
    if (S->session == (uint8_t)SES_RUN && S->next != S->head && window_open(ARG_ S->next) AND_READY(tick)) {
        start_data(ARG);
        return ATT_LINK2_SEND;
    }
    S->flags |= (uint8_t)FL_LINE_IDLE;
    return (S->session == (uint8_t)SES_RUN && S->head == S->base) ? ATT_LINK2_IDLE : ATT_LINK2_NONE;
empty_frame:
    S->f_seq = S->f_head == (uint8_t)ATT_LINK2_T_SYN ? S->base : S->next;
    S->f_len = 6u;
    start_frame(ARG);
    return ATT_LINK2_SEND;
}

att_link2_result API(poll)(SELF_ uint16_t tick, uint8_t ATT_LINK_MEM *out_byte)
{
    att_link2_result r;
    uint8_t b = (uint8_t)ATT_LINK2_DELIM;
    CHECK_NULL(return ATT_LINK2_E_NULL);
    if (out_byte == NULL) {
        return ATT_LINK2_E_NULL;
    }
    CHECK_BAD(return ATT_LINK2_E_STATE);
    if (S->tx == (uint8_t)TX_IDLE) {
        r = poll_idle(ARG_ tick);
        if (r != ATT_LINK2_SEND) {
            return r;
        }
    }
    switch (S->tx) {
    case TX_LEAD: /* the 0x00 before a frame after an idle line */
        S->tx = (uint8_t)TX_BODY;
        break;
    case TX_BODY:
        b = body_byte(ARG);
        break;
    case TX_DELIM: /* the 0x00 that ends the frame */
        S->tx = (uint8_t)TX_IDLE;
        S->t0 = tick; /* the timer counts from the end of the last frame */
        break;
    default:
        return ATT_LINK2_E_STATE;
    }
    *out_byte = b;
    return ATT_LINK2_SEND;
}
