/*
 * libFuzzer target for the block format (attitude/block.h): the decoder,
 * the sequence tracker and the encoders, built with AddressSanitizer +
 * UndefinedBehaviorSanitizer (`invoke fuzz --target block`).
 *
 * Input: chunks of 7 bytes, an operation byte and 6 record bytes. Even
 * operation: decode the 6 bytes as a record and feed it to a sequence
 * tracker; odd: call one of the encoders (chosen by the operation) with
 * arguments taken from the 6 bytes.
 *
 * Oracles (abort() on a violation), from the header's contract:
 *  - decode: a record whose byte 0 is not the mark is a sample with the
 *    big-endian codes, ATT_OK exactly when every code is <= 4095 (else
 *    ATT_BLOCK_E_CODE); a report has kind = byte 1, ATT_BLOCK_E_KIND
 *    above CHANNELS, ATT_BLOCK_E_FIELD exactly when a field is out of
 *    its range; the fields a kind does not use are 0; every record it
 *    accepts encodes back to the same 6 bytes, and every field it rejects
 *    is rejected by the encoder too.
 *  - the sequence tracker: a sample takes the next number, BOOT restarts
 *    at 0, SELFTEST takes none, a loss report is adopted as it is before
 *    the numbering is fixed, then its slip is its first minus the count
 *    (in -32768..32767), ATT_BLOCK_E_SEQ exactly when it is not 0, and the
 *    count goes on after the report's samples; OVERSAMPLE n sets the
 *    stream's n (BOOT sets it back to 1) and takes no number; CHANNELS
 *    sets the channel set and decimations (BOOT: gyro-only again); in an
 *    aided stream a sample record is the gyro record of the next number
 *    or, as the group of sample n (gyro, then accelerometer when n %
 *    acc_every == 0, then magnetometer when n % mag_every == 0) says, a
 *    record of the last one; a report other than BOOT inside a group
 *    closes it with ATT_BLOCK_E_SEQ and span.part the record due; rejected
 *    records change nothing.
 *  - att_block_seq_decode: the same record and placement as decode + feed,
 *    except that a sample's words are checked against the stream's limit
 *    (4095, or min(n x 4095, ATT_BLOCK_SUM_MAX) after OVERSAMPLE n).
 *  - an encoder returns ATT_OK exactly for arguments in range, and its
 *    record decodes to those arguments.
 *  - NULL pointers give ATT_E_NULL.
 */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "attitude/block.h"
#include "fuzz_harness.h"

static int8_t s8(uint8_t b)
{
    return (int8_t)(b >= 128 ? (int)b - 256 : (int)b);
}

/* CHANNELS' fields, from the header's list: board 1 (GYR alone) or 2, GYR set,
 * no bit above MAG, a decimation exactly for each sensor in the set. */
static int channels_valid(unsigned board, unsigned ch, unsigned acc, unsigned mag)
{
    return (board == 2 || (board == 1 && ch == 1)) && (ch & 1) && ch <= 7 && !!(ch & 2) == (acc != 0)
           && !!(ch & 4) == (mag != 0);
}

/* The record of sample n's group after record `part` (0 gyro, 1 acc, 2 mag), 0 when it was the last. */
static uint8_t part_after(const att_block_seq *s, uint32_t n, uint8_t part)
{
    int acc = (s->channels & 2) && s->acc_every && n % s->acc_every == 0;
    int mag = (s->channels & 4) && s->mag_every && n % s->mag_every == 0;
    if (part == 0 && acc) {
        return 1;
    }
    return (uint8_t)(part < 2 && mag ? 2 : 0);
}

static int same_stream(const att_block_seq *a, const att_block_seq *b)
{
    return a->next == b->next && a->synced == b->synced && a->oversample == b->oversample
           && a->channels == b->channels && a->acc_every == b->acc_every && a->mag_every == b->mag_every
           && a->part == b->part;
}

static int is_loss(unsigned kind)
{
    return kind == ATT_BLOCK_GAVE_UP || kind == ATT_BLOCK_OVERRUN || kind == ATT_BLOCK_ADC_ERROR;
}

/* The decoded record b of raw (status st) against the format. */
static void check_decoded(const uint8_t *raw, const att_block *b, int st)
{
    att_block zero;
    uint8_t enc[ATT_BLOCK_SIZE];
    int e;
    memset(&zero, 0, sizeof zero);
    if (raw[0] != (uint8_t)ATT_BLOCK_MARK) {
        int big = fuzz_be16(raw) > ATT_BLOCK_CODE_MAX || fuzz_be16(raw + 2) > ATT_BLOCK_CODE_MAX
                  || fuzz_be16(raw + 4) > ATT_BLOCK_CODE_MAX;
        FUZZ_CHECK(b->kind == (uint16_t)ATT_BLOCK_SAMPLE && st == (big ? ATT_BLOCK_E_CODE : ATT_OK));
        FUZZ_CHECK(b->code[0] == fuzz_be16(raw) && b->code[1] == fuzz_be16(raw + 2)
                   && b->code[2] == fuzz_be16(raw + 4));
        zero.kind = b->kind;
        memcpy(zero.code, b->code, sizeof zero.code);
        FUZZ_CHECK(memcmp(&zero, b, sizeof zero) == 0); /* nothing else set */
        e = att_block_encode_sample(enc, b->code);
        FUZZ_CHECK(e == st && (st != ATT_OK || memcmp(enc, raw, sizeof enc) == 0));
        return;
    }
    FUZZ_CHECK(b->kind == raw[1]);
    zero.kind = b->kind;
    switch (raw[1]) {
    case ATT_BLOCK_BOOT:
        FUZZ_CHECK(b->version == raw[2] && b->period_ticks == (fuzz_be16(raw + 3) & 0x7FFFu)
                   && b->baud_div == raw[5] && b->link == ((raw[3] & 0x80u) ? 2 : 0));
        FUZZ_CHECK(st
                   == ((raw[2] == ATT_BLOCK_VERSION && (fuzz_be16(raw + 3) & 0x7FFFu) >= 1 && raw[5] != 0)
                           ? ATT_OK
                           : ATT_BLOCK_E_FIELD));
        zero.version = b->version;
        zero.period_ticks = b->period_ticks;
        zero.baud_div = b->baud_div;
        zero.link = b->link;
        e = att_block_encode_boot(enc, (uint16_t)(b->period_ticks | (b->link ? ATT_BLOCK_BOOT_LINK2 : 0)),
                                  b->baud_div);
        if (b->version == ATT_BLOCK_VERSION) { /* the encoder writes no other version */
            FUZZ_CHECK(e == st);
        }
        break;
    case ATT_BLOCK_SELFTEST:
        FUZZ_CHECK(b->status == s8(raw[2]) && b->bad_code == fuzz_be16(raw + 3) && b->attempt == raw[5]);
        FUZZ_CHECK(
            st == (s8(raw[2]) < 0 && fuzz_be16(raw + 3) <= ATT_BLOCK_CODE_MAX ? ATT_OK : ATT_BLOCK_E_FIELD));
        zero.status = b->status;
        zero.bad_code = b->bad_code;
        zero.attempt = b->attempt;
        e = att_block_encode_selftest(enc, b->status, b->bad_code, b->attempt);
        FUZZ_CHECK(e == st);
        break;
    case ATT_BLOCK_GAVE_UP:
    case ATT_BLOCK_OVERRUN:
        FUZZ_CHECK(b->first == fuzz_be16(raw + 2) && b->count == fuzz_be16(raw + 4));
        FUZZ_CHECK(st == (b->count != 0 ? ATT_OK : ATT_BLOCK_E_FIELD));
        zero.first = b->first;
        zero.count = b->count;
        e = att_block_encode_loss(enc, raw[1], b->first, b->count);
        FUZZ_CHECK(e == st);
        break;
    case ATT_BLOCK_ADC_ERROR:
        FUZZ_CHECK(b->first == fuzz_be16(raw + 2) && b->count == 1 && b->status == s8(raw[4]));
        FUZZ_CHECK(st == (s8(raw[4]) < 0 && raw[5] == 0 ? ATT_OK : ATT_BLOCK_E_FIELD));
        zero.first = b->first;
        zero.count = 1;
        zero.status = b->status;
        e = att_block_encode_adc_error(enc, b->first, b->status);
        if (raw[5] == 0) { /* the encoder always writes 0 there */
            FUZZ_CHECK(e == st);
        }
        break;
    case ATT_BLOCK_OVERSAMPLE:
        FUZZ_CHECK(b->oversample == raw[2]);
        FUZZ_CHECK(
            st
            == (raw[2] >= 1 && raw[2] <= ATT_BLOCK_OVERSAMPLE_MAX && raw[3] == 0 && raw[4] == 0 && raw[5] == 0
                    ? ATT_OK
                    : ATT_BLOCK_E_FIELD));
        zero.oversample = b->oversample;
        e = att_block_encode_oversample(enc, b->oversample);
        if (raw[3] == 0 && raw[4] == 0 && raw[5] == 0) { /* the encoder always writes 0 there */
            FUZZ_CHECK(e == st);
        }
        break;
    case ATT_BLOCK_CHANNELS:
        FUZZ_CHECK(b->board == raw[2] && b->channels == raw[3] && b->acc_every == raw[4]
                   && b->mag_every == raw[5]);
        FUZZ_CHECK(st == (channels_valid(raw[2], raw[3], raw[4], raw[5]) ? ATT_OK : ATT_BLOCK_E_FIELD));
        zero.board = b->board;
        zero.channels = b->channels;
        zero.acc_every = b->acc_every;
        zero.mag_every = b->mag_every;
        e = att_block_encode_channels(enc, b->board, b->channels, b->acc_every, b->mag_every);
        FUZZ_CHECK(e == st);
        break;
    default:
        FUZZ_CHECK(st == ATT_BLOCK_E_KIND);
        return;
    }
    FUZZ_CHECK(memcmp(&zero, b, sizeof zero) == 0); /* the fields a kind does not use are 0 */
    FUZZ_CHECK(st != ATT_OK || memcmp(enc, raw, sizeof enc) == 0);
}

/* A sample record fed to the tracker: its place in the numbering and its group. */
static void check_sample(const att_block_seq *before, const att_block_seq *s, const att_block_span *sp,
                         int st)
{
    int inside = before->next > 0 && (before->part == 1 || before->part == 2);
    FUZZ_CHECK(st == ATT_OK && sp->count == 1 && sp->slip == 0 && s->synced == before->synced);
    if (inside) {
        FUZZ_CHECK(sp->first == before->next - 1 && sp->part == before->part && s->next == before->next);
    } else {
        FUZZ_CHECK(sp->first == before->next && sp->part == 0 && s->next == before->next + 1);
    }
    FUZZ_CHECK(s->part == part_after(before, sp->first, sp->part));
    FUZZ_CHECK(s->oversample == before->oversample && s->channels == before->channels
               && s->acc_every == before->acc_every && s->mag_every == before->mag_every);
}

/* A loss report (count >= 1) placed by the tracker: adopted, or its slip. */
static void check_loss(const att_block_seq *before, const att_block_seq *s, const att_block_span *sp,
                       const att_block *b, int cut, int st)
{
    int32_t d;
    uint16_t u;
    if (!before->synced) { /* adopted as it is */
        FUZZ_CHECK(st == (cut ? ATT_BLOCK_E_SEQ : ATT_OK) && sp->first == b->first && sp->count == b->count
                   && sp->slip == 0);
        FUZZ_CHECK(s->synced && s->next == (uint32_t)b->first + b->count);
        return;
    }
    u = (uint16_t)(b->first - (uint16_t)before->next);
    d = u < 0x8000u ? (int32_t)u : (int32_t)u - 65536;
    FUZZ_CHECK(sp->slip == d && st == (d == 0 && !cut ? ATT_OK : ATT_BLOCK_E_SEQ));
    if (d >= 0) {
        FUZZ_CHECK(sp->first == before->next && sp->count == (uint32_t)d + b->count);
    } else {
        FUZZ_CHECK(sp->first == ((uint32_t)-d > before->next ? 0u : before->next - (uint32_t)-d)
                   && sp->count == b->count);
    }
    FUZZ_CHECK(s->next == sp->first + sp->count && s->synced);
}

/* Feed b to the tracker and check the span against the contract. */
static void check_seq(att_block_seq *s, const att_block *b)
{
    att_block_seq before = *s;
    att_block_span sp;
    int st = att_block_seq_feed(s, b, &sp);
    int cut = before.next > 0 && (before.part == 1 || before.part == 2);
    int valid;
    if (b->kind == (uint16_t)ATT_BLOCK_SAMPLE) {
        check_sample(&before, s, &sp, st);
        return;
    }
    if (b->kind == ATT_BLOCK_BOOT) {
        FUZZ_CHECK(st == ATT_OK && sp.first == 0 && sp.count == 0 && sp.part == 0 && s->next == 0 && s->synced
                   && s->oversample == 1 && s->channels == 1 && s->acc_every == 0 && s->mag_every == 0
                   && s->part == 0);
        return;
    }
    valid = b->kind == ATT_BLOCK_SELFTEST
            || (b->kind == ATT_BLOCK_OVERSAMPLE && b->oversample >= 1
                && b->oversample <= ATT_BLOCK_OVERSAMPLE_MAX)
            || (b->kind == ATT_BLOCK_CHANNELS
                && channels_valid(b->board, b->channels, b->acc_every, b->mag_every))
            || (is_loss(b->kind) && b->count != 0);
    if (!valid) { /* rejected: nothing changes */
        int known = is_loss(b->kind) || b->kind == ATT_BLOCK_OVERSAMPLE || b->kind == ATT_BLOCK_CHANNELS;
        FUZZ_CHECK(st == (known ? ATT_BLOCK_E_FIELD : ATT_BLOCK_E_KIND) && same_stream(s, &before));
        return;
    }
    /* placed: a group it interrupts is closed, span.part names the record that was due */
    FUZZ_CHECK(s->part == 0 && sp.part == (cut ? before.part : 0));
    FUZZ_CHECK(s->oversample == (b->kind == ATT_BLOCK_OVERSAMPLE ? b->oversample : before.oversample));
    if (b->kind == ATT_BLOCK_CHANNELS) {
        FUZZ_CHECK(s->channels == b->channels && s->acc_every == b->acc_every
                   && s->mag_every == b->mag_every);
    } else {
        FUZZ_CHECK(s->channels == before.channels && s->acc_every == before.acc_every
                   && s->mag_every == before.mag_every);
    }
    if (is_loss(b->kind)) {
        check_loss(&before, s, &sp, b, cut, st);
        return;
    }
    FUZZ_CHECK(st == (cut ? ATT_BLOCK_E_SEQ : ATT_OK) && sp.first == before.next && sp.count == 0
               && sp.slip == 0 && s->next == before.next && s->synced == before.synced);
}

/* An encoder with arguments from p: ATT_OK exactly in range, and its record decodes back. */
static void check_encode(uint8_t which, const uint8_t *p)
{
    uint8_t enc[ATT_BLOCK_SIZE];
    att_block b;
    int e, want, d;
    switch (which % 8) {
    case 0: {
        uint16_t codes[3];
        codes[0] = (uint16_t)(fuzz_be16(p) & 0x1FFF); /* mostly in range, sometimes not */
        codes[1] = (uint16_t)(fuzz_be16(p + 2) & 0x1FFF);
        codes[2] = (uint16_t)(fuzz_be16(p + 4) & 0x1FFF);
        want = codes[0] > ATT_BLOCK_CODE_MAX || codes[1] > ATT_BLOCK_CODE_MAX || codes[2] > ATT_BLOCK_CODE_MAX
                   ? ATT_BLOCK_E_CODE
                   : ATT_OK;
        e = att_block_encode_sample(enc, codes);
        FUZZ_CHECK(e == want);
        if (e == ATT_OK) {
            d = att_block_decode(enc, &b);
            FUZZ_CHECK(d == ATT_OK && b.kind == (uint16_t)ATT_BLOCK_SAMPLE
                       && memcmp(b.code, codes, sizeof codes) == 0);
        }
        { /* in place, as the firmware does: the codes' memory is the block */
            uint16_t words[3];
            memcpy(words, codes, sizeof codes);
            FUZZ_CHECK(att_block_encode_sample((uint8_t *)words, words) == want);
            if (want == ATT_OK) {
                FUZZ_CHECK(att_block_decode((const uint8_t *)words, &b) == ATT_OK
                           && memcmp(b.code, codes, sizeof codes) == 0);
            }
        }
        return;
    }
    case 1:
        e = att_block_encode_boot(enc, fuzz_be16(p), p[2]);
        FUZZ_CHECK(e == ((fuzz_be16(p) & 0x7FFFu) >= 1 && p[2] != 0 ? ATT_OK : ATT_BLOCK_E_FIELD));
        if (e == ATT_OK) {
            FUZZ_CHECK(att_block_decode(enc, &b) == ATT_OK && b.kind == ATT_BLOCK_BOOT
                       && b.period_ticks == (fuzz_be16(p) & 0x7FFFu) && b.link == ((p[0] & 0x80u) ? 2 : 0)
                       && b.baud_div == p[2] && b.version == ATT_BLOCK_VERSION);
        }
        return;
    case 2:
        e = att_block_encode_selftest(enc, s8(p[0]), fuzz_be16(p + 1), p[3]);
        FUZZ_CHECK(e
                   == (s8(p[0]) < 0 && fuzz_be16(p + 1) <= ATT_BLOCK_CODE_MAX ? ATT_OK : ATT_BLOCK_E_FIELD));
        if (e == ATT_OK) {
            FUZZ_CHECK(att_block_decode(enc, &b) == ATT_OK && b.kind == ATT_BLOCK_SELFTEST
                       && b.status == s8(p[0]) && b.bad_code == fuzz_be16(p + 1) && b.attempt == p[3]);
        }
        return;
    case 3:
        e = att_block_encode_loss(enc, p[0] % 6, fuzz_be16(p + 1), fuzz_be16(p + 3));
        want = p[0] % 6 != ATT_BLOCK_GAVE_UP && p[0] % 6 != ATT_BLOCK_OVERRUN ? ATT_BLOCK_E_KIND
               : fuzz_be16(p + 3) == 0                                        ? ATT_BLOCK_E_FIELD
                                                                              : ATT_OK;
        FUZZ_CHECK(e == want);
        if (e == ATT_OK) {
            FUZZ_CHECK(att_block_decode(enc, &b) == ATT_OK && b.kind == p[0] % 6
                       && b.first == fuzz_be16(p + 1) && b.count == fuzz_be16(p + 3));
        }
        return;
    case 5:
        e = att_block_encode_oversample(enc, p[0]);
        FUZZ_CHECK(e == (p[0] >= 1 && p[0] <= ATT_BLOCK_OVERSAMPLE_MAX ? ATT_OK : ATT_BLOCK_E_FIELD));
        if (e == ATT_OK) {
            FUZZ_CHECK(att_block_decode(enc, &b) == ATT_OK && b.kind == ATT_BLOCK_OVERSAMPLE
                       && b.oversample == p[0]);
        }
        return;
    case 6: {
        uint16_t sums[3];
        uint8_t n = (uint8_t)(p[0] % 18); /* 0..17: both ends of 1..16 and beyond */
        uint32_t lim = (uint32_t)n * ATT_BLOCK_CODE_MAX;
        att_block_seq s;
        att_block_span sp;
        uint8_t ov[ATT_BLOCK_SIZE];
        if (lim > ATT_BLOCK_SUM_MAX) {
            lim = ATT_BLOCK_SUM_MAX;
        }
        sums[0] = fuzz_be16(p + 1);
        sums[1] = (uint16_t)(fuzz_be16(p + 3) >> (p[0] & 3)); /* smaller words too */
        sums[2] = (uint16_t)((uint16_t)p[5] << (p[0] & 7));
        want = n < 1 || n > ATT_BLOCK_OVERSAMPLE_MAX             ? ATT_BLOCK_E_FIELD
               : sums[0] > lim || sums[1] > lim || sums[2] > lim ? ATT_BLOCK_E_CODE
                                                                 : ATT_OK;
        e = att_block_encode_sums(enc, sums, n);
        FUZZ_CHECK(e == want);
        if (e == ATT_OK) { /* decoded in its stream: after BOOT and OVERSAMPLE n */
            att_block_seq_init(&s);
            FUZZ_CHECK(att_block_encode_boot(ov, 72, 8) == ATT_OK
                       && att_block_seq_decode(&s, ov, &b, &sp) == ATT_OK);
            FUZZ_CHECK(att_block_encode_oversample(ov, n) == ATT_OK
                       && att_block_seq_decode(&s, ov, &b, &sp) == ATT_OK);
            FUZZ_CHECK(att_block_seq_decode(&s, enc, &b, &sp) == ATT_OK
                       && b.kind == (uint16_t)ATT_BLOCK_SAMPLE && memcmp(b.code, sums, sizeof sums) == 0
                       && sp.first == 0 && sp.count == 1);
            if (n == 1) { /* n = 1 gives att_block_encode_sample's bytes */
                FUZZ_CHECK(att_block_encode_sample(ov, sums) == ATT_OK && memcmp(ov, enc, sizeof ov) == 0);
            }
        }
        return;
    }
    case 7:
        e = att_block_encode_channels(enc, (uint8_t)(p[0] & 3), (uint8_t)(p[1] & 15),
                                      (uint8_t)(p[2] >> (p[4] & 7)),
                                      (uint8_t)(p[3] >> (p[5] & 7))); /* small values, 0s: mostly in range */
        FUZZ_CHECK(e
                   == (channels_valid(p[0] & 3u, p[1] & 15u, (uint8_t)(p[2] >> (p[4] & 7)),
                                      (uint8_t)(p[3] >> (p[5] & 7)))
                           ? ATT_OK
                           : ATT_BLOCK_E_FIELD));
        if (e == ATT_OK) {
            FUZZ_CHECK(att_block_decode(enc, &b) == ATT_OK && b.kind == ATT_BLOCK_CHANNELS
                       && b.board == (p[0] & 3) && b.channels == (p[1] & 15) && b.acc_every == enc[4]
                       && b.mag_every == enc[5]);
        }
        return;
    default:
        e = att_block_encode_adc_error(enc, fuzz_be16(p), s8(p[2]));
        FUZZ_CHECK(e == (s8(p[2]) < 0 ? ATT_OK : ATT_BLOCK_E_FIELD));
        if (e == ATT_OK) {
            FUZZ_CHECK(att_block_decode(enc, &b) == ATT_OK && b.kind == ATT_BLOCK_ADC_ERROR
                       && b.first == fuzz_be16(p) && b.count == 1 && b.status == s8(p[2]));
        }
        return;
    }
}

static void misuse(void)
{
    uint8_t raw[ATT_BLOCK_SIZE] = { 0 };
    uint16_t codes[3] = { 0 };
    att_block b;
    att_block_seq s;
    att_block_span sp;
    att_block_seq_init(NULL);
    att_block_seq_init(&s);
    FUZZ_CHECK(att_block_decode(NULL, &b) == ATT_E_NULL && att_block_decode(raw, NULL) == ATT_E_NULL);
    FUZZ_CHECK(att_block_decode(raw, &b) == ATT_OK);
    FUZZ_CHECK(att_block_seq_feed(NULL, &b, &sp) == ATT_E_NULL
               && att_block_seq_feed(&s, NULL, &sp) == ATT_E_NULL
               && att_block_seq_feed(&s, &b, NULL) == ATT_E_NULL);
    FUZZ_CHECK(att_block_encode_sample(NULL, codes) == ATT_E_NULL
               && att_block_encode_sample(raw, NULL) == ATT_E_NULL);
    FUZZ_CHECK(att_block_encode_boot(NULL, 72, 8) == ATT_E_NULL
               && att_block_encode_selftest(NULL, -1, 0, 1) == ATT_E_NULL);
    FUZZ_CHECK(att_block_encode_loss(NULL, ATT_BLOCK_GAVE_UP, 0, 1) == ATT_E_NULL);
    FUZZ_CHECK(att_block_encode_adc_error(NULL, 0, -1) == ATT_E_NULL);
    FUZZ_CHECK(att_block_encode_channels(NULL, ATT_BLOCK_BOARD_AIDED9, 7, 1, 1) == ATT_E_NULL);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    att_block_seq seq;
    size_t i;
    if (size > 0 && data[0] == 0xA5) {
        misuse();
    }
    att_block_seq_init(&seq);
    FUZZ_CHECK(seq.next == 0 && seq.synced == 0);
    for (i = 0; i + 7 <= size; i += 7) {
        const uint8_t *raw = data + i + 1;
        if ((data[i] & 1) == 0) {
            att_block b, b2;
            att_block_seq seq2 = seq;
            att_block_span sp2;
            uint32_t lim = (uint32_t)seq.oversample * ATT_BLOCK_CODE_MAX;
            int st = att_block_decode(raw, &b), st2;
            check_decoded(raw, &b, st);
            /* the receiver's one call: decode against the stream's limit, then place */
            st2 = att_block_seq_decode(&seq2, raw, &b2, &sp2);
            if (lim > ATT_BLOCK_SUM_MAX) {
                lim = ATT_BLOCK_SUM_MAX;
            }
            if (b.kind == (uint16_t)ATT_BLOCK_SAMPLE) {
                int big = b.code[0] > lim || b.code[1] > lim || b.code[2] > lim;
                FUZZ_CHECK(memcmp(b2.code, b.code, sizeof b.code) == 0 && b2.kind == b.kind);
                FUZZ_CHECK(st2 == (big ? ATT_BLOCK_E_CODE : ATT_OK) && sp2.first + 1 == seq2.next
                           && sp2.count == 1);
                b.kind = (uint16_t)ATT_BLOCK_SAMPLE; /* feed it as a sample, as seq_decode did */
            } else if (st == ATT_BLOCK_E_KIND || st == ATT_BLOCK_E_FIELD) {
                FUZZ_CHECK(st2 == st && same_stream(&seq2, &seq)); /* not placed */
            }
            check_seq(&seq, &b);
            if (st == ATT_OK || b.kind == (uint16_t)ATT_BLOCK_SAMPLE) {
                FUZZ_CHECK(same_stream(&seq2, &seq)); /* the same placement as decode + feed */
            }
        } else {
            check_encode((uint8_t)(data[i] >> 1), raw);
        }
    }
    return 0;
}
