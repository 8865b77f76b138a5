/*
 * libattitude — sensor words to body-frame values (prefix att_sensor_):
 * the host's "simple data processing" of the paper (sec. 3.4), from the
 * ADC words of a sample record (attitude/block.h) to body rates and angle
 * increments, in the float and double builds. attitude-rx and the Python
 * package (attitude_c.sensor, the simulator's host stage) both convert
 * with it; the fixed-point build's converter is att_fx_adc_* (attitude/fixed.h).
 *
 * For body axis i, reading channel c = axis[i]:
 *
 *     value_i = sign[i] · (word_c / n − zero_c) · scale_c
 *
 *   word_c   the sample record's word of channel c: the code of one
 *            conversion (n = 1), or the sum of n conversions (a stream
 *            whose OVERSAMPLE report announced n, attitude/block.h);
 *            0 .. n · ATT_BLOCK_CODE_MAX, else ATT_E_RANGE;
 *   zero_c   the channel's reading at zero input, in codes of one
 *            conversion (calibrated: may be fractional), 0 .. 65535;
 *   scale_c  physical units per code (a gyro: rad/s per code), finite and
 *            non-zero (a negative scale flips the channel);
 *   axis     which channel each body axis reads (each channel once);
 *   sign     +1 or -1 per body axis.
 *
 * then a 3x3 correction (att_sensor_set_correction; att_sensor_init sets
 * M = I, b = 0):
 *
 *     out = M · (value − b)
 *
 *   M (mat)  row-major, dimensionless: misalignment and scale-factor
 *            correction (accelerometer), soft iron (magnetometer); finite,
 *            |det M| ≥ 1 / ATT_SENSOR_DET_RECIP, else ATT_E_ARG;
 *   b (bias) in the output's units (m/s² for an accelerometer, µT for a
 *            magnetometer: hard iron; rad/s for a gyro); finite.
 *
 * With M = I and b = 0 out is value bit for bit (the gyro path of every
 * stream before the correction existed). A magnetometer calibration
 * (attitude/aiding.h: m_cal = S (m − h), fitted to this sensor's values
 * with M = I, b = 0) is M = S, b = h: out is then att_magcal_apply's
 * m_cal, bit for bit (the same operations in the same order).
 *
 * Units: a gyro's out is the body rate (rad/s), an accelerometer's the
 * specific force (m/s²), a magnetometer's the field (µT).
 *
 * Gyros: value is the body rate (rad/s); the angle increment of one sample
 * period h (s) is value · h — the board's n conversions at the midpoints of
 * equal sub-intervals form the midpoint-rule mean rate of the period.
 *
 * Caller-owned state, no malloc, no I/O. Errors as att_status: ATT_E_NULL,
 * ATT_E_ARG (a configuration or oversampling count out of its domain),
 * ATT_E_NONFINITE (NaN/Inf in the configuration or the period),
 * ATT_E_RANGE (a word no n-conversion sum of 12-bit codes can be); on an
 * error no output is written.
 */
#ifndef ATTITUDE_SENSOR_H
#define ATTITUDE_SENSOR_H

#include "attitude/block.h"
#include "attitude/common.h"

ATT_API_BEGIN

enum {
    ATT_SENSOR_ZERO_MAX = 65535, /* largest zero reading (codes) */
    ATT_SENSOR_DET_RECIP = 1000  /* a correction needs |det M| ≥ 1/1000: a misalignment, scale-factor
                                    or soft-iron correction is near a rotation (|det| ≈ 1); below it
                                    an axis is (nearly) lost, a configuration mistake */
};

/* A three-axis sensor's calibration and axis mapping (set by att_sensor_init). */
typedef struct {
    att_real zero[3];  /* zero reading per channel, codes of one conversion */
    att_real scale[3]; /* units per code per channel */
    uint8_t axis[3];   /* body axis i reads channel axis[i] */
    int8_t sign[3];    /* ... times sign[i] */
    att_real mat[9];   /* correction M, row-major (identity) */
    att_real bias[3];  /* b, output units (0) */
    uint8_t plain;     /* 1 when M = I and b = 0: out = value, no correction computed */
} att_sensor;

/* Check and store a calibration. axis and sign may be NULL: body axis i
 * reads channel i with sign +1. ATT_OK, ATT_E_NULL (s, zero or scale
 * NULL), ATT_E_NONFINITE, or ATT_E_ARG (zero outside 0..65535, scale 0,
 * axis not a permutation of 0, 1, 2, sign not +1/-1); *s is untouched on
 * an error. */
att_status att_sensor_init(att_sensor *s, const att_real zero[3], const att_real scale[3],
                           const uint8_t axis[3], const int8_t sign[3]);

/* Check and store the correction M (mat, row-major) and b (bias) of a
 * sensor set up by att_sensor_init. ATT_OK, ATT_E_NULL, ATT_E_NONFINITE,
 * ATT_E_ARG (|det M| < 1/ATT_SENSOR_DET_RECIP); *s is untouched on an
 * error. */
att_status att_sensor_set_correction(att_sensor *s, const att_real mat[9], const att_real bias[3]);

/* One sample: words[0..2] (channels) of n conversions each (1..ATT_BLOCK_OVERSAMPLE_MAX) to the
 * body-frame values out[0..2] (a gyro: rad/s), corrected. out may not alias words. */
att_status att_sensor_convert(const att_sensor *s, const uint16_t words[3], uint8_t n, att_real out[3]);

/* m samples (m × 3 words) of a gyro sampled every period seconds (> 0,
 * finite) to angle increments (m × 3 values, rad): out · period each.
 * On an error *err_index (may be NULL) is the first bad sample and no
 * increment is written. */
att_status att_sensor_increments(const att_sensor *s, const uint16_t *words, size_t m, uint8_t n,
                                 att_real period, att_real *dtheta, size_t *err_index);

ATT_API_END

#endif /* ATTITUDE_SENSOR_H */
