/*
 * libattitude — private helpers of the aiding solvers (aiding_*.c); not
 * part of the public API.
 */
#ifndef ATT_SRC_AIDING_INTERNAL_H
#define ATT_SRC_AIDING_INTERNAL_H

#include "att_math.h"
#include "attitude/aiding.h"

#define ATT_AID_TINY    ATT_R(1e-30)
#define ATT_AID_MIN_SIN (ATT_R(ATT_AID_MIN_SIN_PPM) * ATT_R(1e-6))

/* u = v / |v| computed without overflow or underflow (scaled by the largest
 * component first). 0 when |v| is below ATT_AID_TINY (or v is zero). */
static inline int aid_unit(const att_real v[3], att_real u[3])
{
    att_real a = att_fabs(v[0]), n;
    if (att_fabs(v[1]) > a)
        a = att_fabs(v[1]);
    if (att_fabs(v[2]) > a)
        a = att_fabs(v[2]);
    if (!(a > ATT_AID_TINY))
        return 0;
    u[0] = v[0] / a;
    u[1] = v[1] / a;
    u[2] = v[2] / a;
    n = att_sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    u[0] /= n;
    u[1] /= n;
    u[2] /= n;
    return 1;
}

static inline void aid_cross(const att_real a[3], const att_real b[3], att_real c[3])
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

/* Common checks of the two-vector solvers: unit f and m, and f̂ × m̂. */
static inline att_status aid_pair(const att_real f_b[3], const att_real m_b[3], att_real declination_rad,
                                  att_real fu[3], att_real mu[3], att_real fxm[3])
{
    att_real s2;
    if (!att__finite3(f_b) || !att__finite3(m_b) || !isfinite(declination_rad))
        return ATT_E_NONFINITE;
    if (att_fabs(declination_rad) > ATT_PI)
        return ATT_E_ARG;
    if (!aid_unit(f_b, fu))
        return ATT_AID_E_ZERO_F;
    if (!aid_unit(m_b, mu))
        return ATT_AID_E_ZERO_M;
    aid_cross(fu, mu, fxm);
    s2 = fxm[0] * fxm[0] + fxm[1] * fxm[1] + fxm[2] * fxm[2];
    if (!(s2 >= ATT_AID_MIN_SIN * ATT_AID_MIN_SIN))
        return ATT_AID_E_PARALLEL;
    return ATT_OK;
}

#endif /* ATT_SRC_AIDING_INTERNAL_H */
