/* libattitude — common helpers. */
#include "attitude/attitude.h"

/* Every status code of the library's headers with its description, in one
 * table (module ranges: common.h). Descriptions are distinct, so that a
 * description names its code; tests/test_names.py checks that this
 * table and csrc/tests/test_status.c cover every code the headers define,
 * and attitude_c.names takes its error texts from here. */
static const struct {
    att_status code;
    const char *text;
} status_table[] = {
    /* generic (common.h) */
    { ATT_OK, "ok" },
    { ATT_E_NULL, "NULL pointer argument" },
    { ATT_E_ARG, "argument out of range" },
    { ATT_E_NONFINITE, "non-finite input (NaN or Inf)" },
    { ATT_E_RANGE, "value outside representable range" },
    { ATT_E_STATE, "call not valid in current state" },
    { ATT_E_TIMEOUT, "timeout" },
    { ATT_E_BUFFER, "buffer too small" },
    /* integrator.h */
    { ATT_E_INTEG_METHOD, "unknown method, or a call not valid for this method" },
    { ATT_E_INTEG_DIVERGED, "increment too large: the attitude update is non-finite" },
    { ATT_E_INTEG_RANGE,
      "increment too large: beyond pi rad per sample (|dtheta| <= pi; rk4: |omega|*h/2 <= pi)" },
    /* tlc2543.h */
    { TLC2543_E_EOC_TIMEOUT, "TLC2543: EOC did not rise (conversion never ended): EOC stuck low?" },
    { TLC2543_E_SELFTEST_MID, "TLC2543 self-test: (Vref+ + Vref-)/2 code is not 0x800 +- tolerance" },
    { TLC2543_E_SELFTEST_REFM, "TLC2543 self-test: Vref- code is not 0x000 + tolerance" },
    { TLC2543_E_SELFTEST_REFP, "TLC2543 self-test: Vref+ code is not 0xFFF - tolerance" },
    /* link.h */
    { ATT_LINK_E_NULL, "link: NULL pointer" },
    { ATT_LINK_E_CONFIG, "link configuration out of range" },
    { ATT_LINK_E_BUSY, "link sender busy with the previous block" },
    { ATT_LINK_E_STATE, "link state corrupted" },
    /* fixed.h */
    { ATT_FX_E_RANGE, "value outside its fixed-point format's range" },
    { ATT_FX_E_METHOD, "unknown fixed-point method" },
    { ATT_FX_E_ZERO, "zero quaternion (fixed point: too small to normalize)" },
    /* block.h */
    { ATT_BLOCK_E_CODE, "sample code above its stream's limit" },
    { ATT_BLOCK_E_KIND, "unknown report kind" },
    { ATT_BLOCK_E_FIELD, "report field out of range" },
    { ATT_BLOCK_E_SEQ, "report out of sequence: a loss report disagrees with the sample count, or a report "
                       "cut a group short" },
    /* aiding.h */
    { ATT_AID_E_ZERO_F, "specific force is zero: no up direction" },
    { ATT_AID_E_ZERO_M, "magnetic field is zero: no north direction" },
    { ATT_AID_E_PARALLEL, "specific force and field are parallel: heading undefined" },
    { ATT_AID_E_MOVING, "static window: spread above its limit (moving start)" },
    { ATT_AID_E_FEW, "too few samples" },
    { ATT_AID_E_SINGULAR, "Gauss-Newton: Jacobian singular at an iterate" },
    { ATT_AID_E_NOCONV, "Gauss-Newton: no convergence within the iteration limit" },
    { ATT_AID_E_SPAN, "the samples do not span enough directions for this fit" },
    { ATT_AID_E_FIT, "the samples do not lie on an ellipsoid" },
    /* ahrs.h */
    { ATT_E_AHRS_DT, "attitude filter: time step not finite or not positive" },
    { ATT_E_AHRS_UNITS, "specific force far from gravity: accelerometer not in m/s^2?" },
    { ATT_E_AHRS_SETTINGS, "filter setting outside its domain" },
    { ATT_E_AHRS_DIVERGED, "filter state not finite" },
    { ATT_E_AHRS_ALIGN, "no initial attitude: the sample cannot align the filter" },
    /* ahrs_thesis.h */
    { ATT_E_TEKF_DT, "thesis EKF: time step not finite or not positive" },
    { ATT_E_TEKF_SETTINGS, "thesis EKF setting outside its domain" },
    { ATT_E_TEKF_DIVERGED, "thesis EKF state not finite" },
    { ATT_E_TEKF_ALIGN, "no initial attitude: the sample cannot align the thesis EKF" },
    /* ahrs_gnss9.h */
    { ATT_E_G9_DT, "GNSS nine-state filter: time step not finite or not positive" },
    { ATT_E_G9_SETTINGS, "GNSS nine-state filter setting outside its domain" },
    { ATT_E_G9_DIVERGED, "GNSS nine-state filter state not finite" },
    { ATT_E_G9_ALIGN, "no initial attitude: the sample cannot align the GNSS nine-state filter" },
    { ATT_E_G9_AGE, "GNSS nine-state filter: GNSS age not finite, negative or above max_gnss_age" },
    /* denoise.h */
    { ATT_E_WDEN_WAVELET, "denoiser: unknown wavelet" },
    { ATT_E_WDEN_MODE, "denoiser: unknown thresholding rule" },
    { ATT_E_WDEN_LEVELS, "denoiser: levels outside 1..ATT_WDEN_MAX_LEVELS" },
    { ATT_E_WDEN_BLOCK,
      "denoiser: block length outside 2..ATT_WDEN_MAX_BLOCK or not a multiple of 2^levels" },
    { ATT_E_WDEN_EDGE, "denoiser: edge_start + edge_end >= block (no sample left to output)" },
    { ATT_E_WDEN_SHORT, "denoiser: flush before one full block was received" },
    { ATT_E_WDEN_OVERFLOW, "denoiser: finite input, but the result overflows" },
    /* ad7927.h */
    { AD7927_E_CHANNEL, "AD7927: an output word names another channel than the one written for that frame" },
    { AD7927_E_FRAME, "AD7927: an output word's leading bit is 1 (DOUT stuck high or no part on the bus?)" },
    { AD7927_E_TRANSFER, "AD7927: the frame-transfer HAL failed" },
    /* link2.h */
    { ATT_LINK2_E_NULL, "link v2: NULL pointer" },
    { ATT_LINK2_E_CONFIG, "link v2 configuration out of range" },
    { ATT_LINK2_E_FULL, "link v2 sender ring full" },
    { ATT_LINK2_E_STATE, "link v2 state corrupted" },
    /* gnss.h */
    { ATT_GNSS_E_NULL, "GNSS parser: NULL pointer" },
    { ATT_GNSS_E_STATE, "GNSS parser state corrupted" },
};

const char *att_status_str(int status)
{
    size_t i;
    for (i = 0; i < sizeof status_table / sizeof status_table[0]; i++) {
        if (status_table[i].code == status) {
            return status_table[i].text;
        }
    }
    return "unknown status";
}

int att_real_size(void)
{
    return (int)sizeof(att_real);
}
