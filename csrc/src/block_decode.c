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
    s->next = 0;
    s->synced = 0;
    s->oversample = 1;
}

int att_block_seq_feed(att_block_seq *s, const att_block *b, att_block_span *span)
{
    uint16_t u;
    int32_t d;
    uint32_t first;
    if (s == NULL || b == NULL || span == NULL) {
        return ATT_E_NULL;
    }
    span->slip = 0;
    switch (b->kind) {
    case ATT_BLOCK_SAMPLE:
        span->first = s->next;
        span->count = 1;
        s->next++;
        return ATT_OK;
    case ATT_BLOCK_BOOT:
        s->next = 0;
        s->synced = 1;
        s->oversample = 1; /* a new stream: plain until it says otherwise */
        span->first = 0;
        span->count = 0;
        return ATT_OK;
    case ATT_BLOCK_SELFTEST:
        span->first = s->next;
        span->count = 0;
        return ATT_OK;
    case ATT_BLOCK_OVERSAMPLE:
        if (b->oversample < 1u || b->oversample > (uint8_t)ATT_BLOCK_OVERSAMPLE_MAX) {
            return ATT_BLOCK_E_FIELD;
        }
        s->oversample = b->oversample;
        span->first = s->next;
        span->count = 0;
        return ATT_OK;
    case ATT_BLOCK_GAVE_UP:
    case ATT_BLOCK_OVERRUN:
    case ATT_BLOCK_ADC_ERROR:
        break;
    default:
        return ATT_BLOCK_E_KIND;
    }
    if (b->count == 0u) {
        return ATT_BLOCK_E_FIELD;
    }
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
