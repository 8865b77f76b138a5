/*
 * libattitude — block format decoder and sequence tracker (see
 * attitude/block.h). Host side (attitude-rx, the Python bindings); kept
 * apart from the encoders of block.c so that the firmware does not link
 * it. Portable C99 (SDCC compiles it too).
 */
#include <string.h>

#include "attitude/block.h"

static uint16_t be16(const uint8_t *p)
{
    return (uint16_t)(((uint16_t)p[0] << 8) | p[1]);
}

/* Byte as a two's complement int8 (without implementation-defined conversion). */
static int8_t s8(uint8_t b)
{
    return (int8_t)((b & 0x80u) != 0u ? (int)b - 256 : (int)b);
}

/* A CHANNELS report's fields: ATT_OK or ATT_BLOCK_E_FIELD (the encoder's checks, the one copy). */
static int channels_check(const att_block *b)
{
    uint8_t tmp[ATT_BLOCK_SIZE];
    return att_block_encode_channels(tmp, b->board, b->channels, b->acc_every, b->mag_every) == ATT_OK
               ? ATT_OK
               : ATT_BLOCK_E_FIELD;
}

int att_block_decode(const uint8_t *raw, att_block *out)
{
    uint8_t i;
    int st = ATT_OK;
    if (raw == NULL || out == NULL) {
        return ATT_E_NULL;
    }
    memset(out, 0, sizeof *out); /* the fields a kind does not use are 0 */
    if (raw[0] != (uint8_t)ATT_BLOCK_MARK) {
        out->kind = (uint16_t)ATT_BLOCK_SAMPLE;
        for (i = 0; i < 3u; i++) {
            out->code[i] = be16(raw + 2 * i);
            if (out->code[i] > (uint16_t)ATT_BLOCK_CODE_MAX) {
                st = ATT_BLOCK_E_CODE;
            }
        }
        return st;
    }
    out->kind = raw[1];
    switch (raw[1]) {
    case ATT_BLOCK_BOOT:
        out->version = raw[2];
        out->period_ticks = (uint16_t)(be16(raw + 3) & 0x7FFFu);
        out->link = (uint8_t)((raw[3] & 0x80u) ? 2u : 0u); /* ATT_BLOCK_BOOT_LINK2 */
        out->baud_div = raw[5];
        if (out->version != (uint8_t)ATT_BLOCK_VERSION || out->period_ticks == 0u
            || out->period_ticks > (uint16_t)ATT_BLOCK_PERIOD_MAX || out->baud_div == 0u) {
            st = ATT_BLOCK_E_FIELD;
        }
        break;
    case ATT_BLOCK_SELFTEST:
        out->status = s8(raw[2]);
        out->bad_code = be16(raw + 3);
        out->attempt = raw[5];
        if (out->status >= 0 || out->bad_code > (uint16_t)ATT_BLOCK_CODE_MAX) {
            st = ATT_BLOCK_E_FIELD;
        }
        break;
    case ATT_BLOCK_GAVE_UP:
    case ATT_BLOCK_OVERRUN:
        out->first = be16(raw + 2);
        out->count = be16(raw + 4);
        if (out->count == 0u) {
            st = ATT_BLOCK_E_FIELD;
        }
        break;
    case ATT_BLOCK_ADC_ERROR:
        out->first = be16(raw + 2);
        out->count = 1;
        out->status = s8(raw[4]);
        if (out->status >= 0 || raw[5] != 0u) {
            st = ATT_BLOCK_E_FIELD;
        }
        break;
    case ATT_BLOCK_OVERSAMPLE:
        out->oversample = raw[2];
        if (raw[2] < 1u || raw[2] > (uint8_t)ATT_BLOCK_OVERSAMPLE_MAX || raw[3] != 0u || raw[4] != 0u
            || raw[5] != 0u) {
            st = ATT_BLOCK_E_FIELD;
        }
        break;
    case ATT_BLOCK_CHANNELS:
        out->board = raw[2];
        out->channels = raw[3];
        out->acc_every = raw[4];
        out->mag_every = raw[5];
        st = channels_check(out);
        break;
    default:
        st = ATT_BLOCK_E_KIND;
        break;
    }
    return st;
}

void att_block_seq_init(att_block_seq *s)
{
    if (s == NULL) {
        return;
    }
    memset(s, 0, sizeof *s);
    s->oversample = 1;
    s->channels = (uint8_t)ATT_BLOCK_CH_GYR;
}

/* The record of a group that is due next (GYR: none, the next sample's gyro record). */
static uint8_t due(const att_block_seq *s)
{
    if (s->next == 0u || (s->part != (uint8_t)ATT_BLOCK_PART_ACC && s->part != (uint8_t)ATT_BLOCK_PART_MAG)) {
        return (uint8_t)ATT_BLOCK_PART_GYR;
    }
    return s->part;
}

/* Whether sample n has a record of the sensor with this channel bit and decimation. */
static int has(const att_block_seq *s, uint32_t n, uint8_t bit, uint8_t every)
{
    return (s->channels & bit) != 0u && every != 0u && n % every == 0u;
}

/* A sample record: the part that is due, of the group it belongs to; then what follows it. */
static void place_sample(att_block_seq *s, att_block_span *span)
{
    uint8_t p = due(s);
    if (p == (uint8_t)ATT_BLOCK_PART_GYR) {
        s->next++;
    }
    span->first = s->next - 1u;
    span->count = 1;
    span->part = p;
    if (p == (uint8_t)ATT_BLOCK_PART_GYR && has(s, span->first, (uint8_t)ATT_BLOCK_CH_ACC, s->acc_every)) {
        s->part = (uint8_t)ATT_BLOCK_PART_ACC;
    } else if (p != (uint8_t)ATT_BLOCK_PART_MAG
               && has(s, span->first, (uint8_t)ATT_BLOCK_CH_MAG, s->mag_every)) {
        s->part = (uint8_t)ATT_BLOCK_PART_MAG;
    } else {
        s->part = (uint8_t)ATT_BLOCK_PART_GYR;
    }
}

/* Whether the tracker can place report b: ATT_OK, ATT_BLOCK_E_FIELD or ATT_BLOCK_E_KIND. */
static int report_check(const att_block *b)
{
    switch (b->kind) {
    case ATT_BLOCK_SELFTEST:
        return ATT_OK;
    case ATT_BLOCK_OVERSAMPLE:
        return b->oversample < 1u || b->oversample > (uint8_t)ATT_BLOCK_OVERSAMPLE_MAX ? ATT_BLOCK_E_FIELD
                                                                                       : ATT_OK;
    case ATT_BLOCK_CHANNELS:
        return channels_check(b);
    case ATT_BLOCK_GAVE_UP:
    case ATT_BLOCK_OVERRUN:
    case ATT_BLOCK_ADC_ERROR:
        return b->count == 0u ? ATT_BLOCK_E_FIELD : ATT_OK;
    default:
        return ATT_BLOCK_E_KIND;
    }
}

/* A loss report (count >= 1): its samples, and a slip against the count. */
static int place_loss(att_block_seq *s, const att_block *b, att_block_span *span)
{
    uint16_t u;
    int32_t d;
    uint32_t first;
    if (!s->synced) { /* joined after BOOT: the report fixes the numbering */
        s->synced = 1;
        span->first = b->first;
        span->count = b->count;
        s->next = (uint32_t)b->first + b->count;
        return ATT_OK;
    }
    /* the report's first relative to the count, in -32768..32767 */
    u = (uint16_t)(b->first - (uint16_t)s->next);
    d = u < 0x8000u ? (int32_t)u : (int32_t)u - 65536L;
    span->slip = d;
    if (d >= 0) { /* d samples vanished unreported before it: missing too */
        span->first = s->next;
        span->count = (uint32_t)d + b->count;
    } else { /* -d records were numbered too many (at most back to 0) */
        first = (uint32_t)-d > s->next ? 0u : s->next - (uint32_t)-d;
        span->first = first;
        span->count = b->count;
    }
    s->next = span->first + span->count;
    return d == 0 ? ATT_OK : ATT_BLOCK_E_SEQ;
}

int att_block_seq_feed(att_block_seq *s, const att_block *b, att_block_span *span)
{
    int st;
    uint8_t cut;
    if (s == NULL || b == NULL || span == NULL) {
        return ATT_E_NULL;
    }
    span->slip = 0;
    span->part = (uint8_t)ATT_BLOCK_PART_GYR;
    if (b->kind == (uint16_t)ATT_BLOCK_SAMPLE) {
        place_sample(s, span);
        return ATT_OK;
    }
    if (b->kind == (uint16_t)ATT_BLOCK_BOOT) { /* a new stream: plain and gyro-only until it says otherwise */
        att_block_seq_init(s);
        s->synced = 1;
        span->first = 0;
        span->count = 0;
        return ATT_OK;
    }
    st = report_check(b);
    if (st != ATT_OK) {
        return st; /* nothing changes */
    }
    cut = due(s); /* a report inside a group closes it */
    s->part = (uint8_t)ATT_BLOCK_PART_GYR;
    span->first = s->next;
    span->count = 0;
    if (b->kind == (uint16_t)ATT_BLOCK_OVERSAMPLE) {
        s->oversample = b->oversample;
    } else if (b->kind == (uint16_t)ATT_BLOCK_CHANNELS) {
        s->channels = b->channels;
        s->acc_every = b->acc_every;
        s->mag_every = b->mag_every;
    } else if (b->kind != (uint16_t)ATT_BLOCK_SELFTEST) {
        st = place_loss(s, b, span);
    }
    if (cut != (uint8_t)ATT_BLOCK_PART_GYR) {
        span->part = cut;
        return ATT_BLOCK_E_SEQ;
    }
    return st;
}

int att_block_seq_decode(att_block_seq *s, const uint8_t *raw, att_block *out, att_block_span *span)
{
    uint32_t limit;
    uint8_t i;
    int st, placed;
    if (s == NULL || raw == NULL || out == NULL || span == NULL) {
        return ATT_E_NULL;
    }
    st = att_block_decode(raw, out);
    if (out->kind == (uint16_t)ATT_BLOCK_SAMPLE) {
        /* the stream's limit instead of the plain one (a zeroed tracker is plain) */
        limit = (uint32_t)(s->oversample > 1u ? s->oversample : 1u) * (uint32_t)ATT_BLOCK_CODE_MAX;
        if (limit > (uint32_t)ATT_BLOCK_SUM_MAX) {
            limit = (uint32_t)ATT_BLOCK_SUM_MAX;
        }
        st = ATT_OK;
        for (i = 0; i < 3u; i++) {
            if ((uint32_t)out->code[i] > limit) {
                st = ATT_BLOCK_E_CODE;
            }
        }
    } else if (st != ATT_OK) {
        return st; /* no place in the numbering */
    }
    placed = att_block_seq_feed(s, out, span);
    return st != ATT_OK ? st : placed;
}
