/*
 * libattitude — the UAV thesis's EKF (ahrs_thesis.h): quaternion and gyro
 * bias states, RK4 time update, the Gauss–Newton quaternion as the
 * measurement. attitude_c/thesis_ekf_reference.py is the independent
 * NumPy model; docs/ahrs.md maps each step to the thesis's equations.
 */
#include "attitude/ahrs_thesis.h"

#include "att_math.h"

#define NX 7

void att_tekf_default_settings(att_tekf_settings *set)
{
    if (set == NULL) {
        return;
    }
    set->gyr_noise = ATT_R(0.01);
    set->bias_noise = ATT_R(0.0);
    set->meas_noise = ATT_R(0.025);
    set->init_q_sigma = ATT_R(0.05);
    set->init_bias_sigma = ATT_R(0.03);
    set->declination = ATT_R(0.0);
    att_gn_defaults(&set->gn);
}

static int fin(att_real x)
{
    return isfinite(x);
}

att_status att_tekf_check_settings(const att_tekf_settings *set)
{
    const att_gn_settings *g;
    if (set == NULL) {
        return ATT_E_NULL;
    }
    g = &set->gn;
    if (!(fin(set->gyr_noise) && set->gyr_noise > 0 && fin(set->bias_noise) && set->bias_noise >= 0
          && fin(set->meas_noise) && set->meas_noise > 0 && fin(set->init_q_sigma) && set->init_q_sigma > 0
          && fin(set->init_bias_sigma) && set->init_bias_sigma >= 0 && fin(set->declination)
          && att_fabs(set->declination) <= ATT_PI)) {
        return ATT_E_TEKF_SETTINGS;
    }
    if (!((g->method == ATT_GN_GAUSS_NEWTON || g->method == ATT_GN_SIMPLIFIED) && g->max_iter >= 1
          && g->max_iter <= 1000 && fin(g->tol_residual) && g->tol_residual >= 0 && fin(g->tol_step)
          && g->tol_step >= 0 && fin(g->accept_residual) && g->accept_residual >= 0 && fin(g->damping)
          && g->damping >= 0 && fin(g->max_step) && g->max_step > 0 && fin(g->singular_tol)
          && g->singular_tol >= 0 && g->singular_tol < 1)) {
        return ATT_E_TEKF_SETTINGS;
    }
    return ATT_OK;
}

static void set_covariance0(att_tekf *s)
{
    int i, j;
    for (i = 0; i < NX; ++i) {
        for (j = 0; j < NX; ++j) {
            s->P[i][j] = 0;
        }
    }
    for (i = 0; i < 4; ++i) {
        s->P[i][i] = s->set.init_q_sigma * s->set.init_q_sigma;
    }
    for (i = 4; i < NX; ++i) {
        s->P[i][i] = s->set.init_bias_sigma * s->set.init_bias_sigma;
    }
}

static int normalize4(att_real q[4])
{
    att_real n = att_sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    int i;
    if (!(n > 0) || !fin(n)) {
        return 0;
    }
    for (i = 0; i < 4; ++i) {
        q[i] /= n;
    }
    return 1;
}

att_status att_tekf_init(att_tekf *s, const att_tekf_settings *set, const att_real q0[4])
{
    att_tekf_settings d;
    att_status st;
    int i;
    if (s == NULL) {
        return ATT_E_NULL;
    }
    if (set == NULL) {
        att_tekf_default_settings(&d);
        set = &d;
    }
    st = att_tekf_check_settings(set);
    if (st != ATT_OK) {
        return st;
    }
    if (q0 != NULL && !att__finite4(q0)) {
        return ATT_E_NONFINITE;
    }
    s->set = *set;
    for (i = 0; i < NX; ++i) {
        s->x[i] = 0;
    }
    s->x[0] = 1;
    s->aligned = 0;
    if (q0 != NULL) {
        for (i = 0; i < 4; ++i) {
            s->x[i] = q0[i];
        }
        if (!normalize4(s->x)) {
            return ATT_E_ARG;
        }
        s->aligned = 1;
    }
    set_covariance0(s);
    for (i = 0; i < 3; ++i) {
        s->gyr_prev[i] = 0;
    }
    s->has_prev = 0;
    s->gn_skipped = 0;
    s->gn_status = ATT_OK;
    s->flags = 0;
    return ATT_OK;
}

/* out = q ⊗ [0, w] (the Ω(w) q = Ξ(q) w of the header). */
static void qmul_vec(const att_real q[4], const att_real w[3], att_real out[4])
{
    out[0] = -q[1] * w[0] - q[2] * w[1] - q[3] * w[2];
    out[1] = q[0] * w[0] + q[2] * w[2] - q[3] * w[1];
    out[2] = q[0] * w[1] + q[3] * w[0] - q[1] * w[2];
    out[3] = q[0] * w[2] + q[1] * w[1] - q[2] * w[0];
}

/* Ξ(q): 4×3, q ⊗ [0, w] = Ξ(q) w. */
static void xi_matrix(const att_real q[4], att_real X[4][3])
{
    X[0][0] = -q[1], X[0][1] = -q[2], X[0][2] = -q[3];
    X[1][0] = q[0], X[1][1] = -q[3], X[1][2] = q[2];
    X[2][0] = q[3], X[2][1] = q[0], X[2][2] = -q[1];
    X[3][0] = -q[2], X[3][1] = q[1], X[3][2] = q[0];
}

/* Ω(w): 4×4, q ⊗ [0, w] = Ω(w) q. */
static void omega_matrix(const att_real w[3], att_real O[4][4])
{
    O[0][0] = 0, O[0][1] = -w[0], O[0][2] = -w[1], O[0][3] = -w[2];
    O[1][0] = w[0], O[1][1] = 0, O[1][2] = w[2], O[1][3] = -w[1];
    O[2][0] = w[1], O[2][1] = -w[2], O[2][2] = 0, O[2][3] = w[0];
    O[3][0] = w[2], O[3][1] = w[1], O[3][2] = -w[0], O[3][3] = 0;
}

/* The thesis's RK4 (eq. 3.21 and its listing): k1 = ½h Ω(w0) q,
 * k2 = ½h Ω(w1)(q + k1/2), k3 = ½h Ω(w1)(q + k2/2), k4 = ½h Ω(w2)(q + k3). */
static void rk4(att_real q[4], const att_real w0[3], const att_real w1[3], const att_real w2[3], att_real h)
{
    att_real k1[4], k2[4], k3[4], k4[4], t[4];
    int i;
    qmul_vec(q, w0, k1);
    for (i = 0; i < 4; ++i) {
        k1[i] *= ATT_R(0.5) * h;
        t[i] = q[i] + k1[i] / 2;
    }
    qmul_vec(t, w1, k2);
    for (i = 0; i < 4; ++i) {
        k2[i] *= ATT_R(0.5) * h;
        t[i] = q[i] + k2[i] / 2;
    }
    qmul_vec(t, w1, k3);
    for (i = 0; i < 4; ++i) {
        k3[i] *= ATT_R(0.5) * h;
        t[i] = q[i] + k3[i];
    }
    qmul_vec(t, w2, k4);
    for (i = 0; i < 4; ++i) {
        k4[i] *= ATT_R(0.5) * h;
        q[i] += (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]) / 6;
    }
}

/* Time update: state and covariance (eq. 3.45, 3.47, 3.50, 3.56). */
static void time_update(att_tekf *s, const att_real gyr[3], att_real h)
{
    att_real w0[3], w1[3], w2[3], O[4][4], X[4][3], Phi[NX][NX], T[NX][NX];
    att_real *q = s->x, *b = s->x + 4;
    att_real qg = ATT_R(0.25) * s->set.gyr_noise * s->set.gyr_noise * h;
    att_real bq = s->set.bias_noise * s->set.bias_noise * h;
    int i, j, k;
    for (i = 0; i < 3; ++i) {
        att_real prev = s->has_prev ? s->gyr_prev[i] : gyr[i];
        w0[i] = prev - b[i];
        w2[i] = gyr[i] - b[i];
        w1[i] = ATT_R(0.5) * (prev + gyr[i]) - b[i];
    }
    /* Φ = I + F h at X_{k−1} (before the state moves) */
    omega_matrix(w1, O);
    xi_matrix(q, X);
    for (i = 0; i < NX; ++i) {
        for (j = 0; j < NX; ++j) {
            Phi[i][j] = (i == j) ? ATT_R(1.0) : ATT_R(0.0);
        }
    }
    for (i = 0; i < 4; ++i) {
        for (j = 0; j < 4; ++j) {
            Phi[i][j] += ATT_R(0.5) * h * O[i][j];
        }
        for (j = 0; j < 3; ++j) {
            Phi[i][4 + j] = -ATT_R(0.5) * h * X[i][j];
        }
    }
    /* P ← Φ P Φᵀ + Q */
    for (i = 0; i < NX; ++i) {
        for (j = 0; j < NX; ++j) {
            att_real acc = 0;
            for (k = 0; k < NX; ++k) {
                acc += Phi[i][k] * s->P[k][j];
            }
            T[i][j] = acc;
        }
    }
    for (i = 0; i < NX; ++i) {
        for (j = 0; j < NX; ++j) {
            att_real acc = 0;
            for (k = 0; k < NX; ++k) {
                acc += T[i][k] * Phi[j][k];
            }
            s->P[i][j] = acc;
        }
    }
    for (i = 0; i < 4; ++i) {
        for (j = 0; j < 4; ++j) {
            s->P[i][j] += qg * (X[i][0] * X[j][0] + X[i][1] * X[j][1] + X[i][2] * X[j][2]);
        }
    }
    for (i = 4; i < NX; ++i) {
        s->P[i][i] += bq;
    }
    /* state: RK4 with the bias-corrected rates, then eq. 3.22 */
    rk4(q, w0, w1, w2, h);
    (void)normalize4(q);
    for (i = 0; i < 3; ++i) {
        s->gyr_prev[i] = gyr[i];
    }
    s->has_prev = 1;
}

/* Cholesky factor of the 4×4 S in place (lower); 0 if not positive definite. */
static int chol4(att_real S[4][4])
{
    int i, j, k;
    for (j = 0; j < 4; ++j) {
        att_real d = S[j][j];
        for (k = 0; k < j; ++k) {
            d -= S[j][k] * S[j][k];
        }
        if (!(d > 0)) {
            return 0;
        }
        S[j][j] = att_sqrt(d);
        for (i = j + 1; i < 4; ++i) {
            att_real v = S[i][j];
            for (k = 0; k < j; ++k) {
                v -= S[i][k] * S[j][k];
            }
            S[i][j] = v / S[j][j];
        }
    }
    return 1;
}

/* Measurement update with the quaternion z (eq. 3.46, 3.48, 3.51, 3.57).
 * Returns 0 when S = H P Hᵀ + R is not positive definite (never with R > 0
 * and a finite P; a guard, not a path). */
static int measurement_update(att_tekf *s, const att_real z[4], att_real h)
{
    att_real S[4][4], K[NX][4], A[NX][NX], T[NX][NX], nu[4];
    att_real r = s->set.meas_noise * s->set.meas_noise / h;
    int i, j, k;
    for (i = 0; i < 4; ++i) {
        for (j = 0; j < 4; ++j) {
            S[i][j] = s->P[i][j] + (i == j ? r : ATT_R(0.0));
        }
    }
    if (!chol4(S)) {
        return 0;
    }
    /* K = P Hᵀ S⁻¹: row i solves S kᵢ = (P Hᵀ)ᵢ (S symmetric) */
    for (i = 0; i < NX; ++i) {
        att_real y[4];
        for (j = 0; j < 4; ++j) {
            att_real v = s->P[i][j];
            for (k = 0; k < j; ++k) {
                v -= S[j][k] * y[k];
            }
            y[j] = v / S[j][j];
        }
        for (j = 3; j >= 0; --j) {
            att_real v = y[j];
            for (k = j + 1; k < 4; ++k) {
                v -= S[k][j] * K[i][k];
            }
            K[i][j] = v / S[j][j];
        }
    }
    for (j = 0; j < 4; ++j) {
        nu[j] = z[j] - s->x[j];
    }
    for (i = 0; i < NX; ++i) {
        att_real v = 0;
        for (j = 0; j < 4; ++j) {
            v += K[i][j] * nu[j];
        }
        s->x[i] += v;
    }
    /* Joseph form: A = I − K H; P ← A P Aᵀ + K R Kᵀ */
    for (i = 0; i < NX; ++i) {
        for (j = 0; j < NX; ++j) {
            A[i][j] = ((i == j) ? ATT_R(1.0) : ATT_R(0.0)) - (j < 4 ? K[i][j] : ATT_R(0.0));
        }
    }
    for (i = 0; i < NX; ++i) {
        for (j = 0; j < NX; ++j) {
            att_real v = 0;
            for (k = 0; k < NX; ++k) {
                v += A[i][k] * s->P[k][j];
            }
            T[i][j] = v;
        }
    }
    for (i = 0; i < NX; ++i) {
        for (j = 0; j < NX; ++j) {
            att_real v = 0;
            for (k = 0; k < NX; ++k) {
                v += T[i][k] * A[j][k];
            }
            for (k = 0; k < 4; ++k) {
                v += r * K[i][k] * K[j][k];
            }
            s->P[i][j] = v;
        }
    }
    (void)normalize4(s->x);
    return 1;
}

static int finite_state(const att_tekf *s)
{
    int i, j;
    for (i = 0; i < NX; ++i) {
        if (!fin(s->x[i])) {
            return 0;
        }
        for (j = 0; j < NX; ++j) {
            if (!fin(s->P[i][j])) {
                return 0;
            }
        }
    }
    return 1;
}

att_status att_tekf_update(att_tekf *s, const att_real gyr[3], const att_real acc[3], const att_real mag[3],
                           att_real dt, att_real q_out[4])
{
    att_tekf saved;
    att_real z[4], qp[4];
    att_status st;
    int i;
    if (s == NULL || gyr == NULL || acc == NULL || mag == NULL) {
        return ATT_E_NULL;
    }
    if (!fin(dt) || !(dt > 0)) {
        return ATT_E_TEKF_DT;
    }
    if (!att__finite3(gyr) || !att__finite3(acc) || !att__finite3(mag)) {
        return ATT_E_NONFINITE;
    }
    if (!s->aligned) {
        st = att_align_accmag(acc, mag, s->set.declination, z);
        if (st != ATT_OK || !att__finite4(z)) {
            return ATT_E_TEKF_ALIGN;
        }
        for (i = 0; i < 4; ++i) {
            s->x[i] = z[i];
        }
        s->aligned = 1;
        for (i = 0; i < 3; ++i) {
            s->gyr_prev[i] = gyr[i];
        }
        s->has_prev = 1;
        s->flags = 0;
        s->gn_status = ATT_OK;
        if (q_out != NULL) {
            for (i = 0; i < 4; ++i) {
                q_out[i] = s->x[i];
            }
        }
        return ATT_OK;
    }
    saved = *s;
    s->flags = 0;
    time_update(s, gyr, dt);
    for (i = 0; i < 4; ++i) {
        qp[i] = s->x[i];
    }
    st = att_gn_solve(acc, mag, s->set.declination, qp, &s->set.gn, z, NULL);
    s->gn_status = st;
    if (st == ATT_OK) {
        att_real dot = z[0] * qp[0] + z[1] * qp[1] + z[2] * qp[2] + z[3] * qp[3];
        if (dot < 0) {
            for (i = 0; i < 4; ++i) {
                z[i] = -z[i];
            }
        }
        if (!measurement_update(s, z, dt)) {
            *s = saved;
            return ATT_E_TEKF_DIVERGED;
        }
    } else {
        s->flags |= ATT_TEKF_F_GN_SKIPPED;
        s->gn_skipped++;
    }
    if (!finite_state(s)) {
        *s = saved;
        return ATT_E_TEKF_DIVERGED;
    }
    if (q_out != NULL) {
        for (i = 0; i < 4; ++i) {
            q_out[i] = s->x[i];
        }
    }
    return ATT_OK;
}

att_status att_tekf_batch(att_tekf *s, const att_real *gyr, const att_real *acc, const att_real *mag,
                          size_t n, const att_real *dt, size_t n_dt, att_real *q_out, size_t *err_index)
{
    size_t k;
    if (s == NULL || (n > 0 && (gyr == NULL || acc == NULL || mag == NULL || dt == NULL))) {
        return ATT_E_NULL;
    }
    if (n > 0 && n_dt != 1 && n_dt != n) {
        return ATT_E_ARG;
    }
    for (k = 0; k < n; ++k) {
        att_status st = att_tekf_update(s, gyr + 3 * k, acc + 3 * k, mag + 3 * k, dt[n_dt == 1 ? 0 : k],
                                        q_out == NULL ? NULL : q_out + 4 * k);
        if (st != ATT_OK) {
            if (err_index != NULL) {
                *err_index = k;
            }
            return st;
        }
    }
    return ATT_OK;
}

att_status att_tekf_attitude(const att_tekf *s, att_real q[4])
{
    int i;
    if (s == NULL || q == NULL) {
        return ATT_E_NULL;
    }
    if (!s->aligned) {
        return ATT_E_STATE;
    }
    for (i = 0; i < 4; ++i) {
        q[i] = s->x[i];
    }
    return ATT_OK;
}

att_status att_tekf_bias(const att_tekf *s, att_real b[3])
{
    int i;
    if (s == NULL || b == NULL) {
        return ATT_E_NULL;
    }
    for (i = 0; i < 3; ++i) {
        b[i] = s->x[4 + i];
    }
    return ATT_OK;
}

unsigned long att_tekf_gn_skipped(const att_tekf *s)
{
    return s == NULL ? 0UL : s->gn_skipped;
}

int att_tekf_flags(const att_tekf *s)
{
    return s == NULL ? 0 : s->flags;
}
