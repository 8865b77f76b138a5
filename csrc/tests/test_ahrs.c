/*
 * Tests of the attitude filter (attitude/ahrs.h): settings and status
 * codes, alignment, convergence to a known static attitude, bias learning
 * at rest, the over-range flag, six-axis operation, and a state left
 * unchanged by a rejected call. The differential tests against the NumPy
 * model are in tests/test_ahrs.py.
 */
#include <math.h>
#include <string.h>

#include "attitude/attitude.h"
#include "att_test.h"

#define G 9.81

/* Body-frame specific force and field of attitude e (z-x-y Euler). */
static void body_vectors(const att_real e[3], att_real f_b[3], att_real m_b[3])
{
    att_real C[9], fn[3] = { 0, 0, (att_real)G }, mn[3] = { 0, 20, -40 };
    int i;
    att_euler_to_dcm(e, C);
    for (i = 0; i < 3; ++i) {
        f_b[i] = C[i] * fn[0] + C[3 + i] * fn[1] + C[6 + i] * fn[2];
        m_b[i] = C[i] * mn[0] + C[3 + i] * mn[1] + C[6 + i] * mn[2];
    }
}

/* Angle between two attitudes, 2 atan2(|v|, |w|) of a* ⊗ b in double
 * (well conditioned at small angles, unlike 2 acos of the dot product). */
static double qangle(const att_real a[4], const att_real b[4])
{
    double w = (double)a[0] * b[0] + (double)a[1] * b[1] + (double)a[2] * b[2] + (double)a[3] * b[3];
    double x = (double)a[0] * b[1] - (double)a[1] * b[0] - (double)a[2] * b[3] + (double)a[3] * b[2];
    double y = (double)a[0] * b[2] + (double)a[1] * b[3] - (double)a[2] * b[0] - (double)a[3] * b[1];
    double z = (double)a[0] * b[3] - (double)a[1] * b[2] + (double)a[2] * b[1] - (double)a[3] * b[0];
    return 2 * atan2(sqrt(x * x + y * y + z * z), fabs(w));
}

static void test_settings(void)
{
    att_ahrs_settings set;
    att_ahrs s;
    att_ahrs_default_settings(&set);
    CHECK_EQ_INT(att_ahrs_check_settings(&set), ATT_OK);
    CHECK_EQ_INT(set.method, ATT_METHOD_RV3_REUSE);
    CHECK_EQ_INT(att_ahrs_check_settings(NULL), ATT_E_NULL);
    set.method = ATT_METHOD_RK4;
    CHECK_EQ_INT(att_ahrs_check_settings(&set), ATT_E_AHRS_SETTINGS);
    CHECK_EQ_INT(att_ahrs_init(&s, &set, NULL), ATT_E_AHRS_SETTINGS);
    att_ahrs_default_settings(&set);
    set.acc_noise = 0;
    CHECK_EQ_INT(att_ahrs_check_settings(&set), ATT_E_AHRS_SETTINGS);
    att_ahrs_default_settings(&set);
    set.gyr_noise = (att_real)NAN;
    CHECK_EQ_INT(att_ahrs_check_settings(&set), ATT_E_AHRS_SETTINGS);
    att_ahrs_default_settings(&set);
    set.gyr_noise_rest = 0; /* a density: must be > 0 */
    CHECK_EQ_INT(att_ahrs_check_settings(&set), ATT_E_AHRS_SETTINGS);
    set.gyr_noise_rest = (att_real)INFINITY;
    CHECK_EQ_INT(att_ahrs_check_settings(&set), ATT_E_AHRS_SETTINGS);
    att_ahrs_default_settings(&set);
    CHECK(set.acc_delay == 0 && set.mag_delay == 0); /* off by default */
    set.acc_delay = (att_real)-0.05;                 /* domain |d| <= 0.05 s, ends included */
    set.mag_delay = (att_real)0.05;
    CHECK_EQ_INT(att_ahrs_check_settings(&set), ATT_OK);
    set.mag_delay = (att_real)0.051;
    CHECK_EQ_INT(att_ahrs_check_settings(&set), ATT_E_AHRS_SETTINGS);
    set.mag_delay = 0;
    set.acc_delay = (att_real)NAN;
    CHECK_EQ_INT(att_ahrs_check_settings(&set), ATT_E_AHRS_SETTINGS);
    set.acc_delay = (att_real)-0.06;
    CHECK_EQ_INT(att_ahrs_init(&s, &set, NULL), ATT_E_AHRS_SETTINGS);
    att_ahrs_default_settings(&set);
    CHECK(set.tilt_tau == 3); /* VQF's accelerometer time constant */
    set.tilt_tau = 0;         /* 0 = off */
    CHECK_EQ_INT(att_ahrs_check_settings(&set), ATT_OK);
    set.tilt_tau = (att_real)-1;
    CHECK_EQ_INT(att_ahrs_check_settings(&set), ATT_E_AHRS_SETTINGS);
    set.tilt_tau = (att_real)NAN;
    CHECK_EQ_INT(att_ahrs_check_settings(&set), ATT_E_AHRS_SETTINGS);
    CHECK_EQ_INT(att_ahrs_init(NULL, NULL, NULL), ATT_E_NULL);
}

/* att_ahrs_check_settings_field names the first field outside its domain, in
 * the struct's order (ahrs.h), as the struct spells it. */
static void test_settings_field_names(void)
{
    att_ahrs_settings set;
    const char *field = "unset";
    att_ahrs_default_settings(&set);
    CHECK_EQ_INT(att_ahrs_check_settings_field(&set, &field), ATT_OK);
    CHECK(field == NULL);
    field = "unset";
    CHECK_EQ_INT(att_ahrs_check_settings_field(NULL, &field), ATT_E_NULL);
    CHECK(field == NULL);
    set.acc_noise = 0; /* a density: > 0 */
    CHECK_EQ_INT(att_ahrs_check_settings_field(&set, &field), ATT_E_AHRS_SETTINGS);
    CHECK(field != NULL && strcmp(field, "acc_noise") == 0);
    CHECK_EQ_INT(att_ahrs_check_settings_field(&set, NULL), ATT_E_AHRS_SETTINGS); /* field may be NULL */
    set.mag_delay = (att_real)0.06;                                               /* after acc_noise */
    CHECK_EQ_INT(att_ahrs_check_settings_field(&set, &field), ATT_E_AHRS_SETTINGS);
    CHECK(field != NULL && strcmp(field, "acc_noise") == 0);
    set.gyr_noise_rest = (att_real)NAN; /* before acc_noise */
    CHECK_EQ_INT(att_ahrs_check_settings_field(&set, &field), ATT_E_AHRS_SETTINGS);
    CHECK(field != NULL && strcmp(field, "gyr_noise_rest") == 0);
    set.method = ATT_METHOD_RK4; /* the first field */
    CHECK_EQ_INT(att_ahrs_check_settings_field(&set, &field), ATT_E_AHRS_SETTINGS);
    CHECK(field != NULL && strcmp(field, "method") == 0);
    att_ahrs_default_settings(&set);
    set.mag_reject_factor = (att_real)0.99; /* ≥ 1 */
    CHECK_EQ_INT(att_ahrs_check_settings_field(&set, &field), ATT_E_AHRS_SETTINGS);
    CHECK(field != NULL && strcmp(field, "mag_reject_factor") == 0);
    set.mag_reject_factor = 1;
    set.declination = -(att_real)3.14159265358979323846; /* |D| ≤ π (the library's), ends included */
    CHECK_EQ_INT(att_ahrs_check_settings_field(&set, &field), ATT_OK);
    set.declination = (att_real)-3.15;
    CHECK_EQ_INT(att_ahrs_check_settings_field(&set, &field), ATT_E_AHRS_SETTINGS);
    CHECK(field != NULL && strcmp(field, "declination") == 0);
    att_ahrs_default_settings(&set);
    set.mag_ref_window = set.mag_ref_tau; /* 0 ≤ mag_ref_window ≤ mag_ref_tau, ends included */
    CHECK_EQ_INT(att_ahrs_check_settings_field(&set, &field), ATT_OK);
    set.mag_ref_window = 0;
    CHECK_EQ_INT(att_ahrs_check_settings_field(&set, &field), ATT_OK);
    set.mag_ref_window = set.mag_ref_tau * (att_real)1.01; /* the reference's weight never gets there */
    CHECK_EQ_INT(att_ahrs_check_settings_field(&set, &field), ATT_E_AHRS_SETTINGS);
    CHECK(field != NULL && strcmp(field, "mag_ref_window") == 0);
    att_ahrs_default_settings(&set);
    set.tilt_tau = (att_real)-1; /* the last field */
    CHECK_EQ_INT(att_ahrs_check_settings_field(&set, &field), ATT_E_AHRS_SETTINGS);
    CHECK(field != NULL && strcmp(field, "tilt_tau") == 0);
}

static void test_statuses(void)
{
    att_ahrs s, before;
    att_real e[3] = { 0.3f, 0.1f, -0.2f }, f[3], m[3], w[3] = { 0, 0, 0 }, q[4], fg[3];
    att_real zero4[4] = { 0, 0, 0, 0 };
    int i;
    body_vectors(e, f, m);
    CHECK_EQ_INT(att_ahrs_init(&s, NULL, zero4), ATT_E_ARG);
    CHECK_EQ_INT(att_ahrs_init(&s, NULL, NULL), ATT_OK);
    CHECK_EQ_INT(att_ahrs_attitude(&s, q), ATT_E_STATE);
    CHECK_EQ_INT(att_ahrs_update(&s, w, NULL, m, (att_real)0.01, q), ATT_E_AHRS_ALIGN);
    for (i = 0; i < 3; ++i) {
        fg[i] = f[i] / (att_real)G; /* accelerometer in g */
    }
    CHECK_EQ_INT(att_ahrs_update(&s, w, fg, m, (att_real)0.01, q), ATT_E_AHRS_UNITS);
    CHECK_EQ_INT(att_ahrs_update(&s, w, f, m, 0, q), ATT_E_AHRS_DT);
    CHECK_EQ_INT(att_ahrs_update(&s, w, f, m, (att_real)-0.01, q), ATT_E_AHRS_DT);
    CHECK_EQ_INT(att_ahrs_update(NULL, w, f, m, (att_real)0.01, q), ATT_E_NULL);
    CHECK_EQ_INT(att_ahrs_update(&s, NULL, f, m, (att_real)0.01, q), ATT_E_NULL);
    CHECK_EQ_INT(att_ahrs_update(&s, w, f, m, (att_real)0.01, q), ATT_OK);
    before = s;
    w[1] = (att_real)INFINITY;
    CHECK_EQ_INT(att_ahrs_update(&s, w, f, m, (att_real)0.01, q), ATT_E_NONFINITE);
    CHECK(memcmp(&before, &s, sizeof s) == 0); /* rejected call: state unchanged */
}

/* Static, exact sensors, start 20° off: converges to the truth. */
static void test_static_convergence(void)
{
    att_ahrs s;
    att_real e[3] = { 0.5f, -0.2f, 0.3f }, e0[3] = { 0.8f, -0.1f, 0.2f }, f[3], m[3], q[4], qt[4], q0[4];
    att_real w[3] = { 0, 0, 0 };
    int k;
    body_vectors(e, f, m);
    att_euler_to_quat(e, qt);
    att_euler_to_quat(e0, q0);
    CHECK_EQ_INT(att_ahrs_init(&s, NULL, q0), ATT_OK);
    for (k = 0; k < 24000; ++k) {
        CHECK_EQ_INT(att_ahrs_update(&s, w, f, m, (att_real)0.01, q), ATT_OK);
    }
    /* 240 s: the bulk of the 20° goes in the first seconds (correction time
     * constants of a few seconds in motion); once rest is declared (1.5 s) the
     * process noise is gyr_noise_rest and the time constants are acc_noise /
     * gyr_noise_rest = 12.5 s (tilt), mag_noise / gyr_noise_rest = 50 s
     * (heading): 0.063° remain after 120 s, e^-2.4 of that after 240 s: < 0.01° */
    CHECK(qangle(q, qt) < 0.01 * 3.14159265 / 180);
    if (qangle(q, qt) >= 0.01 * 3.14159265 / 180) {
        printf("static error %g rad\n", qangle(q, qt));
    }
    CHECK(att_ahrs_flags(&s) & ATT_AHRS_F_REST);
}

/* A gyro bias at rest is learned by the zero-rate update, six-axis. */
static void test_rest_bias(void)
{
    att_ahrs s;
    att_real e[3] = { 0, 0.1f, 0.2f }, f[3], m[3], q[4], b[3], as[3], bs[3];
    att_real w[3] = { 0.01f, -0.02f, 0.015f };
    int k;
    body_vectors(e, f, m);
    CHECK_EQ_INT(att_ahrs_init(&s, NULL, NULL), ATT_OK);
    for (k = 0; k < 2000; ++k) {
        CHECK_EQ_INT(att_ahrs_update(&s, w, f, NULL, (att_real)0.01, q), ATT_OK);
    }
    att_ahrs_bias(&s, b);
    for (k = 0; k < 3; ++k) {
        CHECK_CLOSE(b[k], w[k], 1e-3); /* 20 s, zero-rate update: within 0.06°/s */
    }
    CHECK_EQ_INT(att_ahrs_sigma(&s, as, bs), ATT_OK);
    CHECK(bs[2] < 1e-3);
}

static void test_overrange_and_mag_flags(void)
{
    att_ahrs_settings set;
    att_ahrs s;
    att_real e[3] = { 0, 0, 0 }, f[3], m[3], q[4], w[3] = { 0, 0, 5 };
    int k;
    body_vectors(e, f, m);
    att_ahrs_default_settings(&set);
    set.gyro_range = 4;
    CHECK_EQ_INT(att_ahrs_init(&s, &set, NULL), ATT_OK);
    CHECK_EQ_INT(att_ahrs_update(&s, w, f, m, (att_real)0.01, q), ATT_OK);
    CHECK(att_ahrs_flags(&s) & ATT_AHRS_F_OVERRANGE);
    w[2] = 0;
    for (k = 0; k < 1000; ++k) { /* 10 s: the inclination settles, the field reference is learned */
        CHECK_EQ_INT(att_ahrs_update(&s, w, f, m, (att_real)0.01, q), ATT_OK);
    }
    CHECK(!(att_ahrs_flags(&s) & ATT_AHRS_F_OVERRANGE));
    m[0] *= 2; /* field norm doubled: rejected */
    m[1] *= 2;
    m[2] *= 2;
    CHECK_EQ_INT(att_ahrs_update(&s, w, f, m, (att_real)0.01, q), ATT_OK);
    CHECK(att_ahrs_flags(&s) & ATT_AHRS_F_MAG_DISTURBED);
}

/* A magnetometer lagging the gyro by D: turning about the vertical at W with
 * exact sensors, the field sampled at the attitude of t − D (truth by
 * construction). Uncompensated, the filter's heading settles W·D behind;
 * with mag_delay = D the lag is undone up to the series' truncation. */
static double lagged_turn_error(att_real mag_delay)
{
    const double W = 2.0, D = 0.02, DT = 0.01; /* rad/s, s, s: θ = W·D = 0.04 rad */
    att_ahrs_settings set;
    att_ahrs s;
    att_real e[3] = { 0, 0, 0 }, f[3], m[3], q[4], qt[4], w[3] = { 0, 0, (att_real)W };
    int k;
    att_ahrs_default_settings(&set);
    set.mag_delay = mag_delay;
    body_vectors(e, f, m);
    att_euler_to_quat(e, qt);
    CHECK_EQ_INT(att_ahrs_init(&s, &set, qt), ATT_OK);
    for (k = 1; k <= 6000; ++k) { /* 60 s: 12 of the 5 s heading time constants */
        e[0] = (att_real)(W * (k * DT - D));
        body_vectors(e, f, m); /* f is the same at any heading */
        CHECK_EQ_INT(att_ahrs_update(&s, w, f, m, (att_real)DT, q), ATT_OK);
    }
    e[0] = (att_real)(W * 6000 * DT);
    att_euler_to_quat(e, qt);
    return qangle(q, qt);
}

static void test_mag_delay_closed_form(void)
{
    double e0 = lagged_turn_error(0), e1 = lagged_turn_error((att_real)0.02);
    /* uncompensated: the heading follows the lagged field, W·D = 0.04 rad */
    CHECK(fabs(e0 - 0.04) < 0.004);
    /* compensated about the turn axis: the truncation |θ|³/6 = 1.1e-5 rad,
     * plus the float build's rounding of the yaw angle itself (W·t = 120 rad
     * held to ~1e-5 rad in att_real): 1e-4 rad is 2.5 % of the lag */
    CHECK(e1 < 1e-4);
    if (!(e1 < 1e-4) || !(fabs(e0 - 0.04) < 0.004)) {
        printf("lagged turn: error %g rad uncompensated, %g rad compensated\n", e0, e1);
    }
}

/* Inclination (rad) of a reported attitude against the identity: the angle
 * between its up axis, seen from the body (row 3 of C_b^n), and e_z. */
static double inclination(const att_real q[4])
{
    double z = (double)q[0] * q[0] - (double)q[1] * q[1] - (double)q[2] * q[2] + (double)q[3] * q[3];
    double n = (double)q[0] * q[0] + (double)q[1] * q[1] + (double)q[2] * q[2] + (double)q[3] * q[3];
    return acos(fmin(1.0, z / n));
}

/* The reported inclination at rest is the accelerometer's, whatever the state's:
 * started 3° off in tilt, the first report is level (truth by construction:
 * the sensor is level and still) while the Kalman state needs seconds. After
 * that the filtered vector lives in the state's navigation frame, which turns
 * by the state's bias error b̂ (the Kalman filter moves b̂ while it converges):
 * a second-order low-pass follows a ramp with the lag 2ζ/ω0 = τ, so the
 * report stays within τ·max|b̂_horizontal| of level. */
static void test_tilt_reports_the_accelerometer_at_rest(void)
{
    att_ahrs_settings set;
    att_ahrs s;
    att_real e[3] = { 0, 0, 0 }, e0[3] = { 0, (att_real)0.0523599, 0 }, f[3], m[3], q0[4], q[4], b[3];
    att_real w[3] = { 0, 0, 0 };
    int k;
    double worst = 0, first = 0, bmax = 0;
    att_ahrs_default_settings(&set);
    body_vectors(e, f, m);
    att_euler_to_quat(e0, q0); /* 3° of pitch */
    CHECK_EQ_INT(att_ahrs_init(&s, &set, q0), ATT_OK);
    for (k = 0; k < 1000; ++k) {
        CHECK_EQ_INT(att_ahrs_update(&s, w, f, m, (att_real)0.01, q), ATT_OK);
        CHECK_EQ_INT(att_ahrs_bias(&s, b), ATT_OK);
        first = (k == 0) ? inclination(q) : first;
        worst = fmax(worst, inclination(q));
        bmax = fmax(bmax, sqrt((double)b[0] * b[0] + (double)b[1] * b[1]));
    }
    CHECK(first < 1e-6); /* float: the quaternion's rounding, ~1e-7 rad */
    CHECK(bmax > 0 && worst <= set.tilt_tau * bmax);
    CHECK(worst < 0.01 * 0.0523599); /* the state started 3° off */
    if (!(worst <= set.tilt_tau * bmax) || !(first < 1e-6)) {
        printf("tilt at rest: first %g rad, worst %g rad, tau*max|b| %g rad\n", first, worst,
               set.tilt_tau * bmax);
    }
    /* off: the state's own, still most of the 3° after its first (14 %) Kalman step */
    set.tilt_tau = 0;
    CHECK_EQ_INT(att_ahrs_init(&s, &set, q0), ATT_OK);
    CHECK_EQ_INT(att_ahrs_update(&s, w, f, m, (att_real)0.01, q), ATT_OK);
    CHECK(inclination(q) > 0.03);
}

/* Step response: a level sensor whose specific force steps by a horizontal A
 * (an acceleration that starts and stays; below the gate and the rest
 * detector's threshold). The reported inclination follows the low-pass of the
 * true specific force, atan(A·s(t)/g) with s(t) = 1 − e^(−t/τ)(cos(t/τ) +
 * sin(t/τ)) (ζ = 1/√2, ω0 = √2/τ), whatever the Kalman state's tilt does:
 * τ = tilt_tau with the rest detector off, τ·gyr_noise/gyr_noise_rest = 15 s
 * while rest is detected. The step comes after the running-mean start (which
 * spans τ). Tolerance: implicit Euler's error in s is of order ω0·dt (0.0047 at
 * dt = 0.01 s, τ = 3 s), so 1 % of the step angle. */
static int tilt_step_response(int rest_on)
{
    const double A = 0.3, DT = 0.01;
    att_ahrs_settings set;
    att_ahrs s;
    att_real e[3] = { 0, 0, 0 }, f[3], m[3], q0[4], q[4], w[3] = { 0, 0, 0 };
    int k, bad = 0;
    double tau;
    att_ahrs_default_settings(&set);
    /* bias held at 0 (known gyro): the state's frame cannot turn, so the stage's own
     * dynamics are seen alone (a moving bias estimate turns the frame the low-pass
     * lives in: the report then lags that turn by τ, test above) */
    set.bias_noise = 0;
    set.init_bias_sigma = 0;
    if (!rest_on) {
        set.rest_time = 0;
    }
    tau = rest_on ? (double)set.tilt_tau * set.gyr_noise / set.gyr_noise_rest : (double)set.tilt_tau;
    body_vectors(e, f, m);
    att_euler_to_quat(e, q0);
    CHECK_EQ_INT(att_ahrs_init(&s, &set, q0), ATT_OK);
    for (k = 0; k < (int)(1.5 * tau / DT) + 200; ++k) { /* past the start (and rest detection) */
        CHECK_EQ_INT(att_ahrs_update(&s, w, f, NULL, (att_real)DT, q), ATT_OK);
    }
    CHECK(!s.tilt_mean);
    f[0] = (att_real)A;
    for (k = 1; k <= (int)(5 * tau / DT); ++k) {
        double t = k * DT, u = t / tau;
        double want = atan(A * (1 - exp(-u) * (cos(u) + sin(u))) / G);
        CHECK_EQ_INT(att_ahrs_update(&s, w, f, NULL, (att_real)DT, q), ATT_OK);
        CHECK(rest_on == !!(att_ahrs_flags(&s) & ATT_AHRS_F_REST));
        if (k % 100 == 0 && !(fabs(inclination(q) - want) <= 0.01 * atan(A / G) + 1e-6)) {
            printf("tilt step (rest %d): t = %g s, inclination %g rad, closed form %g rad\n", rest_on, t,
                   inclination(q), want);
            bad = 1;
        }
    }
    return bad;
}

static void test_tilt_step_response(void)
{
    CHECK(!tilt_step_response(0));
    CHECK(!tilt_step_response(1));
}

/* Below the horizon the filtered vector says nothing usable: the state's
 * attitude is reported. A state 120° off in tilt with the gate off (so the
 * low-pass takes the sample): the report equals that of the same filter with
 * tilt_tau = 0 (the state is the same: the reported inclination never feeds
 * back into it). */
static void test_tilt_not_below_the_horizon(void)
{
    att_ahrs_settings set;
    att_ahrs s, s0;
    att_real e[3] = { 0, 0, 0 }, e0[3] = { 0, (att_real)2.0944, 0 }, f[3], m[3], q0[4], q[4], qs[4];
    att_real w[3] = { 0, 0, 0 };
    att_ahrs_default_settings(&set);
    set.acc_gate = 0;
    body_vectors(e, f, m);
    att_euler_to_quat(e0, q0);
    CHECK_EQ_INT(att_ahrs_init(&s, &set, q0), ATT_OK);
    set.tilt_tau = 0;
    CHECK_EQ_INT(att_ahrs_init(&s0, &set, q0), ATT_OK);
    CHECK_EQ_INT(att_ahrs_update(&s, w, f, NULL, (att_real)0.01, q), ATT_OK);
    CHECK_EQ_INT(att_ahrs_update(&s0, w, f, NULL, (att_real)0.01, qs), ATT_OK);
    CHECK(s.tilt_f[2] < 0); /* the low-pass took the sample: below the horizon */
    CHECK(memcmp(q, qs, sizeof q) == 0);
    CHECK(qangle(q, q0) > 0.01); /* the state itself moved: the update was made */
}

/* Covariance and heading observability, closed form: level and at rest, bias states
 * off (init_bias_sigma = bias_noise = 0) and no rest detection, the heading variance
 * only grows by gyr_noise²·dt per sample without the magnetometer (no other stage
 * touches it); the flag follows heading_sigma_max. */
static void test_covariance_and_heading_flag(void)
{
    att_ahrs_settings set;
    att_ahrs s, t;
    att_real q0[4] = { 1, 0, 0, 0 }, e[3] = { 0, 0, 0 }, f[3], m[3], g[3] = { 0, 0, 0 }, dt = (att_real)0.01;
    att_real P[9], B[9], sa[3], sb[3], cov[3 * 9], q[3 * 4], gs[9] = { 0 }, fs[9], ms[9];
    double v0, grow, bound2;
    int k, n;
    body_vectors(e, f, m);
    att_ahrs_default_settings(&set);
    set.init_bias_sigma = 0;
    set.bias_noise = 0;
    set.rest_time = 0;
    CHECK_EQ_INT(att_ahrs_init(&s, &set, q0), ATT_OK);
    CHECK_EQ_INT(att_ahrs_covariance(NULL, P, B), ATT_E_NULL);
    CHECK_EQ_INT(att_ahrs_covariance(&s, NULL, NULL), ATT_OK);
    CHECK_EQ_INT(att_ahrs_covariance(&s, P, B), ATT_OK); /* the initial covariance */
    CHECK_CLOSE(P[0], set.init_att_sigma * set.init_att_sigma, 0);
    CHECK_CLOSE(P[1], 0, 0);
    CHECK_CLOSE(B[4], 0, 0);
    v0 = (double)P[8];
    grow = (double)set.gyr_noise * set.gyr_noise * dt;
    for (k = 1; k <= 100; k++) {
        CHECK_EQ_INT(att_ahrs_update(&s, g, f, NULL, dt, NULL), ATT_OK);
        CHECK(att_ahrs_flags(&s) & ATT_AHRS_F_NO_HEADING); /* six-axis: never observable */
    }
    att_ahrs_covariance(&s, P, B);
    /* 100 additions, each rounded by at most half an ulp of ~0.01 (float: 4.7e-10): < 1e-7 */
    CHECK_CLOSE(P[8], v0 + 100 * grow, 1e-5 * v0);
    CHECK(P[1] == P[3] && P[2] == P[6] && P[5] == P[7]); /* symmetric, as stored */
    att_ahrs_sigma(&s, sa, sb);
    CHECK_CLOSE(sa[2] * sa[2], P[8], 1e-6 * P[8]);
    /* the magnetometer brings the heading's 1σ under the bound: observable */
    for (k = 0; k < 2000 && (att_ahrs_flags(&s) & ATT_AHRS_F_NO_HEADING); k++) {
        CHECK_EQ_INT(att_ahrs_update(&s, g, f, m, dt, NULL), ATT_OK);
    }
    CHECK(!(att_ahrs_flags(&s) & ATT_AHRS_F_NO_HEADING));
    for (k = 0; k < 500; k++) {
        att_ahrs_update(&s, g, f, m, dt, NULL);
    }
    CHECK(!(att_ahrs_flags(&s) & ATT_AHRS_F_NO_HEADING));
    /* without it the variance grows by gyr_noise²·dt a sample: the flag returns after
     * n = ceil((bound² − P22)/(gyr_noise²·dt)) samples (± 1 for rounding) */
    att_ahrs_covariance(&s, P, NULL);
    bound2 = (double)set.heading_sigma_max * set.heading_sigma_max;
    n = (int)ceil((bound2 - (double)P[8]) / grow);
    for (k = 1; k < n - 1; k++) {
        att_ahrs_update(&s, g, f, NULL, dt, NULL);
        CHECK(!(att_ahrs_flags(&s) & ATT_AHRS_F_NO_HEADING));
    }
    att_ahrs_update(&s, g, f, NULL, dt, NULL);
    att_ahrs_update(&s, g, f, NULL, dt, NULL);
    att_ahrs_update(&s, g, f, NULL, dt, NULL);
    CHECK(att_ahrs_flags(&s) & ATT_AHRS_F_NO_HEADING);
    /* the batch's covariance output: that of single updates, sample by sample */
    for (k = 0; k < 3; k++) {
        memcpy(fs + 3 * k, f, sizeof f);
        memcpy(ms + 3 * k, m, sizeof m);
    }
    att_ahrs_init(&s, &set, q0);
    t = s;
    CHECK_EQ_INT(att_ahrs_batch_cov(&s, gs, fs, ms, 3, &dt, 1, q, cov, NULL), ATT_OK);
    for (k = 0; k < 3; k++) {
        att_ahrs_update(&t, g, f, m, dt, NULL);
        att_ahrs_covariance(&t, P, NULL);
        CHECK(memcmp(P, cov + 9 * k, sizeof P) == 0);
    }
}

/* The heading's row: the field's heading in the estimate's frame measures δθz + tan(dip)·(δθ·u)
 * (u magnetic north, docs/ahrs.md "Magnetometer"). One sample, the estimate tilted by ε about
 * north with its heading right, the accelerometer trusted (gain ≈ 1): its innovation holds no
 * heading error, so the heading is left (the row's residual is 6ε³ = 6e-6 rad for this field);
 * without the tilt term (H = e_z) it would turn by ≈ tan(dip)·ε = 0.02 rad. The truth is the
 * identity, so δθ = log(q_est*): δθ_y ≈ −2 q_y, δθ_z ≈ −2 q_z. */
static void test_heading_row_tilt_about_north(void)
{
    att_ahrs s;
    att_ahrs_settings set;
    const double eps = 0.01;
    att_real q0[4], q[4], w[3] = { 0, 0, 0 }, f[3] = { 0, 0, (att_real)G }, m[3] = { 0, 20, -40 };
    q0[0] = (att_real)cos(eps / 2);
    q0[1] = 0;
    q0[2] = (att_real)-sin(eps / 2); /* q_est = exp(−ε e_north) */
    q0[3] = 0;
    att_ahrs_default_settings(&set);
    set.acc_noise = (att_real)1e-6;
    set.mag_noise = (att_real)1e-4;
    set.tilt_tau = 0;
    CHECK_EQ_INT(att_ahrs_init(&s, &set, q0), ATT_OK);
    CHECK_EQ_INT(att_ahrs_update(&s, w, f, m, (att_real)0.01, q), ATT_OK);
    CHECK(fabs(2.0 * q[2]) < 1e-6); /* the tilt found: 1 − K_acc = R/(P + R) ≈ 1e-8 */
    CHECK(fabs(2.0 * q[3]) < 1e-5); /* the heading left: 6ε³ = 6e-6 rad */
}

int main(void)
{
    test_settings();
    test_settings_field_names();
    test_statuses();
    test_static_convergence();
    test_rest_bias();
    test_overrange_and_mag_flags();
    test_mag_delay_closed_form();
    test_tilt_reports_the_accelerometer_at_rest();
    test_tilt_step_response();
    test_tilt_not_below_the_horizon();
    test_covariance_and_heading_flag();
    test_heading_row_tilt_about_north();
    return ATT_TEST_REPORT();
}
