/*
 * libattitude — the attitude filter (AHRS), prefix att_ahrs_.
 *
 * An error-state (multiplicative) Kalman filter with six error states:
 * the attitude error δθ (rad, navigation frame ENU: the true attitude is
 * exp(δθ) ⊗ q_est) and the gyro-bias error δb (rad/s, body frame: the
 * true bias is b_est + δb). The attitude is propagated with the library's
 * rotation-vector integrator (integrator.h) fed the bias-corrected angle
 * increments Δθ = (ω − b_est)·dt, so the integrator's coning correction
 * carries into the aided attitude. The error covariance P (6×6) is
 * propagated with F = [[I, −C dt], [0, I]] (C = C_b^n of the current
 * estimate), Q = diag(σ_g² dt I, σ_b² dt I) (σ_g = gyr_noise, or
 * gyr_noise_rest at rest).
 *
 * Aiding (sequential scalar updates, each with a selector H, so the cost
 * is O(36) per scalar):
 *   - accelerometer: the specific force is rotated into the navigation
 *     frame of the estimate (almost inertial: it moves only by the slow
 *     corrections, which are applied to the filtered vector too) and
 *     low-pass filtered there with time constant acc_tau, which averages
 *     out linear acceleration while gravity stays put. The inclination of
 *     that vector measures δθ_x, δθ_y; the gain of the heading and (with
 *     acc_bias = 0) nothing else is zeroed, so the accelerometer never
 *     moves the heading. Innovations larger than acc_gate are rejected;
 *     after acc_reject_max seconds of continuous rejection the update is
 *     accepted again (recovery);
 *   - magnetometer (optional per call: mag == NULL is six-axis): the field
 *     rotated into the navigation frame gives the magnetic heading; the
 *     update touches δθ_z and the bias only (never roll or pitch). The
 *     field's norm and dip are compared with a reference, the weighted
 *     mean of the agreeing samples (weight dt, less while the inclination
 *     is uncertain; a low-pass of time constant mag_ref_tau once it holds
 *     that much); until it holds mag_ref_window seconds a disagreeing
 *     sample restarts it, after that a sample outside mag_norm_tol /
 *     mag_dip_tol is rejected; a new field that stays consistent with
 *     itself for mag_new_time seconds of turning becomes the reference;
 *     after mag_reject_max seconds of continuous rejection updates resume with
 *     the noise scaled by mag_reject_factor (bounded rejection time);
 *   - rest: when the gyro and accelerometer stay within rest_gyr_th /
 *     rest_acc_th of their low-pass values for rest_time seconds, the
 *     low-passed rate measures the bias directly (zero-rate update; bias
 *     states only), and the attitude's process noise density is
 *     gyr_noise_rest (the gyro's own noise: no motion, no model error)
 *     instead of gyr_noise, so the tilt averages the accelerometer longer.
 * Corrections: q ← exp(δθ) ⊗ q, b ← b + δb, the error state reset to 0.
 *
 * The state is caller-owned; no malloc, no global state, no I/O. A batch
 * call is exactly a sequence of single updates. See docs/ahrs.md for the
 * derivation, the settings and the measured accuracy (BROAD).
 */
#ifndef ATTITUDE_AHRS_H
#define ATTITUDE_AHRS_H

#include "attitude/common.h"
#include "attitude/gnss.h"
#include "attitude/integrator.h"

ATT_API_BEGIN

/* Attitude-filter status codes (range -140..-159). */
enum {
    ATT_E_AHRS_DT = -140,       /* time step not finite or ≤ 0 */
    ATT_E_AHRS_UNITS = -141,    /* specific force magnitude far from settings.gravity (units?) */
    ATT_E_AHRS_SETTINGS = -142, /* a setting outside its documented domain */
    ATT_E_AHRS_DIVERGED = -143, /* finite input, non-finite state (state left as at entry) */
    ATT_E_AHRS_ALIGN = -144     /* no attitude yet and the sample cannot give one */
};

/* Flags of the last update (att_ahrs_flags()), a bit set. */
enum {
    ATT_AHRS_F_OVERRANGE = 1,      /* a gyro axis at or above settings.gyro_range */
    ATT_AHRS_F_REST = 2,           /* rest detected: zero-rate bias update made */
    ATT_AHRS_F_ACC_REJECTED = 4,   /* accelerometer update gated out */
    ATT_AHRS_F_MAG_DISTURBED = 8,  /* magnetometer update rejected (norm/dip vs reference) */
    ATT_AHRS_F_MAG_RELEARNED = 16, /* the magnetic reference was replaced in this update */
    ATT_AHRS_F_NO_HEADING = 32,    /* heading not observable: no magnetometer update since
                                  init (six-axis), or the heading's 1σ (the square root of
                                  att_ahrs_covariance's att_cov[8]) has grown past
                                  heading_sigma_max since the last one (docs/ahrs.md,
                                  "Uncertainty") */
    ATT_AHRS_F_GNSS_AIDED = 64,    /* a GNSS velocity used by an update (att_ahrs_update_vel) is
                                  at most settings.gnss_timeout old: the inclination comes
                                  from the GNSS velocities, not the accelerometer's low-pass */
    ATT_AHRS_F_GNSS_REJECTED = 128 /* the GNSS velocities given since the previous update were
                                  refused (fix type, DOP, sigma, a jump, the gate) */
};

/* Settings. Units in brackets; defaults are att_ahrs_default_settings()'s.
 * Domain: every value finite; times > 0 unless "0 = off"; noises > 0. */
typedef struct {
    int method;                   /* att_method, any increment method (not rk4); default rv3-reuse */
    att_real gravity;             /* [m/s²] local gravity, 9.81; unit check: the specific force's norm
                                 must be within [0.25, 4]·gravity at alignment and its slow
                                 (10 s) average within [0.5, 8]·gravity, else ATT_E_AHRS_UNITS */
    att_real gyr_noise;           /* [rad/√s] attitude process noise density σ_g (gyro noise plus
                                 model error) in motion, 0.01 */
    att_real gyr_noise_rest;      /* [rad/√s] σ_g while rest is detected: the gyro's own noise
                                 (no motion, hence no model error), so the tilt averages the
                                 accelerometer over acc_noise/gyr_noise_rest (12.5 s) at rest,
                                 0.002 */
    att_real bias_noise;          /* [rad/s/√s] gyro-bias random walk σ_b, 1e-4 */
    att_real init_att_sigma;      /* [rad] 1σ of the initial attitude error (each axis), 0.1 */
    att_real init_bias_sigma;     /* [rad/s] 1σ of the initial bias (each axis): the gyro's
                                 turn-on bias, 0.01 (0.57°/s) */
    att_real acc_tau;             /* [s] low-pass time constant of the specific force in the
                                 navigation frame, 2.0 (0 = off: raw specific force) */
    att_real acc_noise;           /* [rad·√s] inclination measurement noise density (R = σ²/dt;
                                 σ/σ_g is the correction's time constant, s), 0.025 */
    att_real acc_gate;            /* [rad] innovation gate (magnitude of the 2-D innovation), 0.2
                                 (0 = off) */
    att_real acc_reject_max;      /* [s] continuous rejection after which updates resume, 3.0 */
    att_real mag_noise;           /* [rad·√s] heading measurement noise density (R = σ²/dt), 0.1 */
    att_real mag_norm_tol;        /* [1] relative field-norm tolerance vs the reference, 0.08 */
    att_real mag_dip_tol;         /* [rad] dip tolerance vs the reference, 0.17 (≈10°) */
    att_real mag_ref_tau;         /* [s] the reference (and the candidate) is the weighted mean
                                 of the agreeing samples so far until they hold this much
                                 weight, then a first-order low-pass with this time
                                 constant, 30 */
    att_real mag_ref_window;      /* [s] weight (seconds of well-levelled field) the reference
                                 needs before it rejects: until then a sample outside the
                                 tolerances restarts it from that sample; 0 ≤ it ≤
                                 mag_ref_tau, 5 (docs/ahrs.md, "Magnetic reference") */
    att_real mag_reject_max;      /* [s] continuous rejection after which updates resume with the
                                 noise scaled by mag_reject_factor (bounded rejection), 60 */
    att_real mag_reject_factor;   /* [1] ≥ 1, see mag_reject_max, 2 */
    att_real mag_new_time;        /* [s] a candidate field (consistent with itself in norm and dip)
                                 seen for this long while turning becomes the reference, 20 */
    att_real mag_min_undisturbed; /* [s] the field must agree with the reference this long
                                 before updates resume after a rejection, 0.5 */
    att_real mag_new_gyr;         /* [rad/s] candidate time runs only while |ω| ≥ this, 0.35 (20°/s) */
    att_real declination;         /* [rad] magnetic declination (east positive, |D| ≤ π), 0 */
    att_real rest_time;           /* [s] time within the thresholds before rest is declared, 1.5
                                 (0 = rest detection off) */
    att_real rest_tau;            /* [s] low-pass time constant of the rest detector, 0.5 */
    att_real rest_gyr_th;         /* [rad/s] rest threshold on |ω − ω_lp| and |ω_lp|, 0.035 (2°/s) */
    att_real rest_acc_th;         /* [m/s²] rest threshold on |a − a_lp|, 0.5 */
    att_real rest_noise;          /* [rad/s·√s] zero-rate measurement noise density (R = σ²/dt), 3e-4 */
    att_real gyro_range;          /* [rad/s] gyro full scale: an axis at or above it flags
                                 ATT_AHRS_F_OVERRANGE and inflates the attitude covariance by
                                 (overrange_sigma)² per flagged sample; 0 = no range */
    att_real overrange_sigma;     /* [rad] see gyro_range, 0.05 */
    att_real sensor_delay;        /* [s] |d| ≤ 1: the samples lag the time the output should refer
                                 to by this much; q_out of att_ahrs_update is predicted forward
                                 by it, q ⊗ exp((ω − b)·d) (the state is not: see
                                 att_ahrs_attitude). 0 (off) by default: a property of a
                                 recording set-up, not of the filter (docs/ahrs.md) */
    att_real acc_delay;           /* [s] |d| ≤ 0.05: how long the accelerometer's samples lag the
                                 gyro's (a time-skewed IMU; positive = the accelerometer is
                                 older). Before it is rotated into the navigation frame, a
                                 sample x is turned forward to the gyro's time by the
                                 bias-corrected rate, θ = (ω − b)·d,
                                     x_c = x − θ×x + ½ θ×(θ×x),
                                 the second-order series of exp(−[θ×]) x (the body-frame
                                 view of a navigation-fixed vector at t, from its view at
                                 t − d, at constant rate). Truncation bound
                                 |x_c − exp(−[θ×]) x| ≤ |θ|³/6·√(1 + |θ|²/16)·|x|, e.g.
                                 700°/s × 13 ms: |θ| = 0.16 rad, 7e-4·|x|. x_c feeds the
                                 low-pass and the gate; the unit check on |a| and the rest
                                 detector use the raw sample. 0 (off, no work) by default: a
                                 property of the sensor, declared by the user (docs/ahrs.md,
                                 "Sensor timing") */
    att_real mag_delay;           /* [s] |d| ≤ 0.05: the same for the magnetometer's samples;
                                 the compensated field feeds the norm/dip checks, the
                                 reference and the heading. 0 (off, no work) by default;
                                 attitude_c.aiding_delay estimates it from a recording */
    att_real tilt_tau;            /* [s] the reported inclination's low-pass, 3.0 (0 = off: the
                                 Kalman state's own). The specific force in the filter's
                                 navigation frame (the sample the inclination update uses)
                                 passes a second-order low-pass, ζ = 1/√2, ω0 = √2/tilt_tau
                                 (VQF's accelerometer filter and time constant; the step
                                 response is 1 − e^(−t/τ)(cos(t/τ) + sin(t/τ))), discretized by
                                 implicit Euler (stable for any dt); samples the gate rejects
                                 are not fed; while rest is detected τ is longer by
                                 gyr_noise/gyr_noise_rest (15 s with the defaults), as the
                                 state's own inclination time constant is. It starts as the
                                 mean of the samples fed so far until they span τ (VQF's
                                 start). The reported attitude (q_out, att_ahrs_attitude)
                                 is the state's turned by the smallest rotation that makes
                                 the filtered vector vertical (while it is within 90° of up);
                                 heading, covariance and bias are the state's. See
                                 docs/ahrs.md, "Reported inclination" */
    att_real heading_sigma_max;   /* [rad] > 0: the heading counts as observable (no
                                 ATT_AHRS_F_NO_HEADING) while its 1σ is at most this, after
                                 a magnetometer update; without updates (six-axis, or the
                                 field rejected) the 1σ grows by the gyro's noise and bias
                                 (its variance by at least gyr_noise²·t), so this bounds
                                 the time a rejection may last. 0.0873 (5°) */
    att_real turn_sigma;          /* [√s] ≥ 0: the reported attitude covariance adds v·I, a
                                 variance that grows with the turn rate and fades with
                                 turn_tau, v ← v·τ/(τ + dt) + (turn_sigma·|ω − b|)²·dt: the
                                 error a fast turn makes through the gyro's scale and
                                 misalignment errors, which the aiding then removes. Reported
                                 only (att_ahrs_covariance, the heading flag): the gains use P
                                 alone, so the attitude does not change. 0.002 (BROAD's
                                 3σ coverage, docs/ahrs.md, "Uncertainty"); 0 = off */
    att_real turn_tau;            /* [s] > 0: see turn_sigma, 5.0 */
    /* GNSS velocity aiding (att_ahrs_update_vel; docs/ahrs.md, "GNSS velocity aiding") */
    att_real gnss_vel_sigma;   /* [m/s] > 0: 1σ of each velocity component when the sample
                                 gives none (att_ahrs_vel.sigma = 0), 0.2 */
    att_real gnss_timeout;     /* [s] > 0: aided (ATT_AHRS_F_GNSS_AIDED) while the last velocity
                                 used is at most this old on the filter's clock; also the
                                 longest interval two velocities are compared over. Must
                                 exceed gnss_window plus the receiver's period and latency.
                                 3.0 */
    att_real gnss_max_latency; /* [s] > 0: how far back (behind the filter's clock) a
                                 velocity's time of validity may be; the history's span
                                 (ATT_AHRS_GNSS_HIST entries spaced gnss_max_latency/
                                 (ATT_AHRS_GNSS_HIST − 2) apart), 1.0 */
    att_real gnss_max_pdop;    /* [1] ≥ 0: a sample with a larger PDOP is refused, 10 (0 = no
                                 check; a sample's pdop 0 = unknown passes) */
    att_real gnss_max_sigma;   /* [m/s] ≥ 0: a sample whose sigma is larger is refused, 2.0
                                 (0 = no check) */
    att_real gnss_max_acc;     /* [m/s²] ≥ 0: a velocity that differs from the previous one
                                 used by more than this times their interval (horizontal)
                                 is a jump and refused, 40 (0 = no check) */
    att_real gnss_gate;        /* [1] ≥ 0: innovation gate in standard deviations (each
                                 component against H P Hᵀ + R), 5 (0 = off); not applied
                                 when the aiding (re)starts (not aided): the inclination's
                                 covariances with the other states are dropped and its
                                 variance grows by init_att_sigma² (with a heading, or when
                                 the gate would refuse) instead */
    att_real gnss_window;      /* [s] ≥ 0: the shortest interval two velocities are compared
                                 over (a velocity closer to the previous one used is skipped,
                                 unflagged): the velocity noise's share of the measured angle
                                 falls with the interval, 0.9 (under 1 s: a 1 Hz receiver's
                                 fixes, with jitter, are each compared) */
    att_real gnss_gyr_noise;   /* [rad/√s] > 0: σ_g while GNSS-aided (and not at rest): the
                                 velocities measure the inclination without the
                                 accelerometer's model error, 0.002 */
} att_ahrs_settings;

/* Constants of one time step, derived from the settings and dt; kept in
 * the state and recomputed only when dt changes (part of the state: treat
 * as opaque). */
typedef struct {
    att_real dt;            /* [s] the step they are for; 0 = none yet */
    att_real k_norm;        /* dt/(10 s + dt): low-pass of |a| (unit check) */
    att_real k_rest;        /* dt/(rest_tau + dt) */
    att_real k_acc;         /* dt/(acc_tau + dt), 1 when acc_tau = 0 */
    att_real v_dip;         /* (mag_dip_tol/2)²: the dip variance that halves a field sample's
                            weight in the reference */
    att_real q_att;         /* gyr_noise²·dt */
    att_real q_att_rest;    /* gyr_noise_rest²·dt */
    att_real q_att_gnss;    /* gnss_gyr_noise²·dt */
    att_real q_bias;        /* bias_noise²·dt */
    att_real r_acc;         /* acc_noise²/dt */
    att_real r_mag;         /* mag_noise²/dt */
    att_real r_rest;        /* rest_noise²/dt */
    att_real k_tilt_v;      /* 1/(1 + 2 dt/τ + 2 dt²/τ²), τ = tilt_tau: implicit Euler of the
                            reported inclination's low-pass */
    att_real k_tilt_x;      /* (2 dt/τ²)·k_tilt_v */
    att_real k_tilt_v_rest; /* the same with τ·gyr_noise/gyr_noise_rest (at rest) */
    att_real k_tilt_x_rest;
    att_real tilt_tau_rest; /* [s] tilt_tau·gyr_noise/gyr_noise_rest, τ while at rest */
    int delays;             /* bit 0: acc_delay != 0, bit 1: mag_delay != 0 (an integer test per
                            sample: a float compare is a library call on soft-float targets) */
    int tilt;               /* 1 when tilt_tau > 0 (the same reason) */
    int turn;               /* 1 when turn_sigma > 0 (the same reason) */
    att_real k_turn;        /* turn_tau/(turn_tau + dt) */
    att_real q_turn;        /* turn_sigma²/dt */
} att_ahrs_step;

/* Entries of the GNSS history (att_ahrs_gnss). */
enum {
    ATT_AHRS_GNSS_HIST = 24
};

/* GNSS velocity aiding's part of the state (treat as opaque; docs/ahrs.md, "GNSS
 * velocity aiding"). Written only by att_ahrs_update_vel and at the end of a
 * successful att_ahrs_update, so an update need not save it. */
typedef struct {
    att_real time;                      /* [s] the filter's clock (att_ahrs_time) */
    att_real sv[3];                     /* [m/s] ∫ (f_n − g e_z) dt since the last anchor,
                                             navigation frame of the estimate */
    att_real ht[ATT_AHRS_GNSS_HIST];    /* [s] history: times (ring, oldest first from hhead + 1) */
    att_real hs[ATT_AHRS_GNSS_HIST][3]; /* [m/s] history: sv at those times */
    att_real anchor_t;                  /* [s] the previous velocity's time of validity */
    att_real anchor_s[3];               /* [m/s] sv at anchor_t */
    att_real anchor_v[3];               /* [m/s] the previous velocity (ENU) */
    att_real anchor_var;                /* [m²/s²] its variance per component */
    att_real used_t;                    /* [s] time of validity of the last velocity used */
    int hn;                             /* entries held */
    int hhead;                          /* index of the newest entry */
    int armed;                          /* 1 once a velocity was given: sv and the history run */
    int anchor;                         /* 0: none, 1: horizontal, 2: with the vertical */
    int used;                           /* 1 once a velocity was used in an update */
    int aided;                          /* ATT_AHRS_F_GNSS_AIDED's state at the last update */
    int rejected;                       /* a sample was refused since the last update */
} att_ahrs_gnss;

/* Caller-owned state. Treat as opaque; read it with the accessors. (Order:
 * set and step first; an update saves and restores the members from integ
 * on.) */
typedef struct {
    att_ahrs_settings set;
    att_ahrs_step step;    /* per-step constants for the last dt */
    att_ahrs_gnss gnss;    /* GNSS velocity aiding (not saved by an update: see its type) */
    att_integ integ;       /* attitude q (body → ENU) and the integrator's buffers */
    att_real bias[3];      /* gyro bias estimate b_est [rad/s], body frame */
    att_real P[6][6];      /* error covariance [δθ (rad); δb (rad/s)] */
    att_real acc_lp[3];    /* low-pass specific force, estimate's navigation frame [m/s²] */
    att_real tilt_f[3];    /* tilt_tau's low-pass of the specific force, navigation frame [m/s²];
                              0 until its first sample */
    att_real tilt_fd[3];   /* its rate [m/s³] (the second-order filter's other state) */
    att_real tilt_t;       /* [s] time fed, during the running-mean start */
    att_real acc_norm_lp;  /* slow average of |a| [m/s²] (unit check) */
    att_real acc_rej_time; /* [s] continuous accelerometer rejection */
    att_real mag_ref[2];   /* reference field norm (input units) and dip [rad] */
    att_real mag_rej_time; /* [s] continuous magnetometer rejection */
    att_real mag_cand[2];  /* candidate reference norm and dip */
    att_real mag_cand_t;   /* [s] time the candidate has held while turning */
    att_real mag_ref_w;    /* [s] weight the reference holds (≤ mag_ref_tau) */
    att_real mag_cand_w;   /* [s] weight the candidate holds */
    att_real mag_undist_t; /* [s] time the field has agreed with the reference */
    att_real rest_gyr[3];  /* rest detector low-pass of ω [rad/s] */
    att_real rest_acc[3];  /* rest detector low-pass of a [m/s²] */
    att_real rest_t;       /* [s] time within the rest thresholds */
    int aligned;           /* 1 once the attitude is set (q0 given or aligned) */
    int acc_init;          /* 1 once acc_lp holds a value */
    int mag_ref_valid;     /* 1 once mag_ref holds a value */
    int rest_init;         /* 1 once the rest low-passes hold a value */
    int tilt_mean;         /* 1 while tilt_f is still the running mean of its start */
    int flags;             /* ATT_AHRS_F_* of the last update */
    int heading_seen;      /* 1 once a magnetometer update has measured the heading */
    att_real turn_var;     /* [rad²] the reported covariance's turn term (turn_sigma) */
    att_real mag_ref_var;  /* [1] weighted mean of the accepted samples' (|m|/norm − 1)²,
                              norm the reference's: the field's spread, which gives the
                              reported heading variance its field term (docs/ahrs.md) */
    att_real mag_ref_dvar; /* [1] the same mean of half the squared difference of successive
                              accepted samples' |m|/norm: the white part of that spread */
    att_real mag_prev;     /* the last accepted sample's |m| (input units); 0: none since
                              the reference's start */
} att_ahrs;

/* The defaults listed above. */
void att_ahrs_default_settings(att_ahrs_settings *set);

/* The real (att_real) fields of att_ahrs_settings: how many, and the i-th in the struct's
 * order, 0 <= i < ATT_AHRS_REAL_SETTINGS: its name as spelled in the struct (the library's
 * static string) and its byte offset in the struct (*offset, may be NULL); NULL past the last.
 * An application that reads settings by name (attitude-rx's config file and options) walks
 * this instead of keeping its own list. */
enum {
    ATT_AHRS_REAL_SETTINGS = 44
};
const char *att_ahrs_setting_field(size_t i, size_t *offset);

/* Check a settings struct against the domains above: ATT_OK or
 * ATT_E_AHRS_SETTINGS (ATT_E_NULL for NULL). */
att_status att_ahrs_check_settings(const att_ahrs_settings *set);

/* The same check, naming what fails: *field (may be NULL) is set to the name
 * of the first field, in the struct's order, outside its domain, spelled as
 * in att_ahrs_settings ("acc_noise", "method"), or to NULL when the status is
 * not ATT_E_AHRS_SETTINGS. The string is the library's (static, not to be
 * freed). */
att_status att_ahrs_check_settings_field(const att_ahrs_settings *set, const char **field);

/* Initialize. set == NULL uses the defaults. q0 (body → ENU, normalized
 * here) gives the initial attitude; q0 == NULL leaves the filter
 * unaligned: the first update aligns it from that sample's specific
 * force (roll, pitch) and field (heading; without it, or with a field
 * parallel to gravity, heading 0) by att_align_accmag (aiding.h). Errors:
 * ATT_E_NULL, ATT_E_AHRS_SETTINGS, ATT_E_NONFINITE / ATT_E_ARG (q0). */
att_status att_ahrs_init(att_ahrs *s, const att_ahrs_settings *set, const att_real q0[4]);

/* One sample: gyr [rad/s] (required), acc [m/s², specific force: +g up
 * at rest] (NULL = no accelerometer this sample), mag [any unit, e.g. µT]
 * (NULL = six-axis), dt [s] the time since the previous sample (> 0).
 * Writes the attitude after the update to q_out (may be NULL). Errors
 * (state unchanged): ATT_E_NULL (s or gyr), ATT_E_AHRS_DT,
 * ATT_E_NONFINITE (any input), ATT_E_AHRS_UNITS, ATT_E_AHRS_ALIGN
 * (unaligned and acc == NULL, or zero vectors), ATT_E_AHRS_DIVERGED.
 * Accuracy on real data: docs/ahrs.md (BROAD, mean total RMS ≈ 2°). */
att_status att_ahrs_update(att_ahrs *s, const att_real gyr[3], const att_real acc[3], const att_real mag[3],
                           att_real dt, att_real q_out[4]);

/* n samples (gyr, acc n×3; mag n×3 or NULL; acc must not be NULL), dt:
 * n_dt values, n_dt == 1 (constant step) or n_dt == n (per sample).
 * q_out: n×4 (may be NULL). Exactly n att_ahrs_update() calls; on error
 * *err_index (may be NULL) is the failing sample, samples before it are
 * processed and written, and the state is that after them. */
att_status att_ahrs_batch(att_ahrs *s, const att_real *gyr, const att_real *acc, const att_real *mag,
                          size_t n, const att_real *dt, size_t n_dt, att_real *q_out, size_t *err_index);

/* Current reported attitude (body → ENU, unit, at the time of the last
 * sample): the state's q levelled by tilt_tau's low-pass (the state's own
 * with tilt_tau = 0), without the sensor_delay prediction; ATT_E_STATE
 * before alignment. */
att_status att_ahrs_attitude(const att_ahrs *s, att_real q[4]);

/* Current gyro-bias estimate [rad/s], body frame. */
att_status att_ahrs_bias(const att_ahrs *s, att_real b[3]);

/* 1σ of the attitude error per navigation axis [rad] and of the bias
 * per body axis [rad/s] (square roots of P's diagonal). */
att_status att_ahrs_sigma(const att_ahrs *s, att_real att_sigma[3], att_real bias_sigma[3]);

/* The error covariance after the last update, in two 3×3 blocks, row-major (either
 * pointer may be NULL: not written):
 *   att_cov [rad²]: the attitude error δθ, a rotation vector in the navigation frame
 *     (ENU: x east, y north, z up) with q_true = exp(δθ) ⊗ q_est, q body → ENU:
 *     the rotation that carries the estimate to the truth, about the fixed (world)
 *     axes. For small angles δθ_x, δθ_y are the errors about east and north (the
 *     inclination) and δθ_z the heading error (about up): att_cov[8] is the heading
 *     variance. Element [3i + j] = E[δθ_i δθ_j]: the layout of ROS's
 *     sensor_msgs/Imu.orientation_covariance ("row major about x, y, z axes"; the
 *     message does not say which frame's axes: here the fixed ENU axes).
 *   bias_cov [(rad/s)²]: the gyro-bias error δb (body frame; b_true = b_est + δb).
 * att_cov is the filter's P (its attitude block) plus the turn term v·I of
 * turn_sigma; the reported attitude's levelling (tilt_tau) and the sensor_delay
 * prediction add no term. Before the first update: the initial covariance,
 * init_att_sigma² and init_bias_sigma² on the diagonals. ATT_E_NULL when s is
 * NULL. Consistency of these figures on simulated and real data: docs/ahrs.md,
 * "Uncertainty". */
att_status att_ahrs_covariance(const att_ahrs *s, att_real att_cov[9], att_real bias_cov[9]);

/* att_ahrs_batch that also writes, after each sample k, the attitude covariance of
 * att_ahrs_covariance to cov_out + 9 k (n×9, row-major; may be NULL). */
att_status att_ahrs_batch_cov(att_ahrs *s, const att_real *gyr, const att_real *acc, const att_real *mag,
                              size_t n, const att_real *dt, size_t n_dt, att_real *q_out, att_real *cov_out,
                              size_t *err_index);

/* ATT_AHRS_F_* of the last update (0 when s is NULL). */
int att_ahrs_flags(const att_ahrs *s);

/* One GNSS velocity for att_ahrs_update_vel(). */
typedef struct {
    att_real t;       /* [s] the velocity's time of validity on the filter's clock (att_ahrs_time():
                         the sum of the dt of every att_ahrs_update since init); the caller
                         subtracts the receiver's latency */
    att_real vel[3];  /* [m/s] velocity in the navigation frame ENU: east, north, up */
    att_real sigma;   /* [m/s] ≥ 0: 1σ of each component (NAV-PVT sAcc); 0: settings.gnss_vel_sigma */
    att_real pdop;    /* ≥ 0: position dilution of precision, 0 = unknown */
    uint8_t has_up;   /* 1: vel[2] was measured (NAV-PVT velD); 0: ignore vel[2] (NMEA) */
    uint8_t fix_type; /* att_gnss_fix_type (gnss.h): 2D, 3D and GNSS + dead reckoning are used */
} att_ahrs_vel;

/* Give the filter one GNSS velocity (call between att_ahrs_update calls, any rate 1-10 Hz,
 * in time order). The specific force integrated in the navigation frame between the
 * previous velocity's time of validity and this one's, minus the velocity change, measures
 * the attitude error (docs/ahrs.md, "GNSS velocity aiding"); from the first velocity used
 * until gnss_timeout after the last, it replaces the accelerometer's inclination update
 * (ATT_AHRS_F_GNSS_AIDED). Quality checks (fix type, DOP, sigma, a velocity jump, the
 * innovation gate) refuse a sample: ATT_OK is still returned and ATT_AHRS_F_GNSS_REJECTED
 * is set in the flags of the next update. A velocity less than gnss_window after the previous
 * one used is skipped (unflagged). The first velocity only starts the history; one
 * older than the history holds so far (within gnss_max_latency of the clock), or given
 * before the filter is aligned, is ignored (ATT_OK, no flag). Errors (state unchanged):
 * ATT_E_NULL, ATT_E_NONFINITE, ATT_E_ARG (t later than the filter's clock by more than one
 * step, earlier than it by more than gnss_max_latency, not after the previous velocity's
 * t, or sigma or pdop < 0), ATT_E_AHRS_DIVERGED. */
att_status att_ahrs_update_vel(att_ahrs *s, const att_ahrs_vel *v);

/* The filter's clock [s]: the sum of the dt of every att_ahrs_update since init (0 when s
 * is NULL). Float builds: its resolution is 2⁻²⁴ of its value (5 ms after a day). */
att_real att_ahrs_time(const att_ahrs *s);

/* A parsed fix (gnss.h) as an att_ahrs_vel at time t: ATT_OK, or ATT_E_ARG when the fix has
 * no horizontal velocity (ATT_GNSS_HAS_VEL_NE clear); ATT_E_NULL. vel = (vel_e, vel_n,
 * −vel_d), has_up from ATT_GNSS_HAS_VEL_D, sigma = s_acc (ATT_GNSS_HAS_ACC, else 0), pdop
 * (ATT_GNSS_HAS_PDOP, else 0), fix_type (ATT_GNSS_HAS_FIX_TYPE; without it 2D when the fix
 * is flagged valid), ATT_GNSS_FIX_NONE when the receiver flags the fix invalid. */
#if !defined(__SDCC) /* att_gnss_fix is not built for the 8051 (gnss.h) */
att_status att_ahrs_vel_from_fix(const att_gnss_fix *fix, att_real t, att_ahrs_vel *out);
#endif

ATT_API_END

#endif /* ATTITUDE_AHRS_H */
