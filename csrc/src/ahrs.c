/*
 * libattitude — the attitude filter (ahrs.h): an error-state Kalman
 * filter on top of the rotation-vector integrator. docs/ahrs.md derives
 * every step; attitude_c/ahrs_reference.py is the independent NumPy model.
 * att_ahrs_update runs the stage functions below in the order of a sample's
 * path, each named in docs/ahrs.md's "Code map" beside its section.
 */
#include <stddef.h>
#include <string.h>

#include "attitude/ahrs.h"
#include "attitude/aiding.h"

#include "att_math.h"
#include "settings_domain.h"

#define NX 6

void att_ahrs_default_settings(att_ahrs_settings *set)
{
    if (set == NULL) {
        return;
    }
    set->method = ATT_METHOD_RV3_REUSE;
    set->gravity = ATT_R(9.81);
    set->gyr_noise = ATT_R(0.01);
    set->gyr_noise_rest = ATT_R(0.002);
    set->bias_noise = ATT_R(1e-4);
    set->init_att_sigma = ATT_R(0.1);
    set->init_bias_sigma = ATT_R(0.01);
    set->acc_tau = ATT_R(2.0);
    set->acc_noise = ATT_R(0.025);
    set->acc_gate = ATT_R(0.2);
    set->acc_reject_max = ATT_R(3.0);
    set->mag_noise = ATT_R(0.1);
    set->mag_norm_tol = ATT_R(0.08);
    set->mag_dip_tol = ATT_R(0.17);
    set->mag_ref_tau = ATT_R(30.0);
    set->mag_ref_window = ATT_R(5.0);
    set->mag_reject_max = ATT_R(60.0);
    set->mag_reject_factor = ATT_R(2.0);
    set->mag_new_time = ATT_R(20.0);
    set->mag_new_gyr = ATT_R(0.35);
    set->mag_min_undisturbed = ATT_R(0.5);
    set->declination = ATT_R(0.0);
    set->rest_time = ATT_R(1.5);
    set->rest_tau = ATT_R(0.5);
    set->rest_gyr_th = ATT_R(0.035);
    set->rest_acc_th = ATT_R(0.5);
    set->rest_noise = ATT_R(3e-4);
    set->gyro_range = ATT_R(0.0);
    set->overrange_sigma = ATT_R(0.05);
    set->sensor_delay = ATT_R(0.0);
    set->acc_delay = ATT_R(0.0);
    set->mag_delay = ATT_R(0.0);
    set->tilt_tau = ATT_R(3.0);
    set->heading_sigma_max = ATT_R(0.0873);
    set->turn_sigma = ATT_R(0.002);
    set->turn_tau = ATT_R(5.0);
    set->gnss_vel_sigma = ATT_R(0.2);
    set->gnss_timeout = ATT_R(3.0);
    set->gnss_max_latency = ATT_R(1.0);
    set->gnss_max_pdop = ATT_R(10.0);
    set->gnss_max_sigma = ATT_R(2.0);
    set->gnss_max_acc = ATT_R(40.0);
    set->gnss_gate = ATT_R(5.0);
    set->gnss_window = ATT_R(0.9);
    set->gnss_gyr_noise = ATT_R(0.002);
}

static int fin(att_real x)
{
    return isfinite(x);
}

/* The domain of each real setting (ahrs.h), in the struct's order (settings_domain.h). */
/* clang-format off */
#define DOMAIN(field, rule, bound) ATT__DOMAIN(att_ahrs_settings, field, ATT__##rule, bound)
/* clang-format on */

static const att__domain DOMAINS[] = {
    DOMAIN(gravity, GT, 0),
    DOMAIN(gyr_noise, GT, 0),
    DOMAIN(gyr_noise_rest, GT, 0),
    DOMAIN(bias_noise, GE, 0),
    DOMAIN(init_att_sigma, GT, 0),
    DOMAIN(init_bias_sigma, GE, 0),
    DOMAIN(acc_tau, GE, 0),
    DOMAIN(acc_noise, GT, 0),
    DOMAIN(acc_gate, GE, 0),
    DOMAIN(acc_reject_max, GT, 0),
    DOMAIN(mag_noise, GT, 0),
    DOMAIN(mag_norm_tol, GT, 0),
    DOMAIN(mag_dip_tol, GT, 0),
    DOMAIN(mag_ref_tau, GT, 0),
    DOMAIN(mag_ref_window, GE, 0),
    DOMAIN(mag_reject_max, GT, 0),
    DOMAIN(mag_reject_factor, GE, 1),
    DOMAIN(mag_new_time, GT, 0),
    DOMAIN(mag_min_undisturbed, GE, 0),
    DOMAIN(mag_new_gyr, GE, 0),
    DOMAIN(declination, ABS, ATT_PI),
    DOMAIN(rest_time, GE, 0),
    DOMAIN(rest_tau, GT, 0),
    DOMAIN(rest_gyr_th, GT, 0),
    DOMAIN(rest_acc_th, GT, 0),
    DOMAIN(rest_noise, GT, 0),
    DOMAIN(gyro_range, GE, 0),
    DOMAIN(overrange_sigma, GE, 0),
    DOMAIN(sensor_delay, ABS, 1.0),
    DOMAIN(acc_delay, ABS, 0.05),
    DOMAIN(mag_delay, ABS, 0.05),
    DOMAIN(tilt_tau, GE, 0),
    DOMAIN(heading_sigma_max, GT, 0),
    DOMAIN(turn_sigma, GE, 0),
    DOMAIN(turn_tau, GT, 0),
    DOMAIN(gnss_vel_sigma, GT, 0),
    DOMAIN(gnss_timeout, GT, 0),
    DOMAIN(gnss_max_latency, GT, 0),
    DOMAIN(gnss_max_pdop, GE, 0),
    DOMAIN(gnss_max_sigma, GE, 0),
    DOMAIN(gnss_max_acc, GE, 0),
    DOMAIN(gnss_gate, GE, 0),
    DOMAIN(gnss_window, GE, 0),
    DOMAIN(gnss_gyr_noise, GT, 0),
};

/* every real field has a domain, and the header's count is the table's */
typedef char att__domains_complete[sizeof DOMAINS / sizeof DOMAINS[0] == ATT_AHRS_REAL_SETTINGS ? 1 : -1];

const char *att_ahrs_setting_field(size_t i, size_t *offset)
{
    if (i >= ATT_AHRS_REAL_SETTINGS) {
        return NULL;
    }
    if (offset != NULL) {
        *offset = DOMAINS[i].offset;
    }
    return DOMAINS[i].name;
}

att_status att_ahrs_check_settings_field(const att_ahrs_settings *set, const char **field)
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
    if (set->method < 0 || set->method >= ATT_METHOD_COUNT || set->method == ATT_METHOD_RK4) {
        bad = "method";
    } else if (set->mag_ref_window > set->mag_ref_tau /* the weight is capped at mag_ref_tau */
               && (d == NULL || d->offset > offsetof(att_ahrs_settings, mag_ref_window))) {
        bad = "mag_ref_window"; /* in the struct's order, before any later field out of its domain */
    } else if (d != NULL) {
        bad = d->name;
    }
    if (bad == NULL) {
        return ATT_OK;
    }
    if (field != NULL) {
        *field = bad;
    }
    return ATT_E_AHRS_SETTINGS;
}

att_status att_ahrs_check_settings(const att_ahrs_settings *set)
{
    return att_ahrs_check_settings_field(set, NULL);
}

static void set_initial_cov(att_ahrs *s)
{
    int i, j;
    att_real va = s->set.init_att_sigma * s->set.init_att_sigma;
    att_real vb = s->set.init_bias_sigma * s->set.init_bias_sigma;
    for (i = 0; i < NX; i++) {
        for (j = 0; j < NX; j++) {
            s->P[i][j] = 0;
        }
    }
    for (i = 0; i < 3; i++) {
        s->P[i][i] = va;
        s->P[i + 3][i + 3] = vb;
    }
}

att_status att_ahrs_init(att_ahrs *s, const att_ahrs_settings *set, const att_real q0[4])
{
    att_ahrs_settings d;
    att_status st;
    int i;
    if (s == NULL) {
        return ATT_E_NULL;
    }
    if (set == NULL) {
        att_ahrs_default_settings(&d);
        set = &d;
    }
    st = att_ahrs_check_settings(set);
    if (st != ATT_OK) {
        return st;
    }
    if (q0 != NULL) {
        if (!att__finite4(q0)) {
            return ATT_E_NONFINITE;
        }
        if (q0[0] == 0 && q0[1] == 0 && q0[2] == 0 && q0[3] == 0) {
            return ATT_E_ARG;
        }
    }
    st = att_integ_init(&s->integ, (att_method)set->method, q0);
    if (st != ATT_OK) {
        return st;
    }
    s->set = *set;
    for (i = 0; i < 3; i++) {
        s->bias[i] = 0;
        s->acc_lp[i] = 0;
        s->tilt_f[i] = 0;
        s->tilt_fd[i] = 0;
        s->rest_gyr[i] = 0;
        s->rest_acc[i] = 0;
    }
    set_initial_cov(s);
    s->step.dt = 0;
    s->step.tilt = 0; /* read by att_ahrs_attitude before the first update */
    s->step.turn = 0;
    s->turn_var = 0;
    s->mag_ref_var = 0;
    s->mag_ref_dvar = 0;
    s->mag_prev = 0;
    s->acc_norm_lp = 0;
    s->acc_rej_time = 0;
    s->mag_ref[0] = 0;
    s->mag_ref[1] = 0;
    s->mag_rej_time = 0;
    s->mag_cand[0] = 0;
    s->mag_cand[1] = 0;
    s->mag_cand_t = 0;
    s->mag_undist_t = 0;
    s->mag_ref_w = 0;
    s->mag_cand_w = 0;
    s->rest_t = 0;
    s->aligned = (q0 != NULL);
    s->acc_init = 0;
    s->mag_ref_valid = 0;
    s->rest_init = 0;
    s->tilt_mean = 1;
    s->tilt_t = 0;
    s->flags = 0;
    s->heading_seen = 0;
    memset(&s->gnss, 0, sizeof s->gnss);
    return ATT_OK;
}

/* C = C_b^n of a unit quaternion (docs/conventions.md eq. 1). */
static void q2C(const att_real q[4], att_real C[9])
{
    att_real w = q[0], x = q[1], y = q[2], z = q[3];
    C[0] = w * w + x * x - y * y - z * z;
    C[1] = 2 * (x * y - w * z);
    C[2] = 2 * (x * z + w * y);
    C[3] = 2 * (x * y + w * z);
    C[4] = w * w - x * x + y * y - z * z;
    C[5] = 2 * (y * z - w * x);
    C[6] = 2 * (x * z - w * y);
    C[7] = 2 * (y * z + w * x);
    C[8] = w * w - x * x - y * y + z * z;
}

static void mat_vec(const att_real C[9], const att_real v[3], att_real out[3])
{
    out[0] = C[0] * v[0] + C[1] * v[1] + C[2] * v[2];
    out[1] = C[3] * v[0] + C[4] * v[1] + C[5] * v[2];
    out[2] = C[6] * v[0] + C[7] * v[1] + C[8] * v[2];
}

/* An aiding vector x that lags the gyro by d, turned to the gyro's time
 * (ahrs.h, acc_delay): θ = (ω − b)·d with the bias before this sample's
 * update (the one the propagation used), out = x − θ×x + ½ θ×(θ×x).
 * Called only when d != 0 (no cost with the defaults). */
static void delay_comp(const att_real gyr[3], const att_real b[3], att_real d, const att_real x[3],
                       att_real out[3])
{
    att_real t0 = (gyr[0] - b[0]) * d, t1 = (gyr[1] - b[1]) * d, t2 = (gyr[2] - b[2]) * d;
    att_real c0 = t1 * x[2] - t2 * x[1], c1 = t2 * x[0] - t0 * x[2], c2 = t0 * x[1] - t1 * x[0];
    out[0] = x[0] - c0 + ATT_R(0.5) * (t1 * c2 - t2 * c1);
    out[1] = x[1] - c1 + ATT_R(0.5) * (t2 * c0 - t0 * c2);
    out[2] = x[2] - c2 + ATT_R(0.5) * (t0 * c1 - t1 * c0);
}

/* v ← (I + [θ×]) v: a navigation-frame vector carried through the injection
 * of a small correction θ (as acc_lp). */
static void rotate_small(const att_real th[3], att_real v[3])
{
    att_real v0 = v[0], v1 = v[1], v2 = v[2];
    v[0] = v0 + (th[1] * v2 - th[2] * v1);
    v[1] = v1 + (th[2] * v0 - th[0] * v2);
    v[2] = v2 + (th[0] * v1 - th[1] * v0);
}

static att_real norm3(const att_real v[3])
{
    return att_sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

static att_real wrap_pi(att_real a)
{
    while (a > ATT_PI) {
        a -= ATT_TWO_PI;
    }
    while (a < -ATT_PI) {
        a += ATT_TWO_PI;
    }
    return a;
}

/* A scalar measurement y = h·x with variance R, moving only the states in mask
 * (bit i: state i), from ph = P hᵀ, S = h ph + R and the innovation y − h·x:
 *     K_i = ph_i / S (i in the mask, else 0),   x ← x + K (y − h·x),
 *     P ← P − K phᵀ − ph Kᵀ + K Kᵀ S   (Joseph form, valid for any K).
 * Where one of the two states is outside the mask its gain is 0 and the entry
 * reduces exactly to P_rc − K_r ph_c (or − ph_r K_c); where both are, it is
 * unchanged. P is symmetric: the upper triangle is computed and mirrored.
 * gcc and clang unroll the loops and inline the function into each mask's
 * wrapper below, where the constant mask folds the tests away: straight-line
 * code, no more instructions than the entries written out (docs/ahrs.md, "Code
 * map"). Another compiler runs the loops: the same results, more instructions. */
#if defined(__GNUC__)
#define UNROLLED_INLINE inline __attribute__((always_inline))
#else
#define UNROLLED_INLINE inline
#endif

static UNROLLED_INLINE void masked_update(att_real (*P)[NX], att_real x[NX], const att_real ph[NX],
                                          att_real S, att_real innov, unsigned mask)
{
    att_real K[NX], v;
    int r, c;
#pragma GCC unroll 6
    for (r = 0; r < NX; r++) {
        K[r] = 0;
        if (mask & (1u << r)) {
            K[r] = ph[r] / S;
            x[r] += K[r] * innov;
        }
    }
#pragma GCC unroll 6
    for (r = 0; r < NX; r++) {
#pragma GCC unroll 6
        for (c = r; c < NX; c++) {
            int in_r = (mask >> r) & 1u, in_c = (mask >> c) & 1u;
            if (in_r && in_c) {
                v = P[r][c] - K[r] * ph[c] - ph[r] * K[c] + K[r] * K[c] * S;
            } else if (in_r) {
                v = P[r][c] - K[r] * ph[c];
            } else if (in_c) {
                v = P[r][c] - ph[r] * K[c];
            } else {
                continue;
            }
            P[r][c] = v;
            P[c][r] = v;
        }
    }
}

/* h = e_j: ph = column j, S = P_jj + R. */
static UNROLLED_INLINE void scalar_update(att_real (*P)[NX], att_real x[NX], int j, att_real y, att_real R,
                                          unsigned mask)
{
    att_real pj[NX];
    int r;
#pragma GCC unroll 6
    for (r = 0; r < NX; r++) {
        pj[r] = P[r][j];
    }
    masked_update(P, x, pj, P[j][j] + R, y - x[j], mask);
}

/* h = (a₀, a₁, a₂, 0, 0, 0), a row on the attitude states only (the heading's). */
static UNROLLED_INLINE void attitude_row_update(att_real (*P)[NX], att_real x[NX], const att_real a[3],
                                                att_real y, att_real R, unsigned mask)
{
    att_real ph[NX], S = R, innov = y;
    int r;
#pragma GCC unroll 6
    for (r = 0; r < NX; r++) {
        ph[r] = P[r][0] * a[0] + P[r][1] * a[1] + P[r][2] * a[2];
    }
    for (r = 0; r < 3; r++) {
        S += a[r] * ph[r];
        innov -= a[r] * x[r];
    }
    masked_update(P, x, ph, S, innov, mask);
}

/* The masks: the accelerometer never moves the heading (state 2), the
 * magnetometer never roll and pitch (0, 1), a zero-rate update only the bias. */
#define MASK_ACC  0x3Bu /* δθx, δθy, δb */
#define MASK_MAG  0x3Cu /* δθz, δb */
#define MASK_BIAS 0x38u /* δb */

static void update_acc(att_real P[NX][NX], att_real x[NX], int j, att_real y, att_real R)
{
    scalar_update(P, x, j, y, R, MASK_ACC);
}

static void update_bias(att_real P[NX][NX], att_real x[NX], int j, att_real y, att_real R)
{
    scalar_update(P, x, j, y, R, MASK_BIAS);
}

static void update_mag(att_real P[NX][NX], att_real x[NX], const att_real a[3], att_real y, att_real R)
{
    attitude_row_update(P, x, a, y, R, MASK_MAG);
}

/* A general row h (the GNSS rows'): ph = P hᵀ, S = h ph + R. */
static void dense_update(att_real (*P)[NX], att_real x[NX], const att_real h[NX], att_real y, att_real R,
                         unsigned mask)
{
    att_real ph[NX], S = R, innov = y;
    int r, c;
    for (r = 0; r < NX; r++) {
        ph[r] = 0;
        for (c = 0; c < NX; c++) {
            ph[r] += P[r][c] * h[c];
        }
    }
    for (r = 0; r < NX; r++) {
        S += h[r] * ph[r];
        innov -= h[r] * x[r];
    }
    masked_update(P, x, ph, S, innov, mask);
}

/* P ← F P F' + Q with F = [[I, −C dt], [0, I]] (blocks A = Pθθ, B = Pθb,
 * D = Pbb): A ← A − dt (C B' + B C') + dt² C D C' + qa I,
 * B ← B − dt C D, D ← D + qb I. */
static void propagate_cov(att_real P[NX][NX], const att_real C[9], att_real dt, att_real qa, att_real qb)
{
    att_real M[9], G[9], A[9];
    int i, j, k;
    for (i = 0; i < 3; i++) {
        for (j = 0; j < 3; j++) {
            att_real m = 0, g = 0;
            for (k = 0; k < 3; k++) {
                m += C[3 * i + k] * P[3 + k][3 + j]; /* (C D)ij */
                g += C[3 * i + k] * P[3 + k][j];     /* (C B')ij, B' = Pbθ */
            }
            M[3 * i + j] = m;
            G[3 * i + j] = g;
        }
    }
    for (i = 0; i < 3; i++) {
        for (j = i; j < 3; j++) {
            att_real mc = 0;
            for (k = 0; k < 3; k++) {
                mc += M[3 * i + k] * C[3 * j + k]; /* (C D C')ij */
            }
            A[3 * i + j] = P[i][j] - dt * (G[3 * i + j] + G[3 * j + i]) + dt * dt * mc;
        }
    }
    for (i = 0; i < 3; i++) {
        for (j = i; j < 3; j++) {
            att_real v = A[3 * i + j] + ((i == j) ? qa : 0);
            P[i][j] = v;
            P[j][i] = v;
        }
        for (j = 0; j < 3; j++) {
            att_real v = P[i][3 + j] - dt * M[3 * i + j];
            P[i][3 + j] = v;
            P[3 + j][i] = v;
        }
        P[3 + i][3 + i] += qb;
    }
}

static int finite_state(const att_ahrs *s)
{
    int i;
    if (!att__finite4(s->integ.q) || !att__finite3(s->bias) || !att__finite3(s->acc_lp)
        || !att__finite3(s->tilt_f) || !att__finite3(s->tilt_fd)) {
        return 0;
    }
    for (i = 0; i < NX; i++) {
        if (!fin(s->P[i][i])) {
            return 0;
        }
    }
    return 1;
}

/* The reported attitude: the state's q, or with tilt_tau on, r ⊗ q where r is
 * the smallest rotation taking v = tilt_f/|tilt_f| (navigation frame) to up:
 * axis v × e_z = (v_y, −v_x, 0), angle acos(v_z), half-angle form
 * r = (√((1 + v_z)/2), v_y/(2 r_0), −v_x/(2 r_0), 0), unit for a unit v. Only
 * while v is above the horizon (v_z > 0: r_0 > 0.707). */
static void report_q(const att_ahrs *s, att_real out[4])
{
    const att_real *q = s->integ.q;
    att_real n, vz, r0, r1, r2;
    n = (s->step.tilt && !s->gnss.aided) ? norm3(s->tilt_f) : 0; /* tilt_f = 0 until its first sample */
    vz = (n > 0) ? s->tilt_f[2] / n : 0;
    if (vz <= 0) {
        out[0] = q[0];
        out[1] = q[1];
        out[2] = q[2];
        out[3] = q[3];
        return;
    }
    r0 = att_sqrt((1 + vz) * ATT_R(0.5));
    r1 = s->tilt_f[1] / (2 * r0 * n);
    r2 = -s->tilt_f[0] / (2 * r0 * n);
    out[0] = r0 * q[0] - r1 * q[1] - r2 * q[2];
    out[1] = r0 * q[1] + r1 * q[0] + r2 * q[3];
    out[2] = r0 * q[2] - r1 * q[3] + r2 * q[0];
    out[3] = r0 * q[3] + r1 * q[2] - r2 * q[1];
}

static att_status write_q(const att_ahrs *s, att_real q_out[4])
{
    if (q_out != NULL) {
        report_q(s, q_out);
    }
    return ATT_OK;
}

/* What an update may change: the members from integ on (set and the cached
 * step constants come first and need no saving; ahrs.h keeps that order). */
#define MUTABLE_FROM offsetof(att_ahrs, integ)

static void copy_mutable(att_ahrs *dst, const att_ahrs *src)
{
    memcpy((unsigned char *)dst + MUTABLE_FROM, (const unsigned char *)src + MUTABLE_FROM,
           sizeof(att_ahrs) - MUTABLE_FROM);
}

/* The constants of a step dt (> 0), recomputed only when dt changes. */
static const att_ahrs_step *step_constants(att_ahrs *s, att_real dt)
{
    const att_ahrs_settings *set = &s->set;
    att_ahrs_step *c = &s->step;
    if (c->dt != dt) {
        c->dt = dt;
        c->k_norm = dt / (ATT_R(10.0) + dt);
        c->k_rest = dt / (set->rest_tau + dt);
        c->k_acc = (set->acc_tau > 0) ? dt / (set->acc_tau + dt) : ATT_R(1.0);
        c->q_att = set->gyr_noise * set->gyr_noise * dt;
        c->q_att_rest = set->gyr_noise_rest * set->gyr_noise_rest * dt;
        c->q_att_gnss = set->gnss_gyr_noise * set->gnss_gyr_noise * dt;
        c->q_bias = set->bias_noise * set->bias_noise * dt;
        c->r_acc = set->acc_noise * set->acc_noise / dt;
        c->r_mag = set->mag_noise * set->mag_noise / dt;
        c->v_dip = set->mag_dip_tol * set->mag_dip_tol * ATT_R(0.25);
        c->r_rest = set->rest_noise * set->rest_noise / dt;
        c->delays = (set->acc_delay != 0 ? 1 : 0) | (set->mag_delay != 0 ? 2 : 0);
        c->tilt = set->tilt_tau > 0;
        c->turn = set->turn_sigma > 0;
        c->k_turn = set->turn_tau / (set->turn_tau + dt);
        c->q_turn = set->turn_sigma * set->turn_sigma / dt;
        if (c->tilt) {
            /* ζω0 = 1/τ, ω0² = 2/τ²; at rest τ grows as the state's own inclination
             * time constant does, by gyr_noise/gyr_noise_rest */
            att_real tr = set->tilt_tau * set->gyr_noise / set->gyr_noise_rest;
            att_real u = dt / set->tilt_tau, ur = dt / tr;
            c->tilt_tau_rest = tr;
            c->k_tilt_v = 1 / (1 + 2 * u + 2 * u * u);
            c->k_tilt_x = 2 * u / set->tilt_tau * c->k_tilt_v;
            c->k_tilt_v_rest = 1 / (1 + 2 * ur + 2 * ur * ur);
            c->k_tilt_x_rest = 2 * ur / tr * c->k_tilt_v_rest;
        } else {
            c->k_tilt_v = 0;
            c->k_tilt_x = 0;
            c->k_tilt_v_rest = 0;
            c->k_tilt_x_rest = 0;
            c->tilt_tau_rest = 0;
        }
    }
    return c;
}

/* ---- The stages of one update, in the order of docs/ahrs.md ("Code map") ---- */

/* Inputs: dt, finiteness and the units check of the specific force (nothing is
 * written). *norm_lp is what acc_norm_lp becomes with this sample: |f| itself
 * at the first one, then its slow (10 s) average. */
static att_status check_inputs(const att_ahrs *s, const att_real gyr[3], const att_real acc[3],
                               const att_real mag[3], att_real dt, att_real *norm_lp)
{
    const att_ahrs_settings *set = &s->set;
    att_real an, kn;
    if (!(fin(dt) && dt > 0)) {
        return ATT_E_AHRS_DT;
    }
    if (!att__finite3(gyr) || (acc != NULL && !att__finite3(acc)) || (mag != NULL && !att__finite3(mag))) {
        return ATT_E_NONFINITE;
    }
    *norm_lp = 0;
    if (acc == NULL) {
        return ATT_OK;
    }
    an = norm3(acc);
    if (!s->acc_init) {
        *norm_lp = an;
        return (an >= ATT_R(0.25) * set->gravity && an <= ATT_R(4.0) * set->gravity) ? ATT_OK
                                                                                     : ATT_E_AHRS_UNITS;
    }
    /* the cached constant when dt is unchanged (the state is not touched before the checks) */
    kn = (s->step.dt == dt) ? s->step.k_norm : dt / (ATT_R(10.0) + dt);
    *norm_lp = s->acc_norm_lp + kn * (an - s->acc_norm_lp);
    return (*norm_lp >= ATT_R(0.5) * set->gravity && *norm_lp <= ATT_R(8.0) * set->gravity)
               ? ATT_OK
               : ATT_E_AHRS_UNITS;
}

/* Alignment: an unaligned filter takes its attitude from this sample
 * (att_align_accmag; six-axis, heading 0, without a usable field). */
static att_status align_once(att_ahrs *s, const att_real acc[3], const att_real mag[3])
{
    att_real q0[4];
    att_status st = ATT_AID_E_ZERO_M;
    if (s->aligned) {
        return ATT_OK;
    }
    if (acc == NULL) {
        return ATT_E_AHRS_ALIGN;
    }
    if (mag != NULL) {
        st = att_align_accmag(acc, mag, s->set.declination, q0);
    }
    if (st == ATT_AID_E_ZERO_M || st == ATT_AID_E_PARALLEL) {
        st = att_align_accmag(acc, NULL, s->set.declination, q0);
    }
    if (st != ATT_OK || att_integ_reset(&s->integ, q0) != ATT_OK) {
        return ATT_E_AHRS_ALIGN;
    }
    s->aligned = 1;
    return ATT_OK;
}

/* Gyro over-range: an axis at or above gyro_range (0 = none). */
static int overrange(const att_ahrs_settings *set, const att_real gyr[3])
{
    return set->gyro_range > 0
           && (att_fabs(gyr[0]) >= set->gyro_range || att_fabs(gyr[1]) >= set->gyro_range
               || att_fabs(gyr[2]) >= set->gyro_range);
}

/* Rest detection: first-order low-passes (rest_tau) of ω and f; 1 once
 * |ω − ω_lp|, |ω_lp − b| < rest_gyr_th and |f − f_lp| < rest_acc_th have held
 * for rest_time (raw samples: before any delay compensation). */
static int detect_rest(att_ahrs *s, const att_ahrs_step *k, const att_real gyr[3], const att_real acc[3],
                       att_real dt)
{
    const att_ahrs_settings *set = &s->set;
    att_real dg = 0, da = 0, dw = 0, e, th2;
    int i;
    if (!(set->rest_time > 0 && acc != NULL)) {
        return 0;
    }
    if (!s->rest_init) {
        for (i = 0; i < 3; i++) {
            s->rest_gyr[i] = gyr[i];
            s->rest_acc[i] = acc[i];
        }
        s->rest_init = 1;
        s->rest_t = 0;
        return 0;
    }
    for (i = 0; i < 3; i++) {
        s->rest_gyr[i] += k->k_rest * (gyr[i] - s->rest_gyr[i]);
        s->rest_acc[i] += k->k_rest * (acc[i] - s->rest_acc[i]);
        e = gyr[i] - s->rest_gyr[i];
        dg += e * e;
        e = acc[i] - s->rest_acc[i];
        da += e * e;
        e = s->rest_gyr[i] - s->bias[i];
        dw += e * e;
    }
    th2 = set->rest_gyr_th * set->rest_gyr_th;
    if (dg < th2 && dw < th2 && da < set->rest_acc_th * set->rest_acc_th) {
        s->rest_t += dt;
    } else {
        s->rest_t = 0;
    }
    return s->rest_t >= set->rest_time;
}

/* The reported covariance's turn term (ahrs.h, turn_sigma): v ← v·τ/(τ + dt) +
 * (turn_sigma·|ω − b|)²·dt, the last written turn_sigma²/dt·|Δθ|². Not in P: the
 * gains are not changed by it. */
static void turn_variance(att_ahrs *s, const att_ahrs_step *k, const att_real dth[3])
{
    if (k->turn) {
        s->turn_var =
            k->k_turn * s->turn_var + k->q_turn * (dth[0] * dth[0] + dth[1] * dth[1] + dth[2] * dth[2]);
    }
}

/* Propagation: the bias-corrected increment through the integrator, then
 * P ← F P Fᵀ + Q (at rest with the gyro's own noise), plus overrange_sigma² on
 * the attitude when over range. C = C_b^n of the propagated attitude. 0, or
 * the integrator's error. */
static int propagate(att_ahrs *s, const att_ahrs_step *k, const att_real gyr[3], att_real dt, att_real qa,
                     int over, att_real C[9])
{
    att_real dth[3];
    int i;
    for (i = 0; i < 3; i++) {
        dth[i] = (gyr[i] - s->bias[i]) * dt;
    }
    if (att_integ_update(&s->integ, dth, NULL) < 0) {
        return -1;
    }
    q2C(s->integ.q, C);
    propagate_cov(s->P, C, dt, qa, k->q_bias);
    turn_variance(s, k, dth);
    if (over) {
        att_real o = s->set.overrange_sigma * s->set.overrange_sigma;
        s->P[0][0] += o;
        s->P[1][1] += o;
        s->P[2][2] += o;
    }
    return 0;
}

/* Sensor timing: an aiding sample x (may be NULL) that lags the gyro by d,
 * turned to the gyro's time into out when its delay is on; else x itself. */
static const att_real *at_gyro_time(const att_ahrs *s, const att_real gyr[3], const att_real x[3], int on,
                                    att_real d, att_real out[3])
{
    if (x == NULL || !on) {
        return x;
    }
    delay_comp(gyr, s->bias, d, x, out);
    return out;
}

/* The accelerometer's gate with recovery: 1 when the inclination innovation
 * ang is rejected (above acc_gate, for less than acc_reject_max so far). */
static int acc_gated(att_ahrs *s, att_real ang, att_real dt)
{
    const att_ahrs_settings *set = &s->set;
    if (!(set->acc_gate > 0 && ang > set->acc_gate)) {
        s->acc_rej_time = 0;
        return 0;
    }
    s->acc_rej_time += dt;
    if (s->acc_rej_time < set->acc_reject_max) {
        return 1;
    }
    s->acc_rej_time = 0;
    return 0;
}

/* Accelerometer: f_n = C f (written), its first-order low-pass (acc_tau) in
 * the navigation frame, whose inclination measures δθx, δθy (gated). 1 when
 * the update was made. */
static int acc_update(att_ahrs *s, const att_ahrs_step *k, const att_real C[9], const att_real f[3],
                      att_real norm_lp, att_real dt, int aided, att_real x[NX], int *flags, att_real f_n[3])
{
    att_real v[3], nv, hs, ang, y0 = 0, y1 = 0;
    int i;
    mat_vec(C, f, f_n);
    if (!s->acc_init) {
        for (i = 0; i < 3; i++) {
            s->acc_lp[i] = f_n[i];
        }
        s->acc_init = 1;
    } else {
        for (i = 0; i < 3; i++) {
            s->acc_lp[i] += k->k_acc * (f_n[i] - s->acc_lp[i]);
        }
    }
    s->acc_norm_lp = norm_lp;
    nv = norm3(s->acc_lp);
    if (aided || !(nv > 0)) { /* GNSS-aided: the inclination comes from the velocities */
        s->acc_rej_time = 0;
        return 0;
    }
    for (i = 0; i < 3; i++) {
        v[i] = s->acc_lp[i] / nv;
    }
    /* correction δθ = angle · (v × e_z)/|v × e_z|, v × e_z = (v_y, −v_x, 0) */
    hs = att_sqrt(v[0] * v[0] + v[1] * v[1]);
    ang = att_atan2(hs, v[2]);
    if (hs > 0) {
        y0 = ang * v[1] / hs;
        y1 = -ang * v[0] / hs;
    }
    if (acc_gated(s, ang, dt)) {
        *flags |= ATT_AHRS_F_ACC_REJECTED;
        return 0;
    }
    update_acc(s->P, x, 0, y0, k->r_acc);
    update_acc(s->P, x, 1, y1, k->r_acc);
    return 1;
}

/* Reported inclination: the second-order low-pass (tilt_tau, τ longer at rest)
 * of an accepted f_n, implicit Euler of f'' + 2ζω0 f' + ω0² f = ω0² f_n:
 * f' ← (f' + dt ω0² (f_n − f))/(1 + 2ζω0 dt + ω0² dt²), f ← f + dt f'; it starts
 * as the mean of the samples so far until they span τ (as VQF starts its filter). */
static void tilt_lowpass(att_ahrs *s, const att_ahrs_step *k, const att_real f_n[3], att_real dt, int rest)
{
    int i;
    if (s->tilt_mean) {
        att_real w;
        s->tilt_t += dt;
        w = dt / s->tilt_t;
        for (i = 0; i < 3; i++) {
            s->tilt_f[i] += w * (f_n[i] - s->tilt_f[i]);
        }
        if (s->tilt_t >= (rest ? k->tilt_tau_rest : s->set.tilt_tau)) {
            s->tilt_mean = 0;
        }
    } else {
        att_real kv = rest ? k->k_tilt_v_rest : k->k_tilt_v;
        att_real kx = rest ? k->k_tilt_x_rest : k->k_tilt_x;
        for (i = 0; i < 3; i++) {
            s->tilt_fd[i] = kv * s->tilt_fd[i] + kx * (f_n[i] - s->tilt_f[i]);
            s->tilt_f[i] += dt * s->tilt_fd[i];
        }
    }
}

/* 1 when a field of norm nm and dip agrees with ref (norm, dip) within
 * mag_norm_tol (relative) and mag_dip_tol. */
static int field_agrees(const att_ahrs_settings *set, const att_real ref[2], att_real nm, att_real dip)
{
    return att_fabs(nm - ref[0]) <= set->mag_norm_tol * ref[0] && att_fabs(dip - ref[1]) <= set->mag_dip_tol;
}

/* A field estimate (norm, dip) as a weighted running mean: *W (the weight it
 * holds, s) grows by the sample's weight w up to mag_ref_tau, and the sample
 * moves the estimate by w/W (the mean of the samples so far, then a first-order
 * low-pass of time constant mag_ref_tau). */
static void field_learn(att_real est[2], att_real *W, att_real w, att_real tau, att_real nm, att_real dip)
{
    att_real k;
    *W += w;
    if (*W > tau) {
        *W = tau;
    }
    k = w / *W;
    est[0] += k * (nm - est[0]);
    est[1] += k * (dip - est[1]);
}

static void field_set(att_real est[2], att_real *W, att_real w, att_real nm, att_real dip)
{
    est[0] = nm;
    est[1] = dip;
    *W = w;
}

/* The field's spread about the reference (after field_learn has taken the
 * sample in): the weighted mean of (|m|/norm − 1)², with the reference's weights,
 * and of half the squared step from the last accepted sample (the white part:
 * the magnetometer's noise, which the heading's R already carries). */
static void field_spread(att_ahrs *s, att_real w, att_real nm)
{
    att_real k = w / s->mag_ref_w, d = nm / s->mag_ref[0] - ATT_R(1.0), e;
    s->mag_ref_var += k * (d * d - s->mag_ref_var);
    if (s->mag_prev > 0) {
        e = (nm - s->mag_prev) / s->mag_ref[0];
        s->mag_ref_dvar += k * (ATT_R(0.5) * e * e - s->mag_ref_dvar);
    }
    s->mag_prev = nm;
}

/* The spread starts again with the reference. */
static void field_spread_reset(att_ahrs *s)
{
    s->mag_ref_var = 0;
    s->mag_ref_dvar = 0;
    s->mag_prev = 0;
}

/* The reported heading variance's field term: the norm checks cannot see a
 * disturbance that turns the field about the vertical, so that component is
 * given the variance of the one they see (the norm's spread, relative), which
 * turns the heading by itself over cos(dip); its white part is left out, and
 * what the white part's estimate may be off by (docs/ahrs.md, "Uncertainty"). */
static att_real field_heading_var(const att_ahrs *s)
{
    att_real c = att_cos(s->mag_ref[1]), v;
    if (!(s->mag_ref_w > 0)) {
        return 0;
    }
    /* less twice its own 1σ for white noise, dvar·√(dt/W): a spread that is noise alone
     * stays 0 */
    v = s->mag_ref_var - s->mag_ref_dvar * (ATT_R(1.0) + ATT_R(2.0) * att_sqrt(s->step.dt / s->mag_ref_w));
    c *= c;
    return (s->mag_ref_valid && v > 0) ? v / (c > ATT_R(1e-6) ? c : ATT_R(1e-6)) : 0;
}

/* Magnetic reference, start and candidate: the first sample starts both; the
 * candidate learns a field consistent with itself (else restarts from the
 * sample), its time running only while turning (a field fixed to the body
 * changes with the attitude). */
static void mag_candidate(att_ahrs *s, const att_real gyr[3], att_real nm, att_real dip, att_real w,
                          att_real dt)
{
    const att_ahrs_settings *set = &s->set;
    if (!s->mag_ref_valid) {
        field_set(s->mag_ref, &s->mag_ref_w, w, nm, dip);
        field_set(s->mag_cand, &s->mag_cand_w, w, nm, dip);
        s->mag_ref_valid = 1;
        field_spread_reset(s);
        s->mag_undist_t = set->mag_min_undisturbed;
        s->mag_cand_t = 0;
        return;
    }
    if (field_agrees(set, s->mag_cand, nm, dip)) {
        field_learn(s->mag_cand, &s->mag_cand_w, w, set->mag_ref_tau, nm, dip);
        if (gyr[0] * gyr[0] + gyr[1] * gyr[1] + gyr[2] * gyr[2] >= set->mag_new_gyr * set->mag_new_gyr) {
            s->mag_cand_t += dt;
        }
    } else {
        field_set(s->mag_cand, &s->mag_cand_w, w, nm, dip);
        s->mag_cand_t = 0;
    }
}

/* Magnetic disturbance: the sample against the reference. Undisturbed (for
 * mag_min_undisturbed), it is used and the reference learns it; disturbed, a
 * reference that holds less than mag_ref_window of weight restarts from the
 * sample (used), a candidate held for mag_new_time becomes the reference, else
 * the sample is rejected until mag_reject_max, then used with the noise
 * ×mag_reject_factor². 1 when used, with its noise *r. */
static int mag_accept(att_ahrs *s, const att_ahrs_step *k, att_real nm, att_real dip, att_real w, att_real dt,
                      int *flags, att_real *r)
{
    const att_ahrs_settings *set = &s->set;
    *r = k->r_mag;
    if (field_agrees(set, s->mag_ref, nm, dip)) {
        field_learn(s->mag_ref, &s->mag_ref_w, w, set->mag_ref_tau, nm, dip);
        s->mag_undist_t += dt;
        if (s->mag_undist_t >= set->mag_min_undisturbed) {
            field_spread(s, w, nm); /* the samples the heading uses */
            s->mag_rej_time = 0;
            return 1;
        }
        *flags |= ATT_AHRS_F_MAG_DISTURBED;
        s->mag_rej_time += dt;
        return 0;
    }
    if (s->mag_ref_w < set->mag_ref_window || s->mag_cand_t >= set->mag_new_time) {
        if (s->mag_ref_w < set->mag_ref_window) { /* not yet established: start again here */
            field_set(s->mag_ref, &s->mag_ref_w, w, nm, dip);
        } else { /* a new homogeneous field: it becomes the reference */
            field_set(s->mag_ref, &s->mag_ref_w, s->mag_cand_w, s->mag_cand[0], s->mag_cand[1]);
            *flags |= ATT_AHRS_F_MAG_RELEARNED;
        }
        field_spread_reset(s);
        s->mag_rej_time = 0;
        s->mag_undist_t = set->mag_min_undisturbed;
        return 1;
    }
    s->mag_undist_t = 0;
    *flags |= ATT_AHRS_F_MAG_DISTURBED;
    s->mag_rej_time += dt;
    if (s->mag_rej_time >= set->mag_reject_max) { /* bounded rejection: weak updates again */
        *r *= set->mag_reject_factor * set->mag_reject_factor;
        return 1;
    }
    return 0;
}

/* Magnetometer: m_n = C m; its norm and dip against the reference, its
 * horizontal heading minus the declination measures δθz. A sample's weight in
 * the reference is dt·σ²/(σ² + P_xx + P_yy), σ = mag_dip_tol/2: its dip's
 * share of information while the inclination is uncertain. */
static void mag_update(att_ahrs *s, const att_ahrs_step *k, const att_real C[9], const att_real gyr[3],
                       const att_real mag[3], att_real dt, att_real x[NX], int *flags)
{
    att_real m[3], h, nm, dip, r, w;
    mat_vec(C, mag, m);
    h = att_sqrt(m[0] * m[0] + m[1] * m[1]);
    if (!(h > 0)) {
        return;
    }
    nm = norm3(m);
    dip = att_atan2(-m[2], h);
    w = dt * k->v_dip / (k->v_dip + s->P[0][0] + s->P[1][1]);
    mag_candidate(s, gyr, nm, dip, w, dt);
    if (mag_accept(s, k, nm, dip, w, dt, flags, &r)) {
        /* the heading of m_n measures δθz + tan(dip) (δθ·u), u = (m_x, m_y)/h the horizontal
         * field's direction: an inclination error about magnetic north turns the field's
         * horizontal part (docs/ahrs.md, "Magnetometer"); the gain still moves δθz and δb only */
        att_real row[3] = { 0, 0, 1 };
        row[0] = -m[2] * m[0] / (h * h);
        row[1] = -m[2] * m[1] / (h * h);
        update_mag(s->P, x, row, wrap_pi(att_atan2(m[0], m[1]) - s->set.declination), r);
    }
}

/* Rest: the low-passed rate measures the bias (three zero-rate scalars). */
static void zero_rate_update(att_ahrs *s, const att_ahrs_step *k, att_real x[NX])
{
    int i;
    for (i = 0; i < 3; i++) {
        update_bias(s->P, x, 3 + i, s->rest_gyr[i] - s->bias[i], k->r_rest);
    }
}

/* Injection: q ← exp(δθ) ⊗ q, b ← b + δb; the navigation-frame vectors (acc_lp,
 * and tilt_f, tilt_fd) ← (I + [δθ×]) v. */
static void inject(att_ahrs *s, const att_ahrs_step *k, const att_real x[NX])
{
    if (x[0] != 0 || x[1] != 0 || x[2] != 0) {
        att_real d[4], q0 = s->integ.q[0], q1 = s->integ.q[1], q2 = s->integ.q[2], q3 = s->integ.q[3];
        att__rotvec_delta(x, d);
        s->integ.q[0] = q0 + (d[0] * q0 - d[1] * q1 - d[2] * q2 - d[3] * q3);
        s->integ.q[1] = q1 + (d[0] * q1 + d[1] * q0 + d[2] * q3 - d[3] * q2);
        s->integ.q[2] = q2 + (d[0] * q2 - d[1] * q3 + d[2] * q0 + d[3] * q1);
        s->integ.q[3] = q3 + (d[0] * q3 + d[1] * q2 - d[2] * q1 + d[3] * q0);
        rotate_small(x, s->acc_lp);
        if (k->tilt) {
            rotate_small(x, s->tilt_f);
            rotate_small(x, s->tilt_fd);
        }
    }
    s->bias[0] += x[3];
    s->bias[1] += x[4];
    s->bias[2] += x[5];
}

/* Heading observability (ahrs.h, ATT_AHRS_F_NO_HEADING): p_head is P[2][2] before the
 * magnetometer's stage; only a magnetometer update lowers it (the accelerometer's and
 * the zero-rate updates have zero gain on the heading and leave that entry as it is). */
static int heading_flag(att_ahrs *s, att_real p_head)
{
    att_real m = s->set.heading_sigma_max;
    if (s->P[2][2] < p_head) {
        s->heading_seen = 1;
    }
    return (s->heading_seen && s->P[2][2] + s->turn_var <= m * m) ? 0 : ATT_AHRS_F_NO_HEADING;
}

/* ---- GNSS velocity aiding (docs/ahrs.md, "GNSS velocity aiding") ---- */

/* 1 when the filter is aided at clock time now: a velocity used, at most gnss_timeout old. */
static int gnss_aided_at(const att_ahrs *s, att_real now)
{
    return s->gnss.used && now - s->gnss.used_t <= s->set.gnss_timeout;
}

/* The end of GNSS aiding: the reported inclination's low-pass restarts from the state's
 * own (g e_z at rest: the reported attitude continues from the aided one), the
 * accelerometer's accepted samples then pull it with tilt_tau. */
static void tilt_from_state(att_ahrs *s)
{
    int i;
    for (i = 0; i < 3; i++) {
        s->tilt_f[i] = 0;
        s->tilt_fd[i] = 0;
    }
    s->tilt_f[2] = s->set.gravity;
    s->tilt_t = s->set.tilt_tau;
    s->tilt_mean = 0;
}

static void copy3(att_real dst[3], const att_real src[3])
{
    dst[0] = src[0];
    dst[1] = src[1];
    dst[2] = src[2];
}

/* A history entry at the clock's time holding the current sv. */
static void gnss_push(att_ahrs_gnss *g)
{
    g->hhead = (g->hhead + 1) % ATT_AHRS_GNSS_HIST;
    g->ht[g->hhead] = g->time;
    copy3(g->hs[g->hhead], g->sv);
    if (g->hn < ATT_AHRS_GNSS_HIST) {
        g->hn++;
    }
}

/* End of a successful update: the clock, the flags' state, and once armed the integral
 * sv and the history (an entry when the newest is gnss_max_latency/(HIST − 2) old); a
 * sample without accelerometer breaks the integral: history and anchor start again. */
static void gnss_record(att_ahrs *s, const att_real f_n[3], att_real dt, int aided)
{
    att_ahrs_gnss *g = &s->gnss;
    g->time += dt;
    g->rejected = 0;
    g->aided = aided;
    if (!g->armed) {
        return;
    }
    if (f_n == NULL) {
        g->hn = 0;
        g->anchor = 0;
        g->sv[0] = g->sv[1] = g->sv[2] = 0;
        gnss_push(g);
        return;
    }
    g->sv[0] += f_n[0] * dt;
    g->sv[1] += f_n[1] * dt;
    g->sv[2] += (f_n[2] - s->set.gravity) * dt;
    if (g->time - g->ht[g->hhead] >= s->set.gnss_max_latency / (ATT_AHRS_GNSS_HIST - 2)) {
        gnss_push(g);
    }
}

/* sv at time t, interpolated linearly in the history (the current sv for t at or after
 * the clock): 1, or 0 when t is older than the oldest entry. */
static int gnss_sv_at(const att_ahrs_gnss *g, att_real t, att_real out[3])
{
    att_real t1 = g->time, t0, w;
    const att_real *s1 = g->sv, *s0;
    int n, i, idx = g->hhead;
    if (t >= t1) {
        copy3(out, s1);
        return 1;
    }
    for (n = 0; n < g->hn; n++) {
        t0 = g->ht[idx];
        s0 = g->hs[idx];
        if (t >= t0) {
            w = (t1 > t0) ? (t - t0) / (t1 - t0) : 0;
            for (i = 0; i < 3; i++) {
                out[i] = s0[i] + w * (s1[i] - s0[i]);
            }
            return 1;
        }
        t1 = t0;
        s1 = s0;
        idx = (idx + ATT_AHRS_GNSS_HIST - 1) % ATT_AHRS_GNSS_HIST;
    }
    return 0;
}

/* x ← (x − base) + θ × (x − base + g (t_x − t_a) e_z): an integral re-based to the new
 * anchor and turned by the correction θ (the specific force since the anchor was
 * integrated in the frame before it). */
static void rebase_turn(att_real x[3], const att_real base[3], const att_real th[3], att_real gz)
{
    att_real u0 = x[0] - base[0], u1 = x[1] - base[1], u2 = x[2] - base[2], v2 = u2 + gz;
    x[0] = u0 + (th[1] * v2 - th[2] * u1);
    x[1] = u1 + (th[2] * u0 - th[0] * v2);
    x[2] = u2 + (th[0] * u1 - th[1] * u0);
}

/* The velocity v (time t, sv there sv_t, variance var) becomes the anchor; sv, the
 * history and the anchor's integral are re-based to it and turned by th. */
static void gnss_set_anchor(att_ahrs *s, const att_ahrs_vel *v, const att_real sv_t[3], att_real var,
                            const att_real th[3])
{
    att_ahrs_gnss *g = &s->gnss;
    att_real base[3], grav = s->set.gravity;
    int n, idx = g->hhead;
    copy3(base, sv_t);
    for (n = 0; n < g->hn; n++) {
        rebase_turn(g->hs[idx], base, th, grav * (g->ht[idx] - v->t));
        idx = (idx + ATT_AHRS_GNSS_HIST - 1) % ATT_AHRS_GNSS_HIST;
    }
    rebase_turn(g->sv, base, th, grav * (g->time - v->t));
    g->anchor_t = v->t;
    g->anchor_s[0] = g->anchor_s[1] = g->anchor_s[2] = 0;
    copy3(g->anchor_v, v->vel);
    g->anchor_var = var;
    g->anchor = v->has_up ? 2 : 1;
}

/* The first velocity: the integral and the history start at the clock's time. */
static void gnss_arm(att_ahrs_gnss *g)
{
    g->armed = 1;
    g->hn = 0;
    g->sv[0] = g->sv[1] = g->sv[2] = 0;
    gnss_push(g);
}

/* A sample's checks that return an error (nothing is written). */
static att_status gnss_check(const att_ahrs *s, const att_ahrs_vel *v)
{
    const att_ahrs_gnss *g = &s->gnss;
    if (!fin(v->t) || !fin(v->vel[0]) || !fin(v->vel[1]) || (v->has_up && !fin(v->vel[2])) || !fin(v->sigma)
        || !fin(v->pdop)) {
        return ATT_E_NONFINITE;
    }
    if (v->sigma < 0 || v->pdop < 0 || v->t > g->time + s->step.dt || v->t < g->time - s->set.gnss_max_latency
        || (g->anchor && v->t <= g->anchor_t)) {
        return ATT_E_ARG;
    }
    return ATT_OK;
}

/* The sample's own quality: fix type, PDOP, sigma (1 when usable). */
static int gnss_quality(const att_ahrs_settings *set, const att_ahrs_vel *v, att_real sigma)
{
    if (v->fix_type != ATT_GNSS_FIX_2D && v->fix_type != ATT_GNSS_FIX_3D
        && v->fix_type != ATT_GNSS_FIX_GNSS_DR) {
        return 0;
    }
    if (set->gnss_max_pdop > 0 && v->pdop > set->gnss_max_pdop) {
        return 0;
    }
    return !(set->gnss_max_sigma > 0 && sigma > set->gnss_max_sigma);
}

/* One scalar measurement of the error state: y = h·x + noise of variance r. */
typedef struct {
    att_real h[NX];
    att_real y;
    att_real r;
} gnss_row;

/* Row i of −[F×] (the attitude part of h: r = −F × ... = −[F×] δθ), its bias part
 * h_b = τ h_θ C (δθ at the window's middle = δθ + C τ δb), measurement y. */
static void gnss_row_set(gnss_row *row, const att_real F[3], const att_real u[3], const att_real C[9],
                         att_real tau, att_real y, att_real r)
{
    int j;
    row->h[0] = u[2] * F[1] - u[1] * F[2]; /* u·(−[F×]) for a unit u: (u × F)ᵀ */
    row->h[1] = u[0] * F[2] - u[2] * F[0];
    row->h[2] = u[1] * F[0] - u[0] * F[1];
    for (j = 0; j < 3; j++) {
        row->h[3 + j] = tau * (row->h[0] * C[j] + row->h[1] * C[3 + j] + row->h[2] * C[6 + j]);
    }
    row->y = y;
    row->r = r;
}

/* The rows of one comparison: Δv − Δsv = −[ΔF×] δθ(t_m) + noise, ΔF = Δsv + g Δt e_z.
 * Heading known: the east, north (and up) components. Heading unknown (its column
 * dropped): while |Δv_h| is above 3σ, the horizontal magnitudes compared along Δsv_h
 * (a heading error turns Δsv_h, its length stays); else the components. */
static int gnss_rows(const att_real dsv[3], const att_real dv[3], att_real dT, att_real grav,
                     const att_real C[9], att_real tau, att_real r, int up, int heading, gnss_row rows[3])
{
    static const att_real E[3][3] = { { 1, 0, 0 }, { 0, 1, 0 }, { 0, 0, 1 } };
    att_real F[3], u[3], nv, ns;
    int n = 0;
    F[0] = dsv[0];
    F[1] = dsv[1];
    F[2] = dsv[2] + grav * dT;
    nv = att_sqrt(dv[0] * dv[0] + dv[1] * dv[1]);
    ns = att_sqrt(dsv[0] * dsv[0] + dsv[1] * dsv[1]);
    if (!heading && ns > 0 && nv * nv > 9 * r) {
        u[0] = dsv[0] / ns;
        u[1] = dsv[1] / ns;
        u[2] = 0;
        gnss_row_set(&rows[n++], F, u, C, tau, nv - ns, r);
    } else {
        gnss_row_set(&rows[n++], F, E[0], C, tau, dv[0] - dsv[0], r);
        gnss_row_set(&rows[n++], F, E[1], C, tau, dv[1] - dsv[1], r);
    }
    if (up) {
        gnss_row_set(&rows[n++], F, E[2], C, tau, dv[2] - dsv[2], r);
    }
    if (!heading) {
        int i;
        for (i = 0; i < n; i++) {
            rows[i].h[2] = 0;
        }
    }
    return n;
}

/* The gate: 1 when a row's innovation exceeds gnss_gate standard deviations of
 * h P hᵀ + r (all rows against the prior P). */
static int gnss_gated(const att_ahrs *s, const gnss_row rows[3], int n)
{
    att_real gate = s->set.gnss_gate, S;
    int i, r, c;
    if (!(gate > 0)) {
        return 0;
    }
    for (i = 0; i < n; i++) {
        S = rows[i].r;
        for (r = 0; r < NX; r++) {
            for (c = 0; c < NX; c++) {
                S += rows[i].h[r] * s->P[r][c] * rows[i].h[c];
            }
        }
        if (rows[i].y * rows[i].y > gate * gate * S) {
            return 1;
        }
    }
    return 0;
}

/* A velocity change of |Δv_h| over dT beyond gnss_max_acc·dT: a jump (1). */
static int gnss_jump(const att_ahrs_settings *set, const att_real dv[3], att_real dT)
{
    att_real a = set->gnss_max_acc * dT;
    return set->gnss_max_acc > 0 && dv[0] * dv[0] + dv[1] * dv[1] > a * a;
}

/* (Re)starting the aiding: since the last velocity the accelerometer alone held the
 * inclination, and in a turn or under braking it tilts the state by errors P does not hold
 * (a centripetal acceleration read as gravity), nor their relation to the heading and the
 * bias. The inclination's covariances with the other states are dropped (block diagonal:
 * positive semi-definite as P was), and with grow its variance grows by init_att_sigma², so
 * that it starts again from what the velocities say. */
static void gnss_restart(att_ahrs *s, int grow)
{
    int i, j;
    for (i = 0; i < 2; i++) {
        for (j = 0; j < NX; j++) {
            if (j != i) {
                s->P[i][j] = 0;
                s->P[j][i] = 0;
            }
        }
        if (grow) {
            s->P[i][i] += s->set.init_att_sigma * s->set.init_att_sigma;
        }
    }
}

/* The comparison with the anchor: checks, the Kalman update, the new anchor. */
static att_status gnss_compare(att_ahrs *s, const att_ahrs_vel *v, const att_real sv_t[3], att_real var)
{
    att_ahrs_gnss *g = &s->gnss, gsave = s->gnss;
    att_ahrs save;
    gnss_row rows[3];
    att_real dsv[3], dv[3], C[9], x[NX] = { 0 }, dT = v->t - g->anchor_t;
    int n, i, heading = !(s->flags & ATT_AHRS_F_NO_HEADING);
    for (i = 0; i < 3; i++) {
        dsv[i] = sv_t[i] - g->anchor_s[i];
        dv[i] = v->vel[i] - g->anchor_v[i];
    }
    q2C(s->integ.q, C);
    n = gnss_rows(dsv, dv, dT, s->set.gravity, C, g->time - (v->t + g->anchor_t) * ATT_R(0.5),
                  var + g->anchor_var, v->has_up && g->anchor == 2, heading, rows);
    if (gnss_jump(&s->set, dv, dT)) {
        g->rejected = 1;
        return ATT_OK;
    }
    copy_mutable(&save, s);
    if (gnss_aided_at(s, g->time)) {
        if (gnss_gated(s, rows, n)) {
            g->rejected = 1;
            return ATT_OK;
        }
    } else { /* widened when the velocities see both tilt axes (heading known) or disagree */
        gnss_restart(s, heading || gnss_gated(s, rows, n));
    }
    for (i = 0; i < n; i++) {
        dense_update(s->P, x, rows[i].h, rows[i].y, rows[i].r, heading ? 0x3Fu : 0x3Bu);
    }
    inject(s, &s->step, x);
    if (!finite_state(s)) {
        copy_mutable(s, &save);
        *g = gsave;
        return ATT_E_AHRS_DIVERGED;
    }
    gnss_set_anchor(s, v, sv_t, var, x);
    g->used = 1;
    g->used_t = v->t;
    return ATT_OK;
}

att_status att_ahrs_update_vel(att_ahrs *s, const att_ahrs_vel *v)
{
    static const att_real zero[3] = { 0, 0, 0 };
    att_ahrs_gnss *g;
    att_real sigma, sv_t[3];
    att_status st;
    if (s == NULL || v == NULL) {
        return ATT_E_NULL;
    }
    st = gnss_check(s, v);
    if (st != ATT_OK || !s->aligned) {
        return st;
    }
    g = &s->gnss;
    if (!g->armed) {
        gnss_arm(g);
        return ATT_OK;
    }
    sigma = (v->sigma > 0) ? v->sigma : s->set.gnss_vel_sigma;
    if (!gnss_quality(&s->set, v, sigma)) {
        g->rejected = 1;
        return ATT_OK;
    }
    if (!gnss_sv_at(g, v->t, sv_t)) {
        return ATT_OK;
    }
    if (!g->anchor || v->t - g->anchor_t > s->set.gnss_timeout) {
        gnss_set_anchor(s, v, sv_t, sigma * sigma, zero);
        return ATT_OK;
    }
    if (v->t - g->anchor_t < s->set.gnss_window) { /* too close to the anchor: skipped */
        return ATT_OK;
    }
    return gnss_compare(s, v, sv_t, sigma * sigma);
}

att_real att_ahrs_time(const att_ahrs *s)
{
    return s == NULL ? 0 : s->gnss.time;
}

att_status att_ahrs_vel_from_fix(const att_gnss_fix *fix, att_real t, att_ahrs_vel *out)
{
    if (fix == NULL || out == NULL) {
        return ATT_E_NULL;
    }
    if (!(fix->present & ATT_GNSS_HAS_VEL_NE)) {
        return ATT_E_ARG;
    }
    out->t = t;
    out->vel[0] = fix->vel_e;
    out->vel[1] = fix->vel_n;
    out->has_up = (fix->present & ATT_GNSS_HAS_VEL_D) ? 1 : 0;
    out->vel[2] = out->has_up ? -fix->vel_d : 0;
    out->sigma = (fix->present & ATT_GNSS_HAS_ACC) ? fix->s_acc : 0;
    out->pdop = (fix->present & ATT_GNSS_HAS_PDOP) ? fix->pdop : 0;
    out->fix_type = (fix->present & ATT_GNSS_HAS_FIX_TYPE) ? fix->fix_type : ATT_GNSS_FIX_2D;
    if ((fix->present & ATT_GNSS_HAS_VALID) && !fix->valid) {
        out->fix_type = ATT_GNSS_FIX_NONE;
    }
    return ATT_OK;
}

/* Output: the reported attitude, predicted over sensor_delay (when set) with
 * the corrected rate, q ⊗ exp((ω − b)·d). */
static att_status write_output(const att_ahrs *s, const att_real gyr[3], att_real q_out[4])
{
    att_real ph[3], d[4];
    int i;
    if (q_out == NULL) {
        return ATT_OK;
    }
    report_q(s, q_out);
    if (s->set.sensor_delay != 0) {
        for (i = 0; i < 3; i++) {
            ph[i] = (gyr[i] - s->bias[i]) * s->set.sensor_delay;
        }
        att__rotvec_delta(ph, d);
        att__quat_add_mul(q_out, d);
    }
    return ATT_OK;
}

att_status att_ahrs_update(att_ahrs *s, const att_real gyr[3], const att_real acc[3], const att_real mag[3],
                           att_real dt, att_real q_out[4])
{
    att_ahrs save;
    const att_ahrs_step *k;
    att_real C[9], x[NX] = { 0 }, f_n[3], norm_lp, acc_c[3], mag_c[3], p_head;
    att_status st;
    int rest, flags, aided;
    if (s == NULL || gyr == NULL) {
        return ATT_E_NULL;
    }
    st = check_inputs(s, gyr, acc, mag, dt, &norm_lp);
    if (st == ATT_OK) {
        st = align_once(s, acc, mag);
    }
    if (st != ATT_OK) {
        return st;
    }
    copy_mutable(&save, s);
    k = step_constants(s, dt);
    flags = overrange(&s->set, gyr) ? ATT_AHRS_F_OVERRANGE : 0;
    rest = detect_rest(s, k, gyr, acc, dt);
    aided = gnss_aided_at(s, s->gnss.time + dt);
    if (propagate(s, k, gyr, dt,
                  rest    ? k->q_att_rest
                  : aided ? k->q_att_gnss
                          : k->q_att,
                  flags & ATT_AHRS_F_OVERRANGE, C)
        != 0) {
        copy_mutable(s, &save);
        return ATT_E_AHRS_DIVERGED;
    }
    if (s->gnss.aided && !aided) { /* back to the accelerometer */
        tilt_from_state(s);
    }
    if (k->delays) { /* from here on the aiding samples at the gyro's time (one integer test when both are 0) */
        acc = at_gyro_time(s, gyr, acc, k->delays & 1, s->set.acc_delay, acc_c);
        mag = at_gyro_time(s, gyr, mag, k->delays & 2, s->set.mag_delay, mag_c);
    }
    if (acc != NULL && acc_update(s, k, C, acc, norm_lp, dt, aided, x, &flags, f_n) && k->tilt) {
        tilt_lowpass(s, k, f_n, dt, rest);
    }
    p_head = s->P[2][2];
    if (mag != NULL) {
        mag_update(s, k, C, gyr, mag, dt, x, &flags);
    }
    if (rest) {
        flags |= ATT_AHRS_F_REST;
        zero_rate_update(s, k, x);
    }
    inject(s, k, x);
    flags |= (aided ? ATT_AHRS_F_GNSS_AIDED : 0) | (s->gnss.rejected ? ATT_AHRS_F_GNSS_REJECTED : 0);
    s->flags = flags | heading_flag(s, p_head);
    if (!finite_state(s)) {
        copy_mutable(s, &save);
        return ATT_E_AHRS_DIVERGED;
    }
    gnss_record(s, acc != NULL ? f_n : NULL, dt, aided);
    return write_output(s, gyr, q_out);
}

att_status att_ahrs_batch(att_ahrs *s, const att_real *gyr, const att_real *acc, const att_real *mag,
                          size_t n, const att_real *dt, size_t n_dt, att_real *q_out, size_t *err_index)
{
    return att_ahrs_batch_cov(s, gyr, acc, mag, n, dt, n_dt, q_out, NULL, err_index);
}

att_status att_ahrs_batch_cov(att_ahrs *s, const att_real *gyr, const att_real *acc, const att_real *mag,
                              size_t n, const att_real *dt, size_t n_dt, att_real *q_out, att_real *cov_out,
                              size_t *err_index)
{
    size_t k;
    if (s == NULL || gyr == NULL || acc == NULL || dt == NULL) {
        return ATT_E_NULL;
    }
    if (n_dt != 1 && n_dt != n) {
        return ATT_E_ARG;
    }
    for (k = 0; k < n; k++) {
        att_status st = att_ahrs_update(s, gyr + 3 * k, acc + 3 * k, mag != NULL ? mag + 3 * k : NULL,
                                        n_dt == 1 ? dt[0] : dt[k], q_out != NULL ? q_out + 4 * k : NULL);
        if (st != ATT_OK) {
            if (err_index != NULL) {
                *err_index = k;
            }
            return st;
        }
        if (cov_out != NULL) {
            att_ahrs_covariance(s, cov_out + 9 * k, NULL);
        }
    }
    return ATT_OK;
}

att_status att_ahrs_attitude(const att_ahrs *s, att_real q[4])
{
    if (s == NULL || q == NULL) {
        return ATT_E_NULL;
    }
    if (!s->aligned) {
        return ATT_E_STATE;
    }
    return write_q(s, q);
}

att_status att_ahrs_bias(const att_ahrs *s, att_real b[3])
{
    if (s == NULL || b == NULL) {
        return ATT_E_NULL;
    }
    b[0] = s->bias[0];
    b[1] = s->bias[1];
    b[2] = s->bias[2];
    return ATT_OK;
}

att_status att_ahrs_sigma(const att_ahrs *s, att_real att_sigma[3], att_real bias_sigma[3])
{
    int i;
    if (s == NULL || att_sigma == NULL || bias_sigma == NULL) {
        return ATT_E_NULL;
    }
    for (i = 0; i < 3; i++) {
        att_sigma[i] = att_sqrt(s->P[i][i] > 0 ? s->P[i][i] : 0);
        bias_sigma[i] = att_sqrt(s->P[3 + i][3 + i] > 0 ? s->P[3 + i][3 + i] : 0);
    }
    return ATT_OK;
}

att_status att_ahrs_covariance(const att_ahrs *s, att_real att_cov[9], att_real bias_cov[9])
{
    int i, j;
    if (s == NULL) {
        return ATT_E_NULL;
    }
    for (i = 0; i < 3; i++) {
        for (j = 0; j < 3; j++) {
            if (att_cov != NULL) {
                att_cov[3 * i + j] = s->P[i][j] + (i == j ? s->turn_var : 0);
            }
            if (bias_cov != NULL) {
                bias_cov[3 * i + j] = s->P[3 + i][3 + j];
            }
        }
    }
    if (att_cov != NULL) {
        att_cov[8] += field_heading_var(s);
    }
    return ATT_OK;
}

int att_ahrs_flags(const att_ahrs *s)
{
    return s == NULL ? 0 : s->flags;
}
