/*
 * libattitude — quaternion, attitude matrix, Euler angle and rotation
 * vector math (prefixes att_quat_, att_dcm_, att_euler_, att_rotvec_).
 *
 * Conventions (docs/conventions.md):
 *   - quaternion q = [λ, p1, p2, p3], scalar first, rotating body-frame
 *     vectors into the navigation frame (ENU): v_n = q ⊗ v_b ⊗ q*;
 *   - attitude matrix C = C_b^n of the paper's eq. (1), row-major 3×3
 *     (C[3*i + j] = row i, column j);
 *   - Euler angles of the z-x-y sequence C = R_z(ψ) R_x(θ) R_y(γ), stored
 *     as e = [yaw ψ, pitch θ, roll γ] in radians;
 *   - rotation vector Φ (rad), its quaternion q(Φ) of the paper's eq. (3).
 *
 * Every function writes its outputs through pointers and may be called
 * with out == in (outputs are computed into locals first). Functions that
 * can fail return att_status; ATT_E_NONFINITE for NaN/Inf inputs,
 * ATT_E_ARG for a zero quaternion (and a matrix that is no rotation),
 * ATT_E_RANGE for finite inputs whose result would not be finite or
 * meaningful (limits per function). The `_n` variants process n records
 * stored back to back (q: 4 values, C: 9, e: 3, Φ: 3 per record) and, on
 * error, store the index of the first bad record in *err_index (when
 * err_index is not NULL); records before it are already written.
 */
#ifndef ATTITUDE_QUAT_H
#define ATTITUDE_QUAT_H

#include "attitude/common.h"

ATT_API_BEGIN

/* Orthogonality tolerance of att_dcm_to_quat, in millionths (0.01). */
enum {
    ATT_DCM_ORTHO_TOL_PPM = 10000
};

/* out = a ⊗ b (Hamilton product). No status: the caller keeps the inputs
 * finite with |a|·|b| below the type's largest value (≈ 1e308 in double,
 * 3e38 in float), or checks the result; att_quat_mul_n checks both. */
void att_quat_mul(const att_real a[4], const att_real b[4], att_real out[4]);

/* out = q* = [λ, −p1, −p2, −p3]. */
void att_quat_conj(const att_real q[4], att_real out[4]);

/* out = q / |q|. ATT_E_ARG if |q| == 0, ATT_E_NONFINITE on NaN/Inf. */
att_status att_quat_normalize(const att_real q[4], att_real out[4]);

/* Rotation-vector quaternion q(Φ) = [cos(φ/2), sin(φ/2)/φ · Φ], φ = |Φ|
 * (eq. 3). Accurate for every φ ≤ att_rotvec_max(): a series below
 * φ = 0.2 rad (no division by a near-zero norm), sin/cos of φ/4 above.
 * ATT_E_RANGE for φ > att_rotvec_max() (including vectors whose squared
 * norm overflows, such as [1e300, 0, 0]). */
att_status att_rotvec_to_quat(const att_real phi[3], att_real q[4]);

/* Largest accepted rotation-vector norm (rad): 2^16 = 65536 (≈ 10,430
 * turns). Why: the quaternion depends on φ modulo 4π, so its error is the
 * input's own rounding, |φ|·ε: at 2^16 rad that is 1.5e-11 rad in double
 * and 7.8e-3 rad in float (ε = 2^-24: the float build is trustworthy to a
 * few mrad up there); a thousand times further, the float result would be
 * noise of radians, returned as a plausible unit quaternion. No physical
 * rotation vector of one update comes near (att_integ_dtheta_max(): π). */
att_real att_rotvec_max(void);

/* Rotation vector of a quaternion (the shortest one: φ ≤ π; q and −q give
 * the same answer). ATT_E_ARG for a zero quaternion. */
att_status att_quat_to_rotvec(const att_real q[4], att_real phi[3]);

/* Attitude matrix of eq. (1). q need not be unit: the matrix of q/|q| is
 * returned (C = eq. (1) / |q|²). ATT_E_ARG for a zero quaternion. */
att_status att_quat_to_dcm(const att_real q[4], att_real C[9]);

/* Quaternion of an attitude matrix (Shepperd's method, largest-pivot
 * branch), normalized, with λ ≥ 0. A not-quite-orthogonal C gives the
 * quaternion of a nearby rotation. ATT_E_ARG when C is not near a rotation:
 * an entry of CᵀC − I above ATT_DCM_ORTHO_TOL_PPM · 1e-6 (0.01) in absolute
 * value, or det C ≤ 0 (a reflection); the zero matrix, a scaled rotation
 * or a matrix of garbage have no quaternion (the method would return the
 * identity or an arbitrary one). Why 0.01: far above the rounding of any
 * computed matrix (1e-16 double, 1e-7 float, the fixed-point port's 1e-9)
 * and of an integrated matrix renormalized now and then (1e-6 .. 1e-4),
 * while a departure of 1 % already moves the answer by ~0.005 rad. */
att_status att_dcm_to_quat(const att_real C[9], att_real q[4]);

/* Euler angles [ψ, θ, γ] of C: θ = atan2(C32, sqrt(C12² + C22²)) (equals
 * asin(C32) on a rotation matrix, better conditioned near ±90°),
 * γ = atan2(−C31, C33), ψ = atan2(−C12, C22); ψ, γ in (−π, π].
 * Gimbal lock: when sqrt(C12² + C22²) < ATT_GIMBAL_COS (2^-26 ≈ 1.5e-8
 * = sqrt(DBL_EPSILON) in double, 2^-12 ≈ 2.4e-4 in float; docs/integrator.md), γ = 0 and ψ = atan2(C21, C11). */
att_status att_dcm_to_euler(const att_real C[9], att_real e[3]);

/* C = R_z(ψ) R_x(θ) R_y(γ) for e = [ψ, θ, γ]. */
att_status att_euler_to_dcm(const att_real e[3], att_real C[9]);

/* Euler angles of a quaternion (same rules as att_dcm_to_euler). */
att_status att_quat_to_euler(const att_real q[4], att_real e[3]);

/* q = q_z(ψ) ⊗ q_x(θ) ⊗ q_y(γ), sign chosen so that λ ≥ 0. */
att_status att_euler_to_quat(const att_real e[3], att_real q[4]);

/* Heading from north, positive toward east, in [0, 2π): (−ψ) mod 2π,
 * with ψ the yaw of att_quat_to_euler (gimbal-lock rule included). */
att_status att_quat_heading(const att_real q[4], att_real *heading);

/* Same from an attitude matrix. */
att_status att_dcm_heading(const att_real C[9], att_real *heading);

/* Array forms: n records back to back (see the header comment). */
att_status att_quat_mul_n(const att_real *a, const att_real *b, att_real *out, size_t n, size_t *err_index);
att_status att_quat_normalize_n(const att_real *q, att_real *out, size_t n, size_t *err_index);
att_status att_rotvec_to_quat_n(const att_real *phi, att_real *q, size_t n, size_t *err_index);
att_status att_quat_to_rotvec_n(const att_real *q, att_real *phi, size_t n, size_t *err_index);
att_status att_quat_to_dcm_n(const att_real *q, att_real *C, size_t n, size_t *err_index);
att_status att_dcm_to_quat_n(const att_real *C, att_real *q, size_t n, size_t *err_index);
att_status att_dcm_to_euler_n(const att_real *C, att_real *e, size_t n, size_t *err_index);
att_status att_euler_to_dcm_n(const att_real *e, att_real *C, size_t n, size_t *err_index);
att_status att_quat_to_euler_n(const att_real *q, att_real *e, size_t n, size_t *err_index);
att_status att_euler_to_quat_n(const att_real *e, att_real *q, size_t n, size_t *err_index);
att_status att_quat_heading_n(const att_real *q, att_real *heading, size_t n, size_t *err_index);
att_status att_dcm_heading_n(const att_real *C, att_real *heading, size_t n, size_t *err_index);

ATT_API_END

#endif /* ATTITUDE_QUAT_H */
