/*
 * libattitude — the Gauss-Newton quaternion from specific force and field
 * (csrc/include/attitude/aiding.h; derivation and the deviations from the
 * UAV thesis' listing in docs/aiding.md).
 */
#include "aiding_internal.h"
#include "att_math.h"
#include "attitude/aiding.h"

void att_gn_defaults(att_gn_settings *s)
{
    if (s == NULL)
        return;
    s->method = ATT_GN_GAUSS_NEWTON;
    s->max_iter = 20u;
#if defined(ATT_REAL_F32)
    s->tol_residual = ATT_R(2e-6);
    s->tol_step = ATT_R(2e-6);
    s->accept_residual = ATT_R(1e-4);
#else
    s->tol_residual = ATT_R(1e-13);
    s->tol_step = ATT_R(1e-13);
    s->accept_residual = ATT_R(1e-8);
#endif
    s->damping = ATT_R(1e-4);
    s->max_step = ATT_R(0.5);
    s->singular_tol = ATT_R(1e-6);
}

static int gn_settings_ok(const att_gn_settings *s)
{
    return (s->method == ATT_GN_GAUSS_NEWTON || s->method == ATT_GN_SIMPLIFIED) && s->max_iter >= 1u
           && s->max_iter <= 1000u && isfinite(s->tol_residual) && s->tol_residual >= ATT_R(0.0)
           && isfinite(s->tol_step) && s->tol_step >= ATT_R(0.0) && isfinite(s->accept_residual)
           && s->accept_residual >= ATT_R(0.0) && isfinite(s->damping) && s->damping >= ATT_R(0.0)
           && isfinite(s->max_step) && s->max_step > ATT_R(0.0) && isfinite(s->singular_tol)
           && s->singular_tol >= ATT_R(0.0) && s->singular_tol < ATT_R(1.0);
}

/* r = [C(q)ᵀ e_z − f̂; e_xᵀ C(q) m̂] (unnormalized quadratic form of q). */
static void gn_residual(const att_real q[4], const att_real f[3], const att_real m[3], att_real r[4])
{
    att_real a = q[0], b = q[1], c = q[2], d = q[3];
    r[0] = ATT_R(2.0) * (b * d - a * c) - f[0];
    r[1] = ATT_R(2.0) * (c * d + a * b) - f[1];
    r[2] = (a * a - b * b - c * c + d * d) - f[2];
    r[3] = m[0] * (a * a + b * b - c * c - d * d)
           + ATT_R(2.0) * (m[1] * (b * c - a * d) + m[2] * (b * d + a * c));
}

/* J = ∂r/∂q (4 × 4, row-major). */
static void gn_jacobian(const att_real q[4], const att_real m[3], att_real J[16])
{
    att_real a = ATT_R(2.0) * q[0], b = ATT_R(2.0) * q[1], c = ATT_R(2.0) * q[2], d = ATT_R(2.0) * q[3];
    J[0] = -c;
    J[1] = d;
    J[2] = -a;
    J[3] = b;
    J[4] = b;
    J[5] = a;
    J[6] = d;
    J[7] = c;
    J[8] = a;
    J[9] = -b;
    J[10] = -c;
    J[11] = d;
    J[12] = m[0] * a - m[1] * d + m[2] * c;
    J[13] = m[0] * b + m[1] * c + m[2] * d;
    J[14] = -m[0] * c + m[1] * b + m[2] * a;
    J[15] = -m[0] * d - m[1] * a + m[2] * b;
}

static att_real gn_dot4(const att_real a[4], const att_real b[4])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
}

/* N = JᵀJ (symmetric, full 4 × 4). */
static void gn_normal(const att_real J[16], att_real N[16])
{
    int i, j, k;
    for (i = 0; i < 4; ++i)
        for (j = i; j < 4; ++j) {
            att_real s = ATT_R(0.0);
            for (k = 0; k < 4; ++k)
                s += J[4 * k + i] * J[4 * k + j];
            N[4 * i + j] = s;
            N[4 * j + i] = s;
        }
}

/* LDLᵀ of A + μI (in place into L, D); returns the smallest pivot over the
 * largest diagonal entry of A (a reciprocal-condition estimate), < 0 if a
 * pivot is not positive. */
static att_real gn_ldl(const att_real A[16], att_real mu, att_real L[16], att_real D[4])
{
    att_real dmax = ATT_R(0.0), pmin;
    int i, j, k;
    for (i = 0; i < 4; ++i)
        if (A[5 * i] > dmax)
            dmax = A[5 * i];
    if (!(dmax > ATT_R(0.0)))
        return ATT_R(-1.0);
    pmin = dmax + mu;
    for (j = 0; j < 4; ++j) {
        att_real dj = A[5 * j] + mu;
        for (k = 0; k < j; ++k)
            dj -= L[4 * j + k] * L[4 * j + k] * D[k];
        if (!(dj > ATT_R(0.0)))
            return ATT_R(-1.0);
        D[j] = dj;
        if (dj < pmin)
            pmin = dj;
        L[5 * j] = ATT_R(1.0);
        for (i = j + 1; i < 4; ++i) {
            att_real s = A[4 * i + j];
            for (k = 0; k < j; ++k)
                s -= L[4 * i + k] * L[4 * j + k] * D[k];
            L[4 * i + j] = s / dj;
        }
    }
    return pmin / dmax;
}

/* Solve (L D Lᵀ) x = b. */
static void gn_ldl_solve(const att_real L[16], const att_real D[4], const att_real b[4], att_real x[4])
{
    int i, k;
    for (i = 0; i < 4; ++i) {
        att_real s = b[i];
        for (k = 0; k < i; ++k)
            s -= L[4 * i + k] * x[k];
        x[i] = s;
    }
    for (i = 0; i < 4; ++i)
        x[i] /= D[i];
    for (i = 3; i >= 0; --i) {
        att_real s = x[i];
        for (k = i + 1; k < 4; ++k)
            s -= L[4 * k + i] * x[k];
        x[i] = s;
    }
}

/* out = q_z(angle) ⊗ q for a rotation about nav up given by c = cos(angle/2), s = sin(angle/2). */
static void gn_turn_up(att_real c, att_real s, const att_real q[4], att_real out[4])
{
    att_real a = q[0], b = q[1], cc = q[2], d = q[3];
    out[0] = c * a - s * d;
    out[1] = c * b - s * cc;
    out[2] = c * cc + s * b;
    out[3] = c * d + s * a;
}

static int gn_normalize(att_real q[4])
{
    att_real n = att_sqrt(gn_dot4(q, q));
    if (!(n > ATT_AID_TINY) || !isfinite(n))
        return 0;
    q[0] /= n;
    q[1] /= n;
    q[2] /= n;
    q[3] /= n;
    return 1;
}

att_status att_gn_solve(const att_real f_b[3], const att_real m_b[3], att_real declination_rad,
                        const att_real q0[4], const att_gn_settings *s, att_real q[4], att_gn_result *r)
{
    att_gn_settings def;
    att_gn_result res;
    att_real fu[3], mu_[3], fxm[3], x[4], res4[4], J[16], N[16], L[16], D[4], g[4], dx[4], xn[4], rn[4];
    att_real cost, cost_n, mu, rc, hc, hs, sn, step_n;
    att_status st;
    int i, k, have_j = 0;
    if (f_b == NULL || m_b == NULL || q == NULL)
        return ATT_E_NULL;
    if (s == NULL) {
        att_gn_defaults(&def);
        s = &def;
    }
    if (!gn_settings_ok(s))
        return ATT_E_ARG;
    if (q0 != NULL && !att__finite4(q0))
        return ATT_E_NONFINITE;
    st = aid_pair(f_b, m_b, declination_rad, fu, mu_, fxm);
    if (st != ATT_OK)
        return st;
    /* start: q0, or without it TRIAD's closed form (a cold start from the identity
     * fails to converge on ~0.2 % of attitudes: docs/aiding.md) */
    if (q0 == NULL) {
        st = att_triad(f_b, m_b, declination_rad, xn);
        if (st != ATT_OK)
            return st;
    } else {
        for (i = 0; i < 4; ++i)
            xn[i] = q0[i];
    }
    if (!gn_normalize(xn))
        return ATT_E_ARG;
    /* q_m = q_z(D) ⊗ q0 (the attitude relative to magnetic north) */
    hc = att_cos(ATT_R(0.5) * declination_rad);
    hs = att_sin(ATT_R(0.5) * declination_rad);
    gn_turn_up(hc, hs, xn, x);
    res.iterations = 0u;
    res.jacobians = 0u;
    res.step = ATT_R(0.0);
    gn_residual(x, fu, mu_, res4);
    cost = gn_dot4(res4, res4);
    mu = ATT_R(-1.0);
    st = ATT_AID_E_NOCONV;
    for (;;) {
        if (att_sqrt(cost) <= s->tol_residual) {
            st = ATT_OK;
            break;
        }
        if (res.iterations >= s->max_iter)
            break;
        if (!have_j) { /* at the start, and after each accepted Gauss-Newton step */
            gn_jacobian(x, mu_, J);
            res.jacobians += 1u;
            gn_normal(J, N);
            rc = gn_ldl(N, ATT_R(0.0), L, D);
            if (!(rc >= s->singular_tol * s->singular_tol)) {
                st = ATT_AID_E_SINGULAR;
                break;
            }
            if (mu < ATT_R(0.0))
                mu = s->damping * ATT_R(0.25) * (N[0] + N[5] + N[10] + N[15]);
            have_j = 1;
        }
        res.iterations += 1u;
        /* g = Jᵀ r (with the Jacobian of the start in the simplified method) */
        for (i = 0; i < 4; ++i) {
            g[i] = ATT_R(0.0);
            for (k = 0; k < 4; ++k)
                g[i] -= J[4 * k + i] * res4[k];
        }
        if (gn_ldl(N, mu, L, D) < ATT_R(0.0)) {
            st = ATT_AID_E_SINGULAR;
            break;
        }
        gn_ldl_solve(L, D, g, dx);
        step_n = att_sqrt(gn_dot4(dx, dx));
        if (!isfinite(step_n)) {
            st = ATT_AID_E_SINGULAR;
            break;
        }
        if (step_n > s->max_step) {
            att_real k_ = s->max_step / step_n;
            for (i = 0; i < 4; ++i)
                dx[i] *= k_;
            step_n = s->max_step;
        }
        for (i = 0; i < 4; ++i)
            xn[i] = x[i] + dx[i];
        if (!gn_normalize(xn)) {
            st = ATT_AID_E_SINGULAR;
            break;
        }
        gn_residual(xn, fu, mu_, rn);
        cost_n = gn_dot4(rn, rn);
        if (cost_n < cost) { /* accept */
            for (i = 0; i < 4; ++i) {
                x[i] = xn[i];
                res4[i] = rn[i];
            }
            cost = cost_n;
            res.step = step_n;
            mu *= ATT_R(0.1);
            if (s->method == ATT_GN_GAUSS_NEWTON)
                have_j = 0;
            if (step_n <= s->tol_step) {
                st = att_sqrt(cost) <= s->accept_residual ? ATT_OK : ATT_AID_E_NOCONV;
                break;
            }
        } else { /* reject: more damping */
            mu = mu > ATT_R(0.0) ? mu * ATT_R(10.0) : ATT_R(1e-6) * (N[0] + N[5] + N[10] + N[15]);
            if (!(mu < ATT_R(1e20)))
                break;
            if (step_n <= s->tol_step) { /* no smaller step can help */
                st = att_sqrt(cost) <= s->accept_residual ? ATT_OK : ATT_AID_E_NOCONV;
                break;
            }
        }
    }
    res.residual = att_sqrt(cost);
    if (r != NULL)
        *r = res;
    if (st != ATT_OK)
        return st;
    /* the other root of r4 = 0 points the field south: turn by π about up */
    sn = ATT_R(2.0) * (x[1] * x[2] + x[0] * x[3]) * mu_[0]
         + (x[0] * x[0] - x[1] * x[1] + x[2] * x[2] - x[3] * x[3]) * mu_[1]
         + ATT_R(2.0) * (x[2] * x[3] - x[0] * x[1]) * mu_[2];
    if (sn < ATT_R(0.0)) {
        gn_turn_up(ATT_R(0.0), ATT_R(1.0), x, xn);
        for (i = 0; i < 4; ++i)
            x[i] = xn[i];
    }
    /* back to true north: q = q_z(−D) ⊗ q_m, λ ≥ 0 */
    gn_turn_up(hc, -hs, x, xn);
    if (xn[0] < ATT_R(0.0))
        for (i = 0; i < 4; ++i)
            xn[i] = -xn[i];
    if (!att__finite4(xn))
        return ATT_AID_E_SINGULAR;
    for (i = 0; i < 4; ++i)
        q[i] = xn[i];
    return ATT_OK;
}

att_status att_gn_solve_n(const att_real *f_b, const att_real *m_b, att_real declination_rad,
                          const att_real *q0, const att_gn_settings *s, att_real *q, size_t n, int *status,
                          unsigned int *iterations, att_real *residual)
{
    att_status first = ATT_OK;
    att_gn_result r;
    size_t i;
    if (n == 0u)
        return ATT_OK;
    if (f_b == NULL || m_b == NULL || q == NULL || status == NULL)
        return ATT_E_NULL;
    for (i = 0; i < n; ++i) {
        r.iterations = 0u;
        r.jacobians = 0u;
        r.residual = ATT_R(0.0);
        r.step = ATT_R(0.0);
        status[i] = att_gn_solve(f_b + 3u * i, m_b + 3u * i, declination_rad, q0 != NULL ? q0 + 4u * i : NULL,
                                 s, q + 4u * i, &r);
        if (iterations != NULL)
            iterations[i] = r.iterations;
        if (residual != NULL)
            residual[i] = r.residual;
        if (status[i] != ATT_OK && first == ATT_OK)
            first = status[i];
    }
    return first;
}
