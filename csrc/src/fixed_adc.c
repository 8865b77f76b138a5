/*
 * libattitude fixed point: ADC codes → Q2.30 angle increments, so that the
 * 8051 can do the "simple data processing" step itself. Integer-only.
 * The set-up (att_fx_adc_init) is in fixed_adc_init.c, so firmware whose
 * converter constants come from the host links only the conversion.
 */
#include "attitude/fixed.h"

#include "fixed_internal.h"
#if defined(__SDCC) || defined(ATT_FX_COMPACT)
/* the 8051 build: only this file's two primitives, no 64-bit accumulator
 * (SDCC compiles every static function of fixed_prim.h, used or not) */
#define FX_PRIM_MINIMAL
#include "fixed_prim.h"

/* (hi:lo) = x · y, unsigned 32 × 32 → 64 bits from 16 × 16-bit products
 * (also used by att_fx_adc_init in fixed_adc_init.c) */
void att__fx_uprod(uint32_t x, uint32_t y, uint32_t *hi, uint32_t *lo)
{
    uint32_t p0 = (uint32_t)(uint16_t)x * (uint16_t)y;
    uint32_t p1 = (uint32_t)(uint16_t)x * (uint16_t)(y >> 16);
    uint32_t p2 = (uint32_t)(uint16_t)(x >> 16) * (uint16_t)y;
    uint32_t h = (uint32_t)(uint16_t)(x >> 16) * (uint16_t)(y >> 16);
    uint32_t mid = p1 + p2;
    if (mid < p1) {
        h += 0x10000ul;
    }
    h += mid >> 16;
    mid <<= 16;
    p0 += mid;
    if (p0 < mid) {
        h++;
    }
    *hi = h;
    *lo = p0;
}

/* round(d · m / 2^sh) (nearest, ties toward +inf) for |d| < 2^24,
 * 0 < m < 2^31, 1 ≤ sh ≤ 62, if its magnitude is ≤ ATT_FX_DTHETA_MAX;
 * returns 0 and *out, or -1. Works on the magnitude u = |d|·m:
 * d ≥ 0: floor((u + h)/2^sh); d < 0: −floor((u + h − 1)/2^sh), h = 2^(sh−1),
 * which is floor((d·m + h)/2^sh) of the signed product. */
static int fx_adc_scale(int32_t d, int32_t m, uint8_t sh, int32_t *out)
{
    uint32_t hi, lo, add, r;
    att__fx_uprod(d < 0 ? 0u - (uint32_t)d : (uint32_t)d, (uint32_t)m, &hi, &lo);
    if (sh <= 32u) {
        add = (1ul << (sh - 1u)) - (d < 0 ? 1u : 0u);
        lo += add;
        if (lo < add) {
            hi++;
        }
        r = (sh == 32u) ? hi : ((lo >> sh) | (hi << (32u - sh)));
        if (sh < 32u && (hi >> sh) != 0u) {
            return -1;
        }
    } else {
        /* the half is 2^(sh−1) ≥ 2^32: added to hi; the −1 borrows from it
         * only when lo == 0 */
        add = 1ul << (sh - 33u);
        if (d < 0 && lo == 0u) {
            add -= 1u;
        }
        hi += add;
        r = hi >> (sh - 32u);
    }
    if (r > (uint32_t)ATT_FX_DTHETA_MAX) {
        return -1;
    }
    *out = d < 0 ? -(int32_t)r : (int32_t)r;
    return 0;
}
#else
#include "fixed_prim.h"

void att__fx_uprod(uint32_t x, uint32_t y, uint32_t *hi, uint32_t *lo)
{
    fx_uprod(x, y, hi, lo);
}

static int fx_adc_scale(int32_t d, int32_t m, uint8_t sh, int32_t *out)
{
    fx_acc acc;
    int32_t r;
    fx_zero(&acc);
    fx_mac(&acc, d, m);
    if (fx_round_sat(&acc, sh, &r) != 0 || r > (int32_t)ATT_FX_DTHETA_MAX
        || r < -(int32_t)ATT_FX_DTHETA_MAX) {
        return -1;
    }
    *out = r;
    return 0;
}
#endif

/* d = code·256 − zero (|d| < 2^24, exact); Δθ = round(d · m / 2^s) from the
 * exact 64-bit product (< 2^55), range-checked against ATT_FX_DTHETA_MAX. */
att_status att_fx_adc_convert(const att_fx_adc *a, const uint16_t code[3], att_q30 dtheta[3])
{
    att_q30 r[3];
    uint8_t i;
    if (a == 0 || code == 0 || dtheta == 0) {
        return ATT_E_NULL;
    }
    for (i = 0; i < 3; ++i) {
        int32_t d = (int32_t)((uint32_t)code[i] << 8) - a->zero_q8[i];
        if (fx_adc_scale(d, a->gain[i], a->shift[i], &r[i]) != 0) {
            return (att_status)ATT_FX_E_RANGE;
        }
    }
    dtheta[0] = r[0];
    dtheta[1] = r[1];
    dtheta[2] = r[2];
    return ATT_OK;
}
