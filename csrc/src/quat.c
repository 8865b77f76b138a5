/* libattitude — quaternion / attitude matrix / Euler / rotation vector math. */
#include "attitude/quat.h"

#include "att_math.h"

void att_quat_mul(const att_real a[4], const att_real b[4], att_real out[4])
{
    att_real r0 = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
    att_real r1 = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2];
    att_real r2 = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1];
    att_real r3 = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0];
    out[0] = r0;
    out[1] = r1;
    out[2] = r2;
    out[3] = r3;
}

void att_quat_conj(const att_real q[4], att_real out[4])
{
    out[0] = q[0];
    out[1] = -q[1];
    out[2] = -q[2];
    out[3] = -q[3];
}

/* |q|² with scaling so that tiny or huge finite quaternions do not
 * underflow/overflow: returns the scale m = max|qi| and n2 = |q/m|². */
static att_real quat_scaled_norm2(const att_real q[4], att_real *m)
{
    att_real mx = att_fabs(q[0]);
    int i;
    att_real n2 = ATT_R(0.0);
    for (i = 1; i < 4; i++) {
        att_real a = att_fabs(q[i]);
        if (a > mx) {
            mx = a;
        }
    }
    *m = mx;
    if (mx == ATT_R(0.0)) {
        return ATT_R(0.0);
    }
    for (i = 0; i < 4; i++) {
        att_real v = q[i] / mx;
        n2 += v * v;
    }
    return n2;
}

att_status att_quat_normalize(const att_real q[4], att_real out[4])
{
    att_real m, n2, k;
    int i;
    if (!att__finite4(q)) {
        return ATT_E_NONFINITE;
    }
    n2 = quat_scaled_norm2(q, &m);
    if (m == ATT_R(0.0)) {
        return ATT_E_ARG;
    }
    k = ATT_R(1.0) / att_sqrt(n2);
    for (i = 0; i < 4; i++) {
        out[i] = (q[i] / m) * k;
    }
    return ATT_OK;
}

/* 2^16 rad: see quat.h */
#define ATT_ROTVEC_MAX ATT_R(65536.0)

att_real att_rotvec_max(void)
{
    return ATT_ROTVEC_MAX;
}

att_status att_rotvec_to_quat(const att_real phi[3], att_real q[4])
{
    att_real d[4];
    if (!att__finite3(phi)) {
        return ATT_E_NONFINITE;
    }
    /* each component first (their squares cannot overflow then), the norm next */
    if (att_fabs(phi[0]) > ATT_ROTVEC_MAX || att_fabs(phi[1]) > ATT_ROTVEC_MAX
        || att_fabs(phi[2]) > ATT_ROTVEC_MAX
        || phi[0] * phi[0] + phi[1] * phi[1] + phi[2] * phi[2] > ATT_ROTVEC_MAX * ATT_ROTVEC_MAX) {
        return ATT_E_RANGE;
    }
    att__rotvec_delta(phi, d);
    q[0] = ATT_R(1.0) + d[0];
    q[1] = d[1];
    q[2] = d[2];
    q[3] = d[3];
    return ATT_OK;
}

att_status att_quat_to_rotvec(const att_real q[4], att_real phi[3])
{
    att_real u[4], v2, v, half, k;
    att_status st = att_quat_normalize(q, u);
    if (st != ATT_OK) {
        return st;
    }
    if (u[0] < ATT_R(0.0)) { /* shortest rotation: λ ≥ 0 */
        u[0] = -u[0];
        u[1] = -u[1];
        u[2] = -u[2];
        u[3] = -u[3];
    }
    v2 = u[1] * u[1] + u[2] * u[2] + u[3] * u[3];
    v = att_sqrt(v2);
    half = att_atan2(v, u[0]); /* φ/2 in [0, π/2] */
    if (v2 < ATT_R(1e-6)) {
        /* k = φ/v = 2·asin(v)/v (u is unit, v = sin(φ/2)): series in v²,
         * truncation 5v⁶/112 < 5e-20; no division by a near-zero v */
        k = ATT_R(2.0) * (ATT_R(1.0) + v2 * (ATT_R(1.0 / 6.0) + v2 * ATT_R(3.0 / 40.0)));
    } else {
        k = ATT_R(2.0) * half / v;
    }
    phi[0] = k * u[1];
    phi[1] = k * u[2];
    phi[2] = k * u[3];
    return ATT_OK;
}

att_status att_quat_to_dcm(const att_real q[4], att_real C[9])
{
    att_real u[4], l, a, b, c;
    att_status st = att_quat_normalize(q, u);
    if (st != ATT_OK) {
        return st;
    }
    l = u[0];
    a = u[1];
    b = u[2];
    c = u[3];
    C[0] = l * l + a * a - b * b - c * c;
    C[1] = ATT_R(2.0) * (a * b - l * c);
    C[2] = ATT_R(2.0) * (a * c + l * b);
    C[3] = ATT_R(2.0) * (a * b + l * c);
    C[4] = l * l - a * a + b * b - c * c;
    C[5] = ATT_R(2.0) * (b * c - l * a);
    C[6] = ATT_R(2.0) * (a * c - l * b);
    C[7] = ATT_R(2.0) * (b * c + l * a);
    C[8] = l * l - a * a - b * b + c * c;
    return ATT_OK;
}

static int finite_n(const att_real *v, int n)
{
    int i;
    for (i = 0; i < n; i++) {
        if (!isfinite(v[i])) {
            return 0;
        }
    }
    return 1;
}

/* C is near a rotation: |(CᵀC − I)ij| ≤ ATT_DCM_ORTHO_TOL_PPM·1e-6 and
 * det C > 0 (quat.h). Entries beyond 2 fail at once (their squares could
 * overflow, and no near-orthogonal matrix has them). */
static int near_rotation(const att_real C[9])
{
    const att_real tol = ATT_R(ATT_DCM_ORTHO_TOL_PPM) * ATT_R(1e-6);
    att_real det;
    int i, j, k;
    for (i = 0; i < 9; i++) {
        if (!(att_fabs(C[i]) <= ATT_R(2.0))) {
            return 0;
        }
    }
    for (i = 0; i < 3; i++) {
        for (j = i; j < 3; j++) {
            att_real g = (i == j) ? ATT_R(-1.0) : ATT_R(0.0);
            for (k = 0; k < 3; k++) {
                g += C[3 * k + i] * C[3 * k + j];
            }
            if (!(att_fabs(g) <= tol)) {
                return 0;
            }
        }
    }
    det = C[0] * (C[4] * C[8] - C[5] * C[7]) - C[1] * (C[3] * C[8] - C[5] * C[6])
          + C[2] * (C[3] * C[7] - C[4] * C[6]);
    return det > ATT_R(0.0);
}

att_status att_dcm_to_quat(const att_real C[9], att_real q[4])
{
    /* Shepperd: pick the largest of 4λ², 4p1², 4p2², 4p3². */
    att_real tr, t[4], r[4];
    int i, best = 0;
    if (!finite_n(C, 9)) {
        return ATT_E_NONFINITE;
    }
    if (!near_rotation(C)) {
        return ATT_E_ARG;
    }
    tr = C[0] + C[4] + C[8];
    t[0] = ATT_R(1.0) + tr;
    t[1] = ATT_R(1.0) + C[0] - C[4] - C[8];
    t[2] = ATT_R(1.0) - C[0] + C[4] - C[8];
    t[3] = ATT_R(1.0) - C[0] - C[4] + C[8];
    for (i = 1; i < 4; i++) {
        if (t[i] > t[best]) {
            best = i;
        }
    }
    switch (best) {
    case 0:
        r[0] = t[0];
        r[1] = C[7] - C[5];
        r[2] = C[2] - C[6];
        r[3] = C[3] - C[1];
        break;
    case 1:
        r[0] = C[7] - C[5];
        r[1] = t[1];
        r[2] = C[1] + C[3];
        r[3] = C[2] + C[6];
        break;
    case 2:
        r[0] = C[2] - C[6];
        r[1] = C[1] + C[3];
        r[2] = t[2];
        r[3] = C[5] + C[7];
        break;
    default:
        r[0] = C[3] - C[1];
        r[1] = C[2] + C[6];
        r[2] = C[5] + C[7];
        r[3] = t[3];
        break;
    }
    /* r is column `best` of M = K + I, with K Bar-Itzhack's symmetric 4×4
     * matrix of C; for an orthogonal C, M = 4 q qᵀ and r = 4 q_best q.
     * For a not-quite-orthogonal C (rounded, integrated) M's eigenvalues
     * are 4 + O(δ) and three O(δ): one more product M r (a power-iteration
     * step) moves r to the optimal quaternion (the eigenvector of the
     * largest eigenvalue, Bar-Itzhack 2000) up to O(δ²), so the answer
     * no longer depends on which branch was picked. */
    {
        att_real m00 = t[0], m11 = t[1], m22 = t[2], m33 = t[3];
        att_real m01 = C[7] - C[5], m02 = C[2] - C[6], m03 = C[3] - C[1];
        att_real m12 = C[1] + C[3], m13 = C[2] + C[6], m23 = C[5] + C[7];
        att_real p[4];
        p[0] = m00 * r[0] + m01 * r[1] + m02 * r[2] + m03 * r[3];
        p[1] = m01 * r[0] + m11 * r[1] + m12 * r[2] + m13 * r[3];
        p[2] = m02 * r[0] + m12 * r[1] + m22 * r[2] + m23 * r[3];
        p[3] = m03 * r[0] + m13 * r[1] + m23 * r[2] + m33 * r[3];
        for (i = 0; i < 4; i++) {
            r[i] = p[i];
        }
    }
    if (r[0] < ATT_R(0.0)) {
        r[0] = -r[0];
        r[1] = -r[1];
        r[2] = -r[2];
        r[3] = -r[3];
    }
    /* r = 16·q_best²·q: normalizing gives q (ATT_E_ARG only for a degenerate C) */
    return att_quat_normalize(r, q);
}

static att_real wrap_pi(att_real a)
{
    /* atan2 returns [−π, π]; the convention is (−π, π] */
    return (a <= -ATT_PI) ? ATT_PI : a;
}

/* z-x-y Euler angles (docs/conventions.md): θ = atan2(C32, √(C12² + C22²))
 * (= asin C32, accurate near ±90°); at gimbal lock γ = 0, ψ = atan2(C21, C11). */
att_status att_dcm_to_euler(const att_real C[9], att_real e[3])
{
    att_real ct;
    if (!finite_n(C, 9)) {
        return ATT_E_NONFINITE;
    }
    ct = att_sqrt(C[1] * C[1] + C[4] * C[4]);
    e[1] = att_atan2(C[7], ct);
    if (ct < ATT_GIMBAL_COS) {
        e[0] = wrap_pi(att_atan2(C[3], C[0]));
        e[2] = ATT_R(0.0);
    } else {
        e[0] = wrap_pi(att_atan2(-C[1], C[4]));
        e[2] = wrap_pi(att_atan2(-C[6], C[8]));
    }
    return ATT_OK;
}

att_status att_euler_to_dcm(const att_real e[3], att_real C[9])
{
    att_real sp, cp, st, ct, sg, cg;
    if (!att__finite3(e)) {
        return ATT_E_NONFINITE;
    }
    sp = att_sin(e[0]);
    cp = att_cos(e[0]);
    st = att_sin(e[1]);
    ct = att_cos(e[1]);
    sg = att_sin(e[2]);
    cg = att_cos(e[2]);
    C[0] = cp * cg - sp * st * sg;
    C[1] = -sp * ct;
    C[2] = cp * sg + sp * st * cg;
    C[3] = sp * cg + cp * st * sg;
    C[4] = cp * ct;
    C[5] = sp * sg - cp * st * cg;
    C[6] = -ct * sg;
    C[7] = st;
    C[8] = ct * cg;
    return ATT_OK;
}

att_status att_quat_to_euler(const att_real q[4], att_real e[3])
{
    att_real C[9];
    att_status st = att_quat_to_dcm(q, C);
    if (st != ATT_OK) {
        return st;
    }
    return att_dcm_to_euler(C, e);
}

att_status att_euler_to_quat(const att_real e[3], att_real q[4])
{
    att_real qz[4], qx[4], qy[4], t[4];
    if (!att__finite3(e)) {
        return ATT_E_NONFINITE;
    }
    qz[0] = att_cos(ATT_R(0.5) * e[0]);
    qz[1] = ATT_R(0.0);
    qz[2] = ATT_R(0.0);
    qz[3] = att_sin(ATT_R(0.5) * e[0]);
    qx[0] = att_cos(ATT_R(0.5) * e[1]);
    qx[1] = att_sin(ATT_R(0.5) * e[1]);
    qx[2] = ATT_R(0.0);
    qx[3] = ATT_R(0.0);
    qy[0] = att_cos(ATT_R(0.5) * e[2]);
    qy[1] = ATT_R(0.0);
    qy[2] = att_sin(ATT_R(0.5) * e[2]);
    qy[3] = ATT_R(0.0);
    att_quat_mul(qz, qx, t);
    att_quat_mul(t, qy, q);
    if (q[0] < ATT_R(0.0)) {
        q[0] = -q[0];
        q[1] = -q[1];
        q[2] = -q[2];
        q[3] = -q[3];
    }
    return ATT_OK;
}

static att_real heading_from_yaw(att_real psi)
{
    att_real h = -psi;
    if (h < ATT_R(0.0)) {
        h += ATT_TWO_PI;
    }
    if (h >= ATT_TWO_PI) { /* -psi == -0 + rounding, or h + 2π rounded up */
        h = ATT_R(0.0);
    }
    return h;
}

att_status att_quat_heading(const att_real q[4], att_real *heading)
{
    att_real e[3];
    att_status st = att_quat_to_euler(q, e);
    if (st != ATT_OK) {
        return st;
    }
    *heading = heading_from_yaw(e[0]);
    return ATT_OK;
}

att_status att_dcm_heading(const att_real C[9], att_real *heading)
{
    att_real e[3];
    att_status st = att_dcm_to_euler(C, e);
    if (st != ATT_OK) {
        return st;
    }
    *heading = heading_from_yaw(e[0]);
    return ATT_OK;
}

/* ---- array forms ------------------------------------------------------ */

#define ATT_ARRAY_FORM(NAME, FUNC, IN_STRIDE, OUT_STRIDE, IN_T, OUT_T)                             \
    att_status NAME(const att_real *in, att_real *out, size_t n, size_t *err_index)                \
    {                                                                                              \
        size_t i;                                                                                  \
        for (i = 0; i < n; i++) {                                                                  \
            att_status st = FUNC((const IN_T)(in + (IN_STRIDE)*i), (OUT_T)(out + (OUT_STRIDE)*i)); \
            if (st != ATT_OK) {                                                                    \
                if (err_index != NULL) {                                                           \
                    *err_index = i;                                                                \
                }                                                                                  \
                return st;                                                                         \
            }                                                                                      \
        }                                                                                          \
        return ATT_OK;                                                                             \
    }

ATT_ARRAY_FORM(att_quat_normalize_n, att_quat_normalize, 4, 4, att_real *, att_real *)
ATT_ARRAY_FORM(att_rotvec_to_quat_n, att_rotvec_to_quat, 3, 4, att_real *, att_real *)
ATT_ARRAY_FORM(att_quat_to_rotvec_n, att_quat_to_rotvec, 4, 3, att_real *, att_real *)
ATT_ARRAY_FORM(att_quat_to_dcm_n, att_quat_to_dcm, 4, 9, att_real *, att_real *)
ATT_ARRAY_FORM(att_dcm_to_quat_n, att_dcm_to_quat, 9, 4, att_real *, att_real *)
ATT_ARRAY_FORM(att_dcm_to_euler_n, att_dcm_to_euler, 9, 3, att_real *, att_real *)
ATT_ARRAY_FORM(att_euler_to_dcm_n, att_euler_to_dcm, 3, 9, att_real *, att_real *)
ATT_ARRAY_FORM(att_quat_to_euler_n, att_quat_to_euler, 4, 3, att_real *, att_real *)
ATT_ARRAY_FORM(att_euler_to_quat_n, att_euler_to_quat, 3, 4, att_real *, att_real *)
ATT_ARRAY_FORM(att_quat_heading_n, att_quat_heading, 4, 1, att_real *, att_real *)
ATT_ARRAY_FORM(att_dcm_heading_n, att_dcm_heading, 9, 1, att_real *, att_real *)

att_status att_quat_mul_n(const att_real *a, const att_real *b, att_real *out, size_t n, size_t *err_index)
{
    size_t i;
    for (i = 0; i < n; i++) {
        if (!att__finite4(a + 4 * i) || !att__finite4(b + 4 * i)) {
            if (err_index != NULL) {
                *err_index = i;
            }
            return ATT_E_NONFINITE;
        }
        {
            att_real r[4];
            att_quat_mul(a + 4 * i, b + 4 * i, r);
            if (!att__finite4(r)) { /* finite inputs, overflowing product */
                if (err_index != NULL) {
                    *err_index = i;
                }
                return ATT_E_RANGE;
            }
            out[4 * i] = r[0];
            out[4 * i + 1] = r[1];
            out[4 * i + 2] = r[2];
            out[4 * i + 3] = r[3];
        }
    }
    return ATT_OK;
}
