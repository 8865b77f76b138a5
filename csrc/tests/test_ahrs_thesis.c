/*
 * Tests of the UAV thesis's EKF (attitude/ahrs_thesis.h): settings and
 * status codes, alignment, convergence to a known static attitude with a
 * constant gyro bias learnt, a skipped Gauss-Newton update counted, and a
 * state left unchanged by a rejected call. The differential tests against
 * the NumPy model are in tests/test_ahrs_thesis.py.
 */
#include <math.h>
#include <string.h>

#include "attitude/attitude.h"
#include "att_test.h"

/* Angle between two attitudes [rad], 2 atan2(|v|, |w|) of a* ⊗ b. */
static double qangle(const att_real a[4], const att_real b[4])
{
    double w = (double)a[0] * b[0] + (double)a[1] * b[1] + (double)a[2] * b[2] + (double)a[3] * b[3];
    double x = (double)a[0] * b[1] - (double)a[1] * b[0] - (double)a[2] * b[3] + (double)a[3] * b[2];
    double y = (double)a[0] * b[2] + (double)a[1] * b[3] - (double)a[2] * b[0] - (double)a[3] * b[1];
    double z = (double)a[0] * b[3] - (double)a[1] * b[2] + (double)a[2] * b[1] - (double)a[3] * b[0];
    return 2 * atan2(sqrt(x * x + y * y + z * z), fabs(w));
}

static void body_vectors(const att_real e[3], att_real f_b[3], att_real m_b[3], att_real q[4])
{
    att_real C[9], fn[3] = { 0, 0, (att_real)9.81 }, mn[3] = { 0, 20, -40 };
    int i;
    att_euler_to_dcm(e, C);
    for (i = 0; i < 3; ++i) {
        f_b[i] = C[i] * fn[0] + C[3 + i] * fn[1] + C[6 + i] * fn[2];
        m_b[i] = C[i] * mn[0] + C[3 + i] * mn[1] + C[6 + i] * mn[2];
    }
    att_dcm_to_quat(C, q);
}

static void test_settings(void)
{
    att_tekf_settings set;
    att_tekf s;
    att_real q0[4] = { 0, 0, 0, 0 }, qn[4] = { 1, (att_real)NAN, 0, 0 };
    att_tekf_default_settings(&set);
    CHECK_EQ_INT(att_tekf_check_settings(&set), ATT_OK);
    CHECK_EQ_INT(att_tekf_check_settings(NULL), ATT_E_NULL);
    CHECK(set.bias_noise == 0); /* the thesis's db/dt = 0 */
    set.meas_noise = 0;
    CHECK_EQ_INT(att_tekf_check_settings(&set), ATT_E_TEKF_SETTINGS);
    CHECK_EQ_INT(att_tekf_init(&s, &set, NULL), ATT_E_TEKF_SETTINGS);
    att_tekf_default_settings(&set);
    set.gn.max_iter = 0;
    CHECK_EQ_INT(att_tekf_check_settings(&set), ATT_E_TEKF_SETTINGS);
    att_tekf_default_settings(&set);
    set.gyr_noise = (att_real)NAN;
    CHECK_EQ_INT(att_tekf_check_settings(&set), ATT_E_TEKF_SETTINGS);
    CHECK_EQ_INT(att_tekf_init(NULL, NULL, NULL), ATT_E_NULL);
    CHECK_EQ_INT(att_tekf_init(&s, NULL, q0), ATT_E_ARG);
    CHECK_EQ_INT(att_tekf_init(&s, NULL, qn), ATT_E_NONFINITE);
    CHECK_EQ_INT(att_tekf_flags(NULL), 0);
    CHECK(att_tekf_gn_skipped(NULL) == 0);
}

static void test_statuses(void)
{
    att_tekf s, before;
    att_real g[3] = { 0.01f, 0, 0 }, f[3] = { 0, 0, 9.81f }, m[3] = { 0, 20, -40 }, q[4];
    att_real bad[3] = { 0, (att_real)INFINITY, 0 }, zero[3] = { 0, 0, 0 };
    CHECK_EQ_INT(att_tekf_init(&s, NULL, NULL), ATT_OK);
    CHECK_EQ_INT(att_tekf_attitude(&s, q), ATT_E_STATE);
    /* unaligned and a sample that cannot align */
    CHECK_EQ_INT(att_tekf_update(&s, g, zero, m, 0.01f, q), ATT_E_TEKF_ALIGN);
    CHECK_EQ_INT(att_tekf_update(&s, g, f, m, 0.01f, q), ATT_OK);
    CHECK_EQ_INT(att_tekf_attitude(&s, q), ATT_OK);
    before = s;
    CHECK_EQ_INT(att_tekf_update(&s, g, f, m, 0, q), ATT_E_TEKF_DT);
    CHECK_EQ_INT(att_tekf_update(&s, g, f, m, -1, q), ATT_E_TEKF_DT);
    CHECK_EQ_INT(att_tekf_update(&s, g, f, m, (att_real)NAN, q), ATT_E_TEKF_DT);
    CHECK_EQ_INT(att_tekf_update(&s, bad, f, m, 0.01f, q), ATT_E_NONFINITE);
    CHECK_EQ_INT(att_tekf_update(&s, g, f, bad, 0.01f, q), ATT_E_NONFINITE);
    CHECK_EQ_INT(att_tekf_update(&s, g, f, NULL, 0.01f, q), ATT_E_NULL);
    CHECK(memcmp(&s, &before, sizeof s) == 0);
    /* the Gauss-Newton solve fails (field parallel to gravity): the time
     * update is made, the measurement update skipped and counted */
    CHECK_EQ_INT(att_tekf_update(&s, g, f, f, 0.01f, q), ATT_OK);
    CHECK_EQ_INT(att_tekf_flags(&s), ATT_TEKF_F_GN_SKIPPED);
    CHECK(att_tekf_gn_skipped(&s) == 1);
    CHECK_EQ_INT(att_tekf_update(&s, g, f, m, 0.01f, q), ATT_OK);
    CHECK_EQ_INT(att_tekf_flags(&s), 0);
    CHECK(att_tekf_gn_skipped(&s) == 1);
}

/* Static at a known attitude with a constant gyro bias, started 10° off
 * with the bias unknown: the thesis's filter (bias_noise 0, as eq. 3.52)
 * learns the bias and settles on the truth. */
static void test_static_convergence(void)
{
    att_tekf_settings set;
    att_tekf s;
    att_real e[3] = { 0.7f, 0.2f, -0.3f }, f[3], m[3], qt[4], q[4], b[3], q0[4];
    att_real bias[3] = { 0.01f, -0.02f, 0.015f }, e0[3], C0[9];
    size_t k;
    int i;
    body_vectors(e, f, m, qt);
    for (i = 0; i < 3; ++i) {
        e0[i] = e[i] + (att_real)0.1;
    }
    att_euler_to_dcm(e0, C0);
    att_dcm_to_quat(C0, q0);
    att_tekf_default_settings(&set);
    CHECK_EQ_INT(att_tekf_init(&s, &set, q0), ATT_OK);
    for (k = 0; k < 6000; ++k) { /* 60 s at 100 Hz */
        CHECK_EQ_INT(att_tekf_update(&s, bias, f, m, 0.01f, q), ATT_OK);
    }
    CHECK_EQ_INT(att_tekf_bias(&s, b), ATT_OK);
    /* With db/dt = 0 (no bias process noise) the bias variance falls like
     * 1/t, so the error decays like 1/t, not exponentially: after 60 s it
     * is below 1 % of the 0.02 rad/s step (2e-4 rad/s), and the attitude
     * lags the truth by that error times the correction's time constant
     * (2 σ_m/σ_g = 5 s): 1e-3 rad */
    for (i = 0; i < 3; ++i) {
        CHECK_CLOSE(b[i], bias[i], 2e-4);
    }
    CHECK(qangle(q, qt) < 1e-3);
    CHECK(fabs(1 - (double)(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])) < 1e-5);
}

static void test_batch(void)
{
    att_tekf a, b;
    att_real g[6] = { 0.1f, 0, 0, 0.1f, 0.02f, 0 }, f[6] = { 0, 0, 9.81f, 0, 0.1f, 9.8f };
    att_real m[6] = { 0, 20, -40, 0.5f, 20, -40 }, dt[1] = { 0.01f }, qb[8], qs[4];
    size_t err = 99;
    int k, i;
    CHECK_EQ_INT(att_tekf_init(&a, NULL, NULL), ATT_OK);
    CHECK_EQ_INT(att_tekf_init(&b, NULL, NULL), ATT_OK);
    CHECK_EQ_INT(att_tekf_batch(&a, g, f, m, 2, dt, 1, qb, &err), ATT_OK);
    for (k = 0; k < 2; ++k) {
        CHECK_EQ_INT(att_tekf_update(&b, g + 3 * k, f + 3 * k, m + 3 * k, dt[0], qs), ATT_OK);
        for (i = 0; i < 4; ++i) {
            CHECK(qs[i] == qb[4 * k + i]); /* a batch is exactly the single updates */
        }
    }
    CHECK_EQ_INT(att_tekf_batch(&a, g, f, m, 2, dt, 3, qb, &err), ATT_E_ARG);
    dt[0] = 0;
    CHECK_EQ_INT(att_tekf_batch(&a, g, f, m, 2, dt, 1, qb, &err), ATT_E_TEKF_DT);
    CHECK(err == 0);
}

int main(void)
{
    test_settings();
    test_statuses();
    test_static_convergence();
    test_batch();
    return ATT_TEST_REPORT();
}
