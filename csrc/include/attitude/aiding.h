/*
 * libattitude — aiding solvers: static attitude from the specific force and
 * the Earth's magnetic field (prefixes att_align_, att_triad, att_gn_,
 * att_magcal_, att_magcal2d_). docs/aiding.md gives the derivations and the sources.
 *
 * Frames and quaternion (docs/conventions.md): navigation ENU (x east,
 * y north, z up), body x right, y forward, z up; q = [λ, p1, p2, p3]
 * scalar first, body → nav, returned with λ ≥ 0.
 *
 * Inputs:
 *   f_b  specific force in the body frame (what an accelerometer measures:
 *        at rest it points UP, f_n = [0, 0, +g]); any unit, only its
 *        direction is used;
 *   m_b  magnetic field in the body frame (calibrated: hard and soft iron
 *        removed, see att_magcal_); any unit, only its direction is used;
 *   declination_rad  magnetic declination D (rad), positive when magnetic
 *        north lies EAST of true north; |D| ≤ π.
 * The field's inclination is never needed: only the plane of f and m is.
 *
 * Accuracy (noise-free input): the attitude of the inputs to a few units of
 * the scalar type's epsilon (double: < 1e-12 rad for |pitch| < 89°, tested
 * on 1e5 random attitudes; float: < 1e-5 rad).
 *
 * Every function returns ATT_OK or a status; on error the outputs are not
 * written. No function returns a non-finite value.
 */
#ifndef ATTITUDE_AIDING_H
#define ATTITUDE_AIDING_H

#include "attitude/common.h"

ATT_API_BEGIN

/* Aiding status codes (range -120..-139). */
enum {
    ATT_AID_E_ZERO_F = -120,   /* specific force zero (below 1e-30 in norm): no up direction */
    ATT_AID_E_ZERO_M = -121,   /* magnetic field zero (below 1e-30 in norm): no north */
    ATT_AID_E_PARALLEL = -122, /* f and m (nearly) parallel: |f̂ × m̂| < ATT_AID_MIN_SIN,
                                  heading undefined */
    ATT_AID_E_MOVING = -123,   /* static window: spread above its limit (moving start) */
    ATT_AID_E_FEW = -124,      /* static window: fewer samples than min_samples */
    ATT_AID_E_SINGULAR = -125, /* Gauss-Newton: Jacobian (nearly) singular at an iterate */
    ATT_AID_E_NOCONV = -126,   /* Gauss-Newton: no convergence within max_iter (or the
                                  damping grew without bound, or the final residual is
                                  above accept_residual) */
    ATT_AID_E_SPAN = -127,     /* magnetometer calibration: the samples do not span
                                  enough directions (span below min_span, or the
                                  normal equations are numerically singular) */
    ATT_AID_E_FIT = -128       /* magnetometer calibration: the fitted quadric is not
                                  an ellipsoid (data not on an ellipsoid) */
};

/* The parallel test: sin of the angle between f and m below
 * ATT_AID_MIN_SIN_PPM · 1e-6 (= 1e-4, i.e. 0.0057°) refuses the pair. At
 * that angle one unit of noise across the plane of f and m turns the
 * heading by 1e4 units: a real field (inclination ≤ 89.99°) always passes. */
enum {
    ATT_AID_MIN_SIN_PPM = 100
};

/* ------------------------------------------------------------------ */
/* Initial alignment (FPGA+DSP paper sec. 3.1, in this project's frames) */

/* Roll and pitch from the specific force, magnetic heading from the field
 * levelled by them, plus the declination:
 *   θ = atan2(f_y, √(f_x² + f_z²)),  γ = atan2(−f_x, f_z),
 *   h = R_x(θ) R_y(γ) m_b   (the field in the levelled frame),
 *   ψ = atan2(h_x, h_y) − D   (wrapped to (−π, π]),
 *   q = quaternion of C = R_z(ψ) R_x(θ) R_y(γ).
 * m_b == NULL: six-axis alignment, ψ = 0 (roll and pitch only; the
 * declination is ignored). Roll is undefined at pitch ±90° (f_x = f_z = 0):
 * γ = 0 there, as in att_dcm_to_euler's gimbal-lock rule.
 * Status: ATT_E_NULL (f_b or q NULL), ATT_E_NONFINITE (NaN/Inf input),
 * ATT_E_ARG (|D| > π), ATT_AID_E_ZERO_F, ATT_AID_E_ZERO_M,
 * ATT_AID_E_PARALLEL. */
att_status att_align_accmag(const att_real f_b[3], const att_real m_b[3], att_real declination_rad,
                            att_real q[4]);

/* TRIAD (Black 1964) with gravity the primary vector: the body triad
 * t1 = f̂, t2 = (f × m)/|f × m|, t3 = t1 × t2 and the nav triad of
 * U = [0, 0, 1] and the field's horizontal direction
 * [sin D, cos D, ·]: T1 = U, T2 = [−cos D, sin D, 0], T3 = [−sin D, −cos D, 0];
 * C = Σ Ti tiᵀ. Mathematically the same attitude as att_align_accmag
 * (both take up from f exactly and north from the part of m normal to f);
 * computed with cross products only (no trigonometry but sin/cos of D).
 * Status: as att_align_accmag (m_b is required here: ATT_E_NULL). */
att_status att_triad(const att_real f_b[3], const att_real m_b[3], att_real declination_rad, att_real q[4]);

/* Batch forms: n records back to back (f_b, m_b: 3 values each, q: 4).
 * status[i] (required when n > 0) receives each record's status; a failed
 * record's q is not written and the other records are still processed.
 * Returns ATT_OK when every record succeeded, else the status of the first
 * failed record (ATT_E_NULL when a required pointer is NULL). m_b may be
 * NULL for att_align_accmag_n (six-axis). */
att_status att_align_accmag_n(const att_real *f_b, const att_real *m_b, att_real declination_rad, att_real *q,
                              size_t n, int *status);
att_status att_triad_n(const att_real *f_b, const att_real *m_b, att_real declination_rad, att_real *q,
                       size_t n, int *status);

/* ------------------------------------------------------------------ */
/* Static window: averages the samples of a start at rest and refuses a
 * moving start. Caller-owned; means and spreads are accumulated with
 * Welford's update (numerically stable in float, fixed size, no buffer).
 *
 * Spreads (what the limits compare against):
 *   acc, mag: angular spread (rad) = √(Σ|x_i − x̄|² / (n − 1)) / |x̄|, the
 *     RMS deviation of the samples about their mean over the mean's norm
 *     (to first order the RMS angle between a sample and the mean when
 *     the deviation is across the vector; a change of norm counts too);
 *   gyr: the RMS deviation of the rate about its mean (rad/s) and the
 *     norm of the mean rate (rad/s, bias included).
 */
typedef struct {
    unsigned int min_samples; /* samples needed before _solve (≥ 2); default 50 */
    att_real max_acc_spread;  /* rad, limit of the acc angular spread; default 0.02 */
    att_real max_mag_spread;  /* rad, limit of the mag angular spread; default 0.05 */
    att_real max_gyr_std;     /* rad/s, limit of the rate's RMS deviation; default 0.05 */
    att_real max_gyr_mean;    /* rad/s, limit of |mean rate| (bias + turning); default 0.2 */
    att_real declination_rad; /* rad, magnetic declination (east positive); default 0 */
} att_align_window_settings;

typedef struct {
    att_align_window_settings s;
    unsigned long n;      /* samples added */
    unsigned long n_gyr;  /* samples that carried a rate */
    unsigned long n_mag;  /* samples that carried a field */
    att_real acc_mean[3]; /* running means (Welford) */
    att_real mag_mean[3];
    att_real gyr_mean[3];
    att_real acc_m2; /* Σ|x − x̄|² (Welford, trace form) */
    att_real mag_m2;
    att_real gyr_m2;
} att_align_window;

/* Result of a window (att_align_window_stats). */
typedef struct {
    unsigned long n;     /* samples */
    att_real acc_spread; /* rad (see above) */
    att_real mag_spread; /* rad; 0 when no field was given */
    att_real gyr_std;    /* rad/s; 0 when no rate was given */
    att_real gyr_mean;   /* rad/s, |mean rate|; 0 when no rate was given */
    att_real acc_mean[3];
    att_real mag_mean[3];
} att_align_window_result;

/* The documented defaults. */
void att_align_window_defaults(att_align_window_settings *s);

/* Start an empty window. s == NULL: the defaults. ATT_E_NULL (w NULL),
 * ATT_E_ARG (min_samples < 2, a limit ≤ 0 or NaN, |D| > π). */
att_status att_align_window_init(att_align_window *w, const att_align_window_settings *s);

/* Empty the window (settings kept). */
void att_align_window_reset(att_align_window *w);

/* Add one sample: gyr (rad/s) and mag may be NULL, acc may not. Either
 * every sample of a window carries a rate (a field) or none does (checked
 * by _solve). ATT_E_NULL, ATT_E_NONFINITE (the sample is not added). */
att_status att_align_window_add(att_align_window *w, const att_real gyr[3], const att_real acc[3],
                                const att_real mag[3]);

/* Means and spreads so far (needs n ≥ 2: else ATT_AID_E_FEW). */
att_status att_align_window_stats(const att_align_window *w, att_align_window_result *r);

/* The attitude of the window's means (att_align_accmag, six-axis when the
 * samples carried no field), after the static check. Status: ATT_E_NULL,
 * ATT_AID_E_FEW (n < min_samples), ATT_E_STATE (some but not all samples
 * carried a rate or a field), ATT_AID_E_MOVING (a spread above its limit),
 * or att_align_accmag's. The window is kept (add more and solve again). */
att_status att_align_window_solve(const att_align_window *w, att_real q[4]);

/* ------------------------------------------------------------------ */
/* Gauss-Newton quaternion (UAV thesis sec. 3.2.2, eq. 3.26-3.39, and the
 * simplified Newton of eq. 3.40), with the listing's defects fixed
 * (docs/aiding.md lists each deviation). Unknown: the four components of
 * q_m, the attitude relative to MAGNETIC north (q = q_z(−D) ⊗ q_m), with
 * C(q) the quadratic form of eq. (1) (not divided by |q|²). Residual,
 * from the unit measurements f̂ = f/|f|, m̂ = m/|m|:
 *   r1..3 = C(q)ᵀ e_z − f̂           (eq. 3.26: specific force is up)
 *   r4    = e_xᵀ C(q) m̂              (the field has no EAST component;
 *                                     the thesis listing zeroes the north one)
 * Iteration (Levenberg-Marquardt damped Gauss-Newton, eq. 3.39):
 *   (JᵀJ + μ I) δ = −Jᵀ r,  |δ| clamped to max_step,
 *   q ← (q + δ)/|q + δ|,
 * a step is accepted when it lowers |r|² (then μ ← μ/10), else rejected
 * (μ ← 10 μ); μ starts at damping · trace(JᵀJ)/4. ATT_GN_SIMPLIFIED keeps
 * the Jacobian of the start (eq. 3.40). Stops: |r| ≤ tol_residual, or an
 * accepted |δ| ≤ tol_step (then |r| ≤ accept_residual is required), or
 * max_iter iterations (accepted and rejected steps both count). A
 * converged attitude whose field points SOUTH (e_yᵀ C m̂ < 0, the other
 * root of r4 = 0) is turned by π about up. Singular: the LDLᵀ pivots of
 * JᵀJ give a reciprocal condition number below singular_tol² (i.e.
 * cond(J) > 1/singular_tol).
 *
 * Accuracy (noise-free, warm start within 0.3 rad, double): the truth to
 * < 1e-12 rad in ≤ 6 iterations (tests/test_aiding.py); never non-finite.
 * Without a start (q0 NULL) TRIAD's attitude, an exact root of r (the
 * gravity direction matched, the field in the up/north plane), is the
 * start: every well-posed sample converges, noisy or not. */
typedef enum {
    ATT_GN_GAUSS_NEWTON = 0, /* Jacobian at every iterate (eq. 3.39), damped */
    ATT_GN_SIMPLIFIED = 1    /* Jacobian of the start only (eq. 3.40), damped */
} att_gn_method;

typedef struct {
    int method;               /* att_gn_method; default ATT_GN_GAUSS_NEWTON */
    unsigned int max_iter;    /* iterations (1..1000); default 20 */
    att_real tol_residual;    /* stop when |r| ≤ this (unitless); default 1e-13 (float: 2e-6) */
    att_real tol_step;        /* stop when an accepted |δ| ≤ this; default 1e-13 (float: 2e-6) */
    att_real accept_residual; /* a stop on the step needs |r| ≤ this; default 1e-8 (float: 1e-4) */
    att_real damping;         /* initial μ over trace(JᵀJ)/4 (≥ 0); default 1e-4 */
    att_real max_step;        /* largest |δ| per iteration (quaternion units, > 0); default 0.5 */
    att_real singular_tol;    /* 1/cond(J) below this is singular (0..1); default 1e-6 */
} att_gn_settings;

typedef struct {
    unsigned int iterations; /* iterations done (accepted + rejected steps) */
    unsigned int jacobians;  /* Jacobians evaluated */
    att_real residual;       /* |r| at the returned (or last) iterate */
    att_real step;           /* |δ| of the last accepted step (0 if none) */
} att_gn_result;

/* The documented defaults (in this build's precision). */
void att_gn_defaults(att_gn_settings *s);

/* Solve for q from f_b and m_b (both required; any units), starting at
 * q0 (body → true nav; any nonzero scale; NULL: the TRIAD attitude of
 * f_b and m_b, att_triad, from which every well-posed sample converges), settings s
 * (NULL: the defaults). r (may be NULL) is written whatever the status
 * (except ATT_E_NULL/ATT_E_ARG/ATT_E_NONFINITE). Status: ATT_E_NULL,
 * ATT_E_NONFINITE, ATT_E_ARG (bad settings, |D| > π, q0 zero),
 * ATT_AID_E_ZERO_F, ATT_AID_E_ZERO_M, ATT_AID_E_PARALLEL (as att_triad),
 * ATT_AID_E_SINGULAR, ATT_AID_E_NOCONV; q is written only on ATT_OK. */
att_status att_gn_solve(const att_real f_b[3], const att_real m_b[3], att_real declination_rad,
                        const att_real q0[4], const att_gn_settings *s, att_real q[4], att_gn_result *r);

/* Batch form (as att_triad_n): q0 n starts (NULL: TRIAD's), per-record
 * iterations and final |r| (each may be NULL; written for every record
 * whose inputs were valid, see att_gn_solve). */
att_status att_gn_solve_n(const att_real *f_b, const att_real *m_b, att_real declination_rad,
                          const att_real *q0, const att_gn_settings *s, att_real *q, size_t n, int *status,
                          unsigned int *iterations, att_real *residual);

/* ------------------------------------------------------------------ */
/* Magnetometer calibration: m_cal = S (m − h), h the hard-iron offset, S
 * the soft-iron correction (symmetric positive definite, det S = 1), B the
 * field strength, so that |m_cal| = B on the fitted ellipsoid. Streaming
 * fit with fixed-size sufficient statistics (no sample buffer): the 35
 * moments Σ x^a y^b z^c (a + b + c ≤ 4) of u = (m − c)/s, with c the first
 * sample and s its norm (a shift and scale for conditioning). The solve
 * is the linear least-squares quadric fit with the trace normalization
 * tr A = 3 (docs/aiding.md):
 *   x² + y² + z² = v1 (x² + y² − 2z²) + v2 (x² + z² − 2y²)
 *                  + 2 v3 xy + 2 v4 xz + 2 v5 yz + 2 v6 x + 2 v7 y + 2 v8 z + v9
 * with the model's subset of unknowns: OFFSET (v6..v9: a sphere, S = I),
 * DIAGONAL (v1, v2, v6..v9: axis-aligned ellipsoid), FULL (all nine).
 * S = B_u · M^½ (symmetric square root, no rotation of the axes) with M the
 * ellipsoid's matrix; B = the geometric mean of its semi-axes.
 *
 * Span: √(λ_min(cov u) / tr(cov u)), the RMS spread of the samples along
 * their least-spread direction relative to their total spread (uniform
 * coverage of the sphere: 0.577; a level turn: ~0). Fits below min_span
 * are refused (ATT_AID_E_SPAN).
 *
 * Fit quality (residual): the RMS algebraic residual over 2k (k the
 * ellipsoid's constant): to first order the RMS of |m_cal|/B − 1.
 * Accuracy (double, 500 samples, 1 % noise, cond(S) ≤ 2, |h| ≤ 2 B): the
 * corrected norm's spread within 1.5× the noise (tests/test_magcal.py).
 * The float build accumulates the moments in float: fine for a few
 * thousand samples of ≤ 1 % noise, coarser beyond (docs/aiding.md). */
typedef enum {
    ATT_MAGCAL_OFFSET = 0,   /* hard iron only: sphere, S = I */
    ATT_MAGCAL_DIAGONAL = 1, /* hard iron + per-axis scale (S diagonal) */
    ATT_MAGCAL_FULL = 2,     /* hard + soft iron (S full symmetric) */
    ATT_MAGCAL_MINMAX_2D = 3 /* the MEMS AHRS paper's 2-D min/max method (result only) */
} att_magcal_model;

typedef struct {
    unsigned int min_samples; /* samples needed before a solve (≥ 10); default 20 */
    att_real min_span;        /* refuse below this span (0..0.577); default 0.1 */
} att_magcal_settings;

typedef struct {
    att_magcal_settings s;
    unsigned long n;  /* samples added */
    att_real c[3];    /* shift: the first sample */
    att_real inv_s;   /* 1 / scale (1 / |first sample|, 1 if that is 0) */
    att_real mom[35]; /* Σ x^a y^b z^c of u, degree 0..4 (ordered by degree) */
} att_magcal;

typedef struct {
    int model;         /* att_magcal_model */
    att_real h[3];     /* hard-iron offset (input units) */
    att_real S[9];     /* soft-iron correction, row-major (det 1; diagonal for MINMAX_2D) */
    att_real field;    /* B (input units): |S (m − h)| on the fitted ellipsoid */
    att_real residual; /* ≈ RMS of |m_cal|/B − 1 (0 for MINMAX_2D) */
    att_real span;     /* see above (MINMAX_2D: min(range)/max(range) of x and y) */
    unsigned long n;   /* samples used */
} att_magcal_result;

/* The documented defaults. */
void att_magcal_defaults(att_magcal_settings *s);

/* Start an empty fit (s NULL: defaults). ATT_E_NULL, ATT_E_ARG (min_samples
 * < 10, min_span outside [0, 0.577] or NaN). */
att_status att_magcal_init(att_magcal *c, const att_magcal_settings *s);

/* Add one raw sample (any unit). ATT_E_NULL, ATT_E_NONFINITE (not added). */
att_status att_magcal_add(att_magcal *c, const att_real m[3]);

/* Add n samples (3 values each); stops at the first non-finite one
 * (ATT_E_NONFINITE, *err_index set when err_index is not NULL). */
att_status att_magcal_add_n(att_magcal *c, const att_real *m, size_t n, size_t *err_index);

/* Fit `model` (OFFSET, DIAGONAL or FULL) to the samples so far (the state
 * is kept: add more and solve again). Status: ATT_E_NULL, ATT_E_ARG (bad
 * model), ATT_AID_E_FEW (n < min_samples), ATT_AID_E_SPAN, ATT_AID_E_FIT;
 * r is written only on ATT_OK. */
att_status att_magcal_solve(const att_magcal *c, int model, att_magcal_result *r);

/* m_cal = S (m − h). ATT_E_NULL, ATT_E_NONFINITE. out may alias m. */
att_status att_magcal_apply(const att_magcal_result *r, const att_real m[3], att_real out[3]);

/* n samples (3 values each); stops at the first non-finite one. */
att_status att_magcal_apply_n(const att_magcal_result *r, const att_real *m, att_real *out, size_t n,
                              size_t *err_index);

/* The MEMS AHRS paper's 2-D method (sec. 3.1) for level-turn data: the
 * offsets are the mid-ranges of x and y, the axis with the smaller range
 * is scaled up to the larger: K_x = max(1, (y_max − y_min)/(x_max − x_min)),
 * K_y = max(1, (x_max − x_min)/(y_max − y_min)). Result: h = [x_mid, y_mid, 0],
 * S = diag(K_x, K_y, 1), field = K_x (x_max − x_min)/2 (the horizontal
 * field), model ATT_MAGCAL_MINMAX_2D; apply with att_magcal_apply. z is
 * left alone: only the heading of a level sensor is corrected. */
typedef struct {
    unsigned long n;
    att_real min[2];
    att_real max[2];
} att_magcal2d;

/* Start empty. ATT_E_NULL. */
att_status att_magcal2d_init(att_magcal2d *c);

/* Add one sample (x and y used). ATT_E_NULL, ATT_E_NONFINITE. */
att_status att_magcal2d_add(att_magcal2d *c, const att_real m[3]);

/* ATT_E_NULL, ATT_AID_E_FEW (fewer than 3 samples), ATT_AID_E_SPAN (an
 * axis with no range). */
att_status att_magcal2d_solve(const att_magcal2d *c, att_magcal_result *r);

ATT_API_END

#endif /* ATTITUDE_AIDING_H */
