/*
 * libattitude — the rotation-vector attitude integrator (prefix att_integ_).
 *
 * Q(k+1) = Q(k) ⊗ q(Φ) (paper eq. 4) with the rotation vector Φ of one
 * update interval built from body-frame angle increments Δθ (rad) by one
 * of the methods below (all of the form
 *     Φ = ΣΔθi + k12 Δθ1×Δθ2 + k13 Δθ1×Δθ3 + k23 Δθ2×Δθ3,
 * Δθ1 the oldest increment), or by fourth-order Runge–Kutta on the
 * quaternion kinematic equation Q' = ½ Q ⊗ [0, ω] from body rates ω.
 *
 * The increment is applied as Q ← Q + Q ⊗ [cos(φ/2) − 1, sin(φ/2)/φ · Φ]
 * with cos(φ/2) − 1 computed without cancellation, and Q is renormalized
 * every ATT_INTEG_RENORM_PERIOD updates (first-order, no sqrt/division).
 * See docs/integrator.md for the formulas, their sources and derivations.
 *
 * The state is caller-owned; no malloc, no global state, no I/O.
 * Batch and streaming calls share the same state and semantics: a batch
 * call is exactly a sequence of single updates.
 */
#ifndef ATTITUDE_INTEGRATOR_H
#define ATTITUDE_INTEGRATOR_H

#include "attitude/common.h"

ATT_API_BEGIN

/* Integration methods. The numbers are part of the ABI (Python, the
 * fixed-point port and attitude-rx map names to them): new methods are
 * appended. */
typedef enum {
    ATT_METHOD_RV1 = 0,            /* Φ = Δθ; one update per increment */
    ATT_METHOD_RV2 = 1,            /* two-sample: one update per 2 increments */
    ATT_METHOD_RV3 = 2,            /* paper eq. (5), 33/80 and 57/80: one update per 3 increments */
    ATT_METHOD_RV3_CONING = 3,     /* 9/20 and 27/40 (Ignagni): one update per 3 increments */
    ATT_METHOD_RV3_REUSE = 4,      /* paper sec. 1.2: one update per increment, coning-optimal
                                  correction from the newest increment and the two before
                                  it: Φk = Δθk + (7/60) Δθk−1×Δθk − (1/60) Δθk−2×Δθk */
    ATT_METHOD_RK4 = 5,            /* RK4 from rates at t, t+h/2, t+h (att_integ_update_rate) */
    ATT_METHOD_RV3_REUSE_POLY = 6, /* one update per increment, the newest interval's
                                      quadratic-rate fit from the same three increments
                                      (1/720, −31/720, 121/720); under coning ~70× the
                                      drift of rv3-reuse (docs/integrator.md) */
    ATT_METHOD_COUNT = 7
} att_method;

/* Method coefficients as exact fractions k = NUM / DEN (for fixed-point
 * ports). rv2: Φ = Δθ1 + Δθ2 + k Δθ1×Δθ2. Three-sample forms: k12, k13,
 * k23 of the general form above. Reuse forms (newest increment Δθ3, the
 * two previous Δθ1, Δθ2): Φ = Δθ3 + k12 Δθ1×Δθ2 + k13 Δθ1×Δθ3 +
 * k23 Δθ2×Δθ3 (rv3-reuse: k12 = 0); the second update after init/reset
 * (one previous increment) uses Φ = Δθ2 + (1/12) Δθ1×Δθ2 and the first
 * Φ = Δθ1, in both reuse forms. Derived in attitude_c/reference.py. */
enum {
    ATT_RV2_K_NUM = 2,
    ATT_RV2_DEN = 3,
    ATT_RV3_K12_NUM = 57,
    ATT_RV3_K13_NUM = 33,
    ATT_RV3_K23_NUM = 57,
    ATT_RV3_DEN = 80,
    ATT_RV3C_K12_NUM = 27,
    ATT_RV3C_K13_NUM = 18,
    ATT_RV3C_K23_NUM = 27,
    ATT_RV3C_DEN = 40,
    ATT_RV3R_K12_NUM = 0,
    ATT_RV3R_K13_NUM = -1,
    ATT_RV3R_K23_NUM = 7,
    ATT_RV3R_DEN = 60,
    ATT_RV3RP_K12_NUM = 1,
    ATT_RV3RP_K13_NUM = -31,
    ATT_RV3RP_K23_NUM = 121,
    ATT_RV3RP_DEN = 720,
    ATT_RV3R_START_K_NUM = 1,
    ATT_RV3R_START_DEN = 12
};

/* Renormalization period (updates) and update() results. */
enum {
    ATT_INTEG_RENORM_PERIOD = 16,
    ATT_INTEG_PENDING = 0, /* increment buffered, no new attitude yet */
    ATT_INTEG_UPDATED = 1  /* a new attitude was written to q_out */
};

/* Integrator status codes (range -20..-39). */
enum {
    ATT_E_INTEG_METHOD = -20,   /* unknown method, or a call not valid for this method */
    ATT_E_INTEG_DIVERGED = -21, /* finite input but a non-finite result (cannot happen within the
                                  limits below; kept as the last line of defence) */
    ATT_E_INTEG_RANGE = -22     /* an increment (or rate × half-step) beyond att_integ_dtheta_max() */
};

/* Largest accepted angle per sample (rad): π. Every increment must have
 * |Δθ| ≤ π (Euclidean norm), every rk4 rate sample |ω|·h/2 ≤ π (the angle
 * turned over the half-step between two rate rows); beyond it
 * ATT_E_INTEG_RANGE names the sample. Why π: the algorithms model the
 * rotation within one update by a truncated series in Δθ (docs/integrator.md),
 * whose error terms are O(|Δθ|³..|Δθ|⁵) and exceed the angle itself long
 * before π; and a body turning more than half a turn between two samples is
 * undersampled (its rotation vector is unique only up to |φ| ≤ π, so the
 * motion between samples cannot be recovered). A real gyro channel is far
 * inside the bound (the paper's ±90 °/s at 0.08 s: 0.13 rad). The check also
 * refuses increments whose squares overflow (|Δθ| = 1e200), which the
 * series would turn into a NaN or, worse, a finite meaningless attitude. */
att_real att_integ_dtheta_max(void);

/* Caller-owned state. Treat as opaque; read the attitude with
 * att_integ_attitude(). */
typedef struct {
    att_real q[4];           /* current attitude Q (unit, renormalized periodically) */
    att_real buf[2][3];      /* rv2/rv3: increments of the unfinished update; reuse forms:
                             the two previous increments (buf[1] newest); rk4: the
                             rate at the start of the step (buf[0]) and the midpoint
                             rate (buf[1]) */
    att_real k[3];           /* k12, k13, k23 of the method (or k of rv2 in k[0]) */
    int method;              /* att_method */
    int nbuf;                /* number of valid entries of buf */
    unsigned int since_norm; /* updates since the last renormalization */
    unsigned long updates;   /* attitude updates since init/reset (wraps) */
} att_integ;

/* Canonical name of a method ("rv1", "rv2", "rv3", "rv3-coning",
 * "rv3-reuse", "rk4", "rv3-reuse-poly": the names of attitude_c and
 * attitude-rx --method), or NULL for a value outside att_method. */
const char *att_integ_method_name(att_method method);

/* The method whose att_integ_method_name() is `name` (exact match) into
 * *method: ATT_OK, ATT_E_NULL, or ATT_E_INTEG_METHOD (unknown name,
 * *method untouched). */
att_status att_integ_method_from_name(const char *name, att_method *method);

/* Initialize for `method` with attitude q0 (NULL = identity; normalized
 * here; ATT_E_ARG if zero, ATT_E_NONFINITE if NaN/Inf). */
att_status att_integ_init(att_integ *s, att_method method, const att_real q0[4]);

/* Back to attitude q0 (NULL = identity), buffers cleared, method kept. */
att_status att_integ_reset(att_integ *s, const att_real q0[4]);

/* Current attitude (unit quaternion, λ sign not forced). */
att_status att_integ_attitude(const att_integ *s, att_real q[4]);

/* Number of attitude updates that n more increments (or rate samples for
 * rk4) would produce from the current state. */
size_t att_integ_outputs(const att_integ *s, size_t n);

/* Feed one increment (increment methods). Returns ATT_INTEG_UPDATED and
 * writes the new attitude to q_out (may be NULL) when an update completes,
 * ATT_INTEG_PENDING when the increment was only buffered, or a negative
 * status (state unchanged): ATT_E_NONFINITE, ATT_E_INTEG_RANGE (|Δθ| > π),
 * ATT_E_INTEG_DIVERGED, ATT_E_INTEG_METHOD (rk4 state). The attitude
 * written is always finite and of unit norm (to the renormalization's
 * first order): outputs are checked before they are committed. */
int att_integ_update(att_integ *s, const att_real dtheta[3], att_real q_out[4]);

/* Feed one rate sample (rk4 only). The first sample after init/reset is
 * the rate at the start; then samples alternate midpoint (t+h/2) and end
 * (t+h, which is also the start of the next step). An update completes on
 * each end sample, with step h (s, > 0) given with that end sample (the h
 * given with the midpoint sample is ignored). ATT_E_INTEG_RANGE when one
 * of the step's three rates has |ω|·h/2 > att_integ_dtheta_max() (checked
 * when the step's h is known: with the end sample). */
int att_integ_update_rate(att_integ *s, const att_real omega[3], att_real h, att_real q_out[4]);

/* n increments (n×3 values) in one call, exactly as n att_integ_update()
 * calls. q_out receives the attitude after each completed update (4
 * values each; room for att_integ_outputs(s, n) records), *n_out their
 * number. On error the state is left as it was at entry, *err_index is
 * the index of the offending increment (the first non-finite one, the
 * first one beyond att_integ_dtheta_max(), or the last one of a diverged
 * update) and *n_out is 0. n_out and err_index
 * may be NULL. */
att_status att_integ_batch(att_integ *s, const att_real *dtheta, size_t n, att_real *q_out, size_t *n_out,
                           size_t *err_index);

/* n rate samples (n×3 values, rk4 only), exactly as n
 * att_integ_update_rate() calls; h holds n_h step sizes: n_h == 1 uses
 * h[0] for every update, otherwise h[j] is the step of the j-th update
 * completed in this call (n_h must be ≥ att_integ_outputs(s, n)). Errors
 * as att_integ_batch (ATT_E_ARG: bad h or n_h, err_index = the update;
 * ATT_E_INTEG_RANGE: err_index = the first row of this call whose
 * |ω|·h/2 > π, or the step's end row when the bad row was buffered by an
 * earlier call). */
att_status att_integ_rk4_batch(att_integ *s, const att_real *omega, size_t n, const att_real *h, size_t n_h,
                               att_real *q_out, size_t *n_out, size_t *err_index);

ATT_API_END

#endif /* ATTITUDE_INTEGRATOR_H */
