/*
 * AD7927 driver against the C twin of the device model (csrc/host/), through
 * both HALs: the bit-banged pin HAL (ad7927_pins_transfer over the model's
 * pins) and the frame-transfer HAL (the model as an SPI controller). Every
 * check also requires that the model saw no protocol violation. Expected
 * values come from the datasheet (control-word bits, shadow-word layout,
 * transfer function), not from the driver.
 */
#include "att_test.h"
#include "attitude/ad7927.h"
#include "ad7927_model.h"

static ad7927m model;
static ad7927 adc;
static ad7927m_frame frames[256];
static const ad7927_settings S_DEFAULT = { 1, 0 };

/* Control write DIN word from the datasheet's bit positions (Table 5):
 * WRITE 11, SEQ 10, ADD 8..6, PM 5..4, SHADOW 3, RANGE 1, CODING 0; the
 * 12 bits go out MSB first in bits 15..4 of the 16-bit frame. */
static uint16_t cw(int seq, int add, int pm, int shadow, int range, int coding)
{
    unsigned w = (1u << 11) | ((unsigned)seq << 10) | ((unsigned)add << 6) | ((unsigned)pm << 4)
                 | ((unsigned)shadow << 3) | ((unsigned)range << 1) | (unsigned)coding;
    return (uint16_t)(w << 4);
}

/* The mode words of this file's default settings: normal power, 0..2*REFIN
 * (RANGE = 0), straight binary (CODING = 1). */
static uint16_t plain(int add)
{
    return cw(0, add, 3, 0, 0, 1);
}

static void setup(int pins, const ad7927_settings *s)
{
    CHECK_EQ_INT(ad7927m_init(&model, 2.5, AD7927M_POWERUP_CONTROL, 1), ATT_OK);
    model.frames = frames;
    model.frames_cap = sizeof frames / sizeof frames[0];
    CHECK_EQ_INT(ad7927_init(&adc, pins ? &model.pin_hal : &model.frame_hal, s), ATT_OK);
}

static void set_ramp(void)
{
    double v[8];
    int i;
    for (i = 0; i < 8; i++) {
        v[i] = 0.3 + 0.6 * i; /* 0.3 .. 4.5 V inside 0..5 V */
    }
    CHECK_EQ_INT(ad7927m_set_inputs(&model, v, 8), ATT_OK);
}

static void test_power_up(int pins)
{
    setup(pins, &S_DEFAULT);
    CHECK_EQ_INT(ad7927_scan(&adc, (const uint8_t *)"\0", 1, (int16_t[1]){ 0 }, 0), ATT_E_STATE);
    CHECK_EQ_INT(ad7927_power_up(&adc), ATT_OK);
    CHECK_EQ_INT(model.frames_len, 3);
    CHECK_EQ_INT(frames[0].din, 0xFFFF);
    CHECK_EQ_INT(frames[1].din, 0xFFFF);
    CHECK_EQ_INT(frames[2].din, plain(0));
    /* default power-on state: full shutdown + shadow load pending; frames
     * 1-2 convert nothing valid, frame 3 converts VIN0 */
    CHECK_EQ_INT(frames[0].valid, 0);
    CHECK_EQ_INT(frames[1].valid, 0);
    CHECK_EQ_INT(frames[2].valid, 1);
    CHECK_EQ_INT(frames[2].channel, 0);
    CHECK(frames[2].t - frames[1].t >= 1000);
    CHECK_EQ_INT(adc.pending, 0);
    CHECK_EQ_INT(model.violation, AD7927M_V_NONE);
}

static void test_scan_and_pipeline(int pins)
{
    static const uint8_t ch[7] = { 0, 1, 2, 3, 4, 5, 6 };
    static const uint8_t order[5] = { 6, 2, 7, 0, 3 };
    int16_t codes[7];
    size_t f0;
    int i;
    setup(pins, &S_DEFAULT);
    set_ramp();
    CHECK_EQ_INT(ad7927_power_up(&adc), ATT_OK);
    /* VIN0 is already pending after power-up: 7 frames */
    f0 = model.frames_len;
    CHECK_EQ_INT(ad7927_scan(&adc, ch, 7, codes, 0), ATT_OK);
    CHECK_EQ_INT(model.frames_len - f0, 7);
    for (i = 0; i < 7; i++) {
        CHECK_EQ_INT(codes[i], ad7927m_quantize(0.3 + 0.6 * i, 2.5, 1));
        /* frame i converts the channel written in frame i - 1 */
        CHECK_EQ_INT(frames[f0 + i].channel, ch[i]);
        CHECK_EQ_INT(frames[f0 + i].din, plain(i < 6 ? ch[i + 1] : 0));
        CHECK_EQ_INT(frames[f0 + i].dout >> 12, ch[i]);
    }
    /* a scrambled order: one priming frame (VIN6 is not pending), next = 3 */
    f0 = model.frames_len;
    CHECK_EQ_INT(ad7927_scan(&adc, order, 5, codes, 3), ATT_OK);
    CHECK_EQ_INT(model.frames_len - f0, 6);
    CHECK_EQ_INT(frames[f0].channel, 0); /* the pending VIN0, discarded */
    for (i = 0; i < 5; i++) {
        CHECK_EQ_INT(codes[i], ad7927m_quantize(0.3 + 0.6 * order[i], 2.5, 1));
        CHECK_EQ_INT(frames[f0 + 1 + i].channel, order[i]);
    }
    CHECK_EQ_INT(adc.pending, 3);
    CHECK_EQ_INT(model.violation, AD7927M_V_NONE);
}

static void test_coding_and_range(int pins)
{
    static const uint8_t ch[3] = { 0, 1, 2 };
    ad7927_settings s;
    int16_t codes[3];
    double v[3] = { 0.0, 1.25, 2.4999 };
    s.range_double = 0; /* 0..REFIN = 0..2.5 V */
    s.twos_complement = 1;
    setup(pins, &s);
    CHECK_EQ_INT(ad7927m_set_inputs(&model, v, 3), ATT_OK);
    CHECK_EQ_INT(ad7927_power_up(&adc), ATT_OK);
    CHECK_EQ_INT(frames[2].din, cw(0, 0, 3, 0, 1, 0));
    CHECK_EQ_INT(ad7927_scan(&adc, ch, 3, codes, 0), ATT_OK);
    /* two's complement about mid-range: 0 V -> -2048, REFIN/2 -> 0 */
    CHECK_EQ_INT(codes[0], -2048);
    CHECK_EQ_INT(codes[1], 0);
    CHECK_EQ_INT(codes[2], (int)ad7927m_quantize(2.4999, 2.5, 0) - 2048);
    /* back to straight binary, 0..2*REFIN, inside the same pipeline: the
     * priming frame's output still has the old coding */
    s.range_double = 1;
    s.twos_complement = 0;
    CHECK_EQ_INT(ad7927_configure(&adc, &s), ATT_OK);
    CHECK_EQ_INT(ad7927_scan(&adc, ch, 3, codes, 0), ATT_OK);
    CHECK_EQ_INT(codes[0], 0);
    CHECK_EQ_INT(codes[1], 1024); /* 1.25 V of 5 V */
    CHECK_EQ_INT(model.violation, AD7927M_V_NONE);
}

static void test_sequencer(int pins)
{
    int16_t codes[16];
    uint8_t chans[16];
    size_t f0;
    int i;
    setup(pins, &S_DEFAULT);
    set_ramp();
    CHECK_EQ_INT(ad7927_power_up(&adc), ATT_OK);
    CHECK_EQ_INT(ad7927_seq_read(&adc, codes, chans, 1), ATT_E_STATE);
    f0 = model.frames_len;
    CHECK_EQ_INT(ad7927_seq_start(&adc, 6), ATT_OK);
    CHECK_EQ_INT(frames[f0].din, cw(1, 6, 3, 1, 0, 1));
    /* 16 frames: VIN0..VIN6, wrapping twice */
    CHECK_EQ_INT(ad7927_seq_read(&adc, codes, chans, 16), ATT_OK);
    for (i = 0; i < 16; i++) {
        CHECK_EQ_INT(chans[i], i % 7);
        CHECK_EQ_INT(codes[i], ad7927m_quantize(0.3 + 0.6 * (i % 7), 2.5, 1));
        CHECK_EQ_INT(frames[f0 + 1 + i].din, 0); /* WRITE = 0 */
    }
    /* shadow register: sequence one {1, 4, 6}, sequence two {0, 7} */
    f0 = model.frames_len;
    CHECK_EQ_INT(ad7927_shadow_start(&adc, (1u << 1) | (1u << 4) | (1u << 6), (1u << 0) | (1u << 7)), ATT_OK);
    CHECK_EQ_INT(frames[f0].din, cw(0, 0, 3, 1, 0, 1));
    /* MSB first: seq one VIN0..VIN7 in bits 15..8, seq two in bits 7..0 */
    CHECK_EQ_INT(frames[f0 + 1].din, (1 << 14) | (1 << 11) | (1 << 9) | (1 << 7) | (1 << 0));
    CHECK_EQ_INT(ad7927_seq_read(&adc, codes, chans, 7), ATT_OK);
    {
        static const uint8_t want[7] = { 1, 4, 6, 0, 7, 1, 4 };
        for (i = 0; i < 7; i++) {
            CHECK_EQ_INT(chans[i], want[i]);
            CHECK_EQ_INT(codes[i], ad7927m_quantize(0.3 + 0.6 * want[i], 2.5, 1));
        }
    }
    /* coding change inside the sequence: SEQ = 1, SHADOW = 0 write; the
     * sequence runs on (6, 0, 7, 1) and the new coding applies from the
     * second conversion */
    {
        ad7927_settings s = { 1, 1 };
        CHECK_EQ_INT(ad7927_configure(&adc, &s), ATT_OK);
        f0 = model.frames_len;
        CHECK_EQ_INT(ad7927_seq_read(&adc, codes, chans, 4), ATT_OK);
        CHECK_EQ_INT(frames[f0].din, cw(1, 0, 3, 0, 0, 0));
        CHECK_EQ_INT(frames[f0 + 1].din, 0);
        CHECK_EQ_INT(chans[0], 6);
        CHECK_EQ_INT(chans[3], 1);
        CHECK_EQ_INT(codes[0], ad7927m_quantize(0.3 + 0.6 * 6, 2.5, 1));
        CHECK_EQ_INT(codes[1], -2048 + ad7927m_quantize(0.3, 2.5, 1));
    }
    /* a scan stops the sequence (the sequence's next conversion, VIN4, is
     * the priming frame's output) */
    {
        static const uint8_t two[2] = { 5, 2 };
        f0 = model.frames_len;
        CHECK_EQ_INT(ad7927_scan(&adc, two, 2, codes, 5), ATT_OK);
        CHECK_EQ_INT(frames[f0].channel, 4);
        CHECK_EQ_INT(frames[f0 + 1].channel, 5);
        CHECK_EQ_INT(frames[f0 + 2].channel, 2);
        CHECK_EQ_INT(adc.seq_len, 0);
    }
    CHECK_EQ_INT(model.violation, AD7927M_V_NONE);
}

static void test_power_down(int pins)
{
    static const uint8_t ch[2] = { 3, 5 };
    int16_t codes[2];
    size_t f0;
    setup(pins, &S_DEFAULT);
    set_ramp();
    CHECK_EQ_INT(ad7927_power_up(&adc), ATT_OK);
    f0 = model.frames_len;
    CHECK_EQ_INT(ad7927_power_down(&adc), ATT_OK);
    CHECK_EQ_INT(frames[f0].din, cw(0, 0, 2, 0, 0, 1));
    CHECK_EQ_INT(adc.pending, AD7927_NO_CHANNEL);
    /* wake: one frame in its own transfer (invalid conversion), 1 us, then the scan */
    f0 = model.frames_len;
    CHECK_EQ_INT(ad7927_scan(&adc, ch, 2, codes, 3), ATT_OK);
    CHECK_EQ_INT(model.frames_len - f0, 3);
    CHECK_EQ_INT(frames[f0].valid, 0);
    CHECK(frames[f0 + 1].t - frames[f0].t >= 1000);
    CHECK_EQ_INT(codes[0], ad7927m_quantize(0.3 + 0.6 * 3, 2.5, 1));
    CHECK_EQ_INT(codes[1], ad7927m_quantize(0.3 + 0.6 * 5, 2.5, 1));
    /* a sequence start wakes the part too */
    CHECK_EQ_INT(ad7927_power_down(&adc), ATT_OK);
    CHECK_EQ_INT(ad7927_seq_start(&adc, 2), ATT_OK);
    CHECK_EQ_INT(ad7927_seq_read(&adc, codes, 0, 2), ATT_OK);
    CHECK_EQ_INT(codes[1], ad7927m_quantize(0.9, 2.5, 1));
    CHECK_EQ_INT(model.violation, AD7927M_V_NONE);
}

static int hal_fails(void *ctx, const uint16_t *tx, uint16_t *rx, uint8_t n, uint32_t hold_ns)
{
    (void)ctx;
    (void)tx;
    (void)rx;
    (void)n;
    (void)hold_ns;
    return -5;
}

static void test_faults(int pins)
{
    static const uint8_t ch[3] = { 0, 1, 2 };
    int16_t codes[3] = { 7, 7, 7 };
    /* DOUT stuck high: the leading bit is 1 from the first checked frame */
    setup(pins, &S_DEFAULT);
    model.stuck_dout = 1;
    CHECK_EQ_INT(ad7927_power_up(&adc), AD7927_E_FRAME);
    CHECK_EQ_INT(adc.last_word, 0xFFFF);
    /* DOUT stuck low: 0x0000 names VIN0 (power-up passes), VIN1 gives it away */
    setup(pins, &S_DEFAULT);
    model.stuck_dout = 0;
    CHECK_EQ_INT(ad7927_power_up(&adc), ATT_OK);
    CHECK_EQ_INT(ad7927_scan(&adc, ch, 3, codes, 0), AD7927_E_CHANNEL);
    CHECK_EQ_INT(codes[0], 0); /* kept: VIN0 was "read" before the mismatch */
    CHECK_EQ_INT(adc.last_expect, 1);
    CHECK_EQ_INT(adc.pending, AD7927_NO_CHANNEL);
    /* a wrong channel address in every word */
    setup(pins, &S_DEFAULT);
    set_ramp();
    CHECK_EQ_INT(ad7927_power_up(&adc), ATT_OK);
    model.address_xor = 2;
    CHECK_EQ_INT(ad7927_scan(&adc, ch, 3, codes, 0), AD7927_E_CHANNEL);
    CHECK_EQ_INT(adc.last_word >> 12, 2);
    CHECK_EQ_INT(adc.last_expect, 0);
    model.address_xor = 0; /* the next scan re-primes and works again */
    CHECK_EQ_INT(ad7927_scan(&adc, ch, 3, codes, 0), ATT_OK);
    CHECK_EQ_INT(codes[2], ad7927m_quantize(1.5, 2.5, 1));
    /* DIN stuck low: no write ever lands, the part stays shut down (its
     * invalid word names VIN5): power-up fails */
    setup(pins, &S_DEFAULT);
    model.stuck_din = 0;
    CHECK_EQ_INT(ad7927_power_up(&adc), AD7927_E_CHANNEL);
    /* a failing HAL */
    {
        ad7927_hal bad = { 0, hal_fails };
        CHECK_EQ_INT(ad7927_init(&adc, &bad, 0), ATT_OK);
        CHECK_EQ_INT(ad7927_power_up(&adc), AD7927_E_TRANSFER);
    }
    CHECK_EQ_INT(model.violation, AD7927M_V_NONE);
}

static void test_args(void)
{
    static const uint8_t bad[2] = { 0, 8 };
    int16_t codes[2];
    ad7927_settings s = { 2, 0 };
    ad7927_hal none = { 0, 0 };
    setup(0, 0);
    CHECK_EQ_INT(adc.ctrl, (3 << 4) | 1); /* NULL settings: 0..2*REFIN, straight binary */
    CHECK_EQ_INT(ad7927_init(&adc, &model.frame_hal, &s), ATT_E_ARG);
    CHECK_EQ_INT(ad7927_init(&adc, &none, 0), ATT_E_NULL);
    CHECK_EQ_INT(ad7927_init(0, &model.frame_hal, 0), ATT_E_NULL);
    CHECK_EQ_INT(ad7927_init(&adc, &model.frame_hal, 0), ATT_OK);
    CHECK_EQ_INT(ad7927_power_up(&adc), ATT_OK);
    CHECK_EQ_INT(ad7927_scan(&adc, bad, 2, codes, 0), ATT_E_ARG);
    CHECK_EQ_INT(ad7927_scan(&adc, bad, 0, codes, 0), ATT_E_ARG);
    CHECK_EQ_INT(ad7927_scan(&adc, bad, 17, codes, 0), ATT_E_ARG);
    CHECK_EQ_INT(ad7927_scan(&adc, bad, 1, codes, 8), ATT_E_ARG);
    CHECK_EQ_INT(ad7927_scan(&adc, 0, 1, codes, 0), ATT_E_NULL);
    CHECK_EQ_INT(ad7927_seq_start(&adc, 8), ATT_E_ARG);
    CHECK_EQ_INT(ad7927_shadow_start(&adc, 0, 3), ATT_E_ARG);
    CHECK_EQ_INT(ad7927_configure(&adc, &s), ATT_E_ARG);
    CHECK_EQ_INT(ad7927_din_word(0x7FF), 0xFFF0);
    CHECK_EQ_INT(model.frames_len, 3);                            /* argument errors send nothing */
    CHECK_EQ_INT(ad7927m_init(&model, 2.5, 0x000, 0), ATT_E_ARG); /* PM = 00 */
}

static void test_batch(void)
{
    static const uint8_t ch[7] = { 0, 1, 2, 3, 4, 5, 6 };
    double volts[3 * 7];
    int32_t codes[3 * 7];
    size_t done = 99;
    int i, seq;
    for (i = 0; i < 21; i++) {
        volts[i] = -0.5 + 0.27 * i; /* -0.5 .. 4.9 V, the first clips to 0 */
    }
    for (seq = 0; seq < 2; seq++) {
        setup(seq, &S_DEFAULT);
        CHECK_EQ_INT(ad7927m_convert(&model, &adc, ch, 7, volts, 3, codes, seq, 1, &done), ATT_OK);
        CHECK_EQ_INT(done, 3);
        for (i = 0; i < 21; i++) {
            CHECK_EQ_INT(codes[i], ad7927m_quantize(volts[i], 2.5, 1));
        }
        CHECK_EQ_INT(model.violation, AD7927M_V_NONE);
    }
    model.stuck_dout = 1;
    CHECK_EQ_INT(ad7927m_convert(&model, &adc, ch, 7, volts, 3, codes, 0, 0, &done), AD7927_E_FRAME);
    CHECK_EQ_INT(done, 0);
}

/*
 * Proof that the model checks the timing: the real engine, compiled again
 * below with a deliberately broken pin access that samples DOUT right after
 * the falling edge (before the next bit is valid, t4), is rejected with a
 * "DOUT read before it is valid" violation.
 */
#define AD7927_HAL_CUSTOM    1
#define ad7927_pins_transfer broken_pins_transfer
#define ad7927_din_word      broken_din_word
#define ad7927_init          broken_init
#define ad7927_configure     broken_configure
#define ad7927_power_up      broken_power_up
#define ad7927_scan          broken_scan
#define ad7927_seq_start     broken_seq_start
#define ad7927_shadow_start  broken_shadow_start
#define ad7927_seq_read      broken_seq_read
#define ad7927_power_down    broken_power_down
static int latched_dout;
#define AD7927_CS(p, v)  ((p)->set_cs((p)->ctx, (v)))
#define AD7927_DIN(p, v) ((p)->set_din((p)->ctx, (v)))
/* BROKEN: DOUT is latched the moment SCLK falls */
#define AD7927_SCLK(p, v) \
    ((p)->set_sclk((p)->ctx, (v)), (void)((v) ? 0 : (latched_dout = (p)->get_dout((p)->ctx))))
#define AD7927_DOUT(p)         (latched_dout)
#define AD7927_DELAY_NS(p, ns) ((p)->delay_ns((p)->ctx, (ns)))

#include "../src/ad7927.c" /* header already included: the macros above stay */

static void test_wrong_edge_variant_is_caught(void)
{
    ad7927_hal hal;
    CHECK_EQ_INT(ad7927m_init(&model, 2.5, AD7927M_POWERUP_CONTROL, 1), ATT_OK);
    hal.ctx = &model.pins;
    hal.transfer = broken_pins_transfer;
    CHECK_EQ_INT(broken_init(&adc, &hal, 0), ATT_OK);
    (void)broken_power_up(&adc);
    CHECK_EQ_INT(model.violation, AD7927M_V_DOUT_EARLY);
    CHECK(model.violation_t > 0);
}

int main(void)
{
    int pins;
    for (pins = 0; pins < 2; pins++) {
        test_power_up(pins);
        test_scan_and_pipeline(pins);
        test_coding_and_range(pins);
        test_sequencer(pins);
        test_power_down(pins);
        test_faults(pins);
    }
    test_args();
    test_batch();
    test_wrong_edge_variant_is_caught();
    return ATT_TEST_REPORT();
}
