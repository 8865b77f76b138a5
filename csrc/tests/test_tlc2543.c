/*
 * TLC2543 driver against the C twin of the device model (csrc/host/).
 * Every check also requires that the model saw no protocol violation.
 */
#include "att_test.h"
#include "attitude/tlc2543.h"
#include "tlc2543_model.h"

static tlc2543m model;
static tlc2543 adc;
static tlc2543m_event trace[4096];

static void setup(const tlc2543_settings *s)
{
    CHECK_EQ_INT(tlc2543m_init(&model, 5.0, 0.0, 0xA5Au), ATT_OK);
    CHECK_EQ_INT(tlc2543_init(&adc, &model.hal, s), ATT_OK);
}

/* Expected word for a 12-bit unipolar code in a mode (natural order). */
static long expect_word(uint16_t code, const tlc2543_settings *s)
{
    uint16_t c = s->bipolar ? (uint16_t)(code ^ 0x800u) : code;
    long w = (s->length == TLC2543_LEN_8) ? (c >> 4) : (s->length == TLC2543_LEN_16) ? ((long)c << 4) : c;
    int nbits = (s->length == TLC2543_LEN_8) ? 8 : (s->length == TLC2543_LEN_16) ? 16 : 12;
    if (s->bipolar && (w & (1L << (nbits - 1)))) {
        w -= 1L << nbits;
    }
    return w;
}

static void test_self_test_and_scan(void)
{
    static const uint8_t xyz[3] = { TLC2543_CH_X, TLC2543_CH_Y, TLC2543_CH_Z };
    uint16_t codes[3], st_codes[3];
    double v[3] = { 0.0, 2.5, 5.0 };
    uint32_t conv0;

    setup(0);
    CHECK_EQ_INT(tlc2543_self_test_codes(&adc, st_codes), ATT_OK);
    CHECK_EQ_INT(st_codes[0], 0x800);
    CHECK_EQ_INT(st_codes[1], 0x000);
    CHECK_EQ_INT(st_codes[2], 0xFFF);

    CHECK_EQ_INT(tlc2543m_set_inputs(&model, v, 3), ATT_OK);
    conv0 = model.conversions;
    CHECK_EQ_INT(tlc2543_scan(&adc, xyz, 3, codes, TLC2543_CH_X), ATT_OK);
    CHECK_EQ_INT(model.conversions - conv0, 4); /* first scan: 4 cycles */
    CHECK_EQ_INT(codes[0], 0);
    CHECK_EQ_INT(codes[1], 2048);
    CHECK_EQ_INT(codes[2], 4095);

    /* steady state: 3 cycles; X was converted at the end of the last scan */
    conv0 = model.conversions;
    CHECK_EQ_INT(tlc2543_scan(&adc, xyz, 3, codes, TLC2543_CH_X), ATT_OK);
    CHECK_EQ_INT(model.conversions - conv0, 3);
    CHECK_EQ_INT(codes[0], 0);
    CHECK_EQ_INT(codes[2], 4095);
    CHECK_EQ_INT(model.violation, TLC2543M_V_NONE);
}

static void test_modes(void)
{
    uint8_t len_i, lsbf, bip;
    static const uint8_t lens[3] = { TLC2543_LEN_8, TLC2543_LEN_12, TLC2543_LEN_16 };
    static const uint8_t ch[2] = { 3, 7 };
    double v[11] = { 0 };
    for (len_i = 0; len_i < 3; len_i++) {
        for (lsbf = 0; lsbf < 2; lsbf++) {
            for (bip = 0; bip < 2; bip++) {
                tlc2543_settings s;
                uint16_t words[2];
                s.length = lens[len_i];
                s.lsb_first = lsbf;
                s.bipolar = bip;
                s.eoc_polls = 0;
                setup(&s);
                v[3] = 1.2345;
                v[7] = 4.0;
                CHECK_EQ_INT(tlc2543m_set_inputs(&model, v, 11), ATT_OK);
                CHECK_EQ_INT(tlc2543_scan(&adc, ch, 2, words, TLC2543_TEST_MID), ATT_OK);
                CHECK_EQ_INT(bip ? tlc2543_signed(&adc, words[0]) : words[0],
                             expect_word(tlc2543m_quantize(1.2345, 5.0, 0.0), &s));
                CHECK_EQ_INT(bip ? tlc2543_signed(&adc, words[1]) : words[1],
                             expect_word(tlc2543m_quantize(4.0, 5.0, 0.0), &s));
                CHECK_EQ_INT(tlc2543_clocks(&adc), len_i == 0 ? 8 : len_i == 1 ? 12 : 16);
                CHECK_EQ_INT(model.violation, TLC2543M_V_NONE);
            }
        }
    }
}

static void test_faults(void)
{
    uint16_t w, codes[3];
    tlc2543_settings s = { TLC2543_LEN_12, 0, 0, 5 };

    setup(&s);
    model.stuck_eoc = 0;
    model.eoc_level = 0;
    CHECK_EQ_INT(tlc2543_cycle(&adc, 0, &w), TLC2543_E_EOC_TIMEOUT);
    CHECK(adc.pending >= TLC2543_NO_RESULT);
    CHECK_EQ_INT(model.violation, TLC2543M_V_NONE);

    setup(0);
    model.stuck_dout = 0;
    CHECK_EQ_INT(tlc2543_self_test_codes(&adc, codes), TLC2543_E_SELFTEST_MID);
    CHECK_EQ_INT(codes[0], 0);
    setup(0);
    model.stuck_dout = 1;
    CHECK_EQ_INT(tlc2543_self_test(&adc), TLC2543_E_SELFTEST_MID);
    CHECK_EQ_INT(model.violation, TLC2543M_V_NONE);
}

static void test_power_down_and_args(void)
{
    static const uint8_t bad[2] = { 0, TLC2543_POWER_DOWN };
    static const uint8_t one[1] = { 5 };
    uint16_t codes[2];
    setup(0);
    CHECK_EQ_INT(tlc2543_power_down(&adc), ATT_OK);
    CHECK(adc.pending >= (TLC2543_POWER_DOWN << 4));
    CHECK_EQ_INT(tlc2543_scan(&adc, one, 1, codes, 5), ATT_OK); /* wakes up: 2 cycles */
    CHECK_EQ_INT(model.violation, TLC2543M_V_NONE);
    CHECK_EQ_INT(tlc2543_cycle(&adc, 15, codes), ATT_E_ARG);
    CHECK_EQ_INT(tlc2543_cycle(0, 1, codes), ATT_E_NULL);
    CHECK_EQ_INT(tlc2543_scan(&adc, bad, 2, codes, 0), ATT_E_ARG);
    CHECK_EQ_INT(tlc2543_scan(&adc, one, 0, codes, 0), ATT_E_ARG);
    CHECK_EQ_INT(tlc2543_scan(&adc, one, 1, codes, 15), ATT_E_ARG);
    CHECK_EQ_INT(tlc2543_scan(&adc, 0, 1, codes, 0), ATT_E_NULL);
    {
        tlc2543_settings s = { 2, 0, 0, 0 }; /* length code 2 is not accepted */
        CHECK_EQ_INT(tlc2543_init(&adc, &model.hal, &s), ATT_E_ARG);
        CHECK_EQ_INT(tlc2543_init(&adc, 0, 0), ATT_E_NULL);
    }
    CHECK_EQ_INT(model.violation, TLC2543M_V_NONE);
}

static void test_trace_and_violation(void)
{
    uint16_t w;
    setup(0);
    model.trace = trace;
    model.trace_cap = sizeof trace / sizeof trace[0];
    CHECK_EQ_INT(tlc2543_cycle(&adc, 2, &w), ATT_OK);
    CHECK(model.trace_len > 40u);
    CHECK_EQ_INT(trace[0].signal, TLC2543M_SIG_CS);
    CHECK_EQ_INT(trace[0].value, 0);
    CHECK_EQ_INT(model.trace_dropped, 0);
    /* a driver that clocks right after CS falls is caught */
    tlc2543m_set_cs(&model, 0);
    tlc2543m_set_clock(&model, 1);
    CHECK_EQ_INT(model.violation, TLC2543M_V_CS_SETUP);
}

static void test_batch(void)
{
    static const uint8_t xyz[3] = { 0, 1, 2 };
    double volts[4 * 3] = {
        0.0, 2.5, 5.0, -1.0, 6.0, 1.0, 0.6103515625, 2.5006103515625, 4.99, 3.3, 3.3, 3.3
    };
    int32_t codes[4 * 3];
    size_t done = 99;
    int i;
    setup(0);
    CHECK_EQ_INT(tlc2543m_convert(&model, &adc, xyz, 3, volts, 4, codes, 1, &done), ATT_OK);
    CHECK_EQ_INT(done, 4);
    for (i = 0; i < 12; i++) {
        CHECK_EQ_INT(codes[i], tlc2543m_quantize(volts[i], 5.0, 0.0));
    }
    model.stuck_eoc = 0;
    model.eoc_level = 0;
    CHECK_EQ_INT(tlc2543m_convert(&model, &adc, xyz, 3, volts, 4, codes, 0, &done), TLC2543_E_EOC_TIMEOUT);
    CHECK_EQ_INT(done, 0);
}

/*
 * Proof that the device model checks something: the real driver source,
 * compiled again below with a deliberately broken HAL that samples DATA OUT
 * on the falling edge of I/O CLOCK (the wrong edge: the chip is just
 * shifting the next bit out), is rejected by the model with a "DATA OUT
 * read before it is valid" violation.
 */
/* The broken variant: every public function renamed, custom HAL. */
#define TLC2543_HAL_CUSTOM      1
#define tlc2543_init            broken_init
#define tlc2543_cycle           broken_cycle
#define tlc2543_scan            broken_scan
#define tlc2543_self_test_codes broken_self_test_codes
#define tlc2543_self_test       broken_self_test
#define tlc2543_power_down      broken_power_down
#define tlc2543_signed          broken_signed
#define tlc2543_clocks          broken_clocks

static int latched_dout;

#undef TLC2543_CS
#undef TLC2543_CLOCK
#undef TLC2543_DIN
#undef TLC2543_DOUT
#undef TLC2543_EOC
#undef TLC2543_DELAY_NS
#define TLC2543_CS(d, v)        ((d)->hal->set_cs((d)->hal->ctx, (v)))
#define TLC2543_DIN(d, v)       ((d)->hal->set_din((d)->hal->ctx, (v)))
#define TLC2543_EOC(d)          ((d)->hal->get_eoc((d)->hal->ctx))
#define TLC2543_DELAY_NS(d, ns) ((d)->hal->delay_ns((d)->hal->ctx, (ns)))
/* BROKEN: DATA OUT is latched the moment the clock falls */
#define TLC2543_CLOCK(d, v)                   \
    ((d)->hal->set_clock((d)->hal->ctx, (v)), \
     (void)((v) ? 0 : (latched_dout = (d)->hal->get_dout((d)->hal->ctx))))
#define TLC2543_DOUT(d) (latched_dout)

#include "../src/tlc2543.c" /* header already included: the macros above stay */

static void test_wrong_edge_variant_is_caught(void)
{
    static const uint8_t xyz[3] = { 0, 1, 2 };
    uint16_t codes[3];
    CHECK_EQ_INT(tlc2543m_init(&model, 5.0, 0.0, 0xA5Au), ATT_OK);
    CHECK_EQ_INT(broken_init(&adc, &model.hal, 0), ATT_OK);
    (void)broken_scan(&adc, xyz, 3, codes, 0);
    CHECK_EQ_INT(model.violation, TLC2543M_V_DOUT_EARLY);
    CHECK(model.violation_t > 0);
}

int main(void)
{
    test_self_test_and_scan();
    test_modes();
    test_faults();
    test_power_down_and_args();
    test_trace_and_violation();
    test_batch();
    test_wrong_edge_variant_is_caught();
    return ATT_TEST_REPORT();
}
