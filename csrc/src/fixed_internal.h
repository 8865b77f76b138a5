/*
 * Private declarations shared by the fixed-point sources (csrc/src/fixed*.c).
 */
#ifndef ATT_FIXED_INTERNAL_H
#define ATT_FIXED_INTERNAL_H

#include "attitude/fixed.h"

/* Method coefficients in Q2.30 (k = NUM/DEN of attitude/integrator.h,
 * rounded to nearest). */
#define ATT_FX_K_RV2        715827883L   /* 2/3 */
#define ATT_FX_K_RV3_13     442918502L   /* 33/80 */
#define ATT_FX_K_RV3_23     765041050L   /* 57/80 (= k12) */
#define ATT_FX_K_RV3C_13    483183821L   /* 9/20 */
#define ATT_FX_K_RV3C_23    724775731L   /* 27/40 (= k12) */
#define ATT_FX_K_RV3R_13    (-17895697L) /* -1/60 */
#define ATT_FX_K_RV3R_23    125269879L   /* 7/60 */
#define ATT_FX_K_RV3RP_12   1491308L     /* 1/720 */
#define ATT_FX_K_RV3RP_13   (-46230551L) /* -31/720 */
#define ATT_FX_K_RV3RP_23   180448279L   /* 121/720 */
#define ATT_FX_K_RV3R_START 89478485L    /* 1/12 */

/*
 * Dithered rounding. A rounding whose input varies slowly (the coning
 * correction of a steady motion, s·Φ/2 next to the integer Φ, ...) makes
 * the same error update after update, and the attitude drifts linearly
 * instead of as a random walk. The integrator therefore rounds the
 * rotation vector and the vector part of q(Φ) as floor((x + D)/2^n) with
 * D uniform in [0, 2^n) (unbiased: E = x exactly, error white, variance
 * ≤ 1/4 LSB²). D comes from a 32-bit hash of the attitude quaternion
 * (fx_dither_seed: XOR of the components through MurmurHash3's
 * finalizer, so attitudes a few LSB apart get unrelated values), rotated
 * by a different amount for each of the six roundings of an update
 * (FX_DITHER30(t, k) = top 30 bits of t rotated right by k): results are
 * deterministic and bit-identical on every target, and no state beyond Q
 * is needed. The seed is never 0; t == 0 gives plain
 * round-to-nearest (D = 2^29), used by the public att_fx_phi().
 */
#define FX_ROR(x, k)      ((uint32_t)(((x) >> (k)) | ((x) << (32u - (k)))))
#define FX_DITHER30(t, k) ((t) != 0u ? FX_ROR(t, k) >> 2 : 0x20000000ul)

uint32_t att__fx_dither_seed(const att_q30 q[4]);
#define fx_dither_seed att__fx_dither_seed

/* Domain of q(Φ): |Φ|² ≤ 9.6 rad². The check forms the exact sum of
 * squares (Q4.60, unsigned, < 3·2^62), rounds it to Q.24 (shift 36) and
 * compares with 9.6·2^24 rounded down. */
#define FX_PHI2_MAX_Q24 161061274ul

/* |x| > ATT_FX_DTHETA_MAX, one add and one unsigned compare */
#define FX_DBAD(x) \
    ((uint32_t)((uint32_t)(x) + (uint32_t)ATT_FX_DTHETA_MAX) > 2u * (uint32_t)ATT_FX_DTHETA_MAX)

/* (hi:lo) = x · y, unsigned 32 × 32 → 64 bits (fixed_adc.c) */
void att__fx_uprod(uint32_t x, uint32_t y, uint32_t *hi, uint32_t *lo);

/* 1 if every one of the n values satisfies |x| ≤ ATT_FX_DTHETA_MAX. */
int att__fx_dtheta_ok(const att_q30 *d, uint8_t n);

/* Φ = Δθ1 + Δθ2 + Δθ3 + (k13 Δθ1) × Δθ3 + (k23 Δθ2) × (Δθ3 − Δθ1)
 * (three-sample form with k12 = k23), inputs checked by the caller. */
void att__fx_phi_rv3(const att_q30 d[9], int32_t k13, int32_t k23, uint32_t t, att_q30 phi[3]);

/* Reuse forms with two previous increments: Φ = d3 + (k13 d1 + k23 d2) × d3,
 * plus (k12 d1) × d2 for the polynomial form (poly != 0); inputs checked by
 * the caller. */
void att__fx_phi_reuse(const att_q30 d1[3], const att_q30 d2[3], const att_q30 d3[3], uint8_t poly,
                       uint32_t t, att_q30 phi[3]);

/* c = cos(φ/2), s = sin(φ/2)/(φ/2) (Q2.30) for Φ with |Φ|² ≤ 9.6. */
void att__fx_cs(const att_q30 phi[3], int32_t *c, int32_t *s);

/* Q ← Q ⊗ q(Φ) with the folded renormalization; Φ checked by the caller
 * (|Φ|² ≤ 9.6). Returns ATT_FX_E_RANGE (q untouched) if |Q|² − 1 is
 * outside ±2^-20, i.e. q was not a unit quaternion of this module. */
att_status att__fx_apply(att_q30 q[4], const att_q30 phi[3], uint32_t t);

#endif /* ATT_FIXED_INTERNAL_H */
