/*
 * libattitude fixed point: the update kernel (rotation vector → quaternion,
 * quaternion product with folded renormalization, the rv3 rotation vector).
 * This file alone is what an rv3 update needs (its 8051 flash size is the
 * "rv3 alone" figure of docs/fixed-point.md). Integer-only.
 */
#include "attitude/fixed.h"

#include "fixed_internal.h"
#include "fixed_prim.h"

/* Series coefficients in Q2.30 for v = φ²/8 (φ = |Φ|):
 *   cos(φ/2)          = Σ (−v)^n · 2^n/(2n)!
 *   sin(φ/2) / (φ/2)  = Σ (−v)^n · 2^n/(2n+1)!
 * (the n-th power of φ²/4 = 2v). */
static const int32_t fx_cos_k[8] = {
    1073741824L, 1073741824L, 178956971L, 11930465L, 426088L, 9469L, 143L, 2L
};
static const int32_t fx_sin_k[8] = {
    1073741824L, 357913941L, 35791394L, 1704352L, 47343L, 861L, 11L, 0L
};
/* Largest v (Q2.30) for which degree n+1 suffices: the first omitted term
 * v^(n+2)·2^(n+2)/(2n+4)! of the cosine series is below 2^-33 (the sine
 * series converges faster). Degree 7 covers v ≤ 1.2 (φ ≤ 3.1). */
static const int32_t fx_deg_vmax[6] = {
    28378L, 2349547L, 24989211L, 113507487L, 331839229L, 747556367L
};

int att_fx_dtheta_ok_(const att_q30 *d, uint8_t n)
{
    uint8_t i;
    for (i = 0; i < n; ++i) {
        if (d[i] > (att_q30)ATT_FX_DTHETA_MAX || d[i] < -(att_q30)ATT_FX_DTHETA_MAX) {
            return 0;
        }
    }
    return 1;
}

/*
 * Three-sample rotation vector with k12 = k23 (rv3, rv3-coning):
 *   Φ = Δθ1 + Δθ2 + Δθ3 + a × Δθ3 + b × (Δθ3 − Δθ1),  a = k13 Δθ1, b = k23 Δθ2
 * Inputs Q2.30 with |Δθ| ≤ 0.4 (a, b rounded to Q2.30, |a|,|b| ≤ 0.29;
 * |Δθ3 − Δθ1| ≤ 0.8 exact). Per component: the sum (×2^30) and the four
 * cross-product terms are accumulated exactly in Q4.60 and rounded once
 * to Q2.30; |Φ_i| ≤ 1.2 + 0.83·0.4·... ≤ 1.79 < 2, no saturation needed.
 */
void att_fx_phi_rv3_(const att_q30 d[9], int32_t k13, int32_t k23, att_q30 phi[3])
{
    int32_t a[3], b[3], w[3];
    uint8_t i;
    fx_acc acc;
    for (i = 0; i < 3; ++i) {
        a[i] = fx_mul(k13, d[i], 30);
        b[i] = fx_mul(k23, d[3 + i], 30);
        w[i] = d[6 + i] - d[i];
    }
    for (i = 0; i < 3; ++i) {
        uint8_t j = (uint8_t)((i + 1u) % 3u), k = (uint8_t)((i + 2u) % 3u);
        fx_zero(&acc);
        fx_add_shl(&acc, d[i] + d[3 + i] + d[6 + i], 30);
        fx_mac(&acc, a[j], d[6 + k]);
        fx_msc(&acc, a[k], d[6 + j]);
        fx_mac(&acc, b[j], w[k]);
        fx_msc(&acc, b[k], w[j]);
        phi[i] = fx_round(&acc, 30);
    }
}

/*
 * Q ← Q ⊗ q(Φ), renormalization folded into q:
 * (steps 1-2 in att_fx_cs_)
 *  1. v = |Φ|²/8: exact Q4.60 sum of squares (< 9.6·2^60 < 2^64, unsigned),
 *     rounded to Q2.30 (shift 33); v ≤ 1.2.
 *  2. c = cos(φ/2), s = sin(φ/2)/(φ/2) by Horner in v, Q2.30, one rounding
 *     per step (|partial sums| ≤ 1), degree from fx_deg_vmax.
 *  3. e = |Q|² − 1: exact Q4.60 sum minus 2^60, rounded to Q2.50 (shift 10);
 *     |e| must be ≤ 2^-20 (else ATT_FX_E_RANGE, Q untouched).
 *  4. c ← c − c·e/2, s ← s − s·e/2 (Q2.30 × Q2.50 → shift 51), so that
 *     |Q ⊗ q| = 1 to first order: no separate normalization pass and no
 *     second rounding of Q.
 *  5. q = [c (Q2.30), h = s·Φ/2 (Q2.30 × Q2.30 → Q1.31, shift 30, dithered
 *     rounding, see below)].
 *  6. Q ⊗ q in Q3.61: Q·h terms (Q2.30 × Q1.31) and 2·Q·c (Q2.30 × Q2.30,
 *     doubled); per component the exact sum is bounded by |Q||q| ≈ 2^61,
 *     rounded once to Q2.30 (shift 31).
 */
void att_fx_cs_(const att_q30 phi[3], int32_t *cp, int32_t *sp)
{
    fx_acc acc;
    int32_t v, c, s;
    int8_t n, deg;

    fx_zero(&acc);
    fx_mac(&acc, phi[0], phi[0]);
    fx_mac(&acc, phi[1], phi[1]);
    fx_mac(&acc, phi[2], phi[2]);
    v = (int32_t)fx_round_u(&acc, 33);

    deg = 7;
    for (n = 0; n < 6; ++n) {
        if (v <= fx_deg_vmax[n]) {
            deg = (int8_t)(n + 1);
            break;
        }
    }
    c = fx_cos_k[deg];
    s = fx_sin_k[deg];
    for (n = (int8_t)(deg - 1); n >= 0; --n) {
        c = fx_cos_k[n] - fx_mul(v, c, 30);
        s = fx_sin_k[n] - fx_mul(v, s, 30);
    }
    *cp = c;
    *sp = s;
}

att_status att_fx_apply_(att_q30 q[4], const att_q30 phi[3])
{
    fx_acc acc;
    int32_t c, s, e, h[4]; /* h[0] unused: the scalar part c stays Q2.30 */
    uint8_t n;

    att_fx_cs_(phi, &c, &s);
    fx_zero(&acc);
    fx_mac(&acc, q[0], q[0]);
    fx_mac(&acc, q[1], q[1]);
    fx_mac(&acc, q[2], q[2]);
    fx_mac(&acc, q[3], q[3]);
    fx_add_shl(&acc, -(int32_t)ATT_FX_Q30_ONE, 30);
    if (fx_round_sat(&acc, 10, &e) != 0 || e > (1L << 30) || e < -(1L << 30)) {
        return (att_status)ATT_FX_E_RANGE;
    }
    c -= fx_mul(c, e, 51);
    s -= fx_mul(s, e, 51);

    /* vector part h = s·Φ/2 in Q1.31 (|h| ≤ sin(1.55) < 1), i.e. Q2.30 ×
     * Q2.30 → shift 30, rounded with dither: h = floor((s·Φ + D)/2^30),
     * D ∈ [0, 2^30) a hash of the low bits of Q (Knuth's multiplicative
     * hash). Plain rounding of h is biased for smooth motion: h differs
     * from the integer Φ by the tiny, slowly varying (s − 1)·Φ/2 term, so
     * its rounding error repeats step after step and the attitude drifts
     * linearly. With D uniform the rounding is unbiased (E[h] = s·Φ/2
     * exactly) and the error is white; deterministic, the same on every
     * target. */
    for (n = 0; n < 3; ++n) {
        uint32_t dk = (uint32_t)((uint32_t)q[n + 1] * (uint32_t)2654435761ul) >> 2;
        fx_zero(&acc);
        fx_mac(&acc, s, phi[n]);
        fx_add_shl(&acc, (int32_t)dk - (int32_t)0x20000000L, 0);
        h[n + 1] = fx_round(&acc, 30);
    }

    {
        int32_t r0, r1, r2, r3;
        fx_zero(&acc);
        fx_mac2(&acc, q[0], c);
        fx_msc(&acc, q[1], h[1]);
        fx_msc(&acc, q[2], h[2]);
        fx_msc(&acc, q[3], h[3]);
        r0 = fx_round(&acc, 31);
        fx_zero(&acc);
        fx_mac(&acc, q[0], h[1]);
        fx_mac2(&acc, q[1], c);
        fx_mac(&acc, q[2], h[3]);
        fx_msc(&acc, q[3], h[2]);
        r1 = fx_round(&acc, 31);
        fx_zero(&acc);
        fx_mac(&acc, q[0], h[2]);
        fx_msc(&acc, q[1], h[3]);
        fx_mac2(&acc, q[2], c);
        fx_mac(&acc, q[3], h[1]);
        r2 = fx_round(&acc, 31);
        fx_zero(&acc);
        fx_mac(&acc, q[0], h[3]);
        fx_mac(&acc, q[1], h[2]);
        fx_msc(&acc, q[2], h[1]);
        fx_mac2(&acc, q[3], c);
        r3 = fx_round(&acc, 31);
        q[0] = r0;
        q[1] = r1;
        q[2] = r2;
        q[3] = r3;
    }
    return ATT_OK;
}

att_status att_fx_update_phi(att_q30 q[4], const att_q30 phi[3])
{
    fx_acc acc;
    uint32_t n2;
    if (q == 0 || phi == 0) {
        return ATT_E_NULL;
    }
    /* |Φ|² ≤ 9.6: exact sum of squares (unsigned, < 3·2^62) in Q4.60,
     * rounded to Q?.24 (shift 36, ≤ 12·2^24) */
    fx_zero(&acc);
    fx_mac(&acc, phi[0], phi[0]);
    fx_mac(&acc, phi[1], phi[1]);
    fx_mac(&acc, phi[2], phi[2]);
    n2 = fx_round_u(&acc, 36);
    if (n2 > 161061274ul) { /* 9.6 · 2^24 */
        return (att_status)ATT_FX_E_RANGE;
    }
    return att_fx_apply_(q, phi);
}

att_status att_fx_update_rv3(att_q30 q[4], const att_q30 d[9])
{
    att_q30 phi[3];
    if (q == 0 || d == 0) {
        return ATT_E_NULL;
    }
    if (!att_fx_dtheta_ok_(d, 9)) {
        return (att_status)ATT_FX_E_RANGE;
    }
    att_fx_phi_rv3_(d, ATT_FX_K_RV3_13, ATT_FX_K_RV3_23, phi);
    return att_fx_apply_(q, phi);
}
