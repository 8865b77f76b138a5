/* libattitude — rotation-vector attitude integrator (see integrator.h,
 * docs/integrator.md). */
#include "attitude/integrator.h"

#include "att_math.h"
#include "attitude/quat.h"

static int method_valid(int m)
{
    return m >= 0 && m < (int)ATT_METHOD_COUNT;
}

/* indexed by att_method */
static const char *const method_names[ATT_METHOD_COUNT] = { "rv1",       "rv2", "rv3",           "rv3-coning",
                                                            "rv3-reuse", "rk4", "rv3-reuse-poly" };

const char *att_integ_method_name(att_method method)
{
    return method_valid((int)method) ? method_names[method] : NULL;
}

att_status att_integ_method_from_name(const char *name, att_method *method)
{
    int m;
    if (name == NULL || method == NULL) {
        return ATT_E_NULL;
    }
    for (m = 0; m < (int)ATT_METHOD_COUNT; m++) {
        const char *a = name, *b = method_names[m];
        while (*a != '\0' && *a == *b) {
            a++;
            b++;
        }
        if (*a == *b) {
            *method = (att_method)m;
            return ATT_OK;
        }
    }
    return (att_status)ATT_E_INTEG_METHOD;
}

static int is_reuse(int m)
{
    return m == ATT_METHOD_RV3_REUSE || m == ATT_METHOD_RV3_REUSE_POLY;
}

static void set_coeffs(att_integ *s)
{
    att_real k12 = ATT_R(0.0), k13 = ATT_R(0.0), k23 = ATT_R(0.0);
    switch (s->method) {
    case ATT_METHOD_RV2:
        k12 = ATT_R(ATT_RV2_K_NUM) / ATT_R(ATT_RV2_DEN);
        break;
    case ATT_METHOD_RV3:
        k12 = ATT_R(ATT_RV3_K12_NUM) / ATT_R(ATT_RV3_DEN);
        k13 = ATT_R(ATT_RV3_K13_NUM) / ATT_R(ATT_RV3_DEN);
        k23 = ATT_R(ATT_RV3_K23_NUM) / ATT_R(ATT_RV3_DEN);
        break;
    case ATT_METHOD_RV3_CONING:
        k12 = ATT_R(ATT_RV3C_K12_NUM) / ATT_R(ATT_RV3C_DEN);
        k13 = ATT_R(ATT_RV3C_K13_NUM) / ATT_R(ATT_RV3C_DEN);
        k23 = ATT_R(ATT_RV3C_K23_NUM) / ATT_R(ATT_RV3C_DEN);
        break;
    case ATT_METHOD_RV3_REUSE:
        k12 = ATT_R(ATT_RV3R_K12_NUM) / ATT_R(ATT_RV3R_DEN);
        k13 = ATT_R(ATT_RV3R_K13_NUM) / ATT_R(ATT_RV3R_DEN);
        k23 = ATT_R(ATT_RV3R_K23_NUM) / ATT_R(ATT_RV3R_DEN);
        break;
    case ATT_METHOD_RV3_REUSE_POLY:
        k12 = ATT_R(ATT_RV3RP_K12_NUM) / ATT_R(ATT_RV3RP_DEN);
        k13 = ATT_R(ATT_RV3RP_K13_NUM) / ATT_R(ATT_RV3RP_DEN);
        k23 = ATT_R(ATT_RV3RP_K23_NUM) / ATT_R(ATT_RV3RP_DEN);
        break;
    default:
        break;
    }
    s->k[0] = k12;
    s->k[1] = k13;
    s->k[2] = k23;
}

static att_status load_q0(const att_real q0[4], att_real q[4])
{
    if (q0 == NULL) {
        q[0] = ATT_R(1.0);
        q[1] = ATT_R(0.0);
        q[2] = ATT_R(0.0);
        q[3] = ATT_R(0.0);
        return ATT_OK;
    }
    return att_quat_normalize(q0, q);
}

att_status att_integ_init(att_integ *s, att_method method, const att_real q0[4])
{
    att_real q[4];
    att_status st;
    int i;
    if (s == NULL) {
        return ATT_E_NULL;
    }
    if (!method_valid((int)method)) {
        return (att_status)ATT_E_INTEG_METHOD;
    }
    st = load_q0(q0, q);
    if (st != ATT_OK) {
        return st;
    }
    for (i = 0; i < 4; i++) {
        s->q[i] = q[i];
    }
    for (i = 0; i < 3; i++) {
        s->buf[0][i] = ATT_R(0.0);
        s->buf[1][i] = ATT_R(0.0);
    }
    s->method = (int)method;
    s->nbuf = 0;
    s->since_norm = 0;
    s->updates = 0;
    set_coeffs(s);
    return ATT_OK;
}

att_status att_integ_reset(att_integ *s, const att_real q0[4])
{
    if (s == NULL) {
        return ATT_E_NULL;
    }
    if (!method_valid(s->method)) {
        return ATT_E_STATE;
    }
    return att_integ_init(s, (att_method)s->method, q0);
}

att_status att_integ_attitude(const att_integ *s, att_real q[4])
{
    int i;
    if (s == NULL || q == NULL) {
        return ATT_E_NULL;
    }
    for (i = 0; i < 4; i++) {
        q[i] = s->q[i];
    }
    return ATT_OK;
}

size_t att_integ_outputs(const att_integ *s, size_t n)
{
    size_t nb;
    if (s == NULL || !method_valid(s->method)) {
        return 0;
    }
    nb = (size_t)s->nbuf;
    switch (s->method) {
    case ATT_METHOD_RV2:
        return (nb + n) / 2;
    case ATT_METHOD_RV3:
    case ATT_METHOD_RV3_CONING:
        return (nb + n) / 3;
    case ATT_METHOD_RK4:
        return (nb + n == 0) ? 0 : (nb + n - 1) / 2;
    default:
        return n;
    }
}

att_real att_integ_dtheta_max(void)
{
    return ATT_PI;
}

/* |v|² ≤ π² (v finite or not: NaN and overflowing squares fail). */
static inline int within_pi(const att_real v[3])
{
    att_real p2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    return p2 <= ATT_PI * ATT_PI;
}

/* |ω|·h/2 ≤ π: the angle turned between two rate rows. */
static inline int rate_ok(const att_real w[3], att_real h)
{
    att_real v[3];
    att_real hh = ATT_R(0.5) * h;
    v[0] = w[0] * hh;
    v[1] = w[1] * hh;
    v[2] = w[2] * hh;
    return within_pi(v);
}

/* Status of an increment: ATT_OK, ATT_E_NONFINITE or ATT_E_INTEG_RANGE. */
static inline att_status check_inc(const att_real v[3])
{
    if (within_pi(v)) {
        return ATT_OK;
    }
    return att__finite3(v) ? (att_status)ATT_E_INTEG_RANGE : ATT_E_NONFINITE;
}

/* Apply rotation vector phi to q (locals), renormalizing periodically. */
static inline void step_q(att_real q[4], const att_real phi[3], unsigned int *since_norm)
{
    att_real d[4];
    att__rotvec_delta(phi, d);
    att__quat_add_mul(q, d);
    if (++*since_norm >= (unsigned int)ATT_INTEG_RENORM_PERIOD) {
        att__quat_renorm1(q);
        *since_norm = 0;
    }
}

static void copy3(att_real dst[3], const att_real src[3])
{
    dst[0] = src[0];
    dst[1] = src[1];
    dst[2] = src[2];
}

/* Commit a candidate attitude to the state after checking it. */
static int commit(att_integ *s, const att_real q[4], unsigned int sn, att_real q_out[4])
{
    int i;
    if (!att__finite4(q)) {
        return ATT_E_INTEG_DIVERGED;
    }
    for (i = 0; i < 4; i++) {
        s->q[i] = q[i];
        if (q_out != NULL) {
            q_out[i] = q[i];
        }
    }
    s->since_norm = sn;
    s->updates++;
    return ATT_INTEG_UPDATED;
}

/* Φ of the reuse forms from the two previous increments a (older), b and
 * the newest c: Φ = c + (k13 a + k23 b) × c, plus k12 a × b for the
 * polynomial form (rv3-reuse has k12 = 0: one cross product). One
 * function for the streaming and the batch path, so both round alike. */
static inline void reuse_phi(int method, const att_real k[3], const att_real a[3], const att_real b[3],
                             const att_real c[3], att_real phi[3])
{
    att_real u[3];
    u[0] = k[1] * a[0] + k[2] * b[0];
    u[1] = k[1] * a[1] + k[2] * b[1];
    u[2] = k[1] * a[2] + k[2] * b[2];
    phi[0] = c[0] + (u[1] * c[2] - u[2] * c[1]);
    phi[1] = c[1] + (u[2] * c[0] - u[0] * c[2]);
    phi[2] = c[2] + (u[0] * c[1] - u[1] * c[0]);
    if (method == ATT_METHOD_RV3_REUSE_POLY) {
        att__cross_acc(phi, k[0], a, b);
    }
}

int att_integ_update(att_integ *s, const att_real dtheta[3], att_real q_out[4])
{
    att_real phi[3], q[4];
    unsigned int sn;
    int i, r;
    if (s == NULL || dtheta == NULL) {
        return ATT_E_NULL;
    }
    if (!method_valid(s->method)) {
        return ATT_E_STATE;
    }
    if (s->method == ATT_METHOD_RK4) {
        return ATT_E_INTEG_METHOD;
    }
    r = check_inc(dtheta);
    if (r != ATT_OK) {
        return r;
    }
    copy3(phi, dtheta);
    switch (s->method) {
    case ATT_METHOD_RV2:
        if (s->nbuf < 1) {
            copy3(s->buf[s->nbuf], dtheta);
            s->nbuf++;
            return ATT_INTEG_PENDING;
        }
        phi[0] += s->buf[0][0];
        phi[1] += s->buf[0][1];
        phi[2] += s->buf[0][2];
        att__cross_acc(phi, s->k[0], s->buf[0], dtheta);
        break;
    case ATT_METHOD_RV3:
    case ATT_METHOD_RV3_CONING:
        if (s->nbuf < 2) {
            copy3(s->buf[s->nbuf], dtheta);
            s->nbuf++;
            return ATT_INTEG_PENDING;
        }
        for (i = 0; i < 3; i++) {
            phi[i] += s->buf[0][i] + s->buf[1][i];
        }
        att__cross_acc(phi, s->k[0], s->buf[0], s->buf[1]);
        att__cross_acc(phi, s->k[1], s->buf[0], dtheta);
        att__cross_acc(phi, s->k[2], s->buf[1], dtheta);
        break;
    case ATT_METHOD_RV3_REUSE:
    case ATT_METHOD_RV3_REUSE_POLY:
        if (s->nbuf == 1) {
            att__cross_acc(phi, ATT_R(ATT_RV3R_START_K_NUM) / ATT_R(ATT_RV3R_START_DEN), s->buf[1], dtheta);
        } else if (s->nbuf >= 2) {
            reuse_phi(s->method, s->k, s->buf[0], s->buf[1], dtheta, phi);
        }
        break;
    default: /* rv1 */
        break;
    }
    for (i = 0; i < 4; i++) {
        q[i] = s->q[i];
    }
    sn = s->since_norm;
    step_q(q, phi, &sn);
    r = commit(s, q, sn, q_out);
    if (r < 0) {
        return r;
    }
    if (is_reuse(s->method)) {
        copy3(s->buf[0], s->buf[1]);
        copy3(s->buf[1], dtheta);
        if (s->nbuf < 2) {
            s->nbuf++;
        }
    } else {
        s->nbuf = 0;
    }
    return r;
}

/* RK4 increment d (Q_new = Q + Q ⊗ d) from rates w0, wm, w1 over step h.
 * With a = ½ω0, b = ½ωm, c = ½ω1 (pure quaternions): K1 = a,
 * K2 = (1 + h/2 K1) ⊗ b, K3 = (1 + h/2 K2) ⊗ b, K4 = (1 + h K3) ⊗ c,
 * d = h/6 (K1 + 2 K2 + 2 K3 + K4). */
static void rk4_delta(const att_real w0[3], const att_real wm[3], const att_real w1[3], att_real h,
                      att_real d[4])
{
    att_real K1[4], K2[4], K3[4], K4[4], t[4], b[4], c[4];
    att_real hh = ATT_R(0.5) * h;
    int i;
    K1[0] = ATT_R(0.0);
    b[0] = ATT_R(0.0);
    c[0] = ATT_R(0.0);
    for (i = 0; i < 3; i++) {
        K1[i + 1] = ATT_R(0.5) * w0[i];
        b[i + 1] = ATT_R(0.5) * wm[i];
        c[i + 1] = ATT_R(0.5) * w1[i];
    }
    for (i = 0; i < 4; i++) {
        t[i] = hh * K1[i];
    }
    t[0] += ATT_R(1.0);
    att_quat_mul(t, b, K2);
    for (i = 0; i < 4; i++) {
        t[i] = hh * K2[i];
    }
    t[0] += ATT_R(1.0);
    att_quat_mul(t, b, K3);
    for (i = 0; i < 4; i++) {
        t[i] = h * K3[i];
    }
    t[0] += ATT_R(1.0);
    att_quat_mul(t, c, K4);
    for (i = 0; i < 4; i++) {
        d[i] = (h / ATT_R(6.0)) * (K1[i] + ATT_R(2.0) * (K2[i] + K3[i]) + K4[i]);
    }
}

int att_integ_update_rate(att_integ *s, const att_real omega[3], att_real h, att_real q_out[4])
{
    att_real d[4], q[4];
    unsigned int sn;
    int i, r;
    if (s == NULL || omega == NULL) {
        return ATT_E_NULL;
    }
    if (!method_valid(s->method)) {
        return ATT_E_STATE;
    }
    if (s->method != ATT_METHOD_RK4) {
        return ATT_E_INTEG_METHOD;
    }
    if (!att__finite3(omega)) {
        return ATT_E_NONFINITE;
    }
    if (s->nbuf < 2) {
        copy3(s->buf[s->nbuf], omega);
        s->nbuf++;
        return ATT_INTEG_PENDING;
    }
    if (!(h > ATT_R(0.0)) || !isfinite(h)) {
        return ATT_E_ARG;
    }
    if (!rate_ok(s->buf[0], h) || !rate_ok(s->buf[1], h) || !rate_ok(omega, h)) {
        return ATT_E_INTEG_RANGE;
    }
    rk4_delta(s->buf[0], s->buf[1], omega, h, d);
    for (i = 0; i < 4; i++) {
        q[i] = s->q[i];
    }
    att__quat_add_mul(q, d);
    /* unlike q(Φ), the RK4 step is not norm-preserving (its norm error
     * grows with the rate's variation over the step): renormalize every
     * update, exactly (sqrt) since that error is not always tiny */
    {
        att_real n = att_sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
        for (i = 0; i < 4; i++) {
            q[i] /= n;
        }
    }
    sn = 0;
    r = commit(s, q, sn, q_out);
    if (r < 0) {
        return r;
    }
    copy3(s->buf[0], omega);
    s->nbuf = 1;
    return r;
}

/* ---- batch ------------------------------------------------------------ */

/* Feed increments one by one through att_integ_update (used for the
 * partial frames at both ends of a batch). */
static att_status feed_single(att_integ *s, const att_real *dth, size_t i0, size_t i1, att_real *q_out,
                              size_t *nout, size_t *err_index)
{
    size_t i;
    for (i = i0; i < i1; i++) {
        int r = att_integ_update(s, dth + 3 * i, q_out + 4 * *nout);
        if (r < 0) {
            *err_index = i;
            return (att_status)r;
        }
        if (r == ATT_INTEG_UPDATED) {
            (*nout)++;
        }
    }
    return ATT_OK;
}

/* First increment in [i0, i1) that is not finite or beyond |Δθ| ≤ π, or i1. */
static size_t first_unchecked(const att_real *dth, size_t i0, size_t i1)
{
    size_t i;
    for (i = i0; i < i1; i++) {
        if (!within_pi(dth + 3 * i)) {
            return i;
        }
    }
    return i1; /* none */
}

/* Fast loop over whole frames of m increments (m = 1, 2 or 3) starting at
 * increment i0, with an empty frame buffer. Returns the number of
 * increments consumed, or sets *st on failure. */
static size_t frames_fast(att_integ *s, const att_real *dth, size_t i0, size_t nframes, int m,
                          att_real *q_out, size_t *nout, att_status *st, size_t *err_index)
{
    att_real q[4], phi[3];
    const att_real k12 = s->k[0], k13 = s->k[1], k23 = s->k[2];
    unsigned int sn = s->since_norm;
    size_t f, no = *nout;
    int i;
    for (i = 0; i < 4; i++) {
        q[i] = s->q[i];
    }
    for (f = 0; f < nframes; f++) {
        const att_real *a = dth + 3 * (i0 + (size_t)m * f);
        att_real *o = q_out + 4 * no;
        int ok = within_pi(a); /* |Δθ| ≤ π for each increment of the frame (NaN fails too) */
        if (m == 1) {
            phi[0] = a[0];
            phi[1] = a[1];
            phi[2] = a[2];
        } else if (m == 2) {
            const att_real *b = a + 3;
            ok &= within_pi(b);
            phi[0] = a[0] + b[0] + k12 * (a[1] * b[2] - a[2] * b[1]);
            phi[1] = a[1] + b[1] + k12 * (a[2] * b[0] - a[0] * b[2]);
            phi[2] = a[2] + b[2] + k12 * (a[0] * b[1] - a[1] * b[0]);
        } else {
            const att_real *b = a + 3, *c = a + 6;
            ok &= within_pi(b) & within_pi(c);
            phi[0] = a[0] + b[0] + c[0] + k12 * (a[1] * b[2] - a[2] * b[1])
                     + k13 * (a[1] * c[2] - a[2] * c[1]) + k23 * (b[1] * c[2] - b[2] * c[1]);
            phi[1] = a[1] + b[1] + c[1] + k12 * (a[2] * b[0] - a[0] * b[2])
                     + k13 * (a[2] * c[0] - a[0] * c[2]) + k23 * (b[2] * c[0] - b[0] * c[2]);
            phi[2] = a[2] + b[2] + c[2] + k12 * (a[0] * b[1] - a[1] * b[0])
                     + k13 * (a[0] * c[1] - a[1] * c[0]) + k23 * (b[0] * c[1] - b[1] * c[0]);
        }
        step_q(q, phi, &sn);
        if (!ok || !att__finite4(q)) {
            size_t lo = i0 + (size_t)m * f, hi = lo + (size_t)m;
            size_t bad = first_unchecked(dth, lo, hi);
            *st = (bad < hi) ? check_inc(dth + 3 * bad) : (att_status)ATT_E_INTEG_DIVERGED;
            *err_index = (bad < hi) ? bad : hi - 1;
            return 0;
        }
        o[0] = q[0];
        o[1] = q[1];
        o[2] = q[2];
        o[3] = q[3];
        no++;
    }
    for (i = 0; i < 4; i++) {
        s->q[i] = q[i];
    }
    s->since_norm = sn;
    s->updates += (unsigned long)nframes;
    *nout = no;
    return (size_t)m * nframes;
}

/* Reuse-form fast loop: history already full (nbuf == 2). */
static size_t reuse_fast(att_integ *s, const att_real *dth, size_t i0, size_t n, att_real *q_out,
                         size_t *nout, att_status *st, size_t *err_index)
{
    att_real q[4], phi[3], a[3], b[3];
    const int method = s->method;
    unsigned int sn = s->since_norm;
    size_t j, no = *nout;
    int i;
    for (i = 0; i < 4; i++) {
        q[i] = s->q[i];
    }
    copy3(a, s->buf[0]);
    copy3(b, s->buf[1]);
    for (j = 0; j < n; j++) {
        const att_real *c = dth + 3 * (i0 + j);
        att_real *o = q_out + 4 * no;
        reuse_phi(method, s->k, a, b, c, phi);
        step_q(q, phi, &sn);
        if (!within_pi(c) || !att__finite4(q)) {
            *st = within_pi(c) ? (att_status)ATT_E_INTEG_DIVERGED : check_inc(c);
            *err_index = i0 + j;
            return 0;
        }
        o[0] = q[0];
        o[1] = q[1];
        o[2] = q[2];
        o[3] = q[3];
        no++;
        copy3(a, b);
        copy3(b, c);
    }
    for (i = 0; i < 4; i++) {
        s->q[i] = q[i];
    }
    copy3(s->buf[0], a);
    copy3(s->buf[1], b);
    s->since_norm = sn;
    s->updates += (unsigned long)n;
    *nout = no;
    return n;
}

att_status att_integ_batch(att_integ *s, const att_real *dtheta, size_t n, att_real *q_out, size_t *n_out,
                           size_t *err_index)
{
    att_integ saved;
    att_status st = ATT_OK;
    size_t i = 0, nout = 0, bad = 0;
    int m;
    if (n_out != NULL) {
        *n_out = 0;
    }
    if (s == NULL) {
        return ATT_E_NULL;
    }
    if (n == 0) {
        return ATT_OK;
    }
    if (dtheta == NULL || q_out == NULL) {
        return ATT_E_NULL;
    }
    if (!method_valid(s->method)) {
        return ATT_E_STATE;
    }
    if (s->method == ATT_METHOD_RK4) {
        return (att_status)ATT_E_INTEG_METHOD;
    }
    saved = *s;
    switch (s->method) {
    case ATT_METHOD_RV2:
        m = 2;
        break;
    case ATT_METHOD_RV3:
    case ATT_METHOD_RV3_CONING:
        m = 3;
        break;
    default:
        m = 1;
        break;
    }
    if (is_reuse(s->method)) {
        /* start-up (fewer than two previous increments) one by one */
        while (i < n && s->nbuf < 2 && st == ATT_OK) {
            st = feed_single(s, dtheta, i, i + 1, q_out, &nout, &bad);
            i++;
        }
        if (st == ATT_OK && i < n) {
            i += reuse_fast(s, dtheta, i, n - i, q_out, &nout, &st, &bad);
        }
    } else {
        /* complete the frame left from an earlier call */
        while (i < n && s->nbuf != 0 && st == ATT_OK) {
            st = feed_single(s, dtheta, i, i + 1, q_out, &nout, &bad);
            i++;
        }
        if (st == ATT_OK && i < n) {
            size_t nf = (n - i) / (size_t)m;
            i += frames_fast(s, dtheta, i, nf, m, q_out, &nout, &st, &bad);
        }
        if (st == ATT_OK && i < n) { /* leftovers: buffered (and checked) */
            st = feed_single(s, dtheta, i, n, q_out, &nout, &bad);
        }
    }
    if (st != ATT_OK) {
        *s = saved;
        if (err_index != NULL) {
            *err_index = bad;
        }
        return st;
    }
    if (n_out != NULL) {
        *n_out = nout;
    }
    return ATT_OK;
}

att_status att_integ_rk4_batch(att_integ *s, const att_real *omega, size_t n, const att_real *h, size_t n_h,
                               att_real *q_out, size_t *n_out, size_t *err_index)
{
    att_integ saved;
    size_t i, nout = 0, need;
    if (n_out != NULL) {
        *n_out = 0;
    }
    if (s == NULL) {
        return ATT_E_NULL;
    }
    if (!method_valid(s->method)) {
        return ATT_E_STATE;
    }
    if (s->method != ATT_METHOD_RK4) {
        return (att_status)ATT_E_INTEG_METHOD;
    }
    if (n == 0) {
        return ATT_OK;
    }
    if (omega == NULL || h == NULL || q_out == NULL) {
        return ATT_E_NULL;
    }
    need = att_integ_outputs(s, n);
    if (n_h == 0 || (n_h != 1 && n_h < need)) {
        return ATT_E_ARG;
    }
    saved = *s;
    for (i = 0; i < n; i++) {
        att_real hj = h[n_h == 1 ? 0 : (nout < n_h ? nout : n_h - 1)];
        int r = att_integ_update_rate(s, omega + 3 * i, hj, q_out + 4 * nout);
        if (r < 0) {
            size_t bad = i;
            if (r == ATT_E_INTEG_RANGE) { /* name the first offending row of this call */
                if (i >= 2 && !rate_ok(omega + 3 * (i - 2), hj)) {
                    bad = i - 2;
                } else if (i >= 1 && !rate_ok(omega + 3 * (i - 1), hj)) {
                    bad = i - 1;
                }
            }
            *s = saved;
            if (err_index != NULL) {
                *err_index = bad;
            }
            return (att_status)r;
        }
        if (r == ATT_INTEG_UPDATED) {
            nout++;
        }
    }
    if (n_out != NULL) {
        *n_out = nout;
    }
    return ATT_OK;
}
