/*
 * Fixed-point test vectors for tests/test_fixed_targets.py: the same
 * program is built for the host (64-bit product and, with
 * -DATT_FX_FORCE_HALVES, the 8051's 16-bit-halves product), for ARMv4T
 * bare metal and ARMv4T Linux (run under qemu-arm -cpu ti925t); every
 * build must print exactly the same lines. Each line is a name and an
 * FNV-1a hash of every int32 the module produced for that group, so one
 * differing bit anywhere changes the line.
 */
#include <stdio.h>
#include <string.h>

#include "attitude/fixed.h"

static uint32_t x = 2463534242u;
static uint32_t rnd(void)
{
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    return x;
}

static uint32_t h;
static void hash_reset(void)
{
    h = 2166136261u;
}
static void hash32(int32_t v)
{
    uint32_t u = (uint32_t)v;
    int i;
    for (i = 0; i < 4; ++i) {
        h ^= (u >> (8 * i)) & 0xFFu;
        h *= 16777619u;
    }
}
static void hashn(const int32_t *v, int n)
{
    int i;
    for (i = 0; i < n; ++i) {
        hash32(v[i]);
    }
}

static int32_t inc(int scale)
{
    /* |Δθ| up to 2^scale, with scale 12..28 (≤ 0.25 rad) */
    return (int32_t)(rnd() >> (31 - scale)) - (1 << scale);
}

int main(void)
{
    static att_q30 dd[600 * 3], out[600 * 4];
    att_q30 q[4], a[4], b[4], r[4], C[9], phi[3];
    att_q28 e[3], hd;
    int i, m, st;
    size_t no;

    /* kernel: 200 rv3 updates, increment size varying over 16 octaves */
    hash_reset();
    q[0] = ATT_FX_Q30_ONE;
    q[1] = q[2] = q[3] = 0;
    for (i = 0; i < 200; ++i) {
        att_q30 d[9];
        int k, sc = 12 + (i % 17);
        for (k = 0; k < 9; ++k) {
            d[k] = inc(sc);
        }
        st = att_fx_update_rv3(q, d);
        hash32(st);
        hashn(q, 4);
    }
    printf("rv3_kernel %08lx\n", (unsigned long)h);

    /* kernel: 200 updates of each reuse form over a sliding window */
    for (m = (int)ATT_FX_RV3_REUSE; m <= (int)ATT_FX_RV3_REUSE_POLY; m += 2) {
        att_q30 w[9];
        hash_reset();
        q[0] = ATT_FX_Q30_ONE;
        q[1] = q[2] = q[3] = 0;
        for (i = 0; i < 9; ++i) {
            w[i] = inc(12);
        }
        for (i = 0; i < 200; ++i) {
            int k, sc = 12 + (i % 17);
            for (k = 0; k < 6; ++k) {
                w[k] = w[k + 3];
            }
            for (k = 6; k < 9; ++k) {
                w[k] = inc(sc);
            }
            st = att_fx_update_reuse(q, w, (att_fx_method)m);
            hash32(st);
            hashn(q, 4);
        }
        printf("reuse_kernel_%d %08lx\n", m, (unsigned long)h);
    }

    /* integrator, every method, batch + streaming */
    for (i = 0; i < 600 * 3; ++i) {
        dd[i] = inc(10 + (i / 3) % 19);
    }
    for (m = 0; m <= (int)ATT_FX_RV3_REUSE_POLY; ++m) {
        att_fx_integ s;
        if (m == 5) {
            continue; /* rk4: no fixed-point port */
        }
        hash_reset();
        a[0] = 300000000L;
        a[1] = -200000000L;
        a[2] = 900000000L;
        a[3] = 100000000L;
        hash32(att_fx_integ_init(&s, (att_fx_method)m, a));
        hash32(att_fx_integ_batch(&s, dd, 600, out, &no, 0));
        hashn(out, 4 * (int)no);
        for (i = 0; i < 100; ++i) {
            hash32(att_fx_integ_update(&s, dd + 3 * i, q));
            hashn(s.q, 4);
        }
        printf("integ_%d %08lx\n", m, (unsigned long)h);
    }

    /* primitives on random inputs */
    hash_reset();
    for (i = 0; i < 300; ++i) {
        int k;
        for (k = 0; k < 4; ++k) {
            a[k] = (int32_t)(rnd() % 2147483647u) - 1073741823L;
            b[k] = (int32_t)(rnd() % 1073741823u) - 536870911L;
        }
        hash32(att_fx_quat_normalize(a, a));
        hashn(a, 4);
        hash32(att_fx_quat_mul(a, b, r));
        hashn(r, 4);
        hash32(att_fx_quat_to_dcm(a, C));
        hashn(C, 9);
        hash32(att_fx_quat_to_euler(a, e));
        hashn(e, 3);
        hash32(att_fx_quat_heading(a, &hd));
        hash32(hd);
        for (k = 0; k < 3; ++k) {
            phi[k] = (int32_t)(rnd() >> 1) - 1073741824L;
        }
        hash32(att_fx_rotvec_to_quat(phi, r));
        hashn(r, 4);
        {
            int32_t yy = (int32_t)rnd(), xx = (int32_t)rnd(); /* fixed evaluation order */
            hash32(att_fx_atan2(yy, xx));
        }
    }
    printf("primitives %08lx\n", (unsigned long)h);

    /* ADC converter */
    hash_reset();
    {
        att_fx_adc cv;
        int32_t zero[3] = { 2048L * 256, 2047L * 256 + 77, 1999L * 256 };
        uint32_t scale[3] = { 136520000ul, 140000000ul, 3000000ul };
        uint32_t periods[4] = { 10000000ul, 1000000ul, 100000ul, 3333333ul };
        for (m = 0; m < 4; ++m) {
            hash32(att_fx_adc_init(&cv, zero, scale, periods[m]));
            hashn(cv.gain, 3);
            for (i = 0; i < 200; ++i) {
                uint16_t code[3];
                att_q30 d[3] = { 0, 0, 0 };
                code[0] = (uint16_t)(rnd() & 0xFFFu);
                code[1] = (uint16_t)(rnd() & 0xFFFu);
                code[2] = (uint16_t)(rnd() & 0xFFFFu);
                hash32(att_fx_adc_convert(&cv, code, d));
                hashn(d, 3);
            }
        }
    }
    /* gains over the whole accepted range (shifts 1..62), codes around the
     * zero code (negative products, exact ties) */
    {
        att_fx_adc cv;
        int32_t zero[3] = { 2048L * 256, 128, 65535L * 256 };
        for (m = 0; m < 300; ++m) {
            uint32_t scale[3];
            uint32_t period = 1u + (rnd() >> (rnd() & 31u));
            int st2;
            scale[0] = 1u + (rnd() >> (rnd() & 31u));
            scale[1] = 1u + (rnd() >> (rnd() & 31u));
            scale[2] = 1u + (rnd() >> (rnd() & 31u));
            st2 = att_fx_adc_init(&cv, zero, scale, period);
            hash32(st2);
            if (st2 != ATT_OK) {
                continue;
            }
            hashn(cv.gain, 3);
            hash32(cv.shift[0] | (cv.shift[1] << 8) | ((int32_t)cv.shift[2] << 16));
            for (i = 0; i < 20; ++i) {
                uint16_t code[3];
                att_q30 d[3] = { 0, 0, 0 };
                code[0] = (uint16_t)(2048 + (int)(rnd() % 9u) - 4);
                code[1] = (uint16_t)(rnd() % 3u);
                code[2] = (uint16_t)(65535u - rnd() % 5u);
                hash32(att_fx_adc_convert(&cv, code, d));
                hashn(d, 3);
            }
        }
    }
    printf("adc %08lx\n", (unsigned long)h);
    return 0;
}
