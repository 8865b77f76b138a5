/*
 * Checks of the fixed-point module (attitude/fixed.h) run on the host under
 * ASan + UBSan (signed overflow included) by tests/test_c_programs.py:
 *  - the widening-multiply primitive: the 16-bit-halves implementation (the
 *    8051 path) against the 64-bit one, bit for bit, on edge cases and
 *    random operands (50,000 products, 20,000 accumulate/extract
 *    sequences), for every operation of the accumulator;
 *  - exact saturation / range errors of every public function;
 *  - basic behaviour (identity, known rotations) with tolerances in LSB.
 * Tolerances: 1 LSB of Q2.30 = 2^-30 ≈ 9.3e-10; each comment says why.
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "att_test.h"
#include "attitude/fixed.h"

#include "../src/fixed_prim.h"

#define ONE ATT_FX_Q30_ONE
#define LSB (1.0 / 1073741824.0)

static uint32_t rng_state = 2463534242u;
static uint32_t rnd(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 17;
    rng_state ^= rng_state << 5;
    return rng_state;
}
static int32_t rnd_s(void)
{
    uint32_t u = rnd();
    switch (u & 7u) {
    case 0:
        return (int32_t)(rnd() >> 16) - 32768; /* small */
    case 1:
        return fx_u2s(rnd() | 0x80000000ul); /* negative, large */
    default:
        return fx_u2s(rnd());
    }
}

static const int32_t edge[] = {
    0,           1,      -1,      2,       -2,       0x7FFFFFFF, -0x7FFFFFFF - 1, 0x40000000,
    -0x40000000, 0xFFFF, -0xFFFF, 0x10000, -0x10000, 0x7FFF8000, 12345678,        -87654321
};
#define NEDGE (int)(sizeof edge / sizeof edge[0])

static int acc_equal(const fxw_acc *w, const fxh_acc *h)
{
    return (uint32_t)(w->v >> 32) == h->hi && (uint32_t)w->v == h->lo;
}

static void test_primitive(void)
{
    int i, j, k, bad = 0;
    fxw_acc w;
    fxh_acc h;
    /* products: every edge pair, then random operand pairs */
    for (i = 0; i < NEDGE; ++i) {
        for (j = 0; j < NEDGE; ++j) {
            uint32_t hi, lo;
            int64_t p = (int64_t)edge[i] * edge[j];
            fxh_prod(edge[i], edge[j], &hi, &lo);
            if (hi != (uint32_t)((uint64_t)p >> 32) || lo != (uint32_t)(uint64_t)p) {
                ++bad;
            }
        }
    }
    CHECK_EQ_INT(bad, 0);
    bad = 0;
    for (i = 0; i < 50000; ++i) {
        uint32_t hi, lo, whi, wlo;
        int32_t x = rnd_s(), y = rnd_s();
        fxh_prod(x, y, &hi, &lo);
        fxw_uprod((uint32_t)x, (uint32_t)y, &whi, &wlo);
        {
            int64_t p = (int64_t)x * y;
            if (hi != (uint32_t)((uint64_t)p >> 32) || lo != (uint32_t)(uint64_t)p) {
                ++bad;
            }
        }
        fxh_uprod((uint32_t)x, (uint32_t)y, &hi, &lo);
        if (hi != whi || lo != wlo) {
            ++bad;
        }
    }
    CHECK_EQ_INT(bad, 0);
    /* accumulator sequences and every extraction, random shifts */
    bad = 0;
    for (i = 0; i < 20000; ++i) {
        int n = 1 + (int)(rnd() % 6u);
        uint8_t sh = (uint8_t)(rnd() % 63u), sh31 = (uint8_t)(1u + rnd() % 31u);
        uint8_t b = (uint8_t)(33u + rnd() % 30u);
        int32_t rw, rh;
        int sw, shh;
        fxw_zero(&w);
        fxh_zero(&h);
        if (rnd() & 1u) {
            int32_t x = rnd_s();
            fxw_init_shl31(&w, x);
            fxh_init_shl31(&h, x);
        }
        for (k = 0; k < n; ++k) {
            int32_t x = rnd_s(), y = rnd_s();
            switch (rnd() % 4u) {
            case 0:
                fxw_mac(&w, x, y);
                fxh_mac(&h, x, y);
                break;
            case 1:
                fxw_msc(&w, x, y);
                fxh_msc(&h, x, y);
                break;
            case 2:
                fxw_mac2(&w, x, y);
                fxh_mac2(&h, x, y);
                break;
            default: {
                uint8_t s = (uint8_t)(rnd() % 32u);
                fxw_add_shl(&w, x, s);
                fxh_add_shl(&h, x, s);
            }
            }
        }
        if (!acc_equal(&w, &h)) {
            ++bad;
            continue;
        }
        if (fxw_round(&w, sh) != fxh_round(&h, sh) || fxw_floor(&w, sh31) != fxh_floor(&h, sh31)
            || fxw_small(&w, b) != fxh_small(&h, b)) {
            if (bad < 3)
                printf("r sh=%d %ld %ld f %ld %ld s %d %d\n", sh, (long)fxw_round(&w, sh),
                       (long)fxh_round(&h, sh), (long)fxw_floor(&w, sh31), (long)fxh_floor(&h, sh31),
                       fxw_small(&w, b), fxh_small(&h, b));
            ++bad;
        }
        rw = rh = 0;
        sw = fxw_round_sat(&w, sh, &rw);
        shh = fxh_round_sat(&h, sh, &rh);
        if (sw != shh || rw != rh) {
            ++bad;
        }
        /* reference for round_sat: the exact value in 64-bit signed arithmetic */
        if (sh > 0u && sh < 62u) {
            int64_t v = (w.v >> 63) ? -(int64_t)(~w.v) - 1 : (int64_t)w.v; /* as signed */
            int64_t half = (int64_t)1 << (sh - 1u);
            /* floor((v + half) / 2^sh) without overflow: split (>> of a negative
             * value is arithmetic on gcc and clang) */
            int64_t q = (v >> sh) + (((v & (((int64_t)1 << sh) - 1)) + half) >> sh);
            int fits = (q >= INT32_MIN && q <= INT32_MAX);
            if (fits != (sw == 0) || (fits && q != rw)) {
                if (bad < 3)
                    printf("sat sh=%d v=%lld q=%lld rw=%ld sw=%d\n", sh, (long long)v, (long long)q, (long)rw,
                           sw);
                ++bad;
            }
        }
        if ((w.v >> 63) == 0u) {
            uint8_t su = (uint8_t)(33u + rnd() % 30u);
            if ((uint64_t)((w.v + ((uint64_t)1 << (su - 1u))) >> su) < 0xFFFFFFFFull
                && fxw_round_u(&w, su) != fxh_round_u(&h, su)) {
                ++bad;
            }
        }
    }
    CHECK_EQ_INT(bad, 0);
    /* fx_asr is floor division */
    CHECK_EQ_INT(fx_asr(-1, 1), -1);
    CHECK_EQ_INT(fx_asr(-3, 1), -2);
    CHECK_EQ_INT(fx_asr(-0x7FFFFFFF - 1, 31), -1);
    CHECK_EQ_INT(fx_u2s(0x80000000ul), -0x7FFFFFFF - 1);
    /* ties round toward +inf */
    fxw_zero(&w);
    fxw_add_shl(&w, -3, 0); /* −3 / 2 = −1.5 → −1 */
    CHECK_EQ_INT(fxw_round(&w, 1), -1);
    fxh_zero(&h);
    fxh_add_shl(&h, -3, 0);
    CHECK_EQ_INT(fxh_round(&h, 1), -1);
}

static void test_quat(void)
{
    att_q30 id[4] = { ONE, 0, 0, 0 }, a[4], r[4], big[4] = { ATT_FX_QUAT_MAX + 1, 0, 0, 0 };
    att_q30 C[9], q90[4];
    att_q28 e[3], hd;
    int i;
    /* a random unit quaternion times identity is itself, exactly (products by 2^30) */
    a[0] = 600000000L;
    a[1] = -500000000L;
    a[2] = 400000000L;
    a[3] = 0;
    CHECK_EQ_INT(att_fx_quat_normalize(a, a), ATT_OK);
    CHECK_EQ_INT(att_fx_quat_mul(a, id, r), ATT_OK);
    for (i = 0; i < 4; ++i) {
        CHECK_EQ_INT(r[i], a[i]);
    }
    /* range errors are exact: one LSB over the limit fails, at the limit works */
    CHECK_EQ_INT(att_fx_quat_mul(big, id, r), ATT_FX_E_RANGE);
    big[0] = ATT_FX_QUAT_MAX;
    CHECK_EQ_INT(att_fx_quat_mul(big, id, r), ATT_OK);
    CHECK_EQ_INT(r[0], ATT_FX_QUAT_MAX);
    /* product of two 1.25-quaternions: 1.5625 fits Q2.30; four terms of
     * 1.25² = 6.25 would not: the result is range-checked, never wrapped */
    {
        att_q30 m[4] = { ATT_FX_QUAT_MAX, ATT_FX_QUAT_MAX, ATT_FX_QUAT_MAX, ATT_FX_QUAT_MAX };
        att_q30 n[4] = { ATT_FX_QUAT_MAX, -ATT_FX_QUAT_MAX, -ATT_FX_QUAT_MAX, -ATT_FX_QUAT_MAX };
        r[0] = 77;
        CHECK_EQ_INT(att_fx_quat_mul(m, n, r), ATT_FX_E_RANGE);
        CHECK_EQ_INT(r[0], 77); /* outputs untouched on error */
    }
    /* normalization: tiny and large inputs, zero */
    {
        att_q30 t[4] = { 3, 4, 0, 0 }, z[4] = { 0, 0, 0, 0 };
        CHECK_EQ_INT(att_fx_quat_normalize(t, r), ATT_OK);
        /* 3/5 and 4/5 of 2^30, within 2 LSB (Newton + one correction step) */
        CHECK(labs(r[0] - 644245094L) <= 2 && labs(r[1] - 858993459L) <= 2);
        CHECK_EQ_INT(att_fx_quat_normalize(z, r), ATT_FX_E_ZERO);
    }
    /* 90° about z: q = [cos45, 0, 0, sin45]; C = [[0,-1,0],[1,0,0],[0,0,1]] */
    q90[0] = 759250125L;
    q90[1] = 0;
    q90[2] = 0;
    q90[3] = 759250125L;
    CHECK_EQ_INT(att_fx_quat_to_dcm(q90, C), ATT_OK);
    /* elements within 2 LSB: q rounded (0.5 LSB each) enters squared/products */
    CHECK(labs(C[0]) <= 2 && labs(C[1] + ONE) <= 2 && labs(C[3] - ONE) <= 2 && labs(C[8] - ONE) <= 2);
    CHECK_EQ_INT(att_fx_quat_to_euler(q90, e), ATT_OK);
    /* yaw +90° = π/2 in Q4.28 = 421657428; CORDIC residual ≤ 2 LSB of Q4.28 */
    CHECK(labs(e[0] - 421657428L) <= 4 && labs(e[1]) <= 4 && labs(e[2]) <= 4);
    CHECK_EQ_INT(att_fx_quat_heading(q90, &hd), ATT_OK);
    CHECK(labs(hd - 1264972285L) <= 4); /* heading 270° = 3π/2 */
    /* atan2 quadrants and the (0, 0) convention; π maps to +π */
    CHECK(labs(att_fx_atan2(0, -ONE) - 843314857L) <= 4);
    CHECK(labs(att_fx_atan2(-ONE, 0) + 421657428L) <= 4);
    CHECK_EQ_INT(att_fx_atan2(0, 0), 0);
    CHECK(labs(att_fx_atan2(0x7FFFFFFF, 0x7FFFFFFF) - 210828714L) <= 4);
    CHECK(labs(att_fx_atan2(-0x7FFFFFFF - 1, -0x7FFFFFFF - 1) + 632486143L) <= 4);
    /* gimbal lock: pitch +90° about x: C32 = 1, C12 = C22 = 0 → γ = 0 */
    {
        att_q30 g[4] = { 759250125L, 759250125L, 0, 0 };
        CHECK_EQ_INT(att_fx_quat_to_euler(g, e), ATT_OK);
        CHECK(labs(e[1] - 421657428L) <= 8 && e[2] == 0);
    }
}

static void test_integrator(void)
{
    att_fx_integ s;
    att_q30 d[9], q[4], out[64], phi[3];
    size_t n_out = 99, bad = 99;
    int i;
    /* range of the increments: exactly ATT_FX_DTHETA_MAX passes, one more fails */
    for (i = 0; i < 9; ++i) {
        d[i] = (i % 3 == 0) ? ATT_FX_DTHETA_MAX : 0;
    }
    CHECK_EQ_INT(att_fx_phi(ATT_FX_RV3, d, 3, phi), ATT_OK);
    d[4] = -ATT_FX_DTHETA_MAX - 1;
    CHECK_EQ_INT(att_fx_phi(ATT_FX_RV3, d, 3, phi), ATT_FX_E_RANGE);
    q[0] = ONE;
    q[1] = q[2] = q[3] = 0;
    CHECK_EQ_INT(att_fx_update_rv3(q, d), ATT_FX_E_RANGE);
    CHECK_EQ_INT(q[0], ONE); /* untouched */
    /* worst case in range: every component at ±max (largest |Φ|): no wrap */
    for (i = 0; i < 9; ++i) {
        d[i] = (i & 1) ? -ATT_FX_DTHETA_MAX : ATT_FX_DTHETA_MAX;
    }
    CHECK_EQ_INT(att_fx_phi(ATT_FX_RV3, d, 3, phi), ATT_OK);
    CHECK_EQ_INT(att_fx_update_rv3(q, d), ATT_OK);
    /* a non-unit state is refused, not integrated */
    {
        att_q30 nq[4] = { ONE, ONE / 1000, 0, 0 };
        CHECK_EQ_INT(att_fx_update_rv3(nq, d), ATT_FX_E_RANGE);
        CHECK_EQ_INT(nq[1], ONE / 1000);
    }
    /* a constant rotation about z of 1e-3 rad per increment: after 3000
     * rv1 updates the yaw is 3 rad; the quaternion error is a random walk
     * of ~1 LSB per update: 3000^0.5 · 1.5 LSB ≈ 80 LSB, tolerance 2000 LSB */
    CHECK_EQ_INT(att_fx_integ_init(&s, ATT_FX_RV1, 0), ATT_OK);
    d[0] = 0;
    d[1] = 0;
    d[2] = 1073742; /* 1e-3 rad */
    for (i = 0; i < 3000; ++i) {
        CHECK(att_fx_integ_update(&s, d, q) == ATT_FX_UPDATED || i < 0);
    }
    {
        double ang = 3000.0 * 1073742.0 * LSB;
        CHECK_CLOSE(q[0] * LSB, cos(ang / 2), 2000 * LSB);
        CHECK_CLOSE(q[3] * LSB, sin(ang / 2), 2000 * LSB);
    }
    /* batch: a bad sample anywhere → error, its index, state unchanged */
    {
        att_q30 dd[5 * 3];
        att_fx_integ s2;
        memset(dd, 0, sizeof dd);
        dd[3 * 3 + 1] = ATT_FX_DTHETA_MAX + 1;
        CHECK_EQ_INT(att_fx_integ_init(&s2, ATT_FX_RV3, 0), ATT_OK);
        CHECK_EQ_INT(att_fx_integ_update(&s2, dd, 0), ATT_FX_PENDING);
        s = s2;
        CHECK_EQ_INT(att_fx_integ_batch(&s2, dd, 5, out, &n_out, &bad), ATT_FX_E_RANGE);
        CHECK_EQ_INT(bad, 3);
        CHECK_EQ_INT(n_out, 0);
        CHECK(memcmp(&s, &s2, sizeof s) == 0);
        dd[3 * 3 + 1] = 0;
        CHECK_EQ_INT(att_fx_integ_batch(&s2, dd, 5, out, &n_out, &bad), ATT_OK);
        CHECK_EQ_INT(n_out, 2); /* (1 pending + 5) / 3 */
    }
    CHECK_EQ_INT(att_fx_integ_init(&s, (att_fx_method)7, 0), ATT_FX_E_METHOD);
    CHECK_EQ_INT(att_fx_integ_init(&s, (att_fx_method)5, 0), ATT_FX_E_METHOD); /* rk4: not ported */
    /* batch and streaming give identical bits (fast paths included) */
    {
        static att_q30 dd[40 * 3], qa[40 * 4], qb[4];
        int m;
        for (i = 0; i < 40 * 3; ++i) {
            dd[i] = (int32_t)(rnd() % 2000001u) - 1000000;
        }
        for (m = 0; m <= (int)ATT_FX_RV3_REUSE_POLY; ++m) {
            att_fx_integ sa, sb;
            size_t no = 0, k = 0;
            int r, same = 1;
            if (m == 5) {
                continue; /* rk4: no fixed-point port */
            }
            att_fx_integ_init(&sa, (att_fx_method)m, 0);
            att_fx_integ_init(&sb, (att_fx_method)m, 0);
            CHECK_EQ_INT(att_fx_integ_batch(&sa, dd, 17, qa, &no, 0), ATT_OK);
            CHECK_EQ_INT(att_fx_integ_batch(&sa, dd + 17 * 3, 23, qa + 4 * no, &k, 0), ATT_OK);
            no += k;
            CHECK_EQ_INT(no, att_fx_integ_outputs(&sb, 40));
            k = 0;
            for (i = 0; i < 40; ++i) {
                r = att_fx_integ_update(&sb, dd + 3 * i, qb);
                if (r == ATT_FX_UPDATED) {
                    same = same && memcmp(qb, qa + 4 * k, sizeof qb) == 0;
                    ++k;
                }
            }
            CHECK(same && k == no);
            CHECK(memcmp(sa.q, sb.q, sizeof sa.q) == 0);
        }
    }
}

static void test_adc(void)
{
    att_fx_adc a;
    int32_t zero[3] = { 2048 * 256, 2048 * 256 + 128, 2000 * 256 };
    /* CG-L53 at 0.67 mV/(°/s), 12-bit ADC over 5 V: 0.031786 rad/s per code */
    uint32_t scale[3] = { 136520000ul, 136520000ul, 136520000ul };
    uint16_t code[3] = { 2148, 2048, 1900 };
    att_q30 d[3] = { 5, 5, 5 };
    double g = 136520000.0 / 4294967296.0 * 0.01; /* rad per code at 100 Hz */
    CHECK_EQ_INT(att_fx_adc_init(&a, zero, scale, 10000000ul), ATT_OK);
    CHECK_EQ_INT(att_fx_adc_convert(&a, code, d), ATT_OK);
    /* exact gain (rel. 2^-31) and one rounding: within 1 LSB */
    CHECK_CLOSE(d[0] * LSB, 100 * g, 1.0 * LSB);
    CHECK_CLOSE(d[1] * LSB, -0.5 * g, 1.0 * LSB);
    CHECK_CLOSE(d[2] * LSB, -100 * g, 1.0 * LSB);
    /* zero scale / period are argument errors; a 1 s period with the full
     * 12-bit swing gives 65 rad: out of range, never wrapped */
    scale[0] = 0;
    CHECK_EQ_INT(att_fx_adc_init(&a, zero, scale, 10000000ul), ATT_E_ARG);
    scale[0] = 136520000ul;
    CHECK_EQ_INT(att_fx_adc_init(&a, zero, scale, 0), ATT_E_ARG);
    CHECK_EQ_INT(att_fx_adc_init(&a, zero, scale, 1000000000ul), ATT_OK);
    code[0] = 4095;
    d[0] = 5;
    CHECK_EQ_INT(att_fx_adc_convert(&a, code, d), ATT_FX_E_RANGE);
    CHECK_EQ_INT(d[0], 5);
}

int main(void)
{
    test_primitive();
    test_quat();
    test_integrator();
    test_adc();
    return ATT_TEST_REPORT();
}
