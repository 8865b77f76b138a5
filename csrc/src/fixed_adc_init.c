/*
 * libattitude fixed point: set-up of the ADC-code converter (the gain
 * scale·period formed exactly in integers). Integer-only.
 */
#include "attitude/fixed.h"

#include "fixed_internal.h"

/*
 * gain per Q24.8 code unit, in Q2.30 rad: G = N / (10^9 · 2^10) with
 * N = scale_q32 · period_ns (exact 64-bit product): scale_q32/2^32 rad/s
 * per code × period_ns/10^9 s, /2^8 per Q8 unit, ×2^30 for Q2.30.
 * Long division of N by 10^9, bit by bit (remainder < 2^30, no overflow),
 * until 32 significant quotient bits; rounded to a 31-bit mantissa m and
 * shift s with G = m / 2^s (relative error ≤ 2^-31).
 */
static att_status fx_adc_gain(uint32_t scale_q32, uint32_t period_ns, int32_t *m_out, uint8_t *s_out)
{
    uint32_t hi, lo, rem = 0, m = 0, bit;
    int16_t p;
    uint8_t nb = 0, qb;
    int16_t ex;
    att__fx_uprod(scale_q32, period_ns, &hi, &lo);
    for (p = 63; p > -80 && nb < 32u; --p) {
        if (p >= 32) {
            bit = (hi >> (uint8_t)(p - 32)) & 1u;
        } else if (p >= 0) {
            bit = (lo >> (uint8_t)p) & 1u;
        } else {
            bit = 0;
        }
        rem = (rem << 1) | bit;
        qb = (rem >= 1000000000ul) ? 1u : 0u;
        if (qb) {
            rem -= 1000000000ul;
        }
        if (nb > 0u || qb) {
            m = (m << 1) | qb;
            ++nb;
        }
    }
    if (nb < 32u) {
        return (att_status)ATT_FX_E_RANGE;
    }
    /* quotient ≈ m · 2^(p+1); round m to 31 bits */
    ex = (int16_t)(p + 2);
    m = (m >> 1) + (m & 1u);
    if (m >= 0x80000000ul) {
        m >>= 1;
        ++ex;
    }
    /* G = m · 2^ex / 2^10, shift s = 10 − ex */
    if (10 - ex < 1 || 10 - ex > 62) {
        return (att_status)ATT_FX_E_RANGE;
    }
    *m_out = (int32_t)m;
    *s_out = (uint8_t)(10 - ex);
    return ATT_OK;
}

att_status att_fx_adc_init(att_fx_adc *a, const int32_t zero_q8[3], const uint32_t scale_q32[3],
                           uint32_t period_ns)
{
    int32_t m[3];
    uint8_t s[3], i;
    att_status st;
    if (a == 0 || zero_q8 == 0 || scale_q32 == 0) {
        return ATT_E_NULL;
    }
    if (period_ns == 0u) {
        return ATT_E_ARG;
    }
    for (i = 0; i < 3; ++i) {
        if (scale_q32[i] == 0u || zero_q8[i] < 0 || zero_q8[i] > 16777215L) {
            return ATT_E_ARG;
        }
        st = fx_adc_gain(scale_q32[i], period_ns, &m[i], &s[i]);
        if (st != ATT_OK) {
            return st;
        }
    }
    for (i = 0; i < 3; ++i) {
        a->zero_q8[i] = zero_q8[i];
        a->gain[i] = m[i];
        a->shift[i] = s[i];
    }
    return ATT_OK;
}
