/*
 * libattitude — aiding solvers: static attitude from the specific force and
 * the Earth's magnetic field (prefixes att_align_, att_triad, att_gn_,
 * att_magcal_). docs/aiding.md gives the derivations and the sources.
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

/* Aiding status codes (range -120..-139). */
enum {
    ATT_AID_E_ZERO_F = -120,   /* specific force zero (below 1e-30 in norm): no up direction */
    ATT_AID_E_ZERO_M = -121,   /* magnetic field zero (below 1e-30 in norm): no north */
    ATT_AID_E_PARALLEL = -122, /* f and m (nearly) parallel: |f̂ × m̂| < ATT_AID_MIN_SIN,
                                  heading undefined */
    ATT_AID_E_MOVING = -123,   /* static window: spread above its limit (moving start) */
    ATT_AID_E_FEW = -124       /* static window: fewer samples than min_samples */
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

#endif /* ATTITUDE_AIDING_H */
