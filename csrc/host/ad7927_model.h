/*
 * ad7927_model.h — host-only C twin of the Python AD7927 device model
 * (attitude_c/ad7927/model.py). Same behaviour, same rules, same pin trace
 * and frame log; used by the C tests, the spidev HAL test and the fast
 * batch conversion of the Python API. Not part of the cross-built library.
 *
 * Two ways in: the pin callbacks (m->pins, also reached through
 * m->pin_hal = the bit-banged frame HAL over them) and the frame-transfer
 * HAL m->frame_hal (a hardware SPI controller at m->sclk_period_ns per
 * SCLK cycle). Time is simulated (ns). The first protocol violation is
 * latched in `violation` (an AD7927M_V_* code) with a message; later
 * operations still work but are not checked.
 */
#ifndef ATTITUDE_AD7927_MODEL_H
#define ATTITUDE_AD7927_MODEL_H

#include "attitude/common.h"
#include "attitude/ad7927.h"
#include "devmodel.h"

/* Trace signals (same order as attitude_c.ad7927.model.SIGNALS). */
enum {
    AD7927M_SIG_CS = 0,
    AD7927M_SIG_SCLK = 1,
    AD7927M_SIG_DIN = 2,
    AD7927M_SIG_DOUT = 3,
    AD7927M_SIG_READ_DOUT = 4,
    AD7927M_HIGH_Z = 2 /* DOUT value in the trace while three-state */
};

/* Violation codes (1-based index into model.RULES; 0 = none). */
enum {
    AD7927M_V_NONE = 0,
    AD7927M_V_CLOCK_COUNT = 1,
    AD7927M_V_CS_EARLY = 2,
    AD7927M_V_CS_HOLD = 3,
    AD7927M_V_CS_SETUP = 4,
    AD7927M_V_QUIET_TIME = 5,
    AD7927M_V_CLOCK_TOO_FAST = 6,
    AD7927M_V_CLOCK_TOO_SLOW = 7,
    AD7927M_V_DIN_SETUP = 8,
    AD7927M_V_DIN_HOLD = 9,
    AD7927M_V_DOUT_EARLY = 10,
    AD7927M_V_DOUT_THREE_STATE = 11,
    AD7927M_V_POWER_UP_TIME = 12,
    AD7927M_V_INVALID_POWER_MODE = 13
};

/* Status codes of the batch call (AD7927 range of common.h). */
enum {
    AD7927M_E_VIOLATION = -190 /* the model latched a protocol violation */
};

/* Defaults of the model (model.POWERUP_CONTROL, model.GARBAGE). */
enum {
    AD7927M_POWERUP_CONTROL = 0x020, /* full shutdown (PM = 10) */
    AD7927M_GARBAGE = 0x5A5A,        /* DOUT word of an invalid conversion */
    AD7927M_SCLK_PERIOD_NS = 108     /* frame-level SCLK period: 9.26 MHz */
};

/* One trace event: signal = AD7927M_SIG_*, value 0, 1, or AD7927M_HIGH_Z. */
typedef devm_event ad7927m_event;

typedef struct {
    int64_t t;       /* CS falling edge, ns */
    uint16_t din;    /* DIN word latched */
    uint16_t dout;   /* DOUT word driven */
    uint8_t channel; /* channel converted */
    uint8_t valid;   /* 1: a valid conversion */
} ad7927m_frame;

typedef struct {
    int32_t t_cs_sclk, t_dout_enable, t_dout_access, t_sclk_period, t_sclk_period_max, t_din_setup,
        t_din_hold, t_cs_hold, t_quiet, t_power_up; /* ns, as model.Timing */
} ad7927m_timing;

typedef struct {
    /* configuration (set by ad7927m_init; may be changed between frames) */
    double inputs[8]; /* VIN0..VIN7, V */
    double refin;     /* V */
    ad7927m_timing timing;
    int32_t sclk_period_ns; /* frame-level transfers */
    int8_t stuck_dout;      /* -1: not stuck; 0/1: stuck level (when driven) */
    int8_t stuck_din;       /* -1: not stuck; 0/1: the level the part sees */
    uint8_t address_xor;    /* XORed into the channel address of every output word */
    uint16_t garbage;       /* DOUT word of an invalid conversion (bit 15 cleared) */
    /* trace and frame log: caller-owned buffers (may be NULL / 0) */
    ad7927m_event *trace;
    size_t trace_cap, trace_len, trace_dropped;
    ad7927m_frame *frames;
    size_t frames_cap, frames_len, frames_dropped;
    /* result */
    int violation;        /* AD7927M_V_* of the first violation */
    int64_t violation_t;  /* its time, ns */
    char message[160];    /* its description */
    uint32_t conversions; /* valid conversions */
    /* simulation state (private) */
    int64_t t;
    uint8_t cs, sclk, din, dout_level;
    int64_t t_din, t_cs_rise, t_cs_fall, t_fall, t_rise;
    uint8_t has_cs_rise, has_fall, has_rise, n_fall;
    uint16_t din_word, out_word;
    uint8_t add, range_bit, coding, pm, powered, has_ready, shadow_pending;
    int64_t ready_at;
    uint8_t seq[16], seq_len, seq_pos, next_ch, converting, valid;
    /* HALs into this model */
    ad7927_pins pins;     /* ctx = the model */
    ad7927_hal pin_hal;   /* ctx = &pins, transfer = ad7927_pins_transfer */
    ad7927_hal frame_hal; /* ctx = the model, transfer = ad7927m_transfer */
} ad7927m;

/* Datasheet defaults (model.Timing()). */
void ad7927m_default_timing(ad7927m_timing *timing);

/* Reset the model: inputs 0 V, REFIN, default timing, no faults, power-on
 * state from powerup_control (12-bit control word, PM != 00) and
 * powerup_shadow (a shadow load pending), no trace. Fills the HALs.
 * ATT_E_NONFINITE / ATT_E_ARG on a bad refin or control word. */
int ad7927m_init(ad7927m *m, double refin, uint16_t powerup_control, int powerup_shadow);

/* Set n (<= 8) input voltages. ATT_E_NONFINITE on NaN/Inf. */
int ad7927m_set_inputs(ad7927m *m, const double *volts, size_t n);

/* The straight-binary 12-bit code of v (the part's transfer, clipped). */
uint16_t ad7927m_quantize(double v, double refin, int range_double);

/* Pin callbacks (also reachable through m->pins). */
void ad7927m_set_cs(void *ctx, int level);
void ad7927m_set_sclk(void *ctx, int level);
void ad7927m_set_din(void *ctx, int level);
int ad7927m_get_dout(void *ctx);
void ad7927m_delay_ns(void *ctx, uint32_t ns);

/* Frame-level transfer (the HAL contract of ad7927.h); ctx = the model.
 * Returns 0, or ATT_E_STATE while a pin-level frame is in progress. */
int ad7927m_transfer(void *ctx, const uint16_t *tx, uint16_t *rx, uint8_t n, uint32_t hold_ns);

/*
 * Batch conversion through the C driver (`dev`, initialised on one of the
 * model's HALs): if power_up, ad7927_power_up first; then for each of n
 * rows, the inputs of `channels` (nch of them) are set to
 * volts[row * nch + k] and the row is read — sequence = 0: one
 * ad7927_scan(channels, nch, next = channels[0]) (nch frames in steady
 * state); sequence = 1: channels must be 0..nch-1, the consecutive
 * sequence is started at the beginning of the call (ad7927_seq_start, one
 * frame) and each row is one ad7927_seq_read of nch frames. Every conversion of row i is sampled
 * within row i's frames. codes[row * nch + k] = the code. Returns ATT_OK, a
 * driver error, ATT_E_NONFINITE (a NaN/Inf voltage), ATT_E_ARG or
 * AD7927M_E_VIOLATION; *rows_done = rows fully converted.
 */
int ad7927m_convert(ad7927m *m, ad7927 *dev, const uint8_t *channels, uint8_t nch, const double *volts,
                    size_t n, int32_t *codes, int sequence, int power_up, size_t *rows_done);

#endif /* ATTITUDE_AD7927_MODEL_H */
