/*
 * libattitude fixed point: quaternion product and normalization, attitude
 * matrix, Euler angles and heading (CORDIC). Integer-only; formats,
 * rounding and saturation as documented in attitude/fixed.h and below.
 */
#include "attitude/fixed.h"

#include "fixed_internal.h"
#include "fixed_prim.h"

static int fx_quat_in_range(const att_q30 q[4])
{
    uint8_t i;
    for (i = 0; i < 4; ++i) {
        if (q[i] > (att_q30)ATT_FX_QUAT_MAX || q[i] < -(att_q30)ATT_FX_QUAT_MAX) {
            return 0;
        }
    }
    return 1;
}

/* Four products of |x|,|y| ≤ 1.25·2^30: |sum| ≤ 6.25·2^60 < 2^63, exact.
 * Each component rounded once (shift 30) with a range check. */
att_status att_fx_quat_mul(const att_q30 a[4], const att_q30 b[4], att_q30 out[4])
{
    fx_acc acc;
    int32_t r[4];
    if (a == 0 || b == 0 || out == 0) {
        return ATT_E_NULL;
    }
    if (!fx_quat_in_range(a) || !fx_quat_in_range(b)) {
        return (att_status)ATT_FX_E_RANGE;
    }
    fx_zero(&acc);
    fx_mac(&acc, a[0], b[0]);
    fx_msc(&acc, a[1], b[1]);
    fx_msc(&acc, a[2], b[2]);
    fx_msc(&acc, a[3], b[3]);
    if (fx_round_sat(&acc, 30, &r[0]) != 0) {
        return (att_status)ATT_FX_E_RANGE;
    }
    fx_zero(&acc);
    fx_mac(&acc, a[0], b[1]);
    fx_mac(&acc, a[1], b[0]);
    fx_mac(&acc, a[2], b[3]);
    fx_msc(&acc, a[3], b[2]);
    if (fx_round_sat(&acc, 30, &r[1]) != 0) {
        return (att_status)ATT_FX_E_RANGE;
    }
    fx_zero(&acc);
    fx_mac(&acc, a[0], b[2]);
    fx_msc(&acc, a[1], b[3]);
    fx_mac(&acc, a[2], b[0]);
    fx_mac(&acc, a[3], b[1]);
    if (fx_round_sat(&acc, 30, &r[2]) != 0) {
        return (att_status)ATT_FX_E_RANGE;
    }
    fx_zero(&acc);
    fx_mac(&acc, a[0], b[3]);
    fx_mac(&acc, a[1], b[2]);
    fx_msc(&acc, a[2], b[1]);
    fx_mac(&acc, a[3], b[0]);
    if (fx_round_sat(&acc, 30, &r[3]) != 0) {
        return (att_status)ATT_FX_E_RANGE;
    }
    out[0] = r[0];
    out[1] = r[1];
    out[2] = r[2];
    out[3] = r[3];
    return ATT_OK;
}

/* q(Φ) = [c, s·Φ/2]: c, s from att__fx_cs (Horner in v = φ²/8), vector
 * part Q2.30 × Q2.30 → shift 31. |Φ|² > 9.6 → ATT_FX_E_RANGE. */
att_status att_fx_rotvec_to_quat(const att_q30 phi[3], att_q30 q[4])
{
    int32_t c, s;
    if (phi == 0 || q == 0) {
        return ATT_E_NULL;
    }
    if (!fx_phi_in_range(phi, FX_PHI2_MAX_Q24)) {
        return (att_status)ATT_FX_E_RANGE;
    }
    att__fx_cs(phi, &c, &s);
    q[1] = fx_mul(s, phi[0], 31);
    q[2] = fx_mul(s, phi[1], 31);
    q[3] = fx_mul(s, phi[2], 31);
    q[0] = c;
    return ATT_OK;
}

/* One first-order normalization step q ← q (1 − (|q|² − 1)/2) for
 * |q|² − 1 within ±2^-20 (Q2.50 error term, shift 51). */
static void fx_norm_step(att_q30 q[4])
{
    fx_acc acc;
    int32_t e;
    uint8_t i;
    fx_zero(&acc);
    for (i = 0; i < 4; ++i) {
        fx_mac(&acc, q[i], q[i]);
    }
    fx_add_shl(&acc, -(int32_t)ATT_FX_Q30_ONE, 30);
    e = fx_round(&acc, 10);
    for (i = 0; i < 4; ++i) {
        q[i] -= fx_mul(q[i], e, 51);
    }
}

/*
 * Normalization without division:
 *  1. scale q by 2^j (exact) so that max|q_i| ∈ [2^29, 1.25·2^30]: |q| ∈ [0.5, 2.5);
 *  2. m = |q|² (exact Q4.60 sum, rounded to Q4.28), reduced to [1, 4) by
 *     a factor 4^i, i ∈ {−1, 0, 1};
 *  3. r = 1/√m by Newton r ← r (3 − m r²)/2 (Q2.30, 6 steps from 0.85 or
 *     0.6: relative error < 2^-28);
 *  4. out = q · r · 2^i (shift 30 − i), then one first-order step against
 *     the exact 64-bit norm (fx_norm_step): within 2 LSB of unit.
 */
att_status att_fx_quat_normalize(const att_q30 q[4], att_q30 out[4])
{
    att_q30 t[4];
    uint32_t mx = 0, a;
    uint8_t i, j = 0, k;
    int8_t e2 = 0;
    int32_t m, r;
    fx_acc acc;
    if (q == 0 || out == 0) {
        return ATT_E_NULL;
    }
    if (!fx_quat_in_range(q)) {
        return (att_status)ATT_FX_E_RANGE;
    }
    for (i = 0; i < 4; ++i) {
        a = (q[i] < 0) ? (uint32_t)(-q[i]) : (uint32_t)q[i];
        if (a > mx) {
            mx = a;
        }
    }
    if (mx == 0u) {
        return (att_status)ATT_FX_E_ZERO;
    }
    while (mx < 0x20000000ul) {
        mx <<= 1;
        ++j;
    }
    fx_zero(&acc);
    for (i = 0; i < 4; ++i) {
        /* |q_i|·2^j ≤ 1.25·2^30: exact */
        t[i] = (q[i] < 0) ? -(att_q30)((uint32_t)(-q[i]) << j) : (att_q30)((uint32_t)q[i] << j);
        fx_mac(&acc, t[i], t[i]);
    }
    m = (int32_t)fx_round_u(&acc, 32); /* Q4.28, [0.25, 6.25) */
    if (m < (int32_t)ATT_FX_Q28_ONE) {
        m <<= 2;
        e2 = 1;
    } else if (m >= 4L * (int32_t)ATT_FX_Q28_ONE) {
        m = fx_asr(m + 2, 2);
        e2 = -1;
    }
    r = (m < 2L * (int32_t)ATT_FX_Q28_ONE) ? 912680550L /* 0.85 */ : 644245094L /* 0.6 */;
    for (k = 0; k < 6; ++k) {
        int32_t r2 = fx_mul(r, r, 30);                                /* Q2.30, ≤ 1 */
        int32_t g = 3L * (int32_t)ATT_FX_Q28_ONE - fx_mul(m, r2, 30); /* Q4.28 */
        r = fx_mul(r, g, 29);                                         /* Q2.30 × Q4.28 / 2 */
    }
    for (i = 0; i < 4; ++i) {
        t[i] = fx_mul(t[i], r, (uint8_t)(30 - e2));
    }
    fx_norm_step(t);
    for (i = 0; i < 4; ++i) {
        out[i] = t[i];
    }
    return ATT_OK;
}

/* Off-diagonal element 2(q_a1 q_b1 ± q_a2 q_b2) (minus if neg): exact Q4.60
 * sum, shift 29, range-checked. Returns 0 or -1. */
static int fx_off(const att_q30 q[4], uint8_t a1, uint8_t b1, uint8_t a2, uint8_t b2, uint8_t neg,
                  int32_t *out)
{
    fx_acc acc;
    fx_zero(&acc);
    fx_mac(&acc, q[a1], q[b1]);
    if (neg) {
        fx_msc(&acc, q[a2], q[b2]);
    } else {
        fx_mac(&acc, q[a2], q[b2]);
    }
    return fx_round_sat(&acc, 29, out);
}

/* Eq. (1). Diagonal: Q4.60 sum of four squares → shift 30; off-diagonal:
 * 2(ab ± cd) → shift 29. Sums ≤ 6.25·2^60, exact; elements range-checked. */
att_status att_fx_quat_to_dcm(const att_q30 q[4], att_q30 C[9])
{
    fx_acc acc;
    int32_t r[9];
    uint8_t i;
    if (q == 0 || C == 0) {
        return ATT_E_NULL;
    }
    if (!fx_quat_in_range(q)) {
        return (att_status)ATT_FX_E_RANGE;
    }
    /* diagonal */
    for (i = 0; i < 3; ++i) {
        uint8_t k;
        fx_zero(&acc);
        fx_mac(&acc, q[0], q[0]);
        for (k = 1; k <= 3; ++k) {
            if (k == i + 1u) {
                fx_mac(&acc, q[k], q[k]);
            } else {
                fx_msc(&acc, q[k], q[k]);
            }
        }
        if (fx_round_sat(&acc, 30, &r[4u * i]) != 0) {
            return (att_status)ATT_FX_E_RANGE;
        }
    }
    if (fx_off(q, 1, 2, 0, 3, 1, &r[1]) != 0       /* C12 = 2(p1p2 − λp3) */
        || fx_off(q, 1, 3, 0, 2, 0, &r[2]) != 0    /* C13 = 2(p1p3 + λp2) */
        || fx_off(q, 1, 2, 0, 3, 0, &r[3]) != 0    /* C21 = 2(p1p2 + λp3) */
        || fx_off(q, 2, 3, 0, 1, 1, &r[5]) != 0    /* C23 = 2(p2p3 − λp1) */
        || fx_off(q, 1, 3, 0, 2, 1, &r[6]) != 0    /* C31 = 2(p1p3 − λp2) */
        || fx_off(q, 2, 3, 0, 1, 0, &r[7]) != 0) { /* C32 = 2(p2p3 + λp1) */
        return (att_status)ATT_FX_E_RANGE;
    }
    for (i = 0; i < 9; ++i) {
        C[i] = r[i];
    }
    return ATT_OK;
}

/* CORDIC arctangent table: atan(2^-i) as binary angles (2^32 = 2π), rounded. */
static const uint32_t fx_atan_bam[30] = { 536870912ul, 316933406ul, 167458907ul, 85004756ul, 42667331ul,
                                          21354465ul,  10679838ul,  5340245ul,   2670163ul,  1335087ul,
                                          667544ul,    333772ul,    166886ul,    83443ul,    41722ul,
                                          20861ul,     10430ul,     5215ul,      2608ul,     1304ul,
                                          652ul,       326ul,       163ul,       81ul,       41ul,
                                          20ul,        10ul,        5ul,         3ul,        1ul };

/*
 * CORDIC vectoring: angle of (x, y) as a binary angle (uint32, 2^32 = 2π)
 * and, if mag != 0, the magnitude √(x² + y²) in the scale of x and y
 * (rounded; the gain 1/K = 0.6072529350 applied as a Q2.30 product).
 * The inputs are first scaled by 2^sh so that max(|x|, |y|) ∈ [2^28, 2^29)
 * (the gain K ≈ 1.647 times √2 then stays below 2^31); a left-half-plane
 * vector is turned by π first; 30 iterations with arithmetic shifts.
 */
static uint32_t fx_cordic(int32_t x, int32_t y, int32_t *mag)
{
    uint32_t ax = (x < 0) ? 0u - (uint32_t)x : (uint32_t)x;
    uint32_t ay = (y < 0) ? 0u - (uint32_t)y : (uint32_t)y;
    uint32_t mx = (ax > ay) ? ax : ay;
    uint32_t z = 0;
    int8_t sh = 0;
    uint8_t i;
    int32_t xs, ys;
    if (mx == 0u) {
        if (mag != 0) {
            *mag = 0;
        }
        return 0;
    }
    while (mx >= 0x20000000ul) {
        mx >>= 1;
        --sh;
    }
    while (mx < 0x10000000ul) {
        mx <<= 1;
        ++sh;
    }
    if (sh < 0) { /* |x|,|y| < 2^31: shifting right by 1..3, rounding down */
        xs = fx_asr(x, (uint8_t)(-sh));
        ys = fx_asr(y, (uint8_t)(-sh));
    } else {
        xs = (x < 0) ? -(int32_t)(ax << sh) : (int32_t)(ax << sh);
        ys = (y < 0) ? -(int32_t)(ay << sh) : (int32_t)(ay << sh);
    }
    if (xs < 0) {
        xs = -xs;
        ys = -ys;
        z = 0x80000000ul;
    }
    for (i = 0; i < 30; ++i) {
        int32_t dx = fx_asr(ys, i), dy = fx_asr(xs, i);
        if (ys > 0) {
            xs += dx;
            ys -= dy;
            z += fx_atan_bam[i];
        } else {
            xs -= dx;
            ys += dy;
            z -= fx_atan_bam[i];
        }
    }
    if (mag != 0) {
        *mag = fx_mul(xs, 652032874L, (uint8_t)(30 + sh)); /* 1/K in Q2.30 */
    }
    if (y == 0) { /* on the x axis: exact, and atan2(0, x < 0) = +π, not −π */
        z = (x < 0) ? 0x80000000ul : 0u;
    }
    return z;
}

/* binary angle (2^32 = 2π) → Q4.28 rad in (−π, π]: × π/8 (Q0.32: 1686629713). */
static att_q28 fx_bam_to_rad(uint32_t z)
{
    int32_t s = fx_u2s(z);
    if (s == (-2147483647L - 1L)) {
        return 843314857L; /* +π */
    }
    return fx_mul(s, 1686629713L, 32);
}

att_q28 att_fx_atan2(int32_t y, int32_t x)
{
    return fx_bam_to_rad(fx_cordic(x, y, 0));
}

att_status att_fx_dcm_to_euler(const att_q30 C[9], att_q28 e[3])
{
    int32_t r;
    uint32_t psi, th, ga;
    if (C == 0 || e == 0) {
        return ATT_E_NULL;
    }
    psi = fx_cordic(C[4], fx_u2s(0u - (uint32_t)C[1]), &r); /* ψ = atan2(−C12, C22) */
    th = fx_cordic(r, C[7], 0);                             /* θ = atan2(C32, cos θ) */
    if (r < (int32_t)ATT_FX_GIMBAL_Q30) {
        ga = 0;
        psi = fx_cordic(C[0], C[3], 0); /* ψ = atan2(C21, C11) */
    } else {
        ga = fx_cordic(C[8], fx_u2s(0u - (uint32_t)C[6]), 0); /* γ = atan2(−C31, C33) */
    }
    e[0] = fx_bam_to_rad(psi);
    e[1] = fx_bam_to_rad(th);
    e[2] = fx_bam_to_rad(ga);
    return ATT_OK;
}

att_status att_fx_quat_to_euler(const att_q30 q[4], att_q28 e[3])
{
    att_q30 C[9];
    att_status st;
    if (q == 0 || e == 0) {
        return ATT_E_NULL;
    }
    st = att_fx_quat_to_dcm(q, C);
    if (st != ATT_OK) {
        return st;
    }
    return att_fx_dcm_to_euler(C, e);
}

att_status att_fx_quat_heading(const att_q30 q[4], att_q28 *heading)
{
    att_q28 e[3];
    att_status st;
    if (q == 0 || heading == 0) {
        return ATT_E_NULL;
    }
    st = att_fx_quat_to_euler(q, e);
    if (st != ATT_OK) {
        return st;
    }
    /* (−ψ) mod 2π: ψ ∈ (−π, π] so −ψ ∈ [−π, π); 2π in Q4.28 = 1686629713 */
    *heading = (e[0] > 0) ? 1686629713L - e[0] : -e[0];
    if (*heading >= 1686629713L) {
        *heading = 0;
    }
    return ATT_OK;
}
