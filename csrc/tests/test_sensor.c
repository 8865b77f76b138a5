/*
 * Tests of the sensor-word converter (attitude/sensor.h): the formula on
 * exactly representable values, axis mapping and signs, oversampled words,
 * every range check, and the batch increments (no write on an error); the
 * correction M (value - b): its checks, closed forms, the plain path bit for
 * bit, and a magnetometer calibration (M = S, b = h) as att_magcal_apply.
 */
#include <float.h>
#include <math.h>
#include <string.h>

#include "attitude/attitude.h"
#include "att_test.h"

static const att_real ZERO[3] = { 2048, 2047.5, 100 };
static const att_real SCALE[3] = { 0.25, -0.5, 2 }; /* units per code: powers of two, exact */

static void test_init_checks_the_calibration(void)
{
    att_sensor s, keep;
    att_real z[3] = { 0, 65535, 1 }, k[3] = { 1, 1, 1 };
    uint8_t axis[3] = { 2, 0, 1 };
    int8_t sign[3] = { 1, -1, 1 };
    CHECK_EQ_INT(att_sensor_init(&s, z, k, NULL, NULL), ATT_OK);
    CHECK_EQ_INT(s.axis[0], 0);
    CHECK_EQ_INT(s.axis[2], 2);
    CHECK_EQ_INT(s.sign[1], 1);
    CHECK_EQ_INT(att_sensor_init(&s, z, k, axis, sign), ATT_OK);
    CHECK_EQ_INT(s.axis[0], 2);
    CHECK_EQ_INT(s.sign[1], -1);
    keep = s;
    CHECK_EQ_INT(att_sensor_init(NULL, z, k, NULL, NULL), ATT_E_NULL);
    CHECK_EQ_INT(att_sensor_init(&s, NULL, k, NULL, NULL), ATT_E_NULL);
    CHECK_EQ_INT(att_sensor_init(&s, z, NULL, NULL, NULL), ATT_E_NULL);
    z[1] = (att_real)NAN;
    CHECK_EQ_INT(att_sensor_init(&s, z, k, NULL, NULL), ATT_E_NONFINITE);
    z[1] = 65536;
    CHECK_EQ_INT(att_sensor_init(&s, z, k, NULL, NULL), ATT_E_ARG);
    z[1] = -0.5;
    CHECK_EQ_INT(att_sensor_init(&s, z, k, NULL, NULL), ATT_E_ARG);
    z[1] = 2048;
    k[2] = (att_real)INFINITY;
    CHECK_EQ_INT(att_sensor_init(&s, z, k, NULL, NULL), ATT_E_NONFINITE);
    k[2] = 0;
    CHECK_EQ_INT(att_sensor_init(&s, z, k, NULL, NULL), ATT_E_ARG);
    k[2] = -1; /* a negative scale flips the channel: allowed */
    CHECK_EQ_INT(att_sensor_init(&s, z, k, NULL, NULL), ATT_OK);
    keep = s;
    axis[1] = 2; /* channel 2 twice */
    CHECK_EQ_INT(att_sensor_init(&s, z, k, axis, NULL), ATT_E_ARG);
    axis[1] = 3;
    CHECK_EQ_INT(att_sensor_init(&s, z, k, axis, NULL), ATT_E_ARG);
    sign[2] = 0;
    CHECK_EQ_INT(att_sensor_init(&s, z, k, NULL, sign), ATT_E_ARG);
    CHECK(memcmp(&s, &keep, sizeof s) == 0); /* untouched on every error */
}

static void test_convert_formula_axes_and_oversampling(void)
{
    att_sensor s;
    att_real v[3];
    uint16_t w[3] = { 2052, 2047, 96 };
    uint8_t axis[3] = { 1, 2, 0 };
    int8_t sign[3] = { -1, 1, 1 };
    CHECK_EQ_INT(att_sensor_init(&s, ZERO, SCALE, NULL, NULL), ATT_OK);
    CHECK_EQ_INT(att_sensor_convert(&s, w, 1, v), ATT_OK);
    CHECK(v[0] == (att_real)1.0);  /* (2052 - 2048) * 0.25 */
    CHECK(v[1] == (att_real)0.25); /* (2047 - 2047.5) * -0.5 */
    CHECK(v[2] == (att_real)-8.0); /* (96 - 100) * 2 */
    /* body axis i = sign[i] * channel axis[i] */
    CHECK_EQ_INT(att_sensor_init(&s, ZERO, SCALE, axis, sign), ATT_OK);
    CHECK_EQ_INT(att_sensor_convert(&s, w, 1, v), ATT_OK);
    CHECK(v[0] == (att_real)-0.25);
    CHECK(v[1] == (att_real)-8.0);
    CHECK(v[2] == (att_real)1.0);
    /* sums of 16 conversions: the mean code, with its fraction */
    CHECK_EQ_INT(att_sensor_init(&s, ZERO, SCALE, NULL, NULL), ATT_OK);
    w[0] = 16 * 2048 + 8; /* mean 2048.5 */
    w[1] = 16 * 2047;     /* mean 2047 */
    w[2] = 16 * 101 + 4;  /* mean 101.25 */
    CHECK_EQ_INT(att_sensor_convert(&s, w, 16, v), ATT_OK);
    CHECK(v[0] == (att_real)0.125);
    CHECK(v[1] == (att_real)0.25);
    CHECK(v[2] == (att_real)2.5);
    w[0] = 3; /* n = 3: the sum divided by 3 */
    w[1] = 3 * 2047 + 1;
    w[2] = 3 * 100;
    CHECK_EQ_INT(att_sensor_convert(&s, w, 3, v), ATT_OK);
    CHECK(v[0] == (att_real)-511.75); /* (1 - 2048) * 0.25 */
    CHECK(v[2] == (att_real)0);
    /* (6142 / 3 - 2047.5) * -0.5 = 1/12: within one rounding of each step */
    CHECK_CLOSE(v[1], 1.0 / 12.0, 4 * 2048 * (sizeof(att_real) == 4 ? FLT_EPSILON : DBL_EPSILON));
}

static void test_convert_range_checks(void)
{
    att_sensor s;
    att_real v[3] = { 7, 7, 7 }, huge[3] = { 1, 1, 1 };
    uint16_t w[3] = { 4095, 0, 4096 };
    CHECK_EQ_INT(att_sensor_init(&s, ZERO, SCALE, NULL, NULL), ATT_OK);
    CHECK_EQ_INT(att_sensor_convert(&s, w, 1, v), ATT_E_RANGE); /* 4096 is no 12-bit code */
    CHECK(v[0] == 7 && v[1] == 7 && v[2] == 7);
    CHECK_EQ_INT(att_sensor_convert(&s, w, 2, v), ATT_OK); /* ... but a sum of two */
    w[2] = 16u * 4095u;
    CHECK_EQ_INT(att_sensor_convert(&s, w, 16, v), ATT_OK);
    w[2] = 16u * 4095u + 1u;
    CHECK_EQ_INT(att_sensor_convert(&s, w, 16, v), ATT_E_RANGE);
    CHECK_EQ_INT(att_sensor_convert(&s, w, 0, v), ATT_E_ARG);
    CHECK_EQ_INT(att_sensor_convert(&s, w, 17, v), ATT_E_ARG);
    CHECK_EQ_INT(att_sensor_convert(NULL, w, 1, v), ATT_E_NULL);
    CHECK_EQ_INT(att_sensor_convert(&s, NULL, 1, v), ATT_E_NULL);
    CHECK_EQ_INT(att_sensor_convert(&s, w, 1, NULL), ATT_E_NULL);
    /* a scale so large that no value is finite: an error, never an Inf */
    huge[0] = sizeof(att_real) == 4 ? (att_real)FLT_MAX : (att_real)DBL_MAX;
    CHECK_EQ_INT(att_sensor_init(&s, ZERO, huge, NULL, NULL), ATT_OK);
    w[0] = 4095;
    w[2] = 0;
    CHECK_EQ_INT(att_sensor_convert(&s, w, 1, v), ATT_E_RANGE);
}

static void test_increments_batch(void)
{
    att_sensor s;
    uint16_t w[4 * 3] = { 2052, 2047, 96, 2048, 2048, 100, 0, 4095, 200, 4095, 0, 0 };
    att_real d[4 * 3], v[3];
    size_t err = 99, k;
    int i;
    CHECK_EQ_INT(att_sensor_init(&s, ZERO, SCALE, NULL, NULL), ATT_OK);
    CHECK_EQ_INT(att_sensor_increments(&s, w, 4, 1, (att_real)0.0625, d, &err), ATT_OK);
    CHECK_EQ_INT(err, 99);
    for (k = 0; k < 4; k++) {
        CHECK_EQ_INT(att_sensor_convert(&s, w + 3 * k, 1, v), ATT_OK);
        for (i = 0; i < 3; i++) {
            CHECK(d[3 * k + (size_t)i] == v[i] * (att_real)0.0625);
        }
    }
    /* a bad sample: its index, and nothing written */
    for (k = 0; k < 12; k++) {
        d[k] = -1;
    }
    w[7] = 4096;
    CHECK_EQ_INT(att_sensor_increments(&s, w, 4, 1, (att_real)0.0625, d, &err), ATT_E_RANGE);
    CHECK_EQ_INT(err, 2);
    for (k = 0; k < 12; k++) {
        CHECK(d[k] == -1);
    }
    CHECK_EQ_INT(att_sensor_increments(&s, w, 4, 1, (att_real)0.0625, d, NULL), ATT_E_RANGE);
    CHECK_EQ_INT(att_sensor_increments(&s, w, 2, 1, 0, d, NULL), ATT_E_ARG);
    CHECK_EQ_INT(att_sensor_increments(&s, w, 2, 1, -1, d, NULL), ATT_E_ARG);
    CHECK_EQ_INT(att_sensor_increments(&s, w, 2, 1, (att_real)NAN, d, NULL), ATT_E_NONFINITE);
    CHECK_EQ_INT(att_sensor_increments(&s, w, 2, 0, 1, d, NULL), ATT_E_ARG);
    CHECK_EQ_INT(att_sensor_increments(&s, NULL, 0, 1, 1, NULL, NULL), ATT_OK); /* nothing to do */
    CHECK_EQ_INT(att_sensor_increments(&s, NULL, 1, 1, 1, d, NULL), ATT_E_NULL);
    CHECK_EQ_INT(att_sensor_increments(NULL, w, 1, 1, 1, d, NULL), ATT_E_NULL);
}

static const att_real IDENTITY[9] = { 1, 0, 0, 0, 1, 0, 0, 0, 1 };
static const att_real NO_BIAS[3] = { 0, 0, 0 };

static void test_correction_checks(void)
{
    att_sensor s, keep;
    att_real m[9], b[3] = { 0.5, -1, 2 };
    int i;
    CHECK_EQ_INT(att_sensor_init(&s, ZERO, SCALE, NULL, NULL), ATT_OK);
    CHECK(memcmp(s.mat, IDENTITY, sizeof IDENTITY) == 0); /* init: M = I, b = 0 */
    CHECK(memcmp(s.bias, NO_BIAS, sizeof NO_BIAS) == 0);
    CHECK_EQ_INT(s.plain, 1);
    keep = s;
    memcpy(m, IDENTITY, sizeof m);
    CHECK_EQ_INT(att_sensor_set_correction(NULL, m, b), ATT_E_NULL);
    CHECK_EQ_INT(att_sensor_set_correction(&s, NULL, b), ATT_E_NULL);
    CHECK_EQ_INT(att_sensor_set_correction(&s, m, NULL), ATT_E_NULL);
    m[5] = (att_real)NAN;
    CHECK_EQ_INT(att_sensor_set_correction(&s, m, b), ATT_E_NONFINITE);
    m[5] = 0;
    b[2] = (att_real)INFINITY;
    CHECK_EQ_INT(att_sensor_set_correction(&s, m, b), ATT_E_NONFINITE);
    b[2] = 2;
    /* diag(1/8, 1/8, 1/16): det 2^-10 < 1/1000; diag(1/8, 1/8, 1/8): det 2^-9 > 1/1000 */
    for (i = 0; i < 9; i++) {
        m[i] = 0;
    }
    m[0] = m[4] = 0.125;
    m[8] = 0.0625;
    CHECK_EQ_INT(att_sensor_set_correction(&s, m, b), ATT_E_ARG);
    m[8] = 0;
    CHECK_EQ_INT(att_sensor_set_correction(&s, m, b), ATT_E_ARG); /* singular */
    /* two equal rows: det exactly 0 though no entry is small */
    memcpy(m, IDENTITY, sizeof m);
    m[3] = 1;
    m[4] = 0;
    CHECK_EQ_INT(att_sensor_set_correction(&s, m, b), ATT_E_ARG);
    /* entries so large that the determinant overflows */
    memcpy(m, IDENTITY, sizeof m);
    m[0] = m[4] = m[8] = sizeof(att_real) == 4 ? (att_real)1e20 : (att_real)1e200;
    CHECK_EQ_INT(att_sensor_set_correction(&s, m, b), ATT_E_ARG);
    CHECK(memcmp(&s, &keep, sizeof s) == 0); /* untouched on every error */
    m[0] = m[4] = m[8] = 0.125;
    CHECK_EQ_INT(att_sensor_set_correction(&s, m, b), ATT_OK);
    CHECK_EQ_INT(s.plain, 0);
    CHECK(s.mat[4] == (att_real)0.125 && s.bias[1] == (att_real)-1);
    /* setting I and 0 again: the plain path */
    CHECK_EQ_INT(att_sensor_set_correction(&s, IDENTITY, NO_BIAS), ATT_OK);
    CHECK(memcmp(&s, &keep, sizeof s) == 0);
    /* a bias alone is a correction */
    CHECK_EQ_INT(att_sensor_set_correction(&s, IDENTITY, b), ATT_OK);
    CHECK_EQ_INT(s.plain, 0);
}

static void test_correction_formula(void)
{
    /* M: a quarter turn about z and z scaled by 2 (exact); b exact */
    static const att_real M[9] = { 0, -1, 0, 1, 0, 0, 0, 0, 2 };
    static const att_real B[3] = { 0.5, 0.25, -4 };
    att_sensor s, plain;
    att_real v[3], p[3], d[2 * 3];
    uint16_t w[2 * 3] = { 2052, 2047, 96, 4095, 0, 300 };
    int i;
    CHECK_EQ_INT(att_sensor_init(&s, ZERO, SCALE, NULL, NULL), ATT_OK);
    plain = s;
    CHECK_EQ_INT(att_sensor_set_correction(&s, M, B), ATT_OK);
    /* value (1, 0.25, -8) (test above); value - b = (0.5, 0, -4) */
    CHECK_EQ_INT(att_sensor_convert(&s, w, 1, v), ATT_OK);
    CHECK(v[0] == 0);              /* -(0) */
    CHECK(v[1] == (att_real)0.5);  /* 0.5 */
    CHECK(v[2] == (att_real)-8.0); /* 2 * -4 */
    /* value (511.75, 1023.75, 400) - b = (511.25, 1023.5, 404) */
    CHECK_EQ_INT(att_sensor_convert(&s, w + 3, 1, v), ATT_OK);
    CHECK(v[0] == (att_real)-1023.5);
    CHECK(v[1] == (att_real)511.25);
    CHECK(v[2] == (att_real)808);
    /* the batch call corrects too: out * period */
    CHECK_EQ_INT(att_sensor_increments(&s, w, 2, 1, (att_real)0.0625, d, NULL), ATT_OK);
    CHECK(d[3] == (att_real)-1023.5 * (att_real)0.0625 && d[5] == (att_real)808 * (att_real)0.0625);
    /* M = I, b = 0 set explicitly: the uncorrected value, bit for bit */
    CHECK_EQ_INT(att_sensor_set_correction(&s, IDENTITY, NO_BIAS), ATT_OK);
    for (i = 0; i < 2; i++) {
        CHECK_EQ_INT(att_sensor_convert(&s, w + 3 * i, 1, v), ATT_OK);
        CHECK_EQ_INT(att_sensor_convert(&plain, w + 3 * i, 1, p), ATT_OK);
        CHECK(memcmp(v, p, sizeof v) == 0);
    }
}

static void test_correction_range(void)
{
    att_sensor s;
    att_real m[9], v[3] = { 7, 7, 7 };
    uint16_t w[3] = { 2052, 2047, 96 };
    memcpy(m, IDENTITY, sizeof m);
    m[0] = (sizeof(att_real) == 4 ? (att_real)FLT_MAX : (att_real)DBL_MAX) / 2; /* det finite */
    CHECK_EQ_INT(att_sensor_init(&s, ZERO, SCALE, NULL, NULL), ATT_OK);
    CHECK_EQ_INT(att_sensor_set_correction(&s, m, NO_BIAS), ATT_OK);
    CHECK_EQ_INT(att_sensor_convert(&s, w, 1, v), ATT_OK); /* value_0 = 1: out_0 = max / 2 */
    CHECK(v[0] == m[0]);
    w[0] = 2060; /* value_0 = 3: out_0 overflows: an error, never an Inf */
    v[0] = v[1] = v[2] = 7;
    CHECK_EQ_INT(att_sensor_convert(&s, w, 1, v), ATT_E_RANGE);
    CHECK(v[0] == 7 && v[1] == 7 && v[2] == 7);
}

/* A magnetometer calibration m_cal = S (m - h) (aiding.h) is M = S, b = h:
 * the corrected words equal att_magcal_apply of the uncorrected values. */
static void test_correction_is_magcal(void)
{
    att_magcal_result r;
    att_sensor plain, s;
    att_real v[3], want[3], got[3];
    uint16_t w[3];
    static const att_real S[9] = { 1.1, 0.05, -0.02, 0.05, 0.93, 0.01, -0.02, 0.01, 0.98 };
    static const att_real H[3] = { 12.5, -7.25, 30.1 };
    static const att_real Z[3] = { 2047.5, 2050.25, 2040 }, K[3] = { 0.0732, -0.0741, 0.0729 }; /* µT/code */
    static const uint8_t AX[3] = { 1, 0, 2 };
    static const int8_t SG[3] = { 1, -1, 1 };
    unsigned k;
    memset(&r, 0, sizeof r);
    memcpy(r.S, S, sizeof S);
    memcpy(r.h, H, sizeof H);
    r.model = ATT_MAGCAL_FULL;
    CHECK_EQ_INT(att_sensor_init(&plain, Z, K, AX, SG), ATT_OK);
    s = plain;
    CHECK_EQ_INT(att_sensor_set_correction(&s, r.S, r.h), ATT_OK);
    for (k = 0; k < 64; k++) {
        w[0] = (uint16_t)(k * 997u % 4096u);
        w[1] = (uint16_t)(4095u - k * 61u);
        w[2] = (uint16_t)(k * 4096u / 64u);
        CHECK_EQ_INT(att_sensor_convert(&plain, w, 1, v), ATT_OK);
        CHECK_EQ_INT(att_magcal_apply(&r, v, want), ATT_OK);
        CHECK_EQ_INT(att_sensor_convert(&s, w, 1, got), ATT_OK);
        CHECK(memcmp(got, want, sizeof got) == 0);
    }
}

int main(void)
{
    test_init_checks_the_calibration();
    test_convert_formula_axes_and_oversampling();
    test_convert_range_checks();
    test_increments_batch();
    test_correction_checks();
    test_correction_formula();
    test_correction_range();
    test_correction_is_magcal();
    return ATT_TEST_REPORT();
}
