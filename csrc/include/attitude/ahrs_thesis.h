/*
 * libattitude — the UAV thesis's own EKF, for reproduction (prefix att_tekf_).
 *
 * "基于 ARM 的嵌入式 UAV 飞控系统设计及实现" (ARM UAV flight-control thesis,
 * sec. 3.2.3 and 3.3, eq. 3.41-3.57), in this project's conventions
 * (body → ENU, scalar first). The library's own filter is ahrs.h; this one
 * is the thesis's design, kept as the thesis has it, limits included
 * (docs/ahrs.md, "The thesis's EKF").
 *
 * State (eq. 3.55): X = [q0 q1 q2 q3 bx by bz]ᵀ, the attitude quaternion
 * (a 4-vector, renormalized after each step, eq. 3.22) and the gyro bias
 * b [rad/s] (random constant, eq. 3.52: ω_out = ω + b + λ1, db/dt = 0).
 *
 * Time update (eq. 3.56, 3.45, 3.47, 3.50), per sample k with step h:
 *   q ← RK4 of q̇ = ½ q ⊗ (ω − b) over h (eq. 3.21 and the thesis's
 *       listing) with the rates at t, t + h/2, t + h taken as ω_{k−1} − b,
 *       ½(ω_{k−1} + ω_k) − b, ω_k − b (the first sample: ω_k throughout);
 *       b unchanged; then q ← q/|q|;
 *   Φ = I + F h, F = ∂f/∂X at X_{k−1} = [[½ Ω(ω̄ − b), −½ Ξ(q)], [0, 0]]
 *       with ω̄ the mid rate, Ω(w) q = q ⊗ [0, w], Ξ(q) w = q ⊗ [0, w];
 *   P ← Φ P Φᵀ + Q, Q = diag(¼ σ_g² h Ξ(q)Ξ(q)ᵀ, σ_b² h I₃) (the gyro's white
 *       noise λ1 mapped through −½ Ξ(q); the thesis gives no values).
 * Measurement update (eq. 3.46, 3.48, 3.51, 3.57), H = [I₄ 0]:
 *   z = the Gauss–Newton quaternion from acc and mag (att_gn_solve,
 *       aiding.h, started at the predicted q), sign-aligned to the
 *       prediction (z ← −z when z·q < 0: q and −q are the same attitude);
 *   K = P Hᵀ (H P Hᵀ + R)⁻¹, R = σ_m²/h I₄;
 *   X ← X + K (z − H X);  P ← (I − K H) P (I − K H)ᵀ + K R Kᵀ (Joseph);
 *   q ← q/|q| (P is not changed by the renormalization, as in the thesis).
 * A Gauss–Newton failure (ATT_AID_E_SINGULAR, _NOCONV, _ZERO_F, _ZERO_M,
 * _PARALLEL) skips the measurement update of that sample: the call still
 * succeeds (time update made), ATT_TEKF_F_GN_SKIPPED is set and the count
 * att_tekf_gn_skipped() grows.
 *
 * Limits (the thesis's own, sec. 3.2.3 end and 3.3): the accelerometer is
 * taken as gravity alone and the magnetometer as the undisturbed field,
 * every sample, with a fixed R: no gating, no disturbance rejection, no
 * rest detection; the magnetometer moves roll and pitch too. Measured on
 * BROAD: docs/ahrs.md.
 *
 * The state is caller-owned; no malloc, no global state, no I/O. A batch
 * call is exactly a sequence of single updates. Double and float builds
 * from one source (att_real).
 */
#ifndef ATTITUDE_AHRS_THESIS_H
#define ATTITUDE_AHRS_THESIS_H

#include "attitude/aiding.h"
#include "attitude/common.h"

ATT_API_BEGIN

/* Status codes of the thesis EKF (range -150..-159 of the filter's). */
enum {
    ATT_E_TEKF_DT = -150,       /* time step not finite or ≤ 0 */
    ATT_E_TEKF_SETTINGS = -151, /* a setting outside its documented domain */
    ATT_E_TEKF_DIVERGED = -152, /* finite input, non-finite state (state left as at entry) */
    ATT_E_TEKF_ALIGN = -153     /* no attitude yet and the sample cannot give one */
};

/* Flags of the last update (att_tekf_flags()). */
enum {
    ATT_TEKF_F_GN_SKIPPED = 1 /* Gauss–Newton failed: measurement update skipped */
};

/* Settings. Units in brackets; defaults are att_tekf_default_settings()'s.
 * "thesis: none" marks a value the thesis does not give (chosen here). */
typedef struct {
    att_real gyr_noise;       /* [rad/√s] σ_g, density of the gyro's white noise λ1 (eq. 3.52);
                                 > 0; default 0.01 (thesis: none; the project's filter's value) */
    att_real bias_noise;      /* [rad/s/√s] σ_b, bias random walk; ≥ 0; default 0 (thesis:
                                 db/dt = 0, eq. 3.52: a random constant) */
    att_real meas_noise;      /* [√s] σ_m, density of the noise of each component of the
                                 Gauss–Newton quaternion, R = σ_m²/h I₄; > 0; default 0.025
                                 (thesis: none; the time constant of the correction is about
                                 2 σ_m/σ_g = 5 s) */
    att_real init_q_sigma;    /* [1] 1σ of each quaternion component at start; > 0; default
                                 0.05 (thesis: none) */
    att_real init_bias_sigma; /* [rad/s] 1σ of each bias component at start; ≥ 0; default 0.03
                                 (thesis: none) */
    att_real declination;     /* [rad] magnetic declination, east positive, |D| ≤ π; default 0
                                 (thesis: "ignored, easily corrected", sec. 3.2.2) */
    att_gn_settings gn;       /* the Gauss–Newton solver's settings (aiding.h); default
                                 att_gn_defaults() (thesis listing: 10000 iterations, stop at
                                 |F_i| < 1e-4 — the aiding module's defaults fix its defects,
                                 docs/aiding.md) */
} att_tekf_settings;

/* Caller-owned state. Treat as opaque; read it with the accessors. */
typedef struct {
    att_tekf_settings set;
    att_real x[7];            /* [q0 q1 q2 q3 (unit), bx by bz (rad/s)] */
    att_real P[7][7];         /* covariance of X */
    att_real gyr_prev[3];     /* [rad/s] previous sample's rate (RK4's rate at t) */
    unsigned long gn_skipped; /* samples whose measurement update was skipped */
    int gn_status;            /* att_gn_solve's status of the last sample (ATT_OK or ATT_AID_E_*) */
    int aligned;              /* 1 once the attitude is set */
    int has_prev;             /* 1 once gyr_prev holds a rate */
    int flags;                /* ATT_TEKF_F_* of the last update */
} att_tekf;

/* The defaults listed above. */
void att_tekf_default_settings(att_tekf_settings *set);

/* ATT_OK or ATT_E_TEKF_SETTINGS (any value outside the domains above,
 * including the gn fields': method 0/1, max_iter 1..1000, tolerances and
 * damping finite ≥ 0, max_step > 0, singular_tol in [0, 1)); ATT_E_NULL. */
att_status att_tekf_check_settings(const att_tekf_settings *set);

/* Initialize. set == NULL: the defaults. q0 (body → ENU, normalized here;
 * NULL: the first update aligns the filter from its acc and mag by
 * att_align_accmag, which is the Gauss–Newton root). Errors: ATT_E_NULL,
 * ATT_E_TEKF_SETTINGS, ATT_E_NONFINITE / ATT_E_ARG (q0 non-finite / zero). */
att_status att_tekf_init(att_tekf *s, const att_tekf_settings *set, const att_real q0[4]);

/* One sample: gyr [rad/s], acc [specific force, any unit, +g up at rest],
 * mag [any unit] (all three required), dt [s] > 0 since the previous
 * sample. The aligning sample (q0 == NULL at init) only sets the attitude.
 * Writes the attitude after the update to q_out (may be NULL; unit, sign
 * as the state's). Errors (state unchanged): ATT_E_NULL, ATT_E_TEKF_DT,
 * ATT_E_NONFINITE, ATT_E_TEKF_ALIGN, ATT_E_TEKF_DIVERGED. A failed
 * Gauss–Newton solve is not an error (see above). */
att_status att_tekf_update(att_tekf *s, const att_real gyr[3], const att_real acc[3], const att_real mag[3],
                           att_real dt, att_real q_out[4]);

/* n samples (gyr, acc, mag n×3), dt: n_dt values (1: constant, or n).
 * q_out n×4 (may be NULL). Exactly n att_tekf_update() calls; on error
 * *err_index (may be NULL) is the failing sample, the samples before it
 * are processed and written. */
att_status att_tekf_batch(att_tekf *s, const att_real *gyr, const att_real *acc, const att_real *mag,
                          size_t n, const att_real *dt, size_t n_dt, att_real *q_out, size_t *err_index);

/* Current attitude (unit, body → ENU); ATT_E_STATE before alignment. */
att_status att_tekf_attitude(const att_tekf *s, att_real q[4]);

/* Current gyro-bias estimate [rad/s], body frame. */
att_status att_tekf_bias(const att_tekf *s, att_real b[3]);

/* Samples whose measurement update was skipped (0 when s is NULL). */
unsigned long att_tekf_gn_skipped(const att_tekf *s);

/* ATT_TEKF_F_* of the last update (0 when s is NULL). */
int att_tekf_flags(const att_tekf *s);

ATT_API_END

#endif /* ATTITUDE_AHRS_THESIS_H */
