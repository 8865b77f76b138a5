/*
 * Tests of the block format (attitude/block.h): encoders against the bytes
 * the header specifies, the decoder's range checks, round trips, the
 * sequence tracker's loss accounting (slips both ways, late join, BOOT),
 * and aided streams (the CHANNELS report, groups, a group cut short).
 */
#include <string.h>

#include "attitude/attitude.h"
#include "att_test.h"

static int bytes_eq(const uint8_t *a, const uint8_t *b)
{
    return memcmp(a, b, ATT_BLOCK_SIZE) == 0;
}

static void test_encoders_write_the_specified_bytes(void)
{
    uint8_t b[ATT_BLOCK_SIZE];
    uint16_t codes[3] = { 0x123, 0xFFF, 0 };
    static const uint8_t sample[6] = { 0x01, 0x23, 0x0F, 0xFF, 0x00, 0x00 };
    static const uint8_t boot[6] = { 0xFE, 0x00, 0x01, 0x00, 0x48, 0x08 }; /* 72 ticks, 9600 baud */
    static const uint8_t self[6] = { 0xFE, 0x01, 0xD7, 0x0F, 0xFF, 0x03 }; /* -41, 0xFFF, attempt 3 */
    static const uint8_t gave[6] = { 0xFE, 0x02, 0x12, 0x34, 0x00, 0x01 };
    static const uint8_t over[6] = { 0xFE, 0x03, 0xFF, 0xFE, 0x01, 0x00 };
    static const uint8_t adc[6] = { 0xFE, 0x04, 0x00, 0x07, 0xD8, 0x00 }; /* sample 7, -40 */

    CHECK_EQ_INT(att_block_encode_sample(b, codes), ATT_OK);
    CHECK(bytes_eq(b, sample));
    CHECK_EQ_INT(att_block_encode_boot(b, 72, 8), ATT_OK);
    CHECK(bytes_eq(b, boot));
    CHECK_EQ_INT(att_block_encode_selftest(b, -41, 0xFFF, 3), ATT_OK);
    CHECK(bytes_eq(b, self));
    CHECK_EQ_INT(att_block_encode_loss(b, ATT_BLOCK_GAVE_UP, 0x1234, 1), ATT_OK);
    CHECK(bytes_eq(b, gave));
    CHECK_EQ_INT(att_block_encode_loss(b, ATT_BLOCK_OVERRUN, 0xFFFE, 256), ATT_OK);
    CHECK(bytes_eq(b, over));
    CHECK_EQ_INT(att_block_encode_adc_error(b, 7, -40), ATT_OK);
    CHECK(bytes_eq(b, adc));
}

static void test_sample_encodes_in_place(void)
{
    /* the firmware scans native words into the block and converts them there */
    union {
        uint16_t w[3];
        uint8_t b[ATT_BLOCK_SIZE];
    } u;
    static const uint8_t want[6] = { 0x0A, 0xBC, 0x00, 0x01, 0x08, 0x00 };
    u.w[0] = 0xABC;
    u.w[1] = 1;
    u.w[2] = 0x800;
    CHECK_EQ_INT(att_block_encode_sample(u.b, u.w), ATT_OK);
    CHECK(bytes_eq(u.b, want));
}

static void test_encoders_reject_out_of_range(void)
{
    uint8_t b[ATT_BLOCK_SIZE];
    uint16_t codes[3] = { 0, 4096, 0 };
    CHECK_EQ_INT(att_block_encode_sample(b, codes), ATT_BLOCK_E_CODE);
    codes[1] = 0xFE00; /* would read as a report */
    CHECK_EQ_INT(att_block_encode_sample(b, codes), ATT_BLOCK_E_CODE);
    CHECK_EQ_INT(att_block_encode_sample(NULL, codes), ATT_E_NULL);
    CHECK_EQ_INT(att_block_encode_sample(b, NULL), ATT_E_NULL);
    CHECK_EQ_INT(att_block_encode_boot(b, 0, 8), ATT_BLOCK_E_FIELD);
    CHECK_EQ_INT(att_block_encode_boot(b, 32768, 8), ATT_BLOCK_E_FIELD); /* the link v2 flag, period 0 */
    CHECK_EQ_INT(att_block_encode_boot(b, 32767, 8), ATT_OK);
    CHECK_EQ_INT(att_block_encode_boot(b, 1, 0), ATT_BLOCK_E_FIELD);
    CHECK_EQ_INT(att_block_encode_boot(NULL, 72, 8), ATT_E_NULL);
    CHECK_EQ_INT(att_block_encode_selftest(b, 0, 0, 1), ATT_BLOCK_E_FIELD);
    CHECK_EQ_INT(att_block_encode_selftest(b, -1, 4096, 1), ATT_BLOCK_E_FIELD);
    CHECK_EQ_INT(att_block_encode_selftest(NULL, -1, 0, 1), ATT_E_NULL);
    CHECK_EQ_INT(att_block_encode_loss(b, ATT_BLOCK_ADC_ERROR, 0, 1), ATT_BLOCK_E_KIND);
    CHECK_EQ_INT(att_block_encode_loss(b, ATT_BLOCK_BOOT, 0, 1), ATT_BLOCK_E_KIND);
    CHECK_EQ_INT(att_block_encode_loss(b, ATT_BLOCK_OVERRUN, 0, 0), ATT_BLOCK_E_FIELD);
    CHECK_EQ_INT(att_block_encode_loss(NULL, ATT_BLOCK_OVERRUN, 0, 1), ATT_E_NULL);
    CHECK_EQ_INT(att_block_encode_adc_error(b, 0, 0), ATT_BLOCK_E_FIELD);
    CHECK_EQ_INT(att_block_encode_adc_error(NULL, 0, -40), ATT_E_NULL);
}

static void test_decoder_reads_every_kind(void)
{
    att_block d;
    static const uint8_t sample[6] = { 0x0F, 0xFF, 0x00, 0x00, 0x08, 0x01 };
    static const uint8_t boot[6] = { 0xFE, 0x00, 0x01, 0x00, 0xD8, 0x30 };
    static const uint8_t self[6] = { 0xFE, 0x01, 0xD8, 0x00, 0x00, 0xFF };
    static const uint8_t over[6] = { 0xFE, 0x03, 0x00, 0x02, 0x00, 0x03 };
    static const uint8_t adc[6] = { 0xFE, 0x04, 0xFF, 0xFF, 0x9C, 0x00 };

    CHECK_EQ_INT(att_block_decode(sample, &d), ATT_OK);
    CHECK_EQ_INT(d.kind, ATT_BLOCK_SAMPLE);
    CHECK_EQ_INT(d.code[0], 4095);
    CHECK_EQ_INT(d.code[1], 0);
    CHECK_EQ_INT(d.code[2], 0x801);
    CHECK_EQ_INT(att_block_decode(boot, &d), ATT_OK);
    CHECK_EQ_INT(d.kind, ATT_BLOCK_BOOT);
    CHECK_EQ_INT(d.version, 1);
    CHECK_EQ_INT(d.period_ticks, 216);
    CHECK_EQ_INT(d.baud_div, 48); /* 57600 baud */
    CHECK_EQ_INT(d.code[0], 0);   /* fields of other kinds are 0 */
    CHECK_EQ_INT(att_block_decode(self, &d), ATT_OK);
    CHECK_EQ_INT(d.kind, ATT_BLOCK_SELFTEST);
    CHECK_EQ_INT(d.status, -40);
    CHECK_EQ_INT(d.bad_code, 0);
    CHECK_EQ_INT(d.attempt, 255);
    CHECK_EQ_INT(att_block_decode(over, &d), ATT_OK);
    CHECK_EQ_INT(d.kind, ATT_BLOCK_OVERRUN);
    CHECK_EQ_INT(d.first, 2);
    CHECK_EQ_INT(d.count, 3);
    CHECK_EQ_INT(att_block_decode(adc, &d), ATT_OK);
    CHECK_EQ_INT(d.kind, ATT_BLOCK_ADC_ERROR);
    CHECK_EQ_INT(d.first, 65535);
    CHECK_EQ_INT(d.count, 1);
    CHECK_EQ_INT(d.status, -100);
}

static void test_decoder_rejects(void)
{
    att_block d;
    uint8_t r[6] = { 0x10, 0x00, 0x00, 0x00, 0x00, 0x00 };
    unsigned v;
    CHECK_EQ_INT(att_block_decode(r, &d), ATT_BLOCK_E_CODE);
    CHECK_EQ_INT(d.kind, ATT_BLOCK_SAMPLE); /* the codes are kept for a log */
    CHECK_EQ_INT(d.code[0], 4096);
    /* every first word: 0..4095 is a sample, 0xFExx a report, the rest a bad code */
    r[0] = r[1] = 0;
    for (v = 0; v <= 0xFFFFu; v++) {
        int st;
        r[4] = (uint8_t)(v >> 8);
        r[5] = (uint8_t)v;
        st = att_block_decode(r, &d);
        if (st != (v <= 4095u ? ATT_OK : ATT_BLOCK_E_CODE)) {
            CHECK_EQ_INT(v, -1);
            break;
        }
    }
    CHECK_EQ_INT(v, 0x10000L);
    r[0] = 0xFE;
    r[1] = 7; /* no such kind */
    CHECK_EQ_INT(att_block_decode(r, &d), ATT_BLOCK_E_KIND);
    CHECK_EQ_INT(d.kind, 7);
    r[1] = 0xFF;
    CHECK_EQ_INT(att_block_decode(r, &d), ATT_BLOCK_E_KIND);
    CHECK(d.kind != ATT_BLOCK_SAMPLE);
    {
        static const uint8_t bad[][6] = {
            { 0xFE, 0x00, 0x02, 0x00, 0x48, 0x08 }, /* BOOT of another format version */
            { 0xFE, 0x00, 0x01, 0x00, 0x00, 0x08 }, /* period 0 */
            { 0xFE, 0x00, 0x01, 0x80, 0x00, 0x08 }, /* period 0 of a link v2 board */
            { 0xFE, 0x00, 0x01, 0x00, 0x48, 0x00 }, /* baud 0 */
            { 0xFE, 0x01, 0x00, 0x00, 0x00, 0x01 }, /* self-test status 0 */
            { 0xFE, 0x01, 0xD7, 0x10, 0x00, 0x01 }, /* bad code 4096 */
            { 0xFE, 0x02, 0x00, 0x05, 0x00, 0x00 }, /* gave up on 0 samples */
            { 0xFE, 0x03, 0x00, 0x05, 0x00, 0x00 }, /* overrun of 0 samples */
            { 0xFE, 0x04, 0x00, 0x05, 0x05, 0x00 }, /* ADC error status 5 */
            { 0xFE, 0x04, 0x00, 0x05, 0xD8, 0x01 }, /* ADC error, last byte not 0 */
            { 0xFE, 0x05, 0x00, 0x00, 0x00, 0x00 }, /* oversample 0 */
            { 0xFE, 0x05, 0x11, 0x00, 0x00, 0x00 }, /* oversample 17 */
            { 0xFE, 0x05, 0x10, 0x00, 0x01, 0x00 }, /* oversample, a padding byte not 0 */
        };
        size_t i;
        for (i = 0; i < sizeof bad / sizeof bad[0]; i++) {
            CHECK_EQ_INT(att_block_decode(bad[i], &d), ATT_BLOCK_E_FIELD);
            CHECK_EQ_INT(d.kind, bad[i][1]);
        }
    }
    CHECK_EQ_INT(att_block_decode(NULL, &d), ATT_E_NULL);
    CHECK_EQ_INT(att_block_decode(r, NULL), ATT_E_NULL);
}

static void test_round_trips(void)
{
    uint8_t b[ATT_BLOCK_SIZE];
    att_block d;
    uint16_t c[3];
    unsigned v;
    int s;
    for (v = 0; v <= 4095u; v += 13u) {
        c[0] = (uint16_t)v;
        c[1] = (uint16_t)(4095u - v);
        c[2] = (uint16_t)((v * 7u) & 4095u);
        CHECK_EQ_INT(att_block_encode_sample(b, c), ATT_OK);
        CHECK_EQ_INT(att_block_decode(b, &d), ATT_OK);
        CHECK(d.kind == ATT_BLOCK_SAMPLE && d.code[0] == c[0] && d.code[1] == c[1] && d.code[2] == c[2]);
    }
    for (s = -128; s <= -1; s++) {
        CHECK_EQ_INT(att_block_encode_adc_error(b, (uint16_t)(s + 200), (int8_t)s), ATT_OK);
        CHECK_EQ_INT(att_block_decode(b, &d), ATT_OK);
        CHECK(d.kind == ATT_BLOCK_ADC_ERROR && d.status == s && d.first == s + 200 && d.count == 1);
        CHECK_EQ_INT(att_block_encode_selftest(b, (int8_t)s, 4095, (uint8_t)-s), ATT_OK);
        CHECK_EQ_INT(att_block_decode(b, &d), ATT_OK);
        CHECK(d.kind == ATT_BLOCK_SELFTEST && d.status == s && d.bad_code == 4095 && d.attempt == -s);
    }
    CHECK_EQ_INT(att_block_encode_boot(b, 32767, 255), ATT_OK);
    CHECK_EQ_INT(att_block_decode(b, &d), ATT_OK);
    CHECK(d.kind == ATT_BLOCK_BOOT && d.period_ticks == 32767 && d.baud_div == 255 && d.version == 1);
    CHECK_EQ_INT(d.link, 0);
    { /* a link v2 board: the top bit of the period word (docs/block.md), by hand */
        static const uint8_t boot2[6] = { 0xFE, 0x00, 0x01, 0x80, 0x48, 0x08 };
        CHECK_EQ_INT(att_block_encode_boot(b, (uint16_t)(72u | ATT_BLOCK_BOOT_LINK2), 8), ATT_OK);
        CHECK(memcmp(b, boot2, 6) == 0);
        CHECK_EQ_INT(att_block_decode(boot2, &d), ATT_OK);
        CHECK(d.kind == ATT_BLOCK_BOOT && d.period_ticks == 72 && d.link == 2 && d.baud_div == 8);
        CHECK_EQ_INT(att_block_encode_boot(b, (uint16_t)ATT_BLOCK_BOOT_LINK2, 8),
                     ATT_BLOCK_E_FIELD); /* period 0 */
    }
    CHECK_EQ_INT(att_block_encode_loss(b, ATT_BLOCK_GAVE_UP, 65535, 65535), ATT_OK);
    CHECK_EQ_INT(att_block_decode(b, &d), ATT_OK);
    CHECK(d.kind == ATT_BLOCK_GAVE_UP && d.first == 65535 && d.count == 65535);
}

/* Feed one record (bytes) to the tracker. */
static int feed(att_block_seq *t, const uint8_t *raw, att_block_span *sp)
{
    att_block d;
    (void)att_block_decode(raw, &d);
    return att_block_seq_feed(t, &d, sp);
}

static void test_tracker_numbers_across_losses(void)
{
    att_block_seq t;
    att_block_span sp;
    uint8_t boot[6], smp[6], loss[6];
    uint16_t c[3] = { 1, 2, 3 };
    int i;
    att_block_seq_init(&t);
    att_block_encode_boot(boot, 72, 8);
    att_block_encode_sample(smp, c);
    CHECK_EQ_INT(feed(&t, boot, &sp), ATT_OK);
    CHECK(sp.first == 0 && sp.count == 0 && sp.slip == 0);
    for (i = 0; i < 3; i++) {
        CHECK_EQ_INT(feed(&t, smp, &sp), ATT_OK);
        CHECK(sp.first == (uint32_t)i && sp.count == 1);
    }
    att_block_encode_loss(loss, ATT_BLOCK_OVERRUN, 3, 4); /* 3..6 lost */
    CHECK_EQ_INT(feed(&t, loss, &sp), ATT_OK);
    CHECK(sp.first == 3 && sp.count == 4 && sp.slip == 0);
    att_block_encode_adc_error(loss, 7, -40);
    CHECK_EQ_INT(feed(&t, loss, &sp), ATT_OK);
    CHECK(sp.first == 7 && sp.count == 1);
    CHECK_EQ_INT(feed(&t, smp, &sp), ATT_OK);
    CHECK_EQ_INT(sp.first, 8);
    /* a gap nobody reported (a whole block lost): the loss report shows it */
    CHECK_EQ_INT(feed(&t, smp, &sp), ATT_OK); /* 9 */
    att_block_encode_loss(loss, ATT_BLOCK_GAVE_UP, 12, 1);
    CHECK_EQ_INT(feed(&t, loss, &sp), ATT_BLOCK_E_SEQ);
    CHECK(sp.first == 10 && sp.count == 3 && sp.slip == 2); /* 10, 11 unreported + 12 */
    CHECK_EQ_INT(feed(&t, smp, &sp), ATT_OK);
    CHECK_EQ_INT(sp.first, 13);
    /* a duplicate (B's 0x00 lost, A resent): numbered one too many */
    CHECK_EQ_INT(feed(&t, smp, &sp), ATT_OK); /* 14, in truth a copy of 13 */
    att_block_encode_loss(loss, ATT_BLOCK_GAVE_UP, 14, 1);
    CHECK_EQ_INT(feed(&t, loss, &sp), ATT_BLOCK_E_SEQ);
    CHECK(sp.first == 14 && sp.count == 1 && sp.slip == -1);
    CHECK_EQ_INT(feed(&t, smp, &sp), ATT_OK);
    CHECK_EQ_INT(sp.first, 15);
    /* a reboot restarts the numbering */
    CHECK_EQ_INT(feed(&t, boot, &sp), ATT_OK);
    CHECK_EQ_INT(feed(&t, smp, &sp), ATT_OK);
    CHECK_EQ_INT(sp.first, 0);
}

static void test_tracker_wraps_and_late_join(void)
{
    att_block_seq t;
    att_block_span sp;
    att_block d;
    uint8_t smp[6], loss[6];
    uint16_t c[3] = { 1, 2, 3 };
    uint32_t i;
    att_block_encode_sample(smp, c);
    /* joined after BOOT: the first loss report's numbering is adopted */
    att_block_seq_init(&t);
    CHECK_EQ_INT(feed(&t, smp, &sp), ATT_OK);
    CHECK_EQ_INT(sp.first, 0);
    att_block_encode_loss(loss, ATT_BLOCK_OVERRUN, 40000, 2);
    CHECK_EQ_INT(feed(&t, loss, &sp), ATT_OK);
    CHECK(sp.first == 40000 && sp.count == 2 && sp.slip == 0);
    CHECK_EQ_INT(t.next, 40002);
    /* report numbers wrap at 2^16; the tracker's do not */
    for (i = 40002; i < 70000u; i++) {
        (void)feed(&t, smp, &sp);
    }
    att_block_encode_loss(loss, ATT_BLOCK_GAVE_UP, (uint16_t)70000u, 1);
    CHECK_EQ_INT(feed(&t, loss, &sp), ATT_OK);
    CHECK(sp.first == 70000u && sp.count == 1 && sp.slip == 0);
    /* SELFTEST takes no number, an unknown kind or a count of 0 changes nothing */
    d.kind = 7;
    CHECK_EQ_INT(att_block_seq_feed(&t, &d, &sp), ATT_BLOCK_E_KIND);
    (void)att_block_decode(loss, &d);
    d.count = 0;
    CHECK_EQ_INT(att_block_seq_feed(&t, &d, &sp), ATT_BLOCK_E_FIELD);
    CHECK_EQ_INT(t.next, 70001u);
    att_block_encode_selftest(loss, -41, 0, 1);
    CHECK_EQ_INT(feed(&t, loss, &sp), ATT_OK);
    CHECK(sp.count == 0 && t.next == 70001u);
    /* a sample with a bad code still takes its number */
    smp[0] = 0x10;
    CHECK_EQ_INT(feed(&t, smp, &sp), ATT_OK);
    CHECK(sp.first == 70001u && sp.count == 1);
    CHECK_EQ_INT(att_block_seq_feed(NULL, &d, &sp), ATT_E_NULL);
    CHECK_EQ_INT(att_block_seq_feed(&t, NULL, &sp), ATT_E_NULL);
    CHECK_EQ_INT(att_block_seq_feed(&t, &d, NULL), ATT_E_NULL);
}

/* Oversampled streams: the OVERSAMPLE report, sample records of sums, and
 * the tracker's per-stream limit (block.h, "Oversampled streams"). */
static void test_oversampled_streams(void)
{
    uint8_t b[ATT_BLOCK_SIZE], raw[ATT_BLOCK_SIZE];
    static const uint8_t over16[6] = { 0xFE, 0x05, 0x10, 0x00, 0x00, 0x00 };
    static const uint8_t sums[6] = { 0x80, 0x00, 0xFD, 0xFF, 0x00, 0x00 };
    uint16_t w[3] = { 0x8000, 0xFDFF, 0 };
    uint16_t plain[3] = { 0x123, 0xFFF, 0 };
    att_block d;
    att_block_seq s;
    att_block_span span;
    unsigned n;

    CHECK_EQ_INT(att_block_encode_oversample(b, 16), ATT_OK);
    CHECK(bytes_eq(b, over16));
    CHECK_EQ_INT(att_block_decode(b, &d), ATT_OK);
    CHECK_EQ_INT(d.kind, ATT_BLOCK_OVERSAMPLE);
    CHECK_EQ_INT(d.oversample, 16);
    CHECK_EQ_INT(att_block_encode_oversample(b, 0), ATT_BLOCK_E_FIELD);
    CHECK_EQ_INT(att_block_encode_oversample(b, 17), ATT_BLOCK_E_FIELD);
    CHECK_EQ_INT(att_block_encode_oversample(NULL, 1), ATT_E_NULL);

    CHECK_EQ_INT(att_block_encode_sums(b, w, 16), ATT_OK);
    CHECK(bytes_eq(b, sums));
    w[1] = 0xFE00; /* byte 0 would read as the report mark */
    CHECK_EQ_INT(att_block_encode_sums(b, w, 16), ATT_BLOCK_E_CODE);
    CHECK(bytes_eq(b, sums)); /* checked before writing */
    w[1] = 2u * 4095u + 1u;
    CHECK_EQ_INT(att_block_encode_sums(b, w, 2), ATT_BLOCK_E_CODE);
    w[1] = 2u * 4095u;
    CHECK_EQ_INT(att_block_encode_sums(b, w, 2), ATT_BLOCK_E_CODE); /* w[0] = 0x8000 > 8190 */
    CHECK_EQ_INT(att_block_encode_sums(b, w, 0), ATT_BLOCK_E_FIELD);
    CHECK_EQ_INT(att_block_encode_sums(b, NULL, 1), ATT_E_NULL);
    /* n = 1 is the plain sample record */
    CHECK_EQ_INT(att_block_encode_sums(raw, plain, 1), ATT_OK);
    CHECK_EQ_INT(att_block_encode_sample(b, plain), ATT_OK);
    CHECK(bytes_eq(b, raw));

    /* the limit of every n: n x 4095, capped at 0xFDFF (n = 16 only) */
    for (n = 1; n <= ATT_BLOCK_OVERSAMPLE_MAX; n++) {
        uint32_t lim = n * 4095u < 0xFDFFu ? n * 4095u : 0xFDFFu;
        uint16_t top[3], over[3];
        top[0] = top[1] = top[2] = (uint16_t)lim;
        over[0] = over[1] = 0;
        over[2] = (uint16_t)(lim + 1u);
        att_block_seq_init(&s);
        att_block_encode_boot(raw, 72, 8);
        CHECK_EQ_INT(att_block_seq_decode(&s, raw, &d, &span), ATT_OK);
        att_block_encode_oversample(raw, (uint8_t)n);
        CHECK_EQ_INT(att_block_seq_decode(&s, raw, &d, &span), ATT_OK);
        CHECK_EQ_INT(span.count, 0);
        CHECK_EQ_INT(s.oversample, n);
        CHECK_EQ_INT(att_block_encode_sums(raw, top, (uint8_t)n), ATT_OK);
        CHECK_EQ_INT(att_block_seq_decode(&s, raw, &d, &span), ATT_OK);
        CHECK_EQ_INT(d.code[2], lim);
        CHECK_EQ_INT(span.first, 0);
        CHECK_EQ_INT(att_block_encode_sums(raw, over, (uint8_t)n), ATT_BLOCK_E_CODE);
        raw[4] = (uint8_t)(over[2] >> 8); /* written by hand: the encoder refuses it */
        raw[5] = (uint8_t)over[2];
        raw[0] = raw[1] = raw[2] = raw[3] = 0;
        CHECK_EQ_INT(att_block_seq_decode(&s, raw, &d, &span), ATT_BLOCK_E_CODE);
        CHECK_EQ_INT(span.first, 1); /* a bad sample still takes its number */
        CHECK_EQ_INT(d.code[2], lim + 1u);
    }

    /* a BOOT makes the stream plain again; a zeroed tracker is plain */
    att_block_encode_boot(raw, 72, 8);
    CHECK_EQ_INT(att_block_seq_decode(&s, raw, &d, &span), ATT_OK);
    CHECK_EQ_INT(s.oversample, 1);
    w[0] = 4096;
    w[1] = w[2] = 0;
    att_block_encode_sums(raw, w, 2);
    CHECK_EQ_INT(att_block_seq_decode(&s, raw, &d, &span), ATT_BLOCK_E_CODE);
    memset(&s, 0, sizeof s);
    CHECK_EQ_INT(att_block_seq_decode(&s, raw, &d, &span), ATT_BLOCK_E_CODE);
    w[0] = 4095;
    att_block_encode_sums(raw, w, 1);
    CHECK_EQ_INT(att_block_seq_decode(&s, raw, &d, &span), ATT_OK);

    /* records with no place: the stream is unchanged */
    att_block_seq_init(&s);
    CHECK_EQ_INT(att_block_seq_decode(&s, over16, &d, &span), ATT_OK);
    raw[0] = 0xFE;
    raw[1] = 0x05;
    raw[2] = 0x00; /* oversample 0 */
    raw[3] = raw[4] = raw[5] = 0;
    CHECK_EQ_INT(att_block_seq_decode(&s, raw, &d, &span), ATT_BLOCK_E_FIELD);
    raw[1] = 0x09;
    CHECK_EQ_INT(att_block_seq_decode(&s, raw, &d, &span), ATT_BLOCK_E_KIND);
    CHECK_EQ_INT(s.oversample, 16);
    CHECK_EQ_INT(s.next, 0);
    /* a loss report after a slip: E_SEQ as att_block_seq_feed says */
    att_block_encode_sums(raw, w, 16);
    CHECK_EQ_INT(att_block_seq_decode(&s, raw, &d, &span), ATT_OK);
    att_block_encode_boot(raw, 72, 8);
    CHECK_EQ_INT(att_block_seq_decode(&s, raw, &d, &span), ATT_OK);
    att_block_encode_loss(raw, ATT_BLOCK_OVERRUN, 3, 1);
    CHECK_EQ_INT(att_block_seq_decode(&s, raw, &d, &span), ATT_BLOCK_E_SEQ);
    CHECK_EQ_INT(span.slip, 3);
    CHECK_EQ_INT(att_block_seq_decode(NULL, raw, &d, &span), ATT_E_NULL);
    CHECK_EQ_INT(att_block_seq_decode(&s, NULL, &d, &span), ATT_E_NULL);
    CHECK_EQ_INT(att_block_seq_decode(&s, raw, NULL, &span), ATT_E_NULL);
    CHECK_EQ_INT(att_block_seq_decode(&s, raw, &d, NULL), ATT_E_NULL);
}

/* CHANNELS' rule, read from block.h's field list by hand: the second opinion. */
static int channels_valid(unsigned board, unsigned ch, unsigned acc, unsigned mag)
{
    int gyro_only = ch == 1u;
    return (board == 2u || (board == 1u && gyro_only)) && (ch & 1u) != 0u && ch <= 7u
           && ((ch & 2u) != 0u) == (acc != 0u) && ((ch & 4u) != 0u) == (mag != 0u);
}

static void test_channels_report(void)
{
    uint8_t b[ATT_BLOCK_SIZE];
    static const uint8_t aided[6] = { 0xFE, 0x06, 0x02, 0x07, 0x01, 0x04 }; /* AIDED9, all, 1, 4 */
    static const uint8_t gyro3[6] = { 0xFE, 0x06, 0x01, 0x01, 0x00, 0x00 };
    static const uint8_t everies[] = { 0, 1, 2, 255 };
    att_block d;
    unsigned board, ch, i, j;

    CHECK_EQ_INT(ATT_BLOCK_CHANNELS, 6);
    CHECK_EQ_INT(att_block_encode_channels(b, ATT_BLOCK_BOARD_AIDED9, 7, 1, 4), ATT_OK);
    CHECK(bytes_eq(b, aided));
    CHECK_EQ_INT(att_block_decode(aided, &d), ATT_OK);
    CHECK(d.kind == ATT_BLOCK_CHANNELS && d.board == 2 && d.channels == 7 && d.acc_every == 1
          && d.mag_every == 4);
    CHECK(d.code[0] == 0 && d.first == 0 && d.oversample == 0); /* fields of other kinds are 0 */
    CHECK_EQ_INT(att_block_encode_channels(b, ATT_BLOCK_BOARD_GYRO3, ATT_BLOCK_CH_GYR, 0, 0), ATT_OK);
    CHECK(bytes_eq(b, gyro3));
    CHECK_EQ_INT(att_block_encode_channels(NULL, 2, 7, 1, 1), ATT_E_NULL);
    /* every board and set with decimations at both ends: encoder and decoder both follow the rule */
    for (board = 0; board < 4u; board++) {
        for (ch = 0; ch < 16u; ch++) {
            for (i = 0; i < sizeof everies; i++) {
                for (j = 0; j < sizeof everies; j++) {
                    int want = channels_valid(board, ch, everies[i], everies[j]) ? ATT_OK : ATT_BLOCK_E_FIELD;
                    uint8_t raw[6] = { 0xFE, 0x06, 0, 0, 0, 0 };
                    raw[2] = (uint8_t)board;
                    raw[3] = (uint8_t)ch;
                    raw[4] = everies[i];
                    raw[5] = everies[j];
                    if (att_block_encode_channels(b, raw[2], raw[3], raw[4], raw[5]) != want
                        || att_block_decode(raw, &d) != want || d.kind != ATT_BLOCK_CHANNELS
                        || d.board != board || d.channels != ch || d.acc_every != raw[4]
                        || d.mag_every != raw[5] || (want == ATT_OK && !bytes_eq(b, raw))) {
                        CHECK_EQ_INT(board * 1000000u + ch * 10000u + i * 100u + j, -1);
                        return;
                    }
                }
            }
        }
    }
}

/* Feed the records of sample n of an aided stream (acc every 2, mag every 4)
 * and check each one's place; returns the records fed. */
static int feed_group(att_block_seq *t, uint32_t n)
{
    static const uint16_t c[3] = { 100, 200, 300 };
    uint8_t smp[ATT_BLOCK_SIZE];
    att_block_span sp;
    int fed = 0;
    att_block_encode_sample(smp, c);
    CHECK_EQ_INT(feed(t, smp, &sp), ATT_OK);
    CHECK(sp.first == n && sp.count == 1 && sp.part == ATT_BLOCK_PART_GYR && sp.slip == 0);
    fed++;
    if (n % 2u == 0u) {
        CHECK_EQ_INT(t->part, ATT_BLOCK_PART_ACC);
        CHECK_EQ_INT(feed(t, smp, &sp), ATT_OK);
        CHECK(sp.first == n && sp.count == 1 && sp.part == ATT_BLOCK_PART_ACC);
        fed++;
    }
    if (n % 4u == 0u) {
        CHECK_EQ_INT(t->part, ATT_BLOCK_PART_MAG);
        CHECK_EQ_INT(feed(t, smp, &sp), ATT_OK);
        CHECK(sp.first == n && sp.count == 1 && sp.part == ATT_BLOCK_PART_MAG);
        fed++;
    }
    CHECK_EQ_INT(t->part, ATT_BLOCK_PART_GYR); /* the group is complete */
    CHECK_EQ_INT(t->next, n + 1u);
    return fed;
}

static void test_tracker_numbers_aided_groups(void)
{
    att_block_seq t;
    att_block_span sp;
    uint8_t raw[ATT_BLOCK_SIZE];
    uint16_t c[3] = { 1, 2, 3 };
    uint32_t n;
    int records = 0;
    att_block_seq_init(&t);
    CHECK(t.channels == ATT_BLOCK_CH_GYR && t.part == ATT_BLOCK_PART_GYR);
    att_block_encode_boot(raw, 72, 48);
    CHECK_EQ_INT(feed(&t, raw, &sp), ATT_OK);
    att_block_encode_channels(raw, ATT_BLOCK_BOARD_AIDED9, 7, 2, 4);
    CHECK_EQ_INT(feed(&t, raw, &sp), ATT_OK);
    CHECK(sp.first == 0 && sp.count == 0 && sp.part == ATT_BLOCK_PART_GYR);
    CHECK(t.channels == 7 && t.acc_every == 2 && t.mag_every == 4 && t.next == 0);
    for (n = 0; n < 12u; n++) {
        records += feed_group(&t, n);
    }
    CHECK_EQ_INT(records, 12 + 6 + 3); /* 12 gyro, 6 accelerometer, 3 magnetometer records */
    /* losses count whole samples */
    att_block_encode_loss(raw, ATT_BLOCK_OVERRUN, 12, 2);
    CHECK_EQ_INT(feed(&t, raw, &sp), ATT_OK);
    CHECK(sp.first == 12 && sp.count == 2 && sp.part == ATT_BLOCK_PART_GYR);
    (void)feed_group(&t, 14);
    /* sample 15 has no acc/mag; 16's group is cut after its gyro record (acc, mag lost) */
    (void)feed_group(&t, 15);
    att_block_encode_sample(raw, c);
    CHECK_EQ_INT(feed(&t, raw, &sp), ATT_OK);
    CHECK(sp.first == 16 && t.part == ATT_BLOCK_PART_ACC);
    att_block_encode_loss(raw, ATT_BLOCK_GAVE_UP, 17, 1);
    CHECK_EQ_INT(feed(&t, raw, &sp), ATT_BLOCK_E_SEQ);
    CHECK(sp.first == 17 && sp.count == 1 && sp.slip == 0 && sp.part == ATT_BLOCK_PART_ACC);
    CHECK(t.next == 18 && t.part == ATT_BLOCK_PART_GYR);
    (void)feed_group(&t, 18);
    /* 20's group cut after its accelerometer record: the magnetometer's was due */
    att_block_encode_sample(raw, c);
    (void)feed_group(&t, 19);
    CHECK_EQ_INT(feed(&t, raw, &sp), ATT_OK);
    CHECK_EQ_INT(feed(&t, raw, &sp), ATT_OK);
    CHECK(sp.first == 20 && sp.part == ATT_BLOCK_PART_ACC && t.part == ATT_BLOCK_PART_MAG);
    att_block_encode_adc_error(raw, 23, -40); /* and 21, 22 vanished: a slip as well */
    CHECK_EQ_INT(feed(&t, raw, &sp), ATT_BLOCK_E_SEQ);
    CHECK(sp.first == 21 && sp.count == 3 && sp.slip == 2 && sp.part == ATT_BLOCK_PART_MAG);
    (void)feed_group(&t, 24);
    /* a rejected CHANNELS changes nothing; a BOOT makes the stream gyro-only again */
    raw[0] = 0xFE;
    raw[1] = 0x06;
    raw[2] = 0x02;
    raw[3] = 0x03;
    raw[4] = 0x00; /* ACC with acc_every 0 */
    raw[5] = 0x00;
    CHECK_EQ_INT(att_block_seq_decode(&t, raw, NULL, &sp), ATT_E_NULL);
    {
        att_block d;
        CHECK_EQ_INT(att_block_seq_decode(&t, raw, &d, &sp), ATT_BLOCK_E_FIELD);
        CHECK_EQ_INT(att_block_seq_feed(&t, &d, &sp), ATT_BLOCK_E_FIELD);
    }
    CHECK(t.channels == 7 && t.acc_every == 2 && t.next == 25);
    att_block_encode_sample(raw, c);
    CHECK_EQ_INT(feed(&t, raw, &sp), ATT_OK); /* gyro of 25 */
    att_block_encode_boot(raw, 72, 48);
    CHECK_EQ_INT(feed(&t, raw, &sp), ATT_OK); /* a reboot, not a cut group */
    CHECK(t.channels == ATT_BLOCK_CH_GYR && t.acc_every == 0 && t.mag_every == 0
          && t.part == ATT_BLOCK_PART_GYR);
    att_block_encode_sample(raw, c);
    for (n = 0; n < 3u; n++) {
        CHECK_EQ_INT(feed(&t, raw, &sp), ATT_OK);
        CHECK(sp.first == n && sp.part == ATT_BLOCK_PART_GYR);
    }
}

/* An oversampled aided stream: OVERSAMPLE then CHANNELS after BOOT; every
 * record of a group has the stream's limit; a zeroed tracker is gyro-only. */
static void test_oversampled_aided_stream(void)
{
    att_block_seq t;
    att_block_span sp;
    att_block d;
    uint8_t raw[ATT_BLOCK_SIZE];
    uint16_t w[3] = { 4u * 4095u, 0, 1 };
    att_block_seq_init(&t);
    att_block_encode_boot(raw, 36, 96);
    CHECK_EQ_INT(att_block_seq_decode(&t, raw, &d, &sp), ATT_OK);
    att_block_encode_oversample(raw, 4);
    CHECK_EQ_INT(att_block_seq_decode(&t, raw, &d, &sp), ATT_OK);
    att_block_encode_channels(raw, ATT_BLOCK_BOARD_AIDED9, ATT_BLOCK_CH_GYR | ATT_BLOCK_CH_ACC, 1, 0);
    CHECK_EQ_INT(att_block_seq_decode(&t, raw, &d, &sp), ATT_OK);
    att_block_encode_sums(raw, w, 4);
    CHECK_EQ_INT(att_block_seq_decode(&t, raw, &d, &sp), ATT_OK);
    CHECK(sp.first == 0 && sp.part == ATT_BLOCK_PART_GYR);
    CHECK_EQ_INT(att_block_seq_decode(&t, raw, &d, &sp), ATT_OK);
    CHECK(sp.first == 0 && sp.part == ATT_BLOCK_PART_ACC && d.code[0] == 4u * 4095u);
    CHECK_EQ_INT(att_block_seq_decode(&t, raw, &d, &sp), ATT_OK); /* gyro of sample 1 */
    raw[0] = 0x40; /* 0x40FC > 4 x 4095 in the accelerometer record of sample 1 */
    CHECK_EQ_INT(att_block_seq_decode(&t, raw, &d, &sp), ATT_BLOCK_E_CODE);
    CHECK(sp.first == 1 && sp.part == ATT_BLOCK_PART_ACC && t.part == ATT_BLOCK_PART_GYR);
    memset(&t, 0, sizeof t); /* zeroed: gyro-only */
    CHECK_EQ_INT(att_block_seq_decode(&t, raw, &d, &sp), ATT_BLOCK_E_CODE);
    CHECK(sp.part == ATT_BLOCK_PART_GYR && t.part == ATT_BLOCK_PART_GYR && t.next == 1);
}

int main(void)
{
    test_encoders_write_the_specified_bytes();
    test_sample_encodes_in_place();
    test_encoders_reject_out_of_range();
    test_decoder_reads_every_kind();
    test_decoder_rejects();
    test_round_trips();
    test_tracker_numbers_across_losses();
    test_tracker_wraps_and_late_join();
    test_oversampled_streams();
    test_channels_report();
    test_tracker_numbers_aided_groups();
    test_oversampled_aided_stream();
    return ATT_TEST_REPORT();
}
