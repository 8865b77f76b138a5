/*
 * libattitude — the MEMS AHRS paper's nine-state filter (ahrs_gnss9.h):
 * strapdown attitude and horizontal velocity, a low-order Kalman filter
 * on their errors aided by GNSS velocity and the magnetic heading, with
 * feedback. attitude_c/gnss9_reference.py is the independent NumPy model;
 * docs/gnss-paper-filter.md maps each step to the paper.
 */
#include "attitude/ahrs_gnss9.h"

#include <stddef.h>

#include "att_math.h"
#include "settings_domain.h"
#include "attitude/aiding.h"
#include "attitude/quat.h"

#define NX ATT_G9_NX

#if defined(ATT_REAL_F32)
#define att_exp expf
#else
#define att_exp exp
#endif

void att_g9_default_settings(att_g9_settings *set)
{
    if (set == NULL) {
        return;
    }
    set->gravity = ATT_R(9.80665);
    set->gyr_noise = ATT_R(1e-3);
    set->drift_noise = ATT_R(1e-5);
    set->acc_noise = ATT_R(0.02);
    set->mag_tau = ATT_R(300.0);
    set->mag_sigma = ATT_R(0.035);
    set->gnss_vel_noise = ATT_R(0.1);
    set->heading_noise = ATT_R(0.0175);
    set->init_tilt_sigma = ATT_R(0.035);
    set->init_heading_sigma = ATT_R(0.17);
    set->init_vel_sigma = ATT_R(0.5);
    set->init_drift_sigma = ATT_R(0.005);
    set->max_gnss_age = ATT_R(1.0);
    set->kf_period = 5;
}

/* The domain of each real setting (ahrs_gnss9.h), in the struct's order (settings_domain.h):
 * positive 1: > 0, 0: ≥ 0. */
/* clang-format off */
#define DOMAIN(field, positive) ATT__DOMAIN(att_g9_settings, field, (positive) ? ATT__GT : ATT__GE, 0)
/* clang-format on */

static const att__domain DOMAINS[] = {
    DOMAIN(gravity, 1),         DOMAIN(gyr_noise, 1),
    DOMAIN(drift_noise, 0),     DOMAIN(acc_noise, 1),
    DOMAIN(mag_tau, 1),         DOMAIN(mag_sigma, 1),
    DOMAIN(gnss_vel_noise, 1),  DOMAIN(heading_noise, 1),
    DOMAIN(init_tilt_sigma, 1), DOMAIN(init_heading_sigma, 1),
    DOMAIN(init_vel_sigma, 1),  DOMAIN(init_drift_sigma, 0),
    DOMAIN(max_gnss_age, 0),
};

att_status att_g9_check_settings_field(const att_g9_settings *set, const char **field)
{
    const char *bad = NULL;
    const att__domain *d;
    if (field != NULL) {
        *field = NULL;
    }
    if (set == NULL) {
        return ATT_E_NULL;
    }
    d = att__out_of_domain(set, DOMAINS, sizeof DOMAINS / sizeof DOMAINS[0]);
    if (d != NULL) {
        bad = d->name;
    }
    if (bad == NULL && (set->kf_period < 1 || set->kf_period > 1000)) {
        bad = "kf_period";
    }
    if (bad == NULL) {
        return ATT_OK;
    }
    if (field != NULL) {
        *field = bad;
    }
    return ATT_E_G9_SETTINGS;
}

att_status att_g9_check_settings(const att_g9_settings *set)
{
    return att_g9_check_settings_field(set, NULL);
}

static void set_covariance0(att_g9 *s)
{
    const att_g9_settings *c = &s->set;
    att_real d[NX];
    int i, j;
    d[ATT_G9_DPSI] = c->mag_sigma * c->mag_sigma;
    d[ATT_G9_DVE] = d[ATT_G9_DVN] = c->init_vel_sigma * c->init_vel_sigma;
    d[ATT_G9_PHIE] = d[ATT_G9_PHIN] = c->init_tilt_sigma * c->init_tilt_sigma;
    d[ATT_G9_PHIU] = c->init_heading_sigma * c->init_heading_sigma;
    d[ATT_G9_EPSX] = d[ATT_G9_EPSY] = d[ATT_G9_EPSZ] = c->init_drift_sigma * c->init_drift_sigma;
    for (i = 0; i < NX; ++i) {
        for (j = 0; j < NX; ++j) {
            s->P[i][j] = i == j ? d[i] : 0;
        }
    }
}

att_status att_g9_init(att_g9 *s, const att_g9_settings *set, const att_real q0[4], const att_real v0[2])
{
    static const att_real unit[4] = { 1, 0, 0, 0 };
    att_g9_settings d;
    att_status st;
    int i;
    if (s == NULL) {
        return ATT_E_NULL;
    }
    if (set == NULL) {
        att_g9_default_settings(&d);
        set = &d;
    }
    st = att_g9_check_settings(set);
    if (st != ATT_OK) {
        return st;
    }
    if ((q0 != NULL && !att__finite4(q0)) || (v0 != NULL && !(isfinite(v0[0]) && isfinite(v0[1])))) {
        return ATT_E_NONFINITE;
    }
    st = att_integ_init(&s->integ, ATT_METHOD_RV3_REUSE, q0 != NULL ? q0 : unit);
    if (st != ATT_OK) {
        return st == ATT_E_NONFINITE ? st : ATT_E_ARG;
    }
    s->set = *set;
    for (i = 0; i < NX; ++i) {
        s->x[i] = 0;
    }
    set_covariance0(s);
    for (i = 0; i < 3; ++i) {
        s->drift[i] = 0;
        s->f_sum[i] = 0;
    }
    for (i = 0; i < 2; ++i) {
        s->v[i] = v0 != NULL ? v0[i] : 0;
        s->acc_h[i] = 0;
    }
    s->t_pending = 0;
    s->n_pending = 0;
    s->aligned = s->heading_set = q0 != NULL;
    s->flags = 0;
    return ATT_OK;
}

/* ---- Kalman prediction --------------------------------------------------- */

/* Φ = I + A T (Φ_ψψ = e^{−T/τ}) for the mean ENU specific force f and C. */
static void transition(const att_g9 *s, const att_real f[3], const att_real C[9], att_real T,
                       att_real F[NX][NX])
{
    int i, j;
    for (i = 0; i < NX; ++i) {
        for (j = 0; j < NX; ++j) {
            F[i][j] = i == j ? 1 : 0;
        }
    }
    F[ATT_G9_DPSI][ATT_G9_DPSI] = att_exp(-T / s->set.mag_tau);
    /* δV̇ = f × φ (horizontal rows) */
    F[ATT_G9_DVE][ATT_G9_PHIN] = -f[2] * T;
    F[ATT_G9_DVE][ATT_G9_PHIU] = f[1] * T;
    F[ATT_G9_DVN][ATT_G9_PHIE] = f[2] * T;
    F[ATT_G9_DVN][ATT_G9_PHIU] = -f[0] * T;
    /* φ̇ = −C ε */
    for (i = 0; i < 3; ++i) {
        for (j = 0; j < 3; ++j) {
            F[ATT_G9_PHIE + i][ATT_G9_EPSX + j] = -C[3 * i + j] * T;
        }
    }
}

static void predict(att_g9 *s)
{
    att_real F[NX][NX], FP[NX][NX], C[9], f[3], x[NX], qd[NX];
    const att_g9_settings *c = &s->set;
    att_real T = s->t_pending, e2;
    int i, j, k;
    for (i = 0; i < 3; ++i) {
        f[i] = s->f_sum[i] / T;
    }
    (void)att_quat_to_dcm(s->integ.q, C);
    transition(s, f, C, T, F);
    for (i = 0; i < NX; ++i) {
        x[i] = 0;
        for (k = 0; k < NX; ++k) {
            x[i] += F[i][k] * s->x[k];
        }
        for (j = 0; j < NX; ++j) {
            FP[i][j] = 0;
            for (k = 0; k < NX; ++k) {
                FP[i][j] += F[i][k] * s->P[k][j];
            }
        }
    }
    e2 = att_exp(ATT_R(-2.0) * T / c->mag_tau);
    qd[ATT_G9_DPSI] = c->mag_sigma * c->mag_sigma * (1 - e2);
    qd[ATT_G9_DVE] = qd[ATT_G9_DVN] = c->acc_noise * c->acc_noise * T;
    qd[ATT_G9_PHIE] = qd[ATT_G9_PHIN] = qd[ATT_G9_PHIU] = c->gyr_noise * c->gyr_noise * T;
    qd[ATT_G9_EPSX] = qd[ATT_G9_EPSY] = qd[ATT_G9_EPSZ] = c->drift_noise * c->drift_noise * T;
    for (i = 0; i < NX; ++i) {
        s->x[i] = x[i];
        for (j = 0; j < NX; ++j) {
            s->P[i][j] = i == j ? qd[i] : 0;
            for (k = 0; k < NX; ++k) {
                s->P[i][j] += FP[i][k] * F[j][k];
            }
        }
    }
    for (i = 0; i < 3; ++i) {
        s->f_sum[i] = 0;
    }
    s->t_pending = 0;
    s->n_pending = 0;
    s->flags |= ATT_G9_F_PREDICTED;
}

static void predict_pending(att_g9 *s)
{
    if (s->n_pending > 0) {
        predict(s);
    }
}

/* ---- strapdown ------------------------------------------------------------ */

static int state_finite(const att_g9 *s)
{
    int i, j;
    if (!att__finite4(s->integ.q) || !att__finite3(s->drift) || !isfinite(s->v[0]) || !isfinite(s->v[1])) {
        return 0;
    }
    for (i = 0; i < NX; ++i) {
        if (!isfinite(s->x[i])) {
            return 0;
        }
        for (j = 0; j < NX; ++j) {
            if (!isfinite(s->P[i][j])) {
                return 0;
            }
        }
    }
    return 1;
}

/* First sample without q0: roll and pitch from the specific force, yaw 0. */
static att_status align_tilt(att_g9 *s, const att_real acc[3])
{
    att_real q[4];
    if (att_align_accmag(acc, NULL, 0, q) != ATT_OK || att_integ_reset(&s->integ, q) != ATT_OK) {
        return ATT_E_G9_ALIGN;
    }
    s->aligned = 1;
    return ATT_OK;
}

static att_status strapdown(att_g9 *s, const att_real gyr[3], const att_real acc[3], att_real dt)
{
    att_real dth[3], C[9], f[3];
    int i, r;
    for (i = 0; i < 3; ++i) {
        dth[i] = (gyr[i] - s->drift[i]) * dt;
    }
    r = att_integ_update(&s->integ, dth, NULL);
    if (r < 0) {
        return r;
    }
    (void)att_quat_to_dcm(s->integ.q, C);
    for (i = 0; i < 3; ++i) {
        f[i] = C[3 * i] * acc[0] + C[3 * i + 1] * acc[1] + C[3 * i + 2] * acc[2];
        s->f_sum[i] += f[i] * dt;
    }
    for (i = 0; i < 2; ++i) {
        s->acc_h[i] = f[i]; /* g_n = [0, 0, −g] has no horizontal part */
        s->v[i] += f[i] * dt;
    }
    s->t_pending += dt;
    s->n_pending += 1;
    return ATT_OK;
}

att_status att_g9_update(att_g9 *s, const att_real gyr[3], const att_real acc[3], att_real dt)
{
    att_g9 saved;
    att_status st;
    if (s == NULL || gyr == NULL || acc == NULL) {
        return ATT_E_NULL;
    }
    if (!isfinite(dt) || !(dt > 0)) {
        return ATT_E_G9_DT;
    }
    if (!att__finite3(gyr) || !att__finite3(acc)) {
        return ATT_E_NONFINITE;
    }
    s->flags = 0;
    if (!s->aligned) {
        return align_tilt(s, acc);
    }
    saved = *s;
    st = strapdown(s, gyr, acc, dt);
    if (st == ATT_OK && s->n_pending >= s->set.kf_period) {
        predict(s);
    }
    if (st == ATT_OK && !state_finite(s)) {
        st = ATT_E_G9_DIVERGED;
    }
    if (st != ATT_OK) {
        *s = saved;
    }
    return st;
}

/* ---- measurement update and feedback --------------------------------------- */

/* Scalar update with the measurement row h (H X = Σ h_i x_i), z, variance r. */
static void scalar_update(att_g9 *s, const att_real h[NX], att_real z, att_real r)
{
    att_real hp[NX], k[NX], innov = z, hph = r;
    int i, j;
    for (j = 0; j < NX; ++j) {
        hp[j] = 0;
        for (i = 0; i < NX; ++i) {
            hp[j] += h[i] * s->P[i][j];
        }
        innov -= h[j] * s->x[j];
    }
    for (i = 0; i < NX; ++i) {
        hph += hp[i] * h[i];
    }
    for (i = 0; i < NX; ++i) {
        k[i] = hp[i] / hph; /* P symmetric: P hᵀ = (h P)ᵀ */
        s->x[i] += k[i] * innov;
    }
    for (i = 0; i < NX; ++i) {
        for (j = 0; j < NX; ++j) {
            s->P[i][j] -= k[i] * hp[j];
        }
    }
}

/* q ← exp(φ̂) ⊗ q, v̂ ← v̂ − δV̂, ε̂ ← ε̂ + ε̂_state; those states zeroed. */
static void feedback(att_g9 *s)
{
    att_real qphi[4], q[4];
    int i;
    (void)att_rotvec_to_quat(&s->x[ATT_G9_PHIE], qphi);
    att_quat_mul(qphi, s->integ.q, q);
    (void)att_quat_normalize(q, s->integ.q);
    for (i = 0; i < 2; ++i) {
        s->v[i] -= s->x[ATT_G9_DVE + i];
    }
    for (i = 0; i < 3; ++i) {
        s->drift[i] += s->x[ATT_G9_EPSX + i];
    }
    for (i = ATT_G9_DVE; i < NX; ++i) {
        s->x[i] = 0;
    }
}

static att_status aiding_begin(att_g9 *s, att_g9 *saved)
{
    if (!s->aligned) {
        return ATT_E_STATE;
    }
    *saved = *s;
    s->flags = 0;
    predict_pending(s);
    return ATT_OK;
}

static att_status aiding_end(att_g9 *s, const att_g9 *saved, int flag)
{
    feedback(s);
    if (!state_finite(s)) {
        *s = *saved;
        return ATT_E_G9_DIVERGED;
    }
    s->flags |= flag;
    return ATT_OK;
}

att_status att_g9_gnss(att_g9 *s, const att_real v_gnss[2], att_real age)
{
    att_g9 saved;
    att_real h[NX] = { 0 };
    att_status st;
    int i;
    if (s == NULL || v_gnss == NULL) {
        return ATT_E_NULL;
    }
    if (!isfinite(v_gnss[0]) || !isfinite(v_gnss[1])) {
        return ATT_E_NONFINITE;
    }
    if (!isfinite(age) || age < 0 || age > s->set.max_gnss_age) {
        return ATT_E_G9_AGE;
    }
    st = aiding_begin(s, &saved);
    if (st != ATT_OK) {
        return st;
    }
    for (i = 0; i < 2; ++i) {
        att_real z = s->v[i] - age * s->acc_h[i] - v_gnss[i];
        h[ATT_G9_DVE + i] = 1;
        scalar_update(s, h, z, s->set.gnss_vel_noise * s->set.gnss_vel_noise);
        h[ATT_G9_DVE + i] = 0;
    }
    return aiding_end(s, &saved, ATT_G9_F_GNSS);
}

/* Angle wrapped to (−π, π]. */
static att_real wrap_pi(att_real a)
{
    while (a > ATT_PI) {
        a -= ATT_TWO_PI;
    }
    while (a <= -ATT_PI) {
        a += ATT_TWO_PI;
    }
    return a;
}

/* The first heading: q ← q_U(ψ_SINS − ψ_mag) ⊗ q (a turn about up). */
static void set_heading(att_g9 *s, att_real dpsi)
{
    att_real rv[3] = { 0, 0, 0 }, qz[4], q[4];
    rv[2] = dpsi;
    (void)att_rotvec_to_quat(rv, qz);
    att_quat_mul(qz, s->integ.q, q);
    (void)att_quat_normalize(q, s->integ.q);
    s->heading_set = 1;
    s->flags |= ATT_G9_F_HEADING_SET;
}

att_status att_g9_heading(att_g9 *s, att_real heading)
{
    att_g9 saved;
    att_real h[NX] = { 0 }, psi, z;
    att_status st;
    if (s == NULL) {
        return ATT_E_NULL;
    }
    if (!isfinite(heading)) {
        return ATT_E_NONFINITE;
    }
    st = aiding_begin(s, &saved);
    if (st != ATT_OK) {
        return st;
    }
    if (att_quat_heading(s->integ.q, &psi) != ATT_OK) {
        *s = saved;
        return ATT_E_G9_DIVERGED;
    }
    z = wrap_pi(psi - heading);
    if (!s->heading_set) {
        set_heading(s, z);
        return ATT_OK;
    }
    h[ATT_G9_DPSI] = -1;
    h[ATT_G9_PHIU] = 1;
    scalar_update(s, h, z, s->set.heading_noise * s->set.heading_noise);
    return aiding_end(s, &saved, ATT_G9_F_HEADING);
}

/* ---- batch ------------------------------------------------------------------ */

/* The aiding after sample k: its GNSS samples from *j on, then its heading. */
static att_status aid_sample(att_g9 *s, size_t k, const att_real *heading, const size_t *gnss_at,
                             const att_real *v_gnss, const att_real *gnss_age, size_t m, size_t *j)
{
    att_status st = ATT_OK;
    for (; st == ATT_OK && *j < m && gnss_at[*j] <= k; ++*j) {
        st = gnss_at[*j] < k ? ATT_E_ARG : att_g9_gnss(s, &v_gnss[2 * *j], gnss_age[*j]);
    }
    if (st == ATT_OK && heading != NULL && isfinite(heading[k])) {
        st = att_g9_heading(s, heading[k]);
    }
    return st;
}

att_status att_g9_batch(att_g9 *s, const att_real *gyr, const att_real *acc, size_t n, const att_real *dt,
                        size_t n_dt, const att_real *heading, const size_t *gnss_at, const att_real *v_gnss,
                        const att_real *gnss_age, size_t m, att_real *q_out, att_real *v_out,
                        size_t *err_index)
{
    size_t k, j = 0;
    att_status st = ATT_OK;
    if (s == NULL || gyr == NULL || acc == NULL || dt == NULL
        || (m > 0 && (gnss_at == NULL || v_gnss == NULL || gnss_age == NULL))) {
        return ATT_E_NULL;
    }
    if (n_dt != 1 && n_dt != n) {
        return ATT_E_ARG;
    }
    for (k = 0; k < n && st == ATT_OK; ++k) {
        st = att_g9_update(s, &gyr[3 * k], &acc[3 * k], dt[n_dt == 1 ? 0 : k]);
        if (st == ATT_OK) {
            st = aid_sample(s, k, heading, gnss_at, v_gnss, gnss_age, m, &j);
        }
        if (st == ATT_OK && q_out != NULL) {
            st = att_g9_attitude(s, &q_out[4 * k]);
        }
        if (st == ATT_OK && v_out != NULL) {
            st = att_g9_velocity(s, &v_out[2 * k]);
        }
        if (st != ATT_OK && err_index != NULL) {
            *err_index = k;
        }
    }
    return st;
}

/* ---- accessors -------------------------------------------------------------- */

att_status att_g9_attitude(const att_g9 *s, att_real q[4])
{
    int i;
    if (s == NULL || q == NULL) {
        return ATT_E_NULL;
    }
    if (!s->aligned) {
        return ATT_E_STATE;
    }
    for (i = 0; i < 4; ++i) {
        q[i] = s->integ.q[i];
    }
    return ATT_OK;
}

att_status att_g9_velocity(const att_g9 *s, att_real v[2])
{
    if (s == NULL || v == NULL) {
        return ATT_E_NULL;
    }
    v[0] = s->v[0];
    v[1] = s->v[1];
    return ATT_OK;
}

att_status att_g9_drift(const att_g9 *s, att_real eps[3])
{
    int i;
    if (s == NULL || eps == NULL) {
        return ATT_E_NULL;
    }
    for (i = 0; i < 3; ++i) {
        eps[i] = s->drift[i];
    }
    return ATT_OK;
}

att_status att_g9_error_state(const att_g9 *s, att_real x[ATT_G9_NX], att_real p_diag[ATT_G9_NX])
{
    int i;
    if (s == NULL || x == NULL) {
        return ATT_E_NULL;
    }
    for (i = 0; i < NX; ++i) {
        x[i] = s->x[i];
        if (p_diag != NULL) {
            p_diag[i] = s->P[i][i];
        }
    }
    return ATT_OK;
}

int att_g9_flags(const att_g9 *s)
{
    return s == NULL ? 0 : s->flags;
}
