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
    CHECK_EQ_INT(att_ahrs_init(NULL, NULL, NULL), ATT_E_NULL);
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
    for (k = 0; k < 12000; ++k) {
        CHECK_EQ_INT(att_ahrs_update(&s, w, f, m, (att_real)0.01, q), ATT_OK);
    }
    /* 120 s: the bulk of the 20° goes in the first seconds (correction time
     * constants of a few seconds in motion); once rest is declared (1.5 s) the
     * process noise is gyr_noise_rest and the time constants are acc_noise /
     * gyr_noise_rest = 12.5 s (tilt), mag_noise / gyr_noise_rest = 25 s
     * (heading): 0.034° remain after 60 s, e^-2.4 of that after 120 s: < 0.01° */
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

int main(void)
{
    test_settings();
    test_statuses();
    test_static_convergence();
    test_rest_bias();
    test_overrange_and_mag_flags();
    test_mag_delay_closed_form();
    return ATT_TEST_REPORT();
}
