/*
 * libattitude — private math helpers (not part of the public API).
 * Scalar-type dependent libm names and small static inline quaternion
 * helpers shared by quat.c and integrator.c.
 */
#ifndef ATT_SRC_MATH_H
#define ATT_SRC_MATH_H

#include <math.h>

#include "attitude/common.h"

#if defined(ATT_REAL_F32)
#define att_sqrt       sqrtf
#define att_sin        sinf
#define att_cos        cosf
#define att_atan2      atan2f
#define att_fabs       fabsf
#define ATT_GIMBAL_COS ((att_real)2.44140625e-4) /* 2^-12 ~ sqrt(FLT_EPSILON) */
#else
#define att_sqrt       sqrt
#define att_sin        sin
#define att_cos        cos
#define att_atan2      atan2
#define att_fabs       fabs
#define ATT_GIMBAL_COS ((att_real)1.4901161193847656e-8) /* 2^-26 = sqrt(DBL_EPSILON) */
#endif

#define ATT_R(x)   ((att_real)(x))
#define ATT_PI     ATT_R(3.14159265358979323846)
#define ATT_TWO_PI ATT_R(6.28318530717958647692)

/* Below this φ² the rotation-vector quaternion uses its Taylor series
 * (terms through φ⁸; truncation < 3e-17 at φ = 0.2 rad). */
#define ATT_ROTVEC_SERIES_PHI2 ATT_R(0.04)

static inline int att__finite3(const att_real v[3])
{
    return isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]);
}

static inline int att__finite4(const att_real v[4])
{
    return isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]) && isfinite(v[3]);
}

/* d = q(Φ) − [1, 0, 0, 0] = [cos(φ/2) − 1, sin(φ/2)/φ · Φ], the first
 * component computed without cancellation. */
static inline void att__rotvec_delta(const att_real phi[3], att_real d[4])
{
    att_real p2 = phi[0] * phi[0] + phi[1] * phi[1] + phi[2] * phi[2];
    att_real c1, s;
    if (p2 < ATT_ROTVEC_SERIES_PHI2) {
        c1 = p2
             * (ATT_R(-0.125)
                + p2 * (ATT_R(1.0 / 384.0) + p2 * (ATT_R(-1.0 / 46080.0) + p2 * ATT_R(1.0 / 10321920.0))));
        s = ATT_R(0.5)
            + p2
                  * (ATT_R(-1.0 / 48.0)
                     + p2
                           * (ATT_R(1.0 / 3840.0)
                              + p2 * (ATT_R(-1.0 / 645120.0) + p2 * ATT_R(1.0 / 185794560.0))));
    } else {
        att_real p = att_sqrt(p2);
        att_real s4 = att_sin(ATT_R(0.25) * p);
        att_real c4 = att_cos(ATT_R(0.25) * p);
        c1 = ATT_R(-2.0) * s4 * s4;
        s = ATT_R(2.0) * s4 * c4 / p;
    }
    d[0] = c1;
    d[1] = s * phi[0];
    d[2] = s * phi[1];
    d[3] = s * phi[2];
}

/* q ← q + q ⊗ d (d from att__rotvec_delta or the RK4 increment). */
static inline void att__quat_add_mul(att_real q[4], const att_real d[4])
{
    att_real a0 = q[0], a1 = q[1], a2 = q[2], a3 = q[3];
    q[0] = a0 + (a0 * d[0] - a1 * d[1] - a2 * d[2] - a3 * d[3]);
    q[1] = a1 + (a0 * d[1] + a1 * d[0] + a2 * d[3] - a3 * d[2]);
    q[2] = a2 + (a0 * d[2] - a1 * d[3] + a2 * d[0] + a3 * d[1]);
    q[3] = a3 + (a0 * d[3] + a1 * d[2] - a2 * d[1] + a3 * d[0]);
}

/* First-order renormalization q ← q (3 − |q|²)/2 (for |q| already ≈ 1). */
static inline void att__quat_renorm1(att_real q[4])
{
    att_real n2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
    att_real k = ATT_R(1.5) - ATT_R(0.5) * n2;
    q[0] *= k;
    q[1] *= k;
    q[2] *= k;
    q[3] *= k;
}

/* out += k · (a × b) */
static inline void att__cross_acc(att_real out[3], att_real k, const att_real a[3], const att_real b[3])
{
    out[0] += k * (a[1] * b[2] - a[2] * b[1]);
    out[1] += k * (a[2] * b[0] - a[0] * b[2]);
    out[2] += k * (a[0] * b[1] - a[1] * b[0]);
}

#endif /* ATT_SRC_MATH_H */
