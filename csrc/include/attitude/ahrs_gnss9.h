/*
 * libattitude — the MEMS AHRS paper's nine-state low-order Kalman filter
 * with GNSS-velocity and magnetic-heading aiding, for reproduction
 * (prefix att_g9_).
 *
 * "基于低成本MEMS器件的捷联航姿系统设计" (MEMS AHRS paper, sec. 1 and 3.3,
 * eq. 7-8), in this project's conventions (body → ENU, scalar first,
 * heading from north toward east). The paper gives the states, the
 * measurements and the noise models in words; what it leaves open (the
 * matrix A, discretization, Q, R, the Markov time constant, P0) is chosen
 * here and tabled in docs/gnss-paper-filter.md.
 *
 * Strapdown part, per IMU sample k (gyr ω̃ [rad/s], specific force f̃
 * [m/s²], step h): the attitude by the library's rotation-vector
 * integrator (integrator.h, rv3-reuse) from Δθ = (ω̃ − ε̂) h; then the
 * horizontal velocity v̂ ← v̂ + h [C f̃ + g]_EN, C = C_b^n of the updated
 * attitude (low speed: no Coriolis, no transport rate, no Earth rate).
 *
 * Error state (eq. 7): X = [δψ, δV_E, δV_N, φ_E, φ_N, φ_U, ε_x, ε_y, ε_z]ᵀ.
 *   δψ   [rad]   the magnetic heading's error, first-order Markov:
 *                dδψ/dt = −δψ/τ + w_ψ (the paper: "the magnetic sensor's
 *                heading error described by a first-order Markov process");
 *   δV   [m/s]   v̂ − v (east, north);
 *   φ    [rad]   misalignment of the computed frame: Ĉ = (I − [φ×]) C,
 *                so the SINS heading is the true heading + φ_U;
 *   ε    [rad/s] residual gyro drift, body axes (ω̃ − ε̂ = ω + ε + w_g),
 *                a random walk (the paper: drift simplified to white noise).
 * Continuous model Ẋ = A X + W (phi-angle error model of a local-level
 * SINS at low speed, Earth and transport rates dropped):
 *   dδV_E/dt = −f_U φ_N + f_N φ_U + w_aE,  dδV_N/dt = f_U φ_E − f_E φ_U + w_aN
 *   (f = C f̃ in ENU: the δV̇ = f × φ terms; accelerometer bias as white
 *   noise w_a, the paper's simplification), dφ/dt = −C ε − C w_g, dε/dt = w_ε.
 * Discretization, every kf_period samples (T = the sum of their steps,
 * f the mean ENU specific force over them, C the last attitude):
 *   Φ = I + A T except Φ_ψψ = exp(−T/τ); Q_d = diag(σ_ψ²(1 − e^{−2T/τ}),
 *   σ_a² T, σ_a² T, σ_g² T ×3, σ_ε² T ×3); P ← Φ P Φᵀ + Q_d.
 * Measurements (eq. 8), Z = H X + V, each a scalar update
 * (K = P Hᵀ/(H P Hᵀ + r), X ← X + K(z − H X), P ← P − K H P):
 *   GNSS velocity: z = v̂(t_gnss) − v_gnss (east, north), H = e_δV, r = σ_v²;
 *   magnetic heading: z = wrap(ψ_SINS − ψ_mag) = φ_U − δψ + v, r = σ_h².
 * Before an update the pending prediction is made (P current). After it
 * the feedback: q ← exp(φ̂) ⊗ q (the ENU rotation undoing the
 * misalignment), v̂ ← v̂ − δV̂, ε̂ ← ε̂ + ε̂_state; those states are then
 * zeroed; δψ (the magnetometer's own error) stays in the state.
 *
 * Limits (the paper's design): drift and accelerometer bias as white
 * noise in the error model, one Markov state for the magnetic error that
 * the heading measurement sees only as φ_U − δψ; low-speed error model;
 * small-angle (linear) model, so the attitude must start within a few
 * degrees (q0, or tilt from the first specific force and heading from the
 * first magnetic heading); no gating of GNSS outliers.
 *
 * The state is caller-owned; no malloc, no global state, no I/O. Double
 * and float builds from one source (att_real).
 */
#ifndef ATTITUDE_AHRS_GNSS9_H
#define ATTITUDE_AHRS_GNSS9_H

#include "attitude/common.h"
#include "attitude/integrator.h"

ATT_API_BEGIN

/* Status codes of the nine-state filter (range -240..-249). */
enum {
    ATT_E_G9_DT = -240,       /* time step not finite or ≤ 0 */
    ATT_E_G9_SETTINGS = -241, /* a setting outside its documented domain */
    ATT_E_G9_DIVERGED = -242, /* finite input, non-finite state (state left as at entry) */
    ATT_E_G9_ALIGN = -243,    /* no attitude yet and the sample cannot give one */
    ATT_E_G9_AGE = -244       /* GNSS age not finite, < 0 or > max_gnss_age */
};

/* Flags of the last call (att_g9_flags()). */
enum {
    ATT_G9_F_PREDICTED = 1,  /* a Kalman prediction was made */
    ATT_G9_F_GNSS = 2,       /* a GNSS velocity update was made */
    ATT_G9_F_HEADING = 4,    /* a magnetic heading update was made */
    ATT_G9_F_HEADING_SET = 8 /* the first heading set the yaw (coarse alignment, no update) */
};

/* Number of states and their indices in X. */
enum {
    ATT_G9_NX = 9,
    ATT_G9_DPSI = 0,
    ATT_G9_DVE = 1,
    ATT_G9_DVN = 2,
    ATT_G9_PHIE = 3,
    ATT_G9_PHIN = 4,
    ATT_G9_PHIU = 5,
    ATT_G9_EPSX = 6,
    ATT_G9_EPSY = 7,
    ATT_G9_EPSZ = 8
};

/* Settings. Units in brackets; defaults are att_g9_default_settings()'s.
 * "paper: none" marks a value the paper does not give (chosen here). */
typedef struct {
    att_real gravity;         /* [m/s²] g of the velocity equation; > 0; default 9.80665 */
    att_real gyr_noise;       /* [rad/√s] σ_g, gyro white noise; > 0; default 1e-3 (paper: none;
                                    ADIS16405 angular random walk 2°/√h is 5.8e-4, rounded up) */
    att_real drift_noise;     /* [rad/s/√s] σ_ε, drift random walk; ≥ 0; default 1e-5 (paper: none) */
    att_real acc_noise;       /* [m/s/√s] σ_a, accelerometer white noise, bias included as the
                                    paper simplifies; > 0; default 0.02 (paper: none) */
    att_real mag_tau;         /* [s] τ, the magnetic error's Markov time constant; > 0;
                                    default 300 (paper: none) */
    att_real mag_sigma;       /* [rad] σ_ψ, the Markov process's steady-state 1σ; > 0;
                                    default 0.035 (2°; paper: none) */
    att_real gnss_vel_noise;  /* [m/s] σ_v, 1σ of each GNSS velocity component; > 0;
                                    default 0.1 (paper: none) */
    att_real heading_noise;   /* [rad] σ_h, white part of the magnetic heading; > 0;
                                    default 0.0175 (1°; paper: none) */
    att_real init_tilt_sigma; /* [rad] 1σ of φ_E, φ_N at start; > 0; default 0.035 (2°) */
    att_real init_heading_sigma; /* [rad] 1σ of φ_U at start; > 0; default 0.17 (10°) */
    att_real init_vel_sigma;     /* [m/s] 1σ of δV at start; > 0; default 0.5 */
    att_real init_drift_sigma;   /* [rad/s] 1σ of each drift at start; ≥ 0; default 0.005 */
    att_real max_gnss_age;       /* [s] largest accepted GNSS age (latency); ≥ 0; default 1 */
    int kf_period;               /* [samples] IMU samples per Kalman prediction; 1..1000;
                                    default 5 (the paper's low-order point is cost) */
} att_g9_settings;

/* Caller-owned state. Treat as opaque; read it with the accessors. */
typedef struct {
    att_g9_settings set;
    att_integ integ;       /* attitude (body → ENU) */
    att_real x[ATT_G9_NX]; /* error state X */
    att_real P[ATT_G9_NX][ATT_G9_NX];
    att_real v[2];      /* [m/s] SINS velocity, east and north */
    att_real drift[3];  /* [rad/s] drift estimate ε̂, body axes */
    att_real acc_h[2];  /* [m/s²] last horizontal acceleration (for v̂ at the GNSS time) */
    att_real f_sum[3];  /* [m/s] Σ f h (ENU) since the last prediction */
    att_real t_pending; /* [s] Σ h since the last prediction */
    int n_pending;      /* samples since the last prediction */
    int aligned;        /* 1 once the attitude is set */
    int heading_set;    /* 1 once the heading is set (q0 given, or the first heading) */
    int flags;          /* ATT_G9_F_* of the last call */
} att_g9;

/* The defaults listed above. */
void att_g9_default_settings(att_g9_settings *set);

/* ATT_OK or ATT_E_G9_SETTINGS; *field (may be NULL) names the first field
 * outside its domain (NULL when none). ATT_E_NULL when set is NULL. */
att_status att_g9_check_settings_field(const att_g9_settings *set, const char **field);

/* att_g9_check_settings_field without the name. */
att_status att_g9_check_settings(const att_g9_settings *set);

/* Initialize. set == NULL: the defaults. q0 (body → ENU, normalized here;
 * NULL: the first update takes roll and pitch from its specific force and
 * the first heading update sets the heading). v0: east, north velocity
 * [m/s] (NULL: 0). Errors: ATT_E_NULL, ATT_E_G9_SETTINGS, ATT_E_NONFINITE
 * (q0, v0), ATT_E_ARG (q0 zero). */
att_status att_g9_init(att_g9 *s, const att_g9_settings *set, const att_real q0[4], const att_real v0[2]);

/* One IMU sample: gyr [rad/s], acc [m/s², specific force, +g up at rest],
 * dt [s] > 0 since the previous sample. Runs the strapdown step and, every
 * kf_period samples, the Kalman prediction. After an init without q0 the
 * first sample only sets roll and pitch (yaw 0) from acc. Errors (state unchanged):
 * ATT_E_NULL, ATT_E_G9_DT, ATT_E_NONFINITE, ATT_E_G9_ALIGN (first sample
 * with zero acc and no q0), ATT_E_G9_DIVERGED, the integrator's
 * ATT_E_INTEG_RANGE. */
att_status att_g9_update(att_g9 *s, const att_real gyr[3], const att_real acc[3], att_real dt);

/* GNSS velocity v_gnss (east, north) [m/s] measured age [s] before the last
 * IMU sample (0 ≤ age ≤ max_gnss_age): z = v̂ − age · a_h − v_gnss with a_h
 * the last horizontal acceleration. Makes the pending prediction, the
 * update and the feedback. Errors (state unchanged): ATT_E_NULL,
 * ATT_E_NONFINITE, ATT_E_G9_AGE, ATT_E_STATE (before the first sample),
 * ATT_E_G9_DIVERGED. */
att_status att_g9_gnss(att_g9 *s, const att_real v_gnss[2], att_real age);

/* Magnetic heading [rad] from north toward east (declination applied by
 * the caller), at the last IMU sample. The first one after an init without
 * q0 sets the yaw (ATT_G9_F_HEADING_SET); later ones are Kalman updates as
 * above. Errors: as att_g9_gnss (no age). */
att_status att_g9_heading(att_g9 *s, att_real heading);

/* n IMU samples (gyr, acc n×3), dt: n_dt values (1: constant, or n).
 * After sample k: the GNSS samples j with gnss_at[j] == k (gnss_at
 * non-decreasing; v_gnss m×2, gnss_age m; m = 0 allows NULLs), then the
 * heading heading[k] when finite (heading may be NULL; NaN = none there).
 * q_out n×4, v_out n×2 (each may be NULL): after sample k's updates. On
 * error *err_index (may be NULL) is the failing sample; the samples before
 * it are processed and written. ATT_E_ARG: gnss_at not non-decreasing. */
att_status att_g9_batch(att_g9 *s, const att_real *gyr, const att_real *acc, size_t n, const att_real *dt,
                        size_t n_dt, const att_real *heading, const size_t *gnss_at, const att_real *v_gnss,
                        const att_real *gnss_age, size_t m, att_real *q_out, att_real *v_out,
                        size_t *err_index);

/* Current attitude (unit, body → ENU); ATT_E_STATE before alignment. */
att_status att_g9_attitude(const att_g9 *s, att_real q[4]);

/* Current SINS velocity (east, north) [m/s]. */
att_status att_g9_velocity(const att_g9 *s, att_real v[2]);

/* Current drift estimate ε̂ [rad/s], body axes. */
att_status att_g9_drift(const att_g9 *s, att_real eps[3]);

/* Error state X (9) and the diagonal of P (9; may be NULL). */
att_status att_g9_error_state(const att_g9 *s, att_real x[ATT_G9_NX], att_real p_diag[ATT_G9_NX]);

/* ATT_G9_F_* of the last call (0 when s is NULL). */
int att_g9_flags(const att_g9 *s);

ATT_API_END

#endif /* ATTITUDE_AHRS_GNSS9_H */
