/*
 * libattitude fixed point: the update kernel (rotation vector → quaternion,
 * quaternion product with folded renormalization, the rv3 rotation vector).
 * This file alone is what an rv3 update needs (its 8051 flash size is the
 * "rv3 alone" figure of docs/fixed-point.md). Integer-only.
 */
#include "attitude/fixed.h"

#include "fixed_internal.h"
#if defined(__SDCC) || defined(ATT_FX_COMPACT)
#define FX_PRIM_MINIMAL
#endif
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

uint32_t att_fx_dither_seed_(const att_q30 q[4])
{
    uint32_t x = (uint32_t)q[0] ^ (uint32_t)q[1] ^ (uint32_t)q[2] ^ (uint32_t)q[3];
    x ^= x >> 16;
    x *= 0x85EBCA6Bul;
    x ^= x >> 13;
    x *= 0xC2B2AE35ul;
    x ^= x >> 16;
    return (x != 0u) ? x : 1u; /* 0 would mean "no dither" */
}

int att_fx_dtheta_ok_(const att_q30 *d, uint8_t n)
{
    uint8_t i;
    for (i = 0; i < n; ++i) {
        if (FX_DBAD(d[i])) {
            return 0;
        }
    }
    return 1;
}

#if defined(__SDCC) || defined(ATT_FX_COMPACT)
/*
 * Compact build (the 8051; on a host with -DATT_FX_COMPACT for testing):
 * the same arithmetic, bit for bit, written for 128 bytes of RAM and a
 * few KB of flash. SDCC's default (non-reentrant) model makes every local
 * variable a static one anyway; here they are shared explicitly: one
 * 64-bit accumulator (fxa_hi:fxa_lo), the multiplier operands, and an
 * 8-word scratch fxs reused by the phases of an update. Loops over small
 * index tables instead of unrolled code; the caller's arrays are read
 * through one loader each (generic pointers are costly on the 8051). The
 * functions are not reentrant (no interrupt handler may call them).
 */
static uint32_t fxa_lo, fxa_hi;  /* accumulator (hi:lo), two's complement */
static int32_t fxa_x, fxa_y;     /* operands of fxa_mac */
static int32_t fxs[8];           /* scratch, see each function */
static const att_q30 *fx_dp;     /* increments of the update */
static att_q30 *fx_qp;           /* attitude being updated */
static uint32_t fx_t;            /* dither seed of the update (0: plain rounding) */

static int32_t fx_d(uint8_t i) { return fx_dp[i]; }
static int32_t fx_q(uint8_t i) { return fx_qp[i]; }

/* fxa += fxa_x · fxa_y: four 16 × 16 → 32-bit partial products, then the
 * two's-complement correction of the high word. */
static void fxa_mac(void)
{
    uint32_t p;
    uint16_t xl = (uint16_t)fxa_x, xh = (uint16_t)((uint32_t)fxa_x >> 16);
    uint16_t yl = (uint16_t)fxa_y, yh = (uint16_t)((uint32_t)fxa_y >> 16);
    p = (uint32_t)xl * yl;
    fxa_lo += p;
    if (fxa_lo < p) {
        fxa_hi++;
    }
    fxa_hi += (uint32_t)xh * yh;
    p = (uint32_t)xl * yh;
    fxa_hi += p >> 16;
    p <<= 16;
    fxa_lo += p;
    if (fxa_lo < p) {
        fxa_hi++;
    }
    p = (uint32_t)xh * yl;
    fxa_hi += p >> 16;
    p <<= 16;
    fxa_lo += p;
    if (fxa_lo < p) {
        fxa_hi++;
    }
    if (fxa_x < 0) {
        fxa_hi -= (uint32_t)fxa_y;
    }
    if (fxa_y < 0) {
        fxa_hi -= (uint32_t)fxa_x;
    }
}

static void fxa_set(uint32_t lo)
{
    fxa_lo = lo;
    fxa_hi = 0;
}

static void fxa_muladd(int32_t x, int32_t y)
{
    fxa_x = x;
    fxa_y = y;
    fxa_mac();
}

/* floor(fxa / 2^sh) for sh = 30 or 31 (low 32 bits) */
static int32_t fxa_floor(uint8_t sh)
{
    return fx_u2s((fxa_lo >> sh) | (fxa_hi << (32u - sh)));
}

/* round(x · y / 2^30) */
static int32_t fxa_mul30(int32_t x, int32_t y)
{
    fxa_set(0x20000000ul);
    fxa_muladd(x, y);
    return fxa_floor(30);
}

/* D of FX_DITHER30 for rotation k */
static uint32_t fxa_dither(uint8_t k)
{
    return FX_DITHER30(fx_t, k);
}

/* cross-product index pairs: component i uses j = (i+1)%3, k = (i+2)%3 */
static const uint8_t fx_j[3] = {1, 2, 0};
static const uint8_t fx_k[3] = {2, 0, 1};
static const uint8_t fx_rot[6] = {1, 11, 22, 6, 17, 27};

/* Φ of the increments at fx_dp (scratch: a = k13 Δθ1 in fxs[0..2],
 * b = k23 Δθ2 in fxs[3..5], Φ_0, Φ_1 in fxs[6], fxs[7] until the end;
 * the result in fxs[0..2]). */
static void fxc_phi_rv3(int32_t k13, int32_t k23)
{
    uint8_t i, j, k;
    for (i = 0; i < 3; ++i) {
        fxs[i] = fxa_mul30(k13, fx_d(i));
        fxs[3 + i] = fxa_mul30(k23, fx_d((uint8_t)(3 + i)));
    }
    for (i = 0; i < 3; ++i) {
        j = fx_j[i];
        k = fx_k[i];
        fxa_set(fxa_dither(fx_rot[i]));
        fxa_muladd(fxs[j], fx_d((uint8_t)(6 + k)));
        fxa_muladd(-fxs[k], fx_d((uint8_t)(6 + j)));
        fxa_muladd(fxs[3 + j], fx_d((uint8_t)(6 + k)) - fx_d(k));
        fxa_muladd(-fxs[3 + k], fx_d((uint8_t)(6 + j)) - fx_d(j));
        /* component 2 uses a0, a1, b0, b1 only: it may overwrite a2 */
        fxs[i < 2u ? 6u + i : 2u] = fx_d(i) + fx_d((uint8_t)(3 + i)) + fx_d((uint8_t)(6 + i))
                                    + fxa_floor(30);
    }
    fxs[0] = fxs[6];
    fxs[1] = fxs[7];
}

#ifndef ATT_FX_RV3_ONLY /* -DATT_FX_RV3_ONLY: att_fx_update_rv3 alone (8051 flash) */
void att_fx_phi_rv3_(const att_q30 d[9], int32_t k13, int32_t k23, uint32_t t, att_q30 phi[3])
{
    fx_dp = d;
    fx_t = t;
    fxc_phi_rv3(k13, k23);
    phi[0] = fxs[0];
    phi[1] = fxs[1];
    phi[2] = fxs[2];
}
#endif

/* c, s into fxs[3], fxs[4] for Φ in fxs[0..2] (v in fxs[5]) */
static void fxc_cs(void)
{
    int8_t n, deg;
    fxa_set(0);
    for (n = 0; n < 3; ++n) {
        fxa_muladd(fxs[n], fxs[n]);
    }
    fxs[5] = (int32_t)((fxa_hi + 1u) >> 1); /* round(Σ/2^33): the half is 2^32 */
    if (fxs[5] <= fx_deg_vmax[0]) {
        fxs[3] = (int32_t)ATT_FX_Q30_ONE - fxs[5];
        fxs[4] = (int32_t)ATT_FX_Q30_ONE - fxa_mul30(fxs[5], fx_sin_k[1]);
        return;
    }
    deg = 7;
    for (n = 1; n < 6; ++n) {
        if (fxs[5] <= fx_deg_vmax[n]) {
            deg = (int8_t)(n + 1);
            break;
        }
    }
    fxs[3] = fx_cos_k[deg];
    fxs[4] = fx_sin_k[deg];
    for (n = (int8_t)(deg - 1); n >= 0; --n) {
        fxs[3] = fx_cos_k[n] - fxa_mul30(fxs[5], fxs[3]);
        fxs[4] = fx_sin_k[n] - fxa_mul30(fxs[5], fxs[4]);
    }
}

#ifndef ATT_FX_RV3_ONLY
void att_fx_cs_(const att_q30 phi[3], int32_t *cp, int32_t *sp)
{
    fxs[0] = phi[0];
    fxs[1] = phi[1];
    fxs[2] = phi[2];
    fxc_cs();
    *cp = fxs[3];
    *sp = fxs[4];
}
#endif

/* rows of Q ⊗ [c, h] besides the 2·q_i·c term: output i adds
 * sign · q[fx_pq] · h[fx_ph] (signs as in the fast version) */
static const uint8_t fx_pq[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
static const uint8_t fx_ph[4][3] = {{0, 1, 2}, {0, 2, 1}, {1, 2, 0}, {2, 1, 0}};
static const uint8_t fx_pneg[4] = {7, 4, 2, 4}; /* bit k set: subtract term k */
static const uint8_t fx_res[3] = {4, 6, 7};

/* Q ← Q ⊗ q(Φ) for Q at fx_qp, Φ in fxs[0..2]. Scratch: h in fxs[0..2]
 * (over Φ), c then c2 in fxs[3], s in fxs[4] then r0, r1 and r2 in
 * fxs[6], fxs[7]; r3 goes straight to Q (Q is not read after it). */
static att_status fxc_apply(void)
{
    uint8_t i, k;
    fxc_cs();
    fxa_set(0);
    for (i = 0; i < 4; ++i) {
        fxa_muladd(fx_q(i), fx_q(i));
    }
    fxa_hi -= 0x10000000ul; /* − 2^60 */
    if ((uint32_t)(fxa_hi + 0x100u) >= 0x200u) { /* |e| ≥ 2^-20 */
        return (att_status)ATT_FX_E_RANGE;
    }
    /* e/2 = round(Σ/2^31): add 2^30 then floor */
    fxa_lo += 0x40000000ul;
    if (fxa_lo < 0x40000000ul) {
        fxa_hi++;
    }
    fxs[3] -= fxa_floor(31);
    fxs[3] = fx_u2s((uint32_t)fxs[3] * 2u - 0x80000000ul); /* c2 */
    for (i = 0; i < 3; ++i) {
        fxa_set(fxa_dither(fx_rot[3 + i]));
        fxa_muladd(fxs[4], fxs[i]);
        fxs[i] = fxa_floor(30);
    }
    for (i = 0; i < 4; ++i) {
        /* q_i·2^31 + 2^30 */
        fxa_lo = ((uint32_t)fx_q(i) << 31) | 0x40000000ul;
        fxa_hi = ((uint32_t)fx_q(i) >> 1) | ((uint32_t)fx_q(i) & 0x80000000ul);
        fxa_muladd(fx_q(i), fxs[3]);
        for (k = 0; k < 3; ++k) {
            int32_t hv = fxs[fx_ph[i][k]];
            fxa_muladd(fx_q(fx_pq[i][k]), (fx_pneg[i] >> k) & 1u ? -hv : hv);
        }
        if (i < 3u) {
            fxs[fx_res[i]] = fxa_floor(31);
        } else {
            fx_qp[3] = fxa_floor(31);
        }
    }
    for (i = 0; i < 3; ++i) {
        fx_qp[i] = fxs[fx_res[i]];
    }
    return ATT_OK;
}

#ifndef ATT_FX_RV3_ONLY
att_status att_fx_apply_(att_q30 q[4], const att_q30 phi[3], uint32_t t)
{
    fxs[0] = phi[0];
    fxs[1] = phi[1];
    fxs[2] = phi[2];
    fx_qp = q;
    fx_t = t;
    return fxc_apply();
}

att_status att_fx_update_phi(att_q30 q[4], const att_q30 phi[3])
{
    uint8_t n;
    if (q == 0 || phi == 0) {
        return ATT_E_NULL;
    }
    fxa_set(0);
    for (n = 0; n < 3; ++n) {
        fxa_muladd(phi[n], phi[n]);
    }
    /* |Φ|² ≤ 9.6: round(Σ/2^36) ≤ 161061274, i.e. (hi + 8) >> 4 */
    if (((fxa_hi + 8u) >> 4) > 161061274ul) {
        return (att_status)ATT_FX_E_RANGE;
    }
    return att_fx_apply_(q, phi, fx_dither_seed(q));
}
#endif

att_status att_fx_update_rv3(att_q30 q[4], const att_q30 d[9])
{
    if (q == 0 || d == 0) {
        return ATT_E_NULL;
    }
    if (!att_fx_dtheta_ok_(d, 9)) {
        return (att_status)ATT_FX_E_RANGE;
    }
    fx_dp = d;
    fx_qp = q;
    fx_t = fx_dither_seed(q);
    fxc_phi_rv3(ATT_FX_K_RV3_13, ATT_FX_K_RV3_23);
    return fxc_apply();
}

#else /* fast build: unrolled, 64-bit or halves primitive from fixed_prim.h */

/*
 * Three-sample rotation vector with k12 = k23 (rv3, rv3-coning):
 *   Φ = Δθ1 + Δθ2 + Δθ3 + a × Δθ3 + b × w,  a = k13 Δθ1, b = k23 Δθ2, w = Δθ3 − Δθ1
 * Inputs Q2.30 with |Δθ| ≤ 0.4: a, b rounded to Q2.30 (|a|, |b| ≤ 0.29),
 * w exact (|w| ≤ 0.8). Per component the four cross-product terms are
 * accumulated exactly in Q4.60 and rounded once to Q2.30 (shift 30), then
 * the exact integer sum is added (= one rounding of the exact total); |Φ_i| ≤ 3·0.4 + 2·0.29·0.4 + 2·0.29·0.8 = 1.9 < 2,
 * so no saturation is needed. Subtracted products use a negated operand
 * (one multiply-accumulate each).
 */
void att_fx_phi_rv3_(const att_q30 d[9], int32_t k13, int32_t k23, uint32_t t, att_q30 phi[3])
{
    int32_t a0, a1, a2, b0, b1, b2, w0, w1, w2, e0, e1, e2;
    fx_acc acc;
    a0 = fx_mul(k13, d[0], 30);
    a1 = fx_mul(k13, d[1], 30);
    a2 = fx_mul(k13, d[2], 30);
    b0 = fx_mul(k23, d[3], 30);
    b1 = fx_mul(k23, d[4], 30);
    b2 = fx_mul(k23, d[5], 30);
    e0 = d[6];
    e1 = d[7];
    e2 = d[8];
    w0 = e0 - d[0];
    w1 = e1 - d[1];
    w2 = e2 - d[2];

    /* round(S·2^30 + X) / 2^30 = S + round(X / 2^30) for an integer sum S
     * (dithered: floor((X + D) / 2^30), see FX_DITHER30) */
    fx_init_u(&acc, FX_DITHER30(t, 1u));
    fx_mac(&acc, a1, e2);
    fx_mac(&acc, -a2, e1);
    fx_mac(&acc, b1, w2);
    fx_mac(&acc, -b2, w1);
    phi[0] = d[0] + d[3] + e0 + fx_floor(&acc, 30);

    fx_init_u(&acc, FX_DITHER30(t, 11u));
    fx_mac(&acc, a2, e0);
    fx_mac(&acc, -a0, e2);
    fx_mac(&acc, b2, w0);
    fx_mac(&acc, -b0, w2);
    phi[1] = d[1] + d[4] + e1 + fx_floor(&acc, 30);

    fx_init_u(&acc, FX_DITHER30(t, 22u));
    fx_mac(&acc, a0, e1);
    fx_mac(&acc, -a1, e0);
    fx_mac(&acc, b0, w1);
    fx_mac(&acc, -b1, w0);
    phi[2] = d[2] + d[5] + e2 + fx_floor(&acc, 30);
}

/*
 * c = cos(φ/2), s = sin(φ/2)/(φ/2) (both Q2.30) for |Φ|² ≤ 9.6:
 *  1. v = |Φ|²/8: exact Q4.60 sum of squares (< 9.6·2^60 < 2^64, unsigned),
 *     rounded to Q2.30 (shift 33); v ≤ 1.2.
 *  2. Horner in v, Q2.30, one rounding per step (|partial sums| ≤ 1),
 *     degree from fx_deg_vmax (degree 1, v ≤ 2.6e-5 i.e. φ ≤ 0.0145 rad,
 *     is the common case and has a short path: c = 1 − v exactly).
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

    if (v <= fx_deg_vmax[0]) {
        *cp = (int32_t)ATT_FX_Q30_ONE - v;
        *sp = (int32_t)ATT_FX_Q30_ONE - fx_mul(v, fx_sin_k[1], 30);
        return;
    }
    deg = 7;
    for (n = 1; n < 6; ++n) {
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

/*
 * Q ← Q ⊗ q(Φ), renormalization folded into q:
 *  1-2. c, s from att_fx_cs_.
 *  3. e = |Q|² − 1: exact Q4.60 sum minus 2^60; |e| < 2^-20 is required
 *     (else ATT_FX_E_RANGE, Q untouched: Q was not a unit quaternion of
 *     this module); e/2 rounded to Q2.30 (shift 31).
 *  4. c ← c − e/2, so that |Q ⊗ q|² = (1 + e)(c² − c·e + |h|²) = 1 + O(e·(1 − c))
 *     + rounding: the norm error is removed at every update, without a
 *     separate normalization pass and without a second rounding of Q.
 *  5. h = s·Φ/2 in Q1.31 (|h| ≤ sin(1.55) < 1): Q2.30 × Q2.30 → shift 30,
 *     dithered rounding h = floor((s·Φ + D)/2^30) with D ∈ [0, 2^30) a
 *     hash of the low bits of Q (Knuth's multiplicative hash). Plain
 *     rounding of h is biased for smooth motion: h differs from the
 *     integer Φ by the tiny, slowly varying (s − 1)·Φ/2, so its rounding
 *     error repeats update after update and the attitude drifts linearly.
 *     With D uniform, E[h] = s·Φ/2 exactly and the error is white.
 *     Deterministic: the same bits on every target.
 *  6. Q ⊗ [c, h] in Q3.61: Q·h terms (Q2.30 × Q1.31) and Q·c twice
 *     (Q2.30 × Q2.30 = Q60, doubled); the exact sum of each component is
 *     bounded by |Q||q| ≈ 2^61 and rounded once to Q2.30 (shift 31).
 */
att_status att_fx_apply_(att_q30 q[4], const att_q30 phi[3], uint32_t t)
{
    fx_acc acc;
    int32_t c, c2, s, e, h1, h2, h3, q0, q1, q2, q3;

    att_fx_cs_(phi, &c, &s);
    q0 = q[0];
    q1 = q[1];
    q2 = q[2];
    q3 = q[3];

    fx_zero(&acc);
    fx_mac(&acc, q0, q0);
    fx_mac(&acc, q1, q1);
    fx_mac(&acc, q2, q2);
    fx_mac(&acc, q3, q3);
    fx_add_shl(&acc, -(int32_t)ATT_FX_Q30_ONE, 30);
    if (!fx_small(&acc, 40)) {
        return (att_status)ATT_FX_E_RANGE;
    }
    e = fx_round(&acc, 31);
    c -= e;

#define FX_H(hk, ROT, pk)                                                         \
    fx_init_u(&acc, FX_DITHER30(t, ROT));                                         \
    fx_mac(&acc, s, pk);                                                          \
    hk = fx_floor(&acc, 30)
    FX_H(h1, 6u, phi[0]);
    FX_H(h2, 17u, phi[1]);
    FX_H(h3, 27u, phi[2]);
#undef FX_H

    /* 2·Q_i·c = Q_i·2^31 + Q_i·c2 with c2 = 2c − 2^31 (fits int32: 0 ≤ c < 2^31);
     * the accumulator starts at Q_i·2^31 + 2^30 (the rounding half). */
    c2 = fx_u2s((uint32_t)c * 2u - 0x80000000ul);
    fx_init_shl31(&acc, q0);
    fx_mac(&acc, q0, c2);
    fx_mac(&acc, q1, -h1);
    fx_mac(&acc, q2, -h2);
    fx_mac(&acc, q3, -h3);
    q[0] = fx_floor(&acc, 31);

    fx_init_shl31(&acc, q1);
    fx_mac(&acc, q0, h1);
    fx_mac(&acc, q1, c2);
    fx_mac(&acc, q2, h3);
    fx_mac(&acc, q3, -h2);
    q[1] = fx_floor(&acc, 31);

    fx_init_shl31(&acc, q2);
    fx_mac(&acc, q0, h2);
    fx_mac(&acc, q1, -h3);
    fx_mac(&acc, q2, c2);
    fx_mac(&acc, q3, h1);
    q[2] = fx_floor(&acc, 31);

    fx_init_shl31(&acc, q3);
    fx_mac(&acc, q0, h3);
    fx_mac(&acc, q1, h2);
    fx_mac(&acc, q2, -h1);
    fx_mac(&acc, q3, c2);
    q[3] = fx_floor(&acc, 31);
    return ATT_OK;
}

att_status att_fx_update_phi(att_q30 q[4], const att_q30 phi[3])
{
    fx_acc acc;
    if (q == 0 || phi == 0) {
        return ATT_E_NULL;
    }
    /* |Φ|² ≤ 9.6: exact sum of squares (unsigned, < 3·2^62) in Q4.60,
     * rounded to Q?.24 (shift 36, ≤ 12·2^24) */
    fx_zero(&acc);
    fx_mac(&acc, phi[0], phi[0]);
    fx_mac(&acc, phi[1], phi[1]);
    fx_mac(&acc, phi[2], phi[2]);
    if (fx_round_u(&acc, 36) > 161061274ul) { /* 9.6 · 2^24 */
        return (att_status)ATT_FX_E_RANGE;
    }
    {
        uint32_t t = fx_dither_seed(q);
        return att_fx_apply_(q, phi, t);
    }
}

att_status att_fx_update_rv3(att_q30 q[4], const att_q30 d[9])
{
    att_q30 phi[3];
    uint32_t t;
    if (q == 0 || d == 0) {
        return ATT_E_NULL;
    }
    if (FX_DBAD(d[0]) || FX_DBAD(d[1]) || FX_DBAD(d[2]) || FX_DBAD(d[3]) || FX_DBAD(d[4])
        || FX_DBAD(d[5]) || FX_DBAD(d[6]) || FX_DBAD(d[7]) || FX_DBAD(d[8])) {
        return (att_status)ATT_FX_E_RANGE;
    }
    t = fx_dither_seed(q);
    att_fx_phi_rv3_(d, ATT_FX_K_RV3_13, ATT_FX_K_RV3_23, t, phi);
    return att_fx_apply_(q, phi, t);
}

#endif /* compact / fast */
