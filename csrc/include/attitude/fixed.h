/*
 * libattitude — fixed-point attitude core (prefix att_fx_), integer-only.
 *
 * The same methods as the float integrator (attitude/integrator.h) in
 * Q-format integer arithmetic, for cores without an FPU (ARM920T) and for
 * the 8051 (AT89S51; SDCC, no `long long`). No float anywhere: the
 * compiled objects reference no soft-float helper. See docs/fixed-point.md
 * for the derivation of the formats, the rounding-noise limit and the
 * measured accuracy.
 *
 * Q formats (CMSIS notation Qm.n: m integer bits including the sign, n
 * fractional bits, stored in int32_t):
 *
 *   name        format  LSB            range            used for
 *   att_q30     Q2.30   2^-30 ≈ 9.3e-10 [-2, 2)         quaternion, attitude matrix,
 *                                                        angle increments Δθ (rad),
 *                                                        rotation vector Φ (rad)
 *   att_q28     Q4.28   2^-28 ≈ 3.7e-9  [-8, 8)         Euler angles and heading (rad)
 *
 *   (Q2.30 = "Q1.30" in TI notation: 1 sign bit, 1 integer bit, 30 fraction bits.)
 *
 * Dynamic range: an increment component may not exceed ATT_FX_DTHETA_MAX
 * = 0.4 rad (2292 °/s at 100 Hz; the design point is ±1000 °/s at 100 Hz
 * = 0.175 rad, and 10 kHz gives 1e-4 rad for 1 rad/s = 107374 LSB).
 * With that bound every intermediate of every method provably fits its
 * format (docs/fixed-point.md, "Headroom"); larger increments return
 * ATT_FX_E_RANGE and never wrap.
 *
 * Rounding: every narrowing step is round-to-nearest, ties toward +inf
 * (add half an LSB, then floor), applied once to an exact 64-bit sum of
 * 32×32-bit products — except two steps of the integrator update (the
 * rotation vector and the vector part of q(Φ)), which are rounded with a
 * deterministic dither (floor((x + D)/2^n), D a hash of the attitude):
 * unbiased, so a steady motion does not turn their rounding error into a
 * linear drift (docs/fixed-point.md, "Dithered rounding").
 * Saturation: functions whose output could leave its format check it and
 * return ATT_FX_E_RANGE (outputs untouched) instead of saturating
 * silently; documented per function.
 *
 * Widening product: one primitive (csrc/src/fixed_prim.h), a 64-bit
 * product on cores with a long multiply (host, ARM SMULL/SMLAL), four
 * 16×16-bit partial products without a 64-bit type (-DATT_FX_FORCE_HALVES),
 * and in the 8051 update kernel 8×8-bit products (MUL AB); all give
 * bit-identical results (tested).
 *
 * Quaternions are [λ, p1, p2, p3] (docs/conventions.md); matrices are
 * row-major C[3*i + j]; Euler angles e = [yaw ψ, pitch θ, roll γ].
 */
#ifndef ATTITUDE_FIXED_H
#define ATTITUDE_FIXED_H

#include "attitude/common.h"

ATT_API_BEGIN

typedef int32_t att_q30; /* Q2.30 */
typedef int32_t att_q28; /* Q4.28 */

/* Constants (enums, so that Python sees them too). */
enum {
    ATT_FX_Q30_ONE = 1073741824,   /* 1.0 in Q2.30 */
    ATT_FX_Q28_ONE = 268435456,    /* 1.0 in Q4.28 */
    ATT_FX_DTHETA_MAX = 429496730, /* 0.4 rad in Q2.30: largest |Δθ| component accepted */
    ATT_FX_QUAT_MAX = 1342177280,  /* 1.25 in Q2.30: largest |component| of an input
                                       quaternion (keeps 4-term 64-bit sums exact) */
    ATT_FX_GIMBAL_Q30 = 16         /* 2^-26 in Q2.30: cos θ below this = gimbal lock */
};

/* Methods: the same numbers as att_method of attitude/integrator.h (5,
 * rk4, has no fixed-point port). */
typedef enum {
    ATT_FX_RV1 = 0,           /* Φ = Δθ, one update per increment */
    ATT_FX_RV2 = 1,           /* Φ = Δθ1 + Δθ2 + (2/3) Δθ1×Δθ2, one update per 2 increments */
    ATT_FX_RV3 = 2,           /* paper eq. (5), 33/80 and 57/80, one update per 3 increments */
    ATT_FX_RV3_CONING = 3,    /* 9/20 and 27/40 (Ignagni), one update per 3 increments */
    ATT_FX_RV3_REUSE = 4,     /* one update per increment, coning-optimal: Φ = Δθ3 +
                                  (7/60) Δθ2×Δθ3 − (1/60) Δθ1×Δθ3 (Δθ3 newest) */
    ATT_FX_RV3_REUSE_POLY = 6 /* one update per increment: Φ = Δθ3 + (1/720) Δθ1×Δθ2
                                  − (31/720) Δθ1×Δθ3 + (121/720) Δθ2×Δθ3.
                                  Both reuse forms: 2nd update Φ = Δθ2 + (1/12) Δθ1×Δθ2,
                                  1st Φ = Δθ1 */
} att_fx_method;

/* Fixed-point status codes (range -80..-99). */
enum {
    ATT_FX_E_RANGE = -80,  /* an input or result outside its Q format's documented range */
    ATT_FX_E_METHOD = -81, /* unknown method */
    ATT_FX_E_ZERO = -82    /* zero (or too small to normalize) quaternion */
};

/* att_fx_integ_update() results. */
enum {
    ATT_FX_PENDING = 0, /* increment buffered, no new attitude yet */
    ATT_FX_UPDATED = 1  /* a new attitude was written */
};

/* Caller-owned integrator state (55 bytes on the 8051). Treat as opaque. */
typedef struct {
    att_q30 q[4];   /* attitude quaternion, Q2.30, |q| = 1 within ±4 LSB */
    att_q30 buf[9]; /* 3 increments (3 values each): rv2/rv3: those of the unfinished
                              update, oldest first (the last one is scratch); reuse forms:
                              the two previous increments, increment `old` the older;
                              Q2.30 rad */
    uint8_t method; /* att_fx_method */
    uint8_t nbuf;   /* valid entries of buf */
    uint8_t old;    /* reuse forms: index of the older increment (0 or 1) */
} att_fx_integ;

/* ADC-code → increment converter (per axis), set up by att_fx_adc_init. */
typedef struct {
    int32_t zero_q8[3]; /* zero-rate code, Q24.8 (code × 256) */
    int32_t gain[3];    /* gain mantissa in [2^30, 2^31) */
    uint8_t shift[3];   /* Δθ(Q2.30) = round((code·256 − zero_q8) · gain / 2^shift) */
} att_fx_adc;

/* ---- primitives ------------------------------------------------------ */

/* out = a ⊗ b. In/out Q2.30; 4-term sums exact in 64 bits (Q4.60), one
 * rounding per component. |a_i|, |b_i| ≤ ATT_FX_QUAT_MAX else
 * ATT_FX_E_RANGE; a result component outside Q2.30 → ATT_FX_E_RANGE
 * (only possible for non-unit inputs). out may alias a or b. */
att_status att_fx_quat_mul(const att_q30 a[4], const att_q30 b[4], att_q30 out[4]);

/* out = q / |q| without division: exact power-of-two prescale, Newton
 * iteration for 1/√(Σq²) (Q2.30, from the exact 64-bit sum rounded to
 * Q4.28), product, then one first-order step against the exact norm;
 * result within 2 LSB of q/|q|. |q_i| ≤ ATT_FX_QUAT_MAX else
 * ATT_FX_E_RANGE; q = 0 → ATT_FX_E_ZERO (any other q is normalized; its
 * direction is only as precise as its integers). */
att_status att_fx_quat_normalize(const att_q30 q[4], att_q30 out[4]);

/* Rotation vector Φ (Q2.30 rad, |Φ| ≤ 3.1, |Φ_i| < 2) → q(Φ) = [cos(φ/2),
 * sin(φ/2)/φ · Φ] (Q2.30). Series in v = φ²/8 (Q2.30, Horner, degree
 * chosen from v so the truncation is < 2^-33; no division, no sqrt).
 * |Φ|² > 9.6 → ATT_FX_E_RANGE. Error (tested): ≤ 0.5 LSB + the Horner
 * error bound Σ v^k · (1 + |Φ|/2) LSB; measured ≤ 1.1 LSB for |Φ| ≤ 2 rad,
 * 3.1 LSB up to 3.1 rad. */
att_status att_fx_rotvec_to_quat(const att_q30 phi[3], att_q30 q[4]);

/* Rotation vector of one update from increments (all Q2.30 rad,
 * |Δθ_i| ≤ ATT_FX_DTHETA_MAX else ATT_FX_E_RANGE). Sum and cross
 * products accumulated exactly in 64 bits (the coefficient first
 * multiplied into the older increment, rounded to Q2.30), one rounding
 * per component. d holds n×3 values oldest first: n = 1 (rv1), 2 (rv2),
 * 3 (rv3 / rv3-coning), and for the reuse forms n = 1, 2 or 3 (start-up
 * forms included). */
att_status att_fx_phi(att_fx_method method, const att_q30 *d, uint8_t n, att_q30 phi[3]);

/* One rv3 update Q ← Q ⊗ q(Φ) with Φ of eq. (5) from d = [Δθ1, Δθ2, Δθ3]
 * (9 values, Q2.30, each |Δθ_i| ≤ ATT_FX_DTHETA_MAX else ATT_FX_E_RANGE).
 * Renormalization folded in: the scalar part of q(Φ) is lowered by
 * (|Q|² − 1)/2 before the product, so |Q| stays within ±4 LSB of 1
 * (measured ≤ 1.7) with no extra rounding of Q. Q must be a unit
 * quaternion within 2^-20 (else ATT_FX_E_RANGE, Q untouched). On the 8051
 * (SDCC) this is the compact, non-reentrant build of the same arithmetic
 * (AT89S51: 2.5 KB code, 64 bytes of static RAM, d may be in code memory);
 * -DATT_FX_RV3_ONLY leaves only this update in fixed_rv.c. */
att_status att_fx_update_rv3(att_q30 q[4], const att_q30 d[9]);

/* One update of a reuse form (method ATT_FX_RV3_REUSE or
 * ATT_FX_RV3_REUSE_POLY, else ATT_FX_E_METHOD) from d = [Δθk−2, Δθk−1,
 * Δθk] (9 values, Q2.30, oldest first; each |Δθ_i| ≤ ATT_FX_DTHETA_MAX
 * else ATT_FX_E_RANGE, Q untouched): Q ← Q ⊗ q(Φ) with the method's Φ,
 * bit for bit the update att_fx_integ_update makes from the third
 * increment on (the caller keeps the three-increment window; the first two
 * updates after a start need the start-up forms of att_fx_integ_update).
 * Q as for att_fx_update_rv3. On the
 * 8051 the compact, non-reentrant build (-DATT_FX_REUSE_ONLY leaves only
 * this update in fixed_rv.c). */
att_status att_fx_update_reuse(att_q30 q[4], const att_q30 d[9], att_fx_method method);

/* The same update for any method from its Φ (Q2.30 rad, |Φ|² ≤ 9.6). */
att_status att_fx_update_phi(att_q30 q[4], const att_q30 phi[3]);

/* ---- integrator ------------------------------------------------------ */

/* Initialize with attitude q0 (Q2.30, NULL = identity; normalized here). */
att_status att_fx_integ_init(att_fx_integ *s, att_fx_method method, const att_q30 q0[4]);

/* Feed one increment (Q2.30 rad). ATT_FX_UPDATED (q_out, may be NULL,
 * receives the attitude), ATT_FX_PENDING, or ATT_FX_E_RANGE (state
 * unchanged). */
int att_fx_integ_update(att_fx_integ *s, const att_q30 dtheta[3], att_q30 q_out[4]);

/* Number of attitude updates n more increments would produce. */
size_t att_fx_integ_outputs(const att_fx_integ *s, size_t n);

/* n increments (n×3 values) exactly as n att_fx_integ_update calls; q_out
 * gets 4 values per completed update (room for att_fx_integ_outputs(s, n)),
 * *n_out their number. All increments are checked first: on
 * ATT_FX_E_RANGE the state is unchanged, *err_index = first bad sample,
 * *n_out = 0. n_out, err_index may be NULL. */
att_status att_fx_integ_batch(att_fx_integ *s, const att_q30 *dtheta, size_t n, att_q30 *q_out, size_t *n_out,
                              size_t *err_index);

/* ---- attitude outputs ------------------------------------------------ */

/* Attitude matrix of eq. (1), Q2.30, row-major. Each element an exact
 * 64-bit sum rounded once. |q_i| ≤ ATT_FX_QUAT_MAX else ATT_FX_E_RANGE;
 * an element outside Q2.30 (non-unit q) → ATT_FX_E_RANGE. */
att_status att_fx_quat_to_dcm(const att_q30 q[4], att_q30 C[9]);

/* Euler angles e = [ψ, θ, γ] (Q4.28 rad) of C (Q2.30): 32-bit CORDIC
 * vectoring (30 iterations, angles accumulated as binary angles, 2^32 =
 * 2π), θ = atan2(C32, √(C12² + C22²)), γ = atan2(−C31, C33),
 * ψ = atan2(−C12, C22); ψ, γ in (−π, π]. Gimbal lock (√(C12² + C22²) <
 * ATT_FX_GIMBAL_Q30): γ = 0, ψ = atan2(C21, C11). Error < 1.2e-7 rad
 * (30 truncating shifts of a vector ≥ 2^28 long; measured 2e-8), roll
 * relative to cos θ. */
att_status att_fx_dcm_to_euler(const att_q30 C[9], att_q28 e[3]);

/* Euler angles of a quaternion (via the matrix). */
att_status att_fx_quat_to_euler(const att_q30 q[4], att_q28 e[3]);

/* Heading (−ψ) mod 2π in [0, 2π), Q4.28 rad, from a quaternion. */
att_status att_fx_quat_heading(const att_q30 q[4], att_q28 *heading);

/* Four-quadrant arctangent atan2(y, x) in Q4.28 rad, (−π, π]; x, y any
 * int32 in the same scale; atan2(0, 0) = 0. */
att_q28 att_fx_atan2(int32_t y, int32_t x);

/* ---- ADC codes → increments (fixed_adc.c; set-up in fixed_adc_init.c) -- */

/* Set up the converter: zero-rate code (Q24.8, code × 256), scale factor
 * (UQ0.32 rad/s per code, i.e. scale × 2^32, must be > 0) and sample
 * period (ns, > 0), per axis for zero and scale. The gain scale·period is
 * formed exactly (64-bit product, long division by 10^9) and kept as a
 * 31-bit mantissa and shift (relative error ≤ 2^-31). ATT_E_ARG for a
 * zero scale/period; ATT_FX_E_RANGE if the gain is too large (> 2^8
 * rad per code) or too small (< 2^-40 rad per code). */
att_status att_fx_adc_init(att_fx_adc *a, const int32_t zero_q8[3], const uint32_t scale_q32[3],
                           uint32_t period_ns);

/* Δθ_i = (code_i − zero_i) · scale_i · period, Q2.30 rad, rounded to
 * nearest (one rounding of an exact 64-bit product). |Δθ_i| >
 * ATT_FX_DTHETA_MAX → ATT_FX_E_RANGE (dtheta untouched). code_i ≤ 65535. */
att_status att_fx_adc_convert(const att_fx_adc *a, const uint16_t code[3], att_q30 dtheta[3]);

ATT_API_END

#endif /* ATTITUDE_FIXED_H */
