/* libattitude own checks: quaternion / matrix / Euler / rotation vector. */
#include <math.h>

#include "att_test.h"
#include "attitude/attitude.h"

#if defined(ATT_REAL_F32)
#define TOL 2e-6 /* a few float32 ulps (6e-8) times the ~10 operations per result */
#else
#define TOL 1e-13 /* a few float64 ulps (1.1e-16) times the operation count */
#endif

static double qdist(const att_real a[4], const att_real b[4])
{
    /* distance between attitudes (q and -q are the same attitude) */
    double dp = 0, dm = 0;
    int i;
    for (i = 0; i < 4; i++) {
        dp += fabs((double)a[i] - (double)b[i]);
        dm += fabs((double)a[i] + (double)b[i]);
    }
    return dp < dm ? dp : dm;
}

static void test_mul_conj(void)
{
    att_real i[4] = { 0, 1, 0, 0 }, j[4] = { 0, 0, 1, 0 }, k[4] = { 0, 0, 0, 1 }, r[4], c[4];
    att_real q[4] = { 0.5, 0.5, -0.5, 0.5 };
    att_quat_mul(i, j, r); /* i j = k */
    CHECK_CLOSE(r[0], 0, 0);
    CHECK_CLOSE(r[3], 1, 0);
    att_quat_mul(j, i, r); /* j i = -k */
    CHECK_CLOSE(r[3], -1, 0);
    att_quat_mul(k, k, r); /* k k = -1 */
    CHECK_CLOSE(r[0], -1, 0);
    att_quat_conj(q, c);
    att_quat_mul(q, c, r);
    CHECK_CLOSE(r[0], 1, TOL);
    CHECK_CLOSE(r[1], 0, TOL);
    att_quat_mul(q, q, q); /* aliasing allowed */
    CHECK_CLOSE(q[0], 0.25 - 0.75, TOL);
}

static void test_normalize(void)
{
    att_real q[4] = { 3, 0, 4, 0 }, z[4] = { 0, 0, 0, 0 }, n[4] = { 0, NAN, 0, 0 }, o[4];
    att_real tiny[4] = { (att_real)1e-30, 0, 0, 0 };
    CHECK_EQ_INT(att_quat_normalize(q, o), ATT_OK);
    CHECK_CLOSE(o[0], 0.6, TOL);
    CHECK_CLOSE(o[2], 0.8, TOL);
    CHECK_EQ_INT(att_quat_normalize(z, o), ATT_E_ARG);
    CHECK_EQ_INT(att_quat_normalize(n, o), ATT_E_NONFINITE);
    CHECK_EQ_INT(att_quat_normalize(tiny, o), ATT_OK); /* no underflow of |q|² */
    CHECK_CLOSE(o[0], 1, TOL);
}

static void test_rotvec(void)
{
    att_real phi[3] = { 0, 0, (att_real)(3.14159265358979323846 / 2) }, q[4], back[3];
    att_real small[3] = { (att_real)1e-12, (att_real)-2e-12, (att_real)3e-12 };
    att_real big[3] = { 1.0, -2.0, 2.0 }; /* 3 rad */
    att_real bad[3] = { 0, INFINITY, 0 };
    CHECK_EQ_INT(att_rotvec_to_quat(phi, q), ATT_OK);
    CHECK_CLOSE(q[0], sqrt(0.5), TOL);
    CHECK_CLOSE(q[3], sqrt(0.5), TOL);
    CHECK_EQ_INT(att_rotvec_to_quat(small, q), ATT_OK);
    CHECK_CLOSE(q[0], 1, TOL);
    CHECK_CLOSE(q[2], 0.5 * (double)small[1], TOL * 1e-12); /* relative TOL */
    CHECK_EQ_INT(att_quat_to_rotvec(q, back), ATT_OK);
    CHECK_CLOSE(back[1], (double)small[1], TOL * 1e-12);
    CHECK_EQ_INT(att_rotvec_to_quat(big, q), ATT_OK);
    CHECK_CLOSE(q[0], cos(1.5), TOL);
    CHECK_CLOSE(q[1], sin(1.5) / 3, TOL);
    CHECK_EQ_INT(att_quat_to_rotvec(q, back), ATT_OK);
    CHECK_CLOSE(back[2], 2, 10 * TOL);
    CHECK_EQ_INT(att_rotvec_to_quat(bad, q), ATT_E_NONFINITE);
    /* series/closed-form boundary at φ = 0.2 is continuous */
    {
        att_real a[3] = { (att_real)0.19999999, 0, 0 }, b[3] = { (att_real)0.20000001, 0, 0 };
        att_real qa[4], qb[4];
        att_rotvec_to_quat(a, qa);
        att_rotvec_to_quat(b, qb);
        CHECK_CLOSE(qa[0], cos(0.5 * (double)a[0]), TOL);
        CHECK_CLOSE(qb[1], sin(0.5 * (double)b[0]), TOL);
    }
}

static void test_dcm(void)
{
    /* 90° about z (yaw +90°): body x (right) -> north, body y (forward) -> west */
    att_real q[4], C[9], e[3] = { (att_real)(3.14159265358979323846 / 2), 0, 0 }, q2[4], e2[3];
    att_real h;
    CHECK_EQ_INT(att_euler_to_quat(e, q), ATT_OK);
    CHECK_EQ_INT(att_quat_to_dcm(q, C), ATT_OK);
    CHECK_CLOSE(C[0], 0, TOL);
    CHECK_CLOSE(C[1], -1, TOL);
    CHECK_CLOSE(C[3], 1, TOL);
    CHECK_CLOSE(C[4], 0, TOL);
    CHECK_CLOSE(C[8], 1, TOL);
    CHECK_EQ_INT(att_quat_heading(q, &h), ATT_OK); /* yaw +90° (CCW) = heading 270° */
    CHECK_CLOSE(h, 1.5 * 3.14159265358979323846, 10 * TOL);
    CHECK_EQ_INT(att_dcm_to_quat(C, q2), ATT_OK);
    CHECK(qdist(q, q2) < 10 * TOL);
    /* general angles round trip */
    e[0] = (att_real)-2.5;
    e[1] = (att_real)0.7;
    e[2] = (att_real)3.0;
    CHECK_EQ_INT(att_euler_to_dcm(e, C), ATT_OK);
    CHECK_EQ_INT(att_dcm_to_euler(C, e2), ATT_OK);
    CHECK_CLOSE(e2[0], -2.5, 10 * TOL);
    CHECK_CLOSE(e2[1], 0.7, 10 * TOL);
    CHECK_CLOSE(e2[2], 3.0, 10 * TOL);
    CHECK_EQ_INT(att_euler_to_quat(e, q), ATT_OK);
    CHECK(q[0] >= 0);
    CHECK_EQ_INT(att_quat_to_euler(q, e2), ATT_OK);
    CHECK_CLOSE(e2[2], 3.0, 10 * TOL);
    /* 180° rotations: every Shepperd branch */
    {
        att_real r[4][4] = { { 1, 0, 0, 0 }, { 0, 1, 0, 0 }, { 0, 0, 1, 0 }, { 0, 0, 0, 1 } };
        int i;
        for (i = 0; i < 4; i++) {
            CHECK_EQ_INT(att_quat_to_dcm(r[i], C), ATT_OK);
            CHECK_EQ_INT(att_dcm_to_quat(C, q2), ATT_OK);
            CHECK(qdist(r[i], q2) < TOL);
        }
    }
}

static void test_gimbal(void)
{
    att_real e[3] = { (att_real)0.4, (att_real)(3.14159265358979323846 / 2), (att_real)0.3 };
    att_real C[9], e2[3], C2[9];
    int i;
    CHECK_EQ_INT(att_euler_to_dcm(e, C), ATT_OK);
    CHECK_EQ_INT(att_dcm_to_euler(C, e2), ATT_OK);
    CHECK(isfinite(e2[0]) && isfinite(e2[1]) && isfinite(e2[2]));
    CHECK_CLOSE(e2[2], 0, 0);          /* documented answer: roll 0 */
    CHECK_CLOSE(e2[0], 0.7, 10 * TOL); /* yaw = ψ + γ at θ = +90° */
    CHECK_CLOSE(e2[1], 3.14159265358979323846 / 2, 10 * TOL);
    CHECK_EQ_INT(att_euler_to_dcm(e2, C2), ATT_OK);
    for (i = 0; i < 9; i++) {
        CHECK_CLOSE(C2[i], C[i], 10 * TOL);
    }
    e[1] = -e[1];
    CHECK_EQ_INT(att_euler_to_dcm(e, C), ATT_OK);
    CHECK_EQ_INT(att_dcm_to_euler(C, e2), ATT_OK);
    CHECK_CLOSE(e2[0], 0.1, 10 * TOL); /* ψ − γ at θ = −90° */
}

static void test_errors_and_arrays(void)
{
    att_real C[2 * 9], q[2 * 4] = { 1, 0, 0, 0, 0, 0, 0, 0 }, e[3] = { 0, NAN, 0 };
    size_t bad = 99;
    CHECK_EQ_INT(att_quat_to_dcm_n(q, C, 2, &bad), ATT_E_ARG);
    CHECK_EQ_INT(bad, 1);
    CHECK_CLOSE(C[0], 1, TOL); /* first record written */
    CHECK_EQ_INT(att_euler_to_quat(e, q), ATT_E_NONFINITE);
    CHECK_EQ_INT(att_euler_to_dcm_n(e, C, 1, NULL), ATT_E_NONFINITE);
    CHECK_EQ_INT(att_quat_mul_n(q, q, q, 0, &bad), ATT_OK);
    /* never a silent wrong number: out-of-domain inputs with finite values */
    {
        att_real big[8] = { 1, 0, 0, 0, (att_real)1e30, 0, 0, 0 }, prod[8], z[9] = { 0 }, r[4];
        att_real v[3] = { (att_real)1e30, 0, 0 };
        /* 1e30² overflows float; double: scale the product up to 1e300 */
#if !defined(ATT_REAL_F32)
        big[4] = (att_real)1e200;
#endif
        CHECK_EQ_INT(att_quat_mul_n(big, big, prod, 2, &bad), ATT_E_RANGE);
        CHECK_EQ_INT(bad, 1);
        CHECK_CLOSE(prod[0], 1, 0);                          /* record 0 written */
        CHECK_EQ_INT(att_rotvec_to_quat(v, r), ATT_E_RANGE); /* |Φ|² overflows */
        v[0] = att_rotvec_max();
        CHECK_EQ_INT(att_rotvec_to_quat(v, r), ATT_OK);
        v[0] = att_rotvec_max() * (att_real)1.01;
        CHECK_EQ_INT(att_rotvec_to_quat(v, r), ATT_E_RANGE);
        CHECK_EQ_INT(att_dcm_to_quat(z, r), ATT_E_ARG); /* zero matrix: no rotation */
        z[0] = z[4] = 2;
        z[8] = 2; /* 2·I */
        CHECK_EQ_INT(att_dcm_to_quat(z, r), ATT_E_ARG);
        z[0] = z[4] = 1;
        z[8] = -1; /* a reflection: det −1 */
        CHECK_EQ_INT(att_dcm_to_quat(z, r), ATT_E_ARG);
        z[8] = (att_real)1.004; /* 0.4 % off: still the quaternion of a nearby rotation */
        CHECK_EQ_INT(att_dcm_to_quat(z, r), ATT_OK);
        CHECK_CLOSE(r[0], 1, 1e-2);
    }
    CHECK(att_real_size() == (int)sizeof(att_real));
}

int main(void)
{
    test_mul_conj();
    test_normalize();
    test_rotvec();
    test_dcm();
    test_gimbal();
    test_errors_and_arrays();
    return ATT_TEST_REPORT();
}
