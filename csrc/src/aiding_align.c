/*
 * libattitude — initial alignment, TRIAD and the static window
 * (csrc/include/attitude/aiding.h; derivations in docs/aiding.md).
 */
#include "attitude/aiding.h"

#include "aiding_internal.h"
#include "att_math.h"
#include "attitude/quat.h"

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
        mu[0] = mu[1] = mu[2] = ATT_R(0.0); /* unused without m_b: defined on every path (gcc -O3) */
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

att_status att_align_accmag_n(const att_real *f_b, const att_real *m_b, att_real declination_rad, att_real *q,
                              size_t n, int *status)
{
    att_status first = ATT_OK;
    size_t i;
    if (n == 0u)
        return ATT_OK;
    if (f_b == NULL || q == NULL || status == NULL)
        return ATT_E_NULL;
    for (i = 0; i < n; ++i) {
        status[i] =
            att_align_accmag(f_b + 3u * i, m_b != NULL ? m_b + 3u * i : NULL, declination_rad, q + 4u * i);
        if (status[i] != ATT_OK && first == ATT_OK)
            first = status[i];
    }
    return first;
}

att_status att_triad_n(const att_real *f_b, const att_real *m_b, att_real declination_rad, att_real *q,
                       size_t n, int *status)
{
    att_status first = ATT_OK;
    size_t i;
    if (n == 0u)
        return ATT_OK;
    if (f_b == NULL || m_b == NULL || q == NULL || status == NULL)
        return ATT_E_NULL;
    for (i = 0; i < n; ++i) {
        status[i] = att_triad(f_b + 3u * i, m_b + 3u * i, declination_rad, q + 4u * i);
        if (status[i] != ATT_OK && first == ATT_OK)
            first = status[i];
    }
    return first;
}
