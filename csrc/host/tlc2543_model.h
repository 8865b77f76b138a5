/*
 * tlc2543_model.h — host-only C twin of the Python TLC2543 device model
 * (attitude_c/tlc2543/model.py). Same behaviour, same rules, same trace;
 * used by the C tests and by the fast batch conversion of the Python API.
 * Not part of the cross-built library.
 *
 * Time is simulated (ns) and only advances in the delay callback. The
 * first protocol violation is latched in `violation` (a TLC2543M_V_* code)
 * with a message; later pin operations still work but are not checked.
 */
#ifndef ATTITUDE_TLC2543_MODEL_H
#define ATTITUDE_TLC2543_MODEL_H

#include "attitude/common.h"
#include "attitude/tlc2543.h"
#include "devmodel.h"

/* Trace signals (same order as attitude_c.tlc2543.model.SIGNALS). */
enum {
    TLC2543M_SIG_CS = 0,
    TLC2543M_SIG_CLOCK = 1,
    TLC2543M_SIG_DIN = 2,
    TLC2543M_SIG_DOUT = 3,
    TLC2543M_SIG_EOC = 4,
    TLC2543M_SIG_READ_DOUT = 5,
    TLC2543M_SIG_READ_EOC = 6,
    TLC2543M_HIGH_Z = 2 /* DOUT value in the trace while CS is high */
};

/* Violation codes (1-based index into model.RULES; 0 = none). */
enum {
    TLC2543M_V_NONE = 0,
    TLC2543M_V_CLOCK_COUNT = 1,
    TLC2543M_V_CS_MID_CYCLE = 2,
    TLC2543M_V_DOUT_EARLY = 3,
    TLC2543M_V_DOUT_CS_HIGH = 4,
    TLC2543M_V_CLOCK_TOO_FAST = 5,
    TLC2543M_V_CS_SETUP = 6,
    TLC2543M_V_CS_TOO_EARLY = 7,
    TLC2543M_V_CS_DURING_CONVERSION = 8,
    TLC2543M_V_EOC_EARLY = 9,
    TLC2543M_V_DIN_SETUP = 10,
    TLC2543M_V_DIN_HOLD = 11,
    TLC2543M_V_CLOCK_CS_HIGH = 12,
    TLC2543M_V_CLOCK_HIGH_AT_CS = 13,
    TLC2543M_V_RESERVED_ADDRESS = 14
};

/* Status codes of the batch call (TLC2543 range of common.h). */
enum {
    TLC2543M_E_VIOLATION = -50 /* the model latched a protocol violation */
};

/* One trace event: signal = TLC2543M_SIG_*, value 0, 1, or TLC2543M_HIGH_Z. */
typedef devm_event tlc2543m_event;

typedef struct {
    int32_t t_cs_setup, t_dout_enable, t_din_setup, t_din_hold, t_clk_high, t_clk_low, t_dout_valid,
        t_eoc_fall, t_conv, t_cs_reassert; /* ns, as model.Timing */
} tlc2543m_timing;

typedef struct {
    /* configuration (set by tlc2543m_init; may be changed between cycles) */
    double inputs[11]; /* AIN0..AIN10, V */
    double vref_plus;  /* V */
    double vref_minus; /* V */
    tlc2543m_timing timing;
    int8_t stuck_eoc;  /* -1: not stuck; 0/1: stuck level */
    int8_t stuck_dout; /* -1: not stuck; 0/1: stuck level (when driven) */
    /* trace: caller-owned buffer (may be NULL / 0) */
    tlc2543m_event *trace;
    size_t trace_cap;
    size_t trace_len;
    size_t trace_dropped; /* events that did not fit */
    /* result */
    int violation;        /* TLC2543M_V_* of the first violation */
    int64_t violation_t;  /* its time, ns */
    char message[160];    /* its description */
    uint32_t conversions; /* conversions completed */
    /* simulation state (private) */
    int64_t t;
    uint8_t cs, clock, din, dout_level, eoc_level;
    int64_t t_din, t_cs_fall, t_rise, t_fall;
    uint8_t n_rise, n_fall, in_byte, nclk; /* nclk 0 = not known yet */
    uint8_t has_last_clock;
    int64_t t_last_clock;
    uint8_t pending_active, pending_address, pending_mode;
    int64_t conv_end;
    uint8_t eoc_fall_pending;
    int64_t eoc_fall_at;
    uint8_t out_bits[16];
    uint8_t out_len;
    tlc2543_hal hal; /* callbacks into this model, ctx = the model */
} tlc2543m;

/* Datasheet defaults (model.Timing()). */
void tlc2543m_default_timing(tlc2543m_timing *timing);

/* Reset the model: inputs 0 V, vref_plus / vref_minus, default timing, no
 * faults, output register = powerup_word, no trace. Fills m->hal. */
int tlc2543m_init(tlc2543m *m, double vref_plus, double vref_minus, uint16_t powerup_word);

/* Set n (<= 11) input voltages. ATT_E_NONFINITE on NaN/Inf. */
int tlc2543m_set_inputs(tlc2543m *m, const double *volts, size_t n);

/* The 12-bit unipolar code of v (the chip's transfer, clipped). */
uint16_t tlc2543m_quantize(double v, double vref_plus, double vref_minus);

/* HAL callbacks (also reachable through m->hal). */
void tlc2543m_set_cs(void *ctx, int level);
void tlc2543m_set_clock(void *ctx, int level);
void tlc2543m_set_din(void *ctx, int level);
int tlc2543m_get_dout(void *ctx);
int tlc2543m_get_eoc(void *ctx);
void tlc2543m_delay_ns(void *ctx, uint32_t ns);

/*
 * Batch conversion through the C driver: for each of n rows, set the
 * inputs of `channels` (nch of them, AIN numbers) to volts[row * nch + k],
 * then one full tlc2543_scan (nch + 1 I/O cycles; the last cycle requests
 * TLC2543_TEST_MID so the next row starts fresh and every row's codes come
 * from that row's voltages). codes[row * nch + k] = the word read
 * (bipolar words sign-extended). If self_test, tlc2543_self_test runs
 * first. Returns ATT_OK, a driver error, ATT_E_NONFINITE (a NaN/Inf
 * voltage) or TLC2543M_E_VIOLATION; *rows_done = rows fully converted
 * (their codes are stored).
 */
int tlc2543m_convert(tlc2543m *m, tlc2543 *dev, const uint8_t *channels, uint8_t nch, const double *volts,
                     size_t n, int32_t *codes, int self_test, size_t *rows_done);

#endif /* ATTITUDE_TLC2543_MODEL_H */
