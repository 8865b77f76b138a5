/*
 * libattitude — initial alignment, TRIAD and the static window
 * (csrc/include/attitude/aiding.h; derivations in docs/aiding.md).
 */
#include "attitude/aiding.h"

#include "att_math.h"
#include "attitude/quat.h"

#define ATT_AID_TINY    ATT_R(1e-30)
#define ATT_AID_MIN_SIN (ATT_R(ATT_AID_MIN_SIN_PPM) * ATT_R(1e-6))

/* u = v / |v| computed without overflow or underflow (scaled by the largest
 * component first). 0 when |v| is below ATT_AID_TINY (or v is zero). */
static int aid_unit(const att_real v[3], att_real u[3])
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

static void aid_cross(const att_real a[3], const att_real b[3], att_real c[3])
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

/* Common checks of the two-vector solvers: unit f and m, and f̂ × m̂. */
static att_status aid_pair(const att_real f_b[3], const att_real m_b[3], att_real declination_rad,
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

att_status att_align_accmag(const att_real f_b[3], const att_real m_b[3], att_real declination_rad,
                            att_real q[4])
{
    att_real fu[3], mu[3], fxm[3], e[3], r, cg, sg, ct, st, hx, hy, psi;
    att_status st_;
    if (f_b == NULL || q == NULL)
        return ATT_E_NULL;
    if (m_b != NULL) {
        st_ = aid_pair(f_b, m_b, declination_rad, fu, mu, fxm);
        if (st_ != ATT_OK)
            return st_;
    } else {
        if (!att__finite3(f_b) || !isfinite(declination_rad))
            return ATT_E_NONFINITE;
        if (att_fabs(declination_rad) > ATT_PI)
            return ATT_E_ARG;
        if (!aid_unit(f_b, fu))
            return ATT_AID_E_ZERO_F;
    }
    /* f_b = |f| [−cθ sγ, sθ, cθ cγ] (third row of C = R_z R_x R_y) */
    r = att_sqrt(fu[0] * fu[0] + fu[2] * fu[2]);
    e[1] = att_atan2(fu[1], r);
    if (r > ATT_R(0.0)) {
        e[2] = att_atan2(-fu[0], fu[2]);
        cg = fu[2] / r;
        sg = -fu[0] / r;
    } else {
        e[2] = ATT_R(0.0);
        cg = ATT_R(1.0);
        sg = ATT_R(0.0);
    }
    if (m_b == NULL) {
        e[0] = ATT_R(0.0);
    } else {
        ct = r;
        st = fu[1];
        /* h = R_x(θ) R_y(γ) m: the field in the levelled frame */
        hx = cg * mu[0] + sg * mu[2];
        hy = ct * mu[1] + st * (sg * mu[0] - cg * mu[2]);
        psi = att_atan2(hx, hy) - declination_rad;
        if (psi > ATT_PI)
            psi -= ATT_TWO_PI;
        else if (psi <= -ATT_PI)
            psi += ATT_TWO_PI;
        e[0] = psi;
    }
    return att_euler_to_quat(e, q);
}

att_status att_triad(const att_real f_b[3], const att_real m_b[3], att_real declination_rad, att_real q[4])
{
    att_real fu[3], mu[3], t2[3], t3[3], T2[2], T3[2], C[9], n, sd, cd;
    att_status st;
    int j;
    if (f_b == NULL || m_b == NULL || q == NULL)
        return ATT_E_NULL;
    st = aid_pair(f_b, m_b, declination_rad, fu, mu, t2);
    if (st != ATT_OK)
        return st;
    n = att_sqrt(t2[0] * t2[0] + t2[1] * t2[1] + t2[2] * t2[2]);
    t2[0] /= n;
    t2[1] /= n;
    t2[2] /= n;
    aid_cross(fu, t2, t3);
    sd = att_sin(declination_rad);
    cd = att_cos(declination_rad);
    T2[0] = -cd; /* nav triad: T1 = [0, 0, 1], T2, T3 horizontal */
    T2[1] = sd;
    T3[0] = -sd;
    T3[1] = -cd;
    for (j = 0; j < 3; ++j) {
        C[0 + j] = T2[0] * t2[j] + T3[0] * t3[j];
        C[3 + j] = T2[1] * t2[j] + T3[1] * t3[j];
        C[6 + j] = fu[j];
    }
    return att_dcm_to_quat(C, q);
}

/* ------------------------------------------------------------------ */

void att_align_window_defaults(att_align_window_settings *s)
{
    if (s == NULL)
        return;
    s->min_samples = 50u;
    s->max_acc_spread = ATT_R(0.02);
    s->max_mag_spread = ATT_R(0.05);
    s->max_gyr_std = ATT_R(0.05);
    s->max_gyr_mean = ATT_R(0.2);
    s->declination_rad = ATT_R(0.0);
}

static int aid_limit_ok(att_real x)
{
    return isfinite(x) && x > ATT_R(0.0);
}

att_status att_align_window_init(att_align_window *w, const att_align_window_settings *s)
{
    att_align_window_settings d;
    if (w == NULL)
        return ATT_E_NULL;
    if (s == NULL) {
        att_align_window_defaults(&d);
        s = &d;
    }
    if (s->min_samples < 2u || !aid_limit_ok(s->max_acc_spread) || !aid_limit_ok(s->max_mag_spread)
        || !aid_limit_ok(s->max_gyr_std) || !aid_limit_ok(s->max_gyr_mean) || !isfinite(s->declination_rad)
        || att_fabs(s->declination_rad) > ATT_PI)
        return ATT_E_ARG;
    w->s = *s;
    att_align_window_reset(w);
    return ATT_OK;
}

void att_align_window_reset(att_align_window *w)
{
    int i;
    if (w == NULL)
        return;
    w->n = 0;
    w->n_gyr = 0;
    w->n_mag = 0;
    for (i = 0; i < 3; ++i) {
        w->acc_mean[i] = ATT_R(0.0);
        w->mag_mean[i] = ATT_R(0.0);
        w->gyr_mean[i] = ATT_R(0.0);
    }
    w->acc_m2 = ATT_R(0.0);
    w->mag_m2 = ATT_R(0.0);
    w->gyr_m2 = ATT_R(0.0);
}

/* Welford: mean += d / n, m2 += d · (x − mean_new), d = x − mean_old. */
static void aid_welford(att_real mean[3], att_real *m2, unsigned long n, const att_real x[3])
{
    att_real inv = ATT_R(1.0) / (att_real)n, acc = ATT_R(0.0);
    int i;
    for (i = 0; i < 3; ++i) {
        att_real d = x[i] - mean[i];
        mean[i] += d * inv;
        acc += d * (x[i] - mean[i]);
    }
    *m2 += acc;
}

att_status att_align_window_add(att_align_window *w, const att_real gyr[3], const att_real acc[3],
                                const att_real mag[3])
{
    if (w == NULL || acc == NULL)
        return ATT_E_NULL;
    if (!att__finite3(acc) || (gyr != NULL && !att__finite3(gyr)) || (mag != NULL && !att__finite3(mag)))
        return ATT_E_NONFINITE;
    w->n += 1u;
    aid_welford(w->acc_mean, &w->acc_m2, w->n, acc);
    if (gyr != NULL) {
        w->n_gyr += 1u;
        aid_welford(w->gyr_mean, &w->gyr_m2, w->n_gyr, gyr);
    }
    if (mag != NULL) {
        w->n_mag += 1u;
        aid_welford(w->mag_mean, &w->mag_m2, w->n_mag, mag);
    }
    return ATT_OK;
}

static att_real aid_norm(const att_real v[3])
{
    return att_sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

/* RMS deviation over the mean's norm; a huge value when the mean is zero. */
static att_real aid_spread(att_real m2, unsigned long n, const att_real mean[3])
{
    att_real sd = att_sqrt(m2 / (att_real)(n - 1u)), nm = aid_norm(mean);
    if (!(nm > ATT_AID_TINY))
        return ATT_R(1e30);
    return sd / nm;
}

att_status att_align_window_stats(const att_align_window *w, att_align_window_result *r)
{
    int i;
    if (w == NULL || r == NULL)
        return ATT_E_NULL;
    if (w->n < 2u)
        return ATT_AID_E_FEW;
    r->n = w->n;
    r->acc_spread = aid_spread(w->acc_m2, w->n, w->acc_mean);
    r->mag_spread = w->n_mag >= 2u ? aid_spread(w->mag_m2, w->n_mag, w->mag_mean) : ATT_R(0.0);
    r->gyr_std = w->n_gyr >= 2u ? att_sqrt(w->gyr_m2 / (att_real)(w->n_gyr - 1u)) : ATT_R(0.0);
    r->gyr_mean = w->n_gyr >= 1u ? aid_norm(w->gyr_mean) : ATT_R(0.0);
    for (i = 0; i < 3; ++i) {
        r->acc_mean[i] = w->acc_mean[i];
        r->mag_mean[i] = w->mag_mean[i];
    }
    return ATT_OK;
}

att_status att_align_window_solve(const att_align_window *w, att_real q[4])
{
    att_align_window_result r;
    att_status st;
    if (w == NULL || q == NULL)
        return ATT_E_NULL;
    if (w->n < w->s.min_samples || w->n < 2u)
        return ATT_AID_E_FEW;
    if ((w->n_gyr != 0u && w->n_gyr != w->n) || (w->n_mag != 0u && w->n_mag != w->n))
        return ATT_E_STATE;
    st = att_align_window_stats(w, &r);
    if (st != ATT_OK)
        return st;
    if (!(r.acc_spread <= w->s.max_acc_spread) || !(r.mag_spread <= w->s.max_mag_spread)
        || !(r.gyr_std <= w->s.max_gyr_std) || !(r.gyr_mean <= w->s.max_gyr_mean)) {
        if (!(aid_norm(r.acc_mean) > ATT_AID_TINY))
            return ATT_AID_E_ZERO_F;
        if (w->n_mag != 0u && !(aid_norm(r.mag_mean) > ATT_AID_TINY))
            return ATT_AID_E_ZERO_M;
        return ATT_AID_E_MOVING;
    }
    return att_align_accmag(r.acc_mean, w->n_mag != 0u ? r.mag_mean : NULL, w->s.declination_rad, q);
}
