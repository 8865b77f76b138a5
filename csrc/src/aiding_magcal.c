/*
 * libattitude — magnetometer calibration: streaming ellipsoid fit from
 * fixed-size moments, its apply function and the 2-D min/max method
 * (csrc/include/attitude/aiding.h; derivation in docs/aiding.md).
 */
#include "aiding_internal.h"
#include "att_math.h"
#include "attitude/aiding.h"

#if defined(ATT_REAL_F32)
#define mc_cbrt        cbrtf
#define MC_PIVOT_RCOND ATT_R(1e-6) /* relative LDLᵀ pivot below this: no span */
#define MC_JACOBI_EPS  ATT_R(1e-7)
#else
#define mc_cbrt        cbrt
#define MC_PIVOT_RCOND ATT_R(1e-12)
#define MC_JACOBI_EPS  ATT_R(1e-15)
#endif
#define MC_MAX_SPAN ATT_R(0.5774) /* √(1/3): the span of a full sphere */
#define MC_NMOM     35
#define MC_NCOL     9

/* Index of the moment Σ x^a y^b z^c (a + b + c ≤ 4): ordered by degree d,
 * then a from d down to 0, then b from d − a down to 0. */
static int mc_idx(int a, int b, int c)
{
    int d = a + b + c;
    return d * (d + 1) * (d + 2) / 6 + (d - a) * (d - a + 1) / 2 + (d - a - b);
}

/* The columns of the fit (polynomials in u) and the target x² + y² + z². */
typedef struct {
    signed char k;
    unsigned char a, b, c;
} mc_term;

typedef struct {
    unsigned char nt;
    mc_term t[3];
} mc_poly;

static const mc_poly MC_COL[MC_NCOL] = {
    { 3, { { 1, 2, 0, 0 }, { 1, 0, 2, 0 }, { -2, 0, 0, 2 } } }, /* x² + y² − 2z² */
    { 3, { { 1, 2, 0, 0 }, { 1, 0, 0, 2 }, { -2, 0, 2, 0 } } }, /* x² + z² − 2y² */
    { 1, { { 2, 1, 1, 0 } } },                                  /* 2xy */
    { 1, { { 2, 1, 0, 1 } } },                                  /* 2xz */
    { 1, { { 2, 0, 1, 1 } } },                                  /* 2yz */
    { 1, { { 2, 1, 0, 0 } } },                                  /* 2x */
    { 1, { { 2, 0, 1, 0 } } },                                  /* 2y */
    { 1, { { 2, 0, 0, 1 } } },                                  /* 2z */
    { 1, { { 1, 0, 0, 0 } } },                                  /* 1 */
};
static const mc_poly MC_TARGET = { 3, { { 1, 2, 0, 0 }, { 1, 0, 2, 0 }, { 1, 0, 0, 2 } } };

/* The columns of each model (OFFSET, DIAGONAL, FULL), -1 terminated. */
static const signed char MC_MODEL[3][MC_NCOL + 1] = {
    { 5, 6, 7, 8, -1 },
    { 0, 1, 5, 6, 7, 8, -1 },
    { 0, 1, 2, 3, 4, 5, 6, 7, 8, -1 },
};

/* Σ p q over the samples, from the moments. */
static att_real mc_inner(const att_real mom[MC_NMOM], const mc_poly *p, const mc_poly *q)
{
    att_real s = ATT_R(0.0);
    int i, j;
    for (i = 0; i < p->nt; ++i)
        for (j = 0; j < q->nt; ++j)
            s += (att_real)(p->t[i].k * q->t[j].k)
                 * mom[mc_idx(p->t[i].a + q->t[j].a, p->t[i].b + q->t[j].b, p->t[i].c + q->t[j].c)];
    return s;
}

void att_magcal_defaults(att_magcal_settings *s)
{
    if (s == NULL)
        return;
    s->min_samples = 20u;
    s->min_span = ATT_R(0.1);
}

att_status att_magcal_init(att_magcal *c, const att_magcal_settings *s)
{
    att_magcal_settings d;
    int i;
    if (c == NULL)
        return ATT_E_NULL;
    if (s == NULL) {
        att_magcal_defaults(&d);
        s = &d;
    }
    if (s->min_samples < 10u || !isfinite(s->min_span) || s->min_span < ATT_R(0.0)
        || s->min_span > MC_MAX_SPAN)
        return ATT_E_ARG;
    c->s = *s;
    c->n = 0u;
    c->inv_s = ATT_R(1.0);
    for (i = 0; i < 3; ++i)
        c->c[i] = ATT_R(0.0);
    for (i = 0; i < MC_NMOM; ++i)
        c->mom[i] = ATT_R(0.0);
    return ATT_OK;
}

att_status att_magcal_add(att_magcal *c, const att_real m[3])
{
    att_real px[5], py[5], pz[5];
    int d, a, b, i = 0;
    if (c == NULL || m == NULL)
        return ATT_E_NULL;
    if (!att__finite3(m))
        return ATT_E_NONFINITE;
    if (c->n == 0u) {
        att_real n = att_sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
        c->c[0] = m[0];
        c->c[1] = m[1];
        c->c[2] = m[2];
        c->inv_s = (n > ATT_AID_TINY && isfinite(n)) ? ATT_R(1.0) / n : ATT_R(1.0);
    }
    px[0] = py[0] = pz[0] = ATT_R(1.0);
    px[1] = (m[0] - c->c[0]) * c->inv_s;
    py[1] = (m[1] - c->c[1]) * c->inv_s;
    pz[1] = (m[2] - c->c[2]) * c->inv_s;
    for (d = 2; d < 5; ++d) {
        px[d] = px[d - 1] * px[1];
        py[d] = py[d - 1] * py[1];
        pz[d] = pz[d - 1] * pz[1];
    }
    for (d = 0; d < 5; ++d)
        for (a = d; a >= 0; --a)
            for (b = d - a; b >= 0; --b)
                c->mom[i++] += px[a] * py[b] * pz[d - a - b];
    c->n += 1u;
    return ATT_OK;
}

att_status att_magcal_add_n(att_magcal *c, const att_real *m, size_t n, size_t *err_index)
{
    size_t i;
    if (n == 0u)
        return ATT_OK;
    if (c == NULL || m == NULL)
        return ATT_E_NULL;
    for (i = 0; i < n; ++i) {
        att_status st = att_magcal_add(c, m + 3u * i);
        if (st != ATT_OK) {
            if (err_index != NULL)
                *err_index = i;
            return st;
        }
    }
    return ATT_OK;
}

/* Cyclic Jacobi on a symmetric 3 × 3 A (row-major): on return the diagonal
 * of A holds the eigenvalues and the columns of V the eigenvectors. */
static void mc_jacobi3(att_real A[9], att_real V[9])
{
    int sweep, p, q, k;
    for (k = 0; k < 9; ++k)
        V[k] = (k % 4 == 0) ? ATT_R(1.0) : ATT_R(0.0);
    for (sweep = 0; sweep < 16; ++sweep) {
        att_real off = att_fabs(A[1]) + att_fabs(A[2]) + att_fabs(A[5]);
        att_real dia = att_fabs(A[0]) + att_fabs(A[4]) + att_fabs(A[8]);
        if (!(off > MC_JACOBI_EPS * dia))
            break;
        for (p = 0; p < 2; ++p)
            for (q = p + 1; q < 3; ++q) {
                att_real apq = A[3 * p + q], th, t, cs, sn;
                if (apq == ATT_R(0.0))
                    continue;
                th = (A[3 * q + q] - A[3 * p + p]) / (ATT_R(2.0) * apq);
                t = ATT_R(1.0) / (att_fabs(th) + att_sqrt(th * th + ATT_R(1.0)));
                if (th < ATT_R(0.0))
                    t = -t;
                cs = ATT_R(1.0) / att_sqrt(t * t + ATT_R(1.0));
                sn = t * cs;
                for (k = 0; k < 3; ++k) { /* A ← A J (columns p, q) */
                    att_real akp = A[3 * k + p], akq = A[3 * k + q];
                    A[3 * k + p] = cs * akp - sn * akq;
                    A[3 * k + q] = sn * akp + cs * akq;
                }
                for (k = 0; k < 3; ++k) { /* A ← Jᵀ A (rows p, q) */
                    att_real apk = A[3 * p + k], aqk = A[3 * q + k];
                    A[3 * p + k] = cs * apk - sn * aqk;
                    A[3 * q + k] = sn * apk + cs * aqk;
                }
                A[3 * p + q] = A[3 * q + p] = ATT_R(0.0);
                for (k = 0; k < 3; ++k) {
                    att_real vkp = V[3 * k + p], vkq = V[3 * k + q];
                    V[3 * k + p] = cs * vkp - sn * vkq;
                    V[3 * k + q] = sn * vkp + cs * vkq;
                }
            }
    }
}

/* span = √(λ_min / tr) of the samples' covariance (u units). */
static att_real mc_span(const att_magcal *c)
{
    att_real n = (att_real)c->n, mean[3], C[9], V[9], lmin, tr;
    mean[0] = c->mom[1] / n;
    mean[1] = c->mom[2] / n;
    mean[2] = c->mom[3] / n;
    C[0] = c->mom[4] / n - mean[0] * mean[0];
    C[1] = C[3] = c->mom[5] / n - mean[0] * mean[1];
    C[2] = C[6] = c->mom[6] / n - mean[0] * mean[2];
    C[4] = c->mom[7] / n - mean[1] * mean[1];
    C[5] = C[7] = c->mom[8] / n - mean[1] * mean[2];
    C[8] = c->mom[9] / n - mean[2] * mean[2];
    mc_jacobi3(C, V);
    tr = C[0] + C[4] + C[8];
    lmin = C[0];
    if (C[4] < lmin)
        lmin = C[4];
    if (C[8] < lmin)
        lmin = C[8];
    if (!(tr > ATT_R(0.0)) || !(lmin > ATT_R(0.0)))
        return ATT_R(0.0);
    return att_sqrt(lmin / tr);
}

att_status att_magcal_solve(const att_magcal *c, int model, att_magcal_result *r)
{
    att_real N[MC_NCOL * MC_NCOL], L[MC_NCOL * MC_NCOL], D[MC_NCOL], rhs[MC_NCOL], x[MC_NCOL], v[MC_NCOL];
    att_real A[9], V[9], b[3], hu[3], w[3], k, tt, rss, span, det, bu, scale, sq[3];
    int cols[MC_NCOL], nc = 0, i, j, l;
    if (c == NULL || r == NULL)
        return ATT_E_NULL;
    if (model < ATT_MAGCAL_OFFSET || model > ATT_MAGCAL_FULL)
        return ATT_E_ARG;
    if (c->n < c->s.min_samples || c->n < 10u)
        return ATT_AID_E_FEW;
    span = mc_span(c);
    if (!(span >= c->s.min_span) || !(span > ATT_R(0.0)))
        return ATT_AID_E_SPAN;
    while (MC_MODEL[model][nc] >= 0) {
        cols[nc] = MC_MODEL[model][nc];
        ++nc;
    }
    /* normal equations N v = rhs, LDLᵀ with a relative pivot check */
    for (i = 0; i < nc; ++i) {
        for (j = 0; j <= i; ++j)
            N[MC_NCOL * i + j] = N[MC_NCOL * j + i] = mc_inner(c->mom, &MC_COL[cols[i]], &MC_COL[cols[j]]);
        rhs[i] = mc_inner(c->mom, &MC_COL[cols[i]], &MC_TARGET);
    }
    for (j = 0; j < nc; ++j) {
        att_real dj = N[MC_NCOL * j + j];
        for (l = 0; l < j; ++l)
            dj -= L[MC_NCOL * j + l] * L[MC_NCOL * j + l] * D[l];
        if (!(dj > MC_PIVOT_RCOND * N[MC_NCOL * j + j]))
            return ATT_AID_E_SPAN;
        D[j] = dj;
        for (i = j + 1; i < nc; ++i) {
            att_real s = N[MC_NCOL * i + j];
            for (l = 0; l < j; ++l)
                s -= L[MC_NCOL * i + l] * L[MC_NCOL * j + l] * D[l];
            L[MC_NCOL * i + j] = s / dj;
        }
    }
    for (i = 0; i < nc; ++i) {
        att_real s = rhs[i];
        for (l = 0; l < i; ++l)
            s -= L[MC_NCOL * i + l] * x[l];
        x[i] = s;
    }
    for (i = 0; i < nc; ++i)
        x[i] /= D[i];
    for (i = nc - 1; i >= 0; --i) {
        att_real s = x[i];
        for (l = i + 1; l < nc; ++l)
            s -= L[MC_NCOL * l + i] * x[l];
        x[i] = s;
    }
    for (i = 0; i < MC_NCOL; ++i)
        v[i] = ATT_R(0.0);
    for (i = 0; i < nc; ++i)
        v[cols[i]] = x[i];
    /* residual sum of squares: Σ T² − vᵀ rhs */
    tt = mc_inner(c->mom, &MC_TARGET, &MC_TARGET);
    rss = tt;
    for (i = 0; i < nc; ++i)
        rss -= x[i] * rhs[i];
    if (rss < ATT_R(0.0))
        rss = ATT_R(0.0);
    /* quadric uᵀAu + 2bᵀu + d = 0 (tr A = 3) */
    A[0] = ATT_R(1.0) - v[0] - v[1];
    A[4] = ATT_R(1.0) - v[0] + ATT_R(2.0) * v[1];
    A[8] = ATT_R(1.0) + ATT_R(2.0) * v[0] - v[1];
    A[1] = A[3] = -v[2];
    A[2] = A[6] = -v[3];
    A[5] = A[7] = -v[4];
    b[0] = -v[5];
    b[1] = -v[6];
    b[2] = -v[7];
    mc_jacobi3(A, V);
    if (!(A[0] > ATT_R(0.0)) || !(A[4] > ATT_R(0.0)) || !(A[8] > ATT_R(0.0)))
        return ATT_AID_E_FIT;
    /* center h_u = −A⁻¹ b = −V Λ⁻¹ Vᵀ b */
    for (i = 0; i < 3; ++i)
        w[i] = (V[i] * b[0] + V[3 + i] * b[1] + V[6 + i] * b[2]) / A[4 * i];
    for (i = 0; i < 3; ++i)
        hu[i] = -(V[3 * i] * w[0] + V[3 * i + 1] * w[1] + V[3 * i + 2] * w[2]);
    k = b[0] * hu[0] + b[1] * hu[1] + b[2] * hu[2] - v[8]; /* bᵀh_u + d, d = −v9 */
    k = -k;
    if (!(k > ATT_R(0.0)) || !isfinite(k))
        return ATT_AID_E_FIT;
    /* M = A/k: eigenvalues μ = λ/k; B_u = (μ1 μ2 μ3)^(-1/6); S = B_u V diag(√μ) Vᵀ */
    for (i = 0; i < 3; ++i)
        sq[i] = att_sqrt(A[4 * i] / k);
    det = sq[0] * sq[1] * sq[2];
    bu = ATT_R(1.0) / mc_cbrt(det);
    scale = ATT_R(1.0) / c->inv_s;
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 3; ++j)
            r->S[3 * i + j] = bu
                              * (V[3 * i] * sq[0] * V[3 * j] + V[3 * i + 1] * sq[1] * V[3 * j + 1]
                                 + V[3 * i + 2] * sq[2] * V[3 * j + 2]);
    for (i = 0; i < 3; ++i)
        r->h[i] = c->c[i] + scale * hu[i];
    r->field = scale * bu;
    r->residual = att_sqrt(rss / (att_real)c->n) / (ATT_R(2.0) * k);
    r->span = span;
    r->model = model;
    r->n = c->n;
    if (!att__finite3(r->h) || !isfinite(r->field) || !isfinite(r->residual))
        return ATT_AID_E_FIT;
    return ATT_OK;
}

att_status att_magcal_apply(const att_magcal_result *r, const att_real m[3], att_real out[3])
{
    att_real d[3];
    int i;
    if (r == NULL || m == NULL || out == NULL)
        return ATT_E_NULL;
    if (!att__finite3(m))
        return ATT_E_NONFINITE;
    for (i = 0; i < 3; ++i)
        d[i] = m[i] - r->h[i];
    for (i = 0; i < 3; ++i)
        out[i] = r->S[3 * i] * d[0] + r->S[3 * i + 1] * d[1] + r->S[3 * i + 2] * d[2];
    if (!att__finite3(out))
        return ATT_E_RANGE;
    return ATT_OK;
}

att_status att_magcal_apply_n(const att_magcal_result *r, const att_real *m, att_real *out, size_t n,
                              size_t *err_index)
{
    size_t i;
    if (n == 0u)
        return ATT_OK;
    if (r == NULL || m == NULL || out == NULL)
        return ATT_E_NULL;
    for (i = 0; i < n; ++i) {
        att_status st = att_magcal_apply(r, m + 3u * i, out + 3u * i);
        if (st != ATT_OK) {
            if (err_index != NULL)
                *err_index = i;
            return st;
        }
    }
    return ATT_OK;
}

/* ------------------------------------------------------------------ */

att_status att_magcal2d_init(att_magcal2d *c)
{
    if (c == NULL)
        return ATT_E_NULL;
    c->n = 0u;
    c->min[0] = c->min[1] = ATT_R(0.0);
    c->max[0] = c->max[1] = ATT_R(0.0);
    return ATT_OK;
}

att_status att_magcal2d_add(att_magcal2d *c, const att_real m[3])
{
    int i;
    if (c == NULL || m == NULL)
        return ATT_E_NULL;
    if (!att__finite3(m))
        return ATT_E_NONFINITE;
    for (i = 0; i < 2; ++i) {
        if (c->n == 0u || m[i] < c->min[i])
            c->min[i] = m[i];
        if (c->n == 0u || m[i] > c->max[i])
            c->max[i] = m[i];
    }
    c->n += 1u;
    return ATT_OK;
}

att_status att_magcal2d_solve(const att_magcal2d *c, att_magcal_result *r)
{
    att_real rx, ry, kx, ky;
    int i;
    if (c == NULL || r == NULL)
        return ATT_E_NULL;
    if (c->n < 3u)
        return ATT_AID_E_FEW;
    rx = c->max[0] - c->min[0];
    ry = c->max[1] - c->min[1];
    if (!(rx > ATT_R(0.0)) || !(ry > ATT_R(0.0)) || !isfinite(rx) || !isfinite(ry))
        return ATT_AID_E_SPAN;
    kx = ry > rx ? ry / rx : ATT_R(1.0);
    ky = rx > ry ? rx / ry : ATT_R(1.0);
    for (i = 0; i < 9; ++i)
        r->S[i] = ATT_R(0.0);
    r->S[0] = kx;
    r->S[4] = ky;
    r->S[8] = ATT_R(1.0);
    r->h[0] = ATT_R(0.5) * (c->max[0] + c->min[0]);
    r->h[1] = ATT_R(0.5) * (c->max[1] + c->min[1]);
    r->h[2] = ATT_R(0.0);
    r->field = ATT_R(0.5) * kx * rx;
    r->residual = ATT_R(0.0);
    r->span = rx < ry ? rx / ry : ry / rx;
    r->model = ATT_MAGCAL_MINMAX_2D;
    r->n = c->n;
    return ATT_OK;
}
