/*
 * Checks of the wavelet denoiser (attitude/denoise.h), run on the host under
 * ASan + UBSan (tests/test_c_programs.py) and on the emulated ARMv4T core
 * (tests/test_cross_bare.py), double and float. Truth comes from closed
 * forms (filter identities, Haar sums, σ√(2 ln n)), from sorting (median),
 * from invariants (perfect reconstruction, Parseval, constants and ramps
 * passing unchanged, preserved segment sums) and from the stream's own
 * contract (push_n == pushes, roll-back on error). The comparison with
 * PyWavelets and the NumPy reference is in tests/test_denoise.py.
 */
#include <float.h>
#include <math.h>
#include <string.h>

#include "att_test.h"
#include "attitude/denoise.h"

#include "../src/denoise_internal.h"

#if defined(ATT_REAL_F32)
#define EPS     1.1920929e-7 /* float32 machine epsilon */
#define REALMAX FLT_MAX
#else
#define EPS     2.220446049250313e-16 /* float64 machine epsilon */
#define REALMAX DBL_MAX
#endif
/* Finite values whose block sums overflow: τ·x in the line fit (|τ| up to
 * 31.5 for N = 64) for HUGEV, (x0 − x1)/√2 of a Haar detail for ±BIGV. */
#define HUGEV  ((att_real)(REALMAX / 8))
#define BIGV   ((att_real)(REALMAX * 0.9))
/* One transform level is F ≤ 8 products summed per coefficient: ≤ 8 roundings
 * of size EPS/2 relative to Σ|h||x| ≤ 1.6·max|x| (‖h‖₁ of db4 is 1.6); L ≤ 5
 * levels there and back is ≤ 80 such sums, so 256·EPS·max|x| bounds a round
 * trip with a factor ~2 to spare. */
#define TOL_RT (256.0 * EPS)

#define NMAX 256
static att_real x[NMAX], c[NMAX], y[NMAX], tmp[NMAX], scratch[2 * NMAX];

static unsigned long rng_state = 12345u;
static double urand(void) /* uniform in [-1, 1): a 32-bit LCG (Numerical Recipes) */
{
    rng_state = (rng_state * 1664525u + 1013904223u) & 0xFFFFFFFFu;
    return (double)rng_state / 2147483648.0 - 1.0;
}

static const int wavelets[3] = { ATT_WDEN_HAAR, ATT_WDEN_DB2, ATT_WDEN_DB4 };

/* The defaults with a 64-sample block (L = 3, Es = 24, Ee = 8, hop 32): the
 * stream tests below are written for it. */
static void small_config(att_wden_config *cfg)
{
    att_wden_config_default(cfg);
    cfg->levels = 3;
    cfg->block = 64;
    cfg->edge_start = 24;
    cfg->edge_end = 8;
}
static const size_t taps_of[3] = { 2, 4, 8 };
static const int moments_of[3] = { 1, 2, 4 };

static void test_config(void)
{
    att_wden_config cfg;
    CHECK_EQ_INT(att_wden_config_default(NULL), ATT_E_NULL);
    CHECK_EQ_INT(att_wden_config_default(&cfg), ATT_OK);
    CHECK_EQ_INT(cfg.wavelet, ATT_WDEN_DB4);
    CHECK_EQ_INT(cfg.mode, ATT_WDEN_SOFT);
    CHECK_EQ_INT(cfg.levels, 4);
    CHECK_EQ_INT(cfg.block, 128);
    CHECK_EQ_INT(cfg.edge_start, 56);
    CHECK_EQ_INT(cfg.edge_end, 24);
    CHECK_EQ_INT(cfg.detrend, 1);
    CHECK_EQ_INT(att_wden_config_check(&cfg), ATT_OK);
    CHECK_EQ_INT(att_wden_state_len(&cfg), 128);
    CHECK_EQ_INT(att_wden_scratch_len(&cfg), 256);
    CHECK_EQ_INT(att_wden_max_out(&cfg), 104);
    CHECK_EQ_INT(att_wden_latency(&cfg), 71);
    CHECK_EQ_INT(ATT_WDEN_LATENCY(128, 56), 71);
    CHECK_EQ_INT(att_wden_config_check(NULL), ATT_E_NULL);
    cfg.wavelet = 3;
    CHECK_EQ_INT(att_wden_config_check(&cfg), ATT_E_WDEN_WAVELET);
    CHECK_EQ_INT(att_wden_state_len(&cfg), 0);
    cfg.wavelet = -1;
    CHECK_EQ_INT(att_wden_config_check(&cfg), ATT_E_WDEN_WAVELET);
    att_wden_config_default(&cfg);
    cfg.mode = 2;
    CHECK_EQ_INT(att_wden_config_check(&cfg), ATT_E_WDEN_MODE);
    att_wden_config_default(&cfg);
    cfg.levels = 0;
    CHECK_EQ_INT(att_wden_config_check(&cfg), ATT_E_WDEN_LEVELS);
    cfg.levels = ATT_WDEN_MAX_LEVELS + 1;
    CHECK_EQ_INT(att_wden_config_check(&cfg), ATT_E_WDEN_LEVELS);
    att_wden_config_default(&cfg);
    cfg.block = 60; /* not a multiple of 16 */
    CHECK_EQ_INT(att_wden_config_check(&cfg), ATT_E_WDEN_BLOCK);
    cfg.block = (size_t)ATT_WDEN_MAX_BLOCK * 2;
    CHECK_EQ_INT(att_wden_config_check(&cfg), ATT_E_WDEN_BLOCK);
    cfg.levels = 1;
    cfg.block = 0;
    CHECK_EQ_INT(att_wden_config_check(&cfg), ATT_E_WDEN_BLOCK);
    att_wden_config_default(&cfg);
    cfg.edge_start = 64;
    cfg.edge_end = 64; /* Es + Ee = N */
    CHECK_EQ_INT(att_wden_config_check(&cfg), ATT_E_WDEN_EDGE);
    cfg.edge_end = 63;
    CHECK_EQ_INT(att_wden_config_check(&cfg), ATT_OK);
    cfg.edge_start = 0;
    cfg.edge_end = 127;
    CHECK_EQ_INT(att_wden_config_check(&cfg), ATT_OK);
    cfg.edge_end = (size_t)-1; /* no overflow in the Es + Ee < N test */
    CHECK_EQ_INT(att_wden_config_check(&cfg), ATT_E_WDEN_EDGE);
    cfg.edge_end = 0;
    cfg.edge_start = (size_t)-1;
    CHECK_EQ_INT(att_wden_config_check(&cfg), ATT_E_WDEN_EDGE);
    att_wden_config_default(&cfg);
    cfg.detrend = 2;
    CHECK_EQ_INT(att_wden_config_check(&cfg), ATT_E_ARG);
    cfg.detrend = 0;
    cfg.levels = 6;
    cfg.block = 64; /* one approximation coefficient: allowed */
    cfg.edge_start = 24;
    cfg.edge_end = 8;
    CHECK_EQ_INT(att_wden_config_check(&cfg), ATT_OK);
}

/* Filter identities (Daubechies 1992, ch. 6): Σh = √2, Σh[k]h[k+2m] = δ_m,
 * g[k] = (−1)^k h[F−1−k], Σ k^j g[k] = 0 for j < p (p vanishing moments). */
static void test_filters(void)
{
    att_real h[ATT_WDEN_MAX_TAPS], g[ATT_WDEN_MAX_TAPS];
    size_t f, k, w;
    int m, j;
    for (w = 0; w < 3; w++) {
        double sum = 0;
        CHECK_EQ_INT(att_wden_filters(wavelets[w], h, g, &f), ATT_OK);
        CHECK_EQ_INT(f, taps_of[w]);
        for (k = 0; k < f; k++)
            sum += (double)h[k];
        CHECK_CLOSE(sum, sqrt(2.0), 4 * EPS); /* 8 rounded constants summed */
        for (m = 0; 2 * m < (int)f; m++) {
            double dot = 0;
            for (k = 0; k + 2 * (size_t)m < f; k++)
                dot += (double)h[k] * (double)h[k + 2 * (size_t)m];
            CHECK_CLOSE(dot, m == 0 ? 1.0 : 0.0, 8 * EPS);
        }
        for (k = 0; k < f; k++)
            CHECK_CLOSE(g[k], (k & 1u) ? -h[f - 1 - k] : h[f - 1 - k], 0);
        for (j = 0; j < moments_of[w]; j++) {
            double mom = 0, scale = 0;
            for (k = 0; k < f; k++) {
                mom += pow((double)k, j) * (double)g[k];
                scale += pow((double)k, j) * fabs((double)g[k]);
            }
            CHECK_CLOSE(mom, 0.0, 8 * EPS * scale);
        }
    }
    CHECK_EQ_INT(att_wden_filters(7, h, g, &f), ATT_E_WDEN_WAVELET);
    CHECK_EQ_INT(att_wden_filters(ATT_WDEN_DB2, NULL, g, &f), ATT_E_NULL);
}

static double max_abs_diff(const att_real *a, const att_real *b, size_t n)
{
    double m = 0;
    size_t i;
    for (i = 0; i < n; i++)
        if (fabs((double)a[i] - (double)b[i]) > m)
            m = fabs((double)a[i] - (double)b[i]);
    return m;
}

static void test_transform(void)
{
    static const struct {
        size_t n;
        unsigned int levels;
    } shapes[] = { { 2, 1 }, { 4, 2 }, { 8, 3 }, { 64, 3 }, { 96, 5 }, { 256, 4 } };
    size_t w, s, i;
    for (w = 0; w < 3; w++) {
        for (s = 0; s < sizeof shapes / sizeof shapes[0]; s++) {
            const size_t n = shapes[s].n;
            const unsigned int lv = shapes[s].levels;
            double e_in = 0, e_out = 0;
            for (i = 0; i < n; i++)
                x[i] = (att_real)urand();
            CHECK_EQ_INT(att_wden_dwt(wavelets[w], lv, x, n, c, tmp), ATT_OK);
            for (i = 0; i < n; i++) {
                e_in += (double)x[i] * (double)x[i];
                e_out += (double)c[i] * (double)c[i];
            }
            CHECK_CLOSE(e_out, e_in, TOL_RT * e_in); /* Parseval: orthonormal */
            CHECK_EQ_INT(att_wden_idwt(wavelets[w], lv, c, n, y, tmp), ATT_OK);
            CHECK(max_abs_diff(x, y, n) <= TOL_RT);
            /* in place both ways */
            memcpy(y, x, sizeof x);
            CHECK_EQ_INT(att_wden_dwt(wavelets[w], lv, y, n, y, tmp), ATT_OK);
            CHECK(max_abs_diff(y, c, n) == 0);
            CHECK_EQ_INT(att_wden_idwt(wavelets[w], lv, y, n, y, tmp), ATT_OK);
            CHECK(max_abs_diff(x, y, n) <= TOL_RT);
            /* a constant has no details (Σg = 0), and cA_L = 2^{L/2}·value */
            for (i = 0; i < n; i++)
                x[i] = (att_real)3.25;
            CHECK_EQ_INT(att_wden_dwt(wavelets[w], lv, x, n, c, tmp), ATT_OK);
            for (i = n >> lv; i < n; i++)
                CHECK_CLOSE(c[i], 0.0, TOL_RT * 3.25);
            CHECK_CLOSE(c[0], 3.25 * pow(2.0, 0.5 * lv), TOL_RT * 3.25 * pow(2.0, 0.5 * lv));
        }
    }
    /* Haar, one level, closed form: cA = (x0 + x1)/√2, cD = (x0 − x1)/√2 */
    x[0] = 1;
    x[1] = 3;
    x[2] = -2;
    x[3] = 5;
    CHECK_EQ_INT(att_wden_dwt(ATT_WDEN_HAAR, 1, x, 4, c, tmp), ATT_OK);
    CHECK_CLOSE(c[0], 4 / sqrt(2.0), 2 * EPS * 4);
    CHECK_CLOSE(c[1], 3 / sqrt(2.0), 2 * EPS * 4);
    CHECK_CLOSE(c[2], -2 / sqrt(2.0), 2 * EPS * 4);
    CHECK_CLOSE(c[3], -7 / sqrt(2.0), 2 * EPS * 4);
    /* db4 kills a cubic away from the wrap (4 vanishing moments): level 1,
     * cD[i] uses x[2i−3 .. 2i+4], inside [0, 64) for 2 ≤ i ≤ 29 */
    for (i = 0; i < 64; i++) {
        double t = (double)i / 64.0;
        x[i] = (att_real)(1 + t - 2 * t * t + 3 * t * t * t);
    }
    CHECK_EQ_INT(att_wden_dwt(ATT_WDEN_DB4, 1, x, 64, c, tmp), ATT_OK);
    for (i = 2; i <= 29; i++)
        CHECK_CLOSE(c[32 + i], 0.0, 64 * EPS * 3);
    /* errors */
    CHECK_EQ_INT(att_wden_dwt(ATT_WDEN_DB4, 3, x, 60, c, tmp), ATT_E_WDEN_BLOCK);
    CHECK_EQ_INT(att_wden_dwt(ATT_WDEN_DB4, 0, x, 64, c, tmp), ATT_E_WDEN_LEVELS);
    CHECK_EQ_INT(att_wden_dwt(9, 1, x, 64, c, tmp), ATT_E_WDEN_WAVELET);
    CHECK_EQ_INT(att_wden_dwt(ATT_WDEN_DB4, 1, NULL, 64, c, tmp), ATT_E_NULL);
    CHECK_EQ_INT(att_wden_idwt(ATT_WDEN_DB4, 1, c, 64, y, NULL), ATT_E_NULL);
    CHECK_EQ_INT(att_wden_idwt(ATT_WDEN_DB4, 7, c, 64, y, tmp), ATT_E_WDEN_BLOCK);
    x[5] = (att_real)NAN;
    c[7] = 99;
    CHECK_EQ_INT(att_wden_dwt(ATT_WDEN_DB2, 2, x, 64, c, tmp), ATT_E_NONFINITE);
    CHECK_CLOSE(c[7], 99, 0); /* untouched */
    CHECK_EQ_INT(att_wden_idwt(ATT_WDEN_DB2, 2, x, 64, y, tmp), ATT_E_NONFINITE);
    /* finite but overflowing: the Haar detail (x0 − x1)/√2 of ±0.9·max */
    x[0] = BIGV;
    x[1] = -BIGV;
    CHECK_EQ_INT(att_wden_dwt(ATT_WDEN_HAAR, 1, x, 2, c, tmp), ATT_E_WDEN_OVERFLOW);
}

static void test_threshold(void)
{
    att_real v[6] = { 3, -3, 1, -1, 2, 0 };
    CHECK_EQ_INT(att_wden_threshold(v, 6, 2, ATT_WDEN_SOFT), ATT_OK);
    CHECK_CLOSE(v[0], 1, 0);
    CHECK_CLOSE(v[1], -1, 0);
    CHECK_CLOSE(v[2], 0, 0);
    CHECK_CLOSE(v[3], 0, 0);
    CHECK_CLOSE(v[4], 0, 0); /* |c| = λ: soft gives 0 */
    CHECK_CLOSE(v[5], 0, 0);
    v[0] = 3;
    v[1] = -3;
    v[2] = 1;
    v[3] = -1;
    v[4] = 2;
    CHECK_EQ_INT(att_wden_threshold(v, 6, 2, ATT_WDEN_HARD), ATT_OK);
    CHECK_CLOSE(v[0], 3, 0);
    CHECK_CLOSE(v[1], -3, 0);
    CHECK_CLOSE(v[2], 0, 0);
    CHECK_CLOSE(v[3], 0, 0);
    CHECK_CLOSE(v[4], 2, 0); /* |c| = λ: hard keeps it */
    v[0] = (att_real)0.5;
    CHECK_EQ_INT(att_wden_threshold(v, 1, 0, ATT_WDEN_SOFT), ATT_OK);
    CHECK_CLOSE(v[0], 0.5, 0); /* λ = 0: identity */
    CHECK_EQ_INT(att_wden_threshold(v, 1, -1, ATT_WDEN_SOFT), ATT_E_ARG);
    CHECK_EQ_INT(att_wden_threshold(v, 1, (att_real)INFINITY, ATT_WDEN_SOFT), ATT_E_NONFINITE);
    CHECK_EQ_INT(att_wden_threshold(v, 1, 1, 5), ATT_E_WDEN_MODE);
    CHECK_EQ_INT(att_wden_threshold(NULL, 1, 1, ATT_WDEN_SOFT), ATT_E_NULL);
    v[0] = (att_real)NAN;
    CHECK_EQ_INT(att_wden_threshold(v, 1, 1, ATT_WDEN_SOFT), ATT_E_NONFINITE);
}

static void sort(att_real *a, size_t n) /* insertion sort: the truth for the selection */
{
    size_t i, j;
    for (i = 1; i < n; i++) {
        att_real v = a[i];
        for (j = i; j > 0 && a[j - 1] > v; j--)
            a[j] = a[j - 1];
        a[j] = v;
    }
}

static void test_median(void)
{
    static att_real a[NMAX], s[NMAX];
    att_real med;
    size_t n, k, i, trial;
    unsigned int depth;
    /* every n up to 40 and a few larger, random values with duplicates */
    for (trial = 0; trial < 60; trial++) {
        n = trial < 40 ? trial + 1 : 41 + (trial - 40) * 10;
        for (i = 0; i < n; i++)
            s[i] = a[i] = (att_real)(trial % 3 == 0 ? (double)(int)(4 * urand()) : urand());
        sort(s, n);
        CHECK_EQ_INT(att_wden_median(a, n, &med), ATT_OK);
        CHECK_CLOSE(med, (n & 1u) ? (double)s[n / 2] : 0.5 * ((double)s[n / 2 - 1] + (double)s[n / 2]),
                    EPS); /* the mean of two values in [-1, 1]: one rounding */
        /* every rank, and the heapsort fallback forced at every depth */
        for (depth = 0; depth < 4; depth++) {
            for (k = 0; k < n; k += 1 + n / 7) {
                for (i = 0; i < n; i++)
                    a[i] = (att_real)(trial % 3 == 0 ? (double)(int)(4 * urand()) : urand());
                memcpy(s, a, n * sizeof a[0]);
                sort(s, n);
                CHECK_CLOSE(att__wden_select(a, n, k, depth), s[k], 0);
                for (i = 0; i < k; i++)
                    CHECK(a[i] <= a[k]);
                for (i = k + 1; i < n; i++)
                    CHECK(a[i] >= a[k]);
            }
        }
    }
    /* sorted, reversed, all equal: the pivot choices' bad cases */
    for (i = 0; i < 101; i++)
        a[i] = (att_real)i;
    CHECK_EQ_INT(att_wden_median(a, 101, &med), ATT_OK);
    CHECK_CLOSE(med, 50, 0);
    for (i = 0; i < 100; i++)
        a[i] = (att_real)(100 - i);
    CHECK_EQ_INT(att_wden_median(a, 100, &med), ATT_OK);
    CHECK_CLOSE(med, 50.5, 0);
    for (i = 0; i < 100; i++)
        a[i] = 7;
    CHECK_EQ_INT(att_wden_median(a, 100, &med), ATT_OK);
    CHECK_CLOSE(med, 7, 0);
    /* the mean of the two middle values does not overflow */
    a[0] = a[1] = BIGV;
    CHECK_EQ_INT(att_wden_median(a, 2, &med), ATT_OK);
    CHECK_CLOSE(med, BIGV, 0);
    a[0] = -BIGV;
    CHECK_EQ_INT(att_wden_median(a, 2, &med), ATT_OK);
    CHECK_CLOSE(med, 0, 0);
    CHECK_EQ_INT(att__wden_depth(1), 2);
    CHECK_EQ_INT(att__wden_depth(64), 14);
    CHECK_EQ_INT(att_wden_median(a, 0, &med), ATT_E_ARG);
    CHECK_EQ_INT(att_wden_median(NULL, 2, &med), ATT_E_NULL);
    a[1] = (att_real)NAN;
    CHECK_EQ_INT(att_wden_median(a, 2, &med), ATT_E_NONFINITE);
}

static void test_sigma(void)
{
    att_real d[5] = { -4, 1, 2, -3, 0 }, sigma, lambda;
    /* median |d| = 2 */
    CHECK_EQ_INT(att_wden_mad_sigma(d, 5, tmp, &sigma), ATT_OK);
    CHECK_CLOSE(sigma, 2 / 0.6744897501960817, 2 * EPS * 3);
    CHECK_CLOSE(d[0], -4, 0); /* d untouched */
    CHECK_EQ_INT(att_wden_universal(1, 64, &lambda), ATT_OK);
    CHECK_CLOSE(lambda, sqrt(2 * log(64.0)), 4 * EPS * 3);
    CHECK_EQ_INT(att_wden_universal(0, 64, &lambda), ATT_OK);
    CHECK_CLOSE(lambda, 0, 0);
    CHECK_EQ_INT(att_wden_universal(-1, 64, &lambda), ATT_E_ARG);
    CHECK_EQ_INT(att_wden_universal(1, 0, &lambda), ATT_E_ARG);
    CHECK_EQ_INT(att_wden_universal((att_real)NAN, 4, &lambda), ATT_E_NONFINITE);
    CHECK_EQ_INT(att_wden_mad_sigma(d, 0, tmp, &sigma), ATT_E_ARG);
    d[2] = (att_real)INFINITY;
    CHECK_EQ_INT(att_wden_mad_sigma(d, 5, tmp, &sigma), ATT_E_NONFINITE);
}

/* A line a + b·i (+ optional noise) into x[0..n). */
static void line(att_real *dst, size_t n, double a, double b, double noise)
{
    size_t i;
    for (i = 0; i < n; i++)
        dst[i] = (att_real)(a + b * (double)i + noise * urand());
}

static void test_block(void)
{
    att_wden_config cfg;
    att_real sigma;
    size_t w, mode, i;
    double sx, sy;
    for (w = 0; w < 3; w++) {
        for (mode = 0; mode < 2; mode++) {
            small_config(&cfg);
            cfg.wavelet = wavelets[w];
            cfg.mode = (int)mode;
            /* a ramp passes unchanged with detrend (the noise-free σ is 0) */
            line(x, 64, 0.3, -0.02, 0);
            CHECK_EQ_INT(att_wden_block(&cfg, x, y, scratch, &sigma), ATT_OK);
            CHECK(max_abs_diff(x, y, 64) <= TOL_RT);
            CHECK(sigma <= TOL_RT);
            /* a constant passes unchanged without detrend too */
            cfg.detrend = 0;
            line(x, 64, -1.5, 0, 0);
            CHECK_EQ_INT(att_wden_block(&cfg, x, y, scratch, NULL), ATT_OK);
            CHECK(max_abs_diff(x, y, 64) <= TOL_RT * 1.5);
            /* noise: the sum is kept (details have zero sum), the noise shrinks */
            cfg.detrend = 1;
            line(x, 64, 0.5, 0.001, 0.01);
            CHECK_EQ_INT(att_wden_block(&cfg, x, y, scratch, &sigma), ATT_OK);
            sx = sy = 0;
            for (i = 0; i < 64; i++) {
                sx += (double)x[i];
                sy += (double)y[i];
            }
            CHECK_CLOSE(sy, sx, 64 * TOL_RT);     /* 64 samples of ~0.5 summed, each good to TOL_RT */
            CHECK(sigma > 0.002 && sigma < 0.01); /* uniform ±0.01 noise: σ = 0.0058 */
            /* in place */
            memcpy(c, x, sizeof x);
            CHECK_EQ_INT(att_wden_block(&cfg, c, c, scratch, NULL), ATT_OK);
            CHECK(max_abs_diff(c, y, 64) == 0);
        }
    }
    small_config(&cfg);
    x[3] = (att_real)NAN;
    CHECK_EQ_INT(att_wden_block(&cfg, x, y, scratch, NULL), ATT_E_NONFINITE);
    line(x, 64, 0, 1, 0);
    x[3] = HUGEV;
    x[4] = HUGEV;
    CHECK_EQ_INT(att_wden_block(&cfg, x, y, scratch, NULL), ATT_E_WDEN_OVERFLOW);
    cfg.levels = 0;
    CHECK_EQ_INT(att_wden_block(&cfg, x, y, scratch, NULL), ATT_E_WDEN_LEVELS);
    CHECK_EQ_INT(att_wden_block(NULL, x, y, scratch, NULL), ATT_E_NULL);
}

/* ---- the stream ------------------------------------------------------------------ */

#define SLEN 600
static att_real sin_[SLEN], sout[SLEN + NMAX], sout2[SLEN + NMAX];
static att_real ring1[NMAX], ring2[NMAX], ring3[NMAX];

/* Feed sin_[0..n) one sample at a time, then flush; returns the outputs. */
static size_t run_stream(const att_wden_config *cfg, size_t n, att_real *out)
{
    att_wden s;
    size_t k = 0, i, got = 0;
    int r;
    CHECK_EQ_INT(att_wden_init(&s, cfg, ring1, NMAX, scratch, 2 * NMAX), ATT_OK);
    for (i = 0; i < n; i++) {
        size_t want = att_wden_outputs(&s, 1);
        r = att_wden_push(&s, sin_[i], out + k);
        CHECK_EQ_INT(r, want);
        if (r < 0)
            return k;
        k += (size_t)r;
        CHECK_EQ_INT(att_wden_pending(&s), i + 1 - k);
    }
    CHECK_EQ_INT(att_wden_flush(&s, out + k, NMAX, &got), ATT_OK);
    CHECK_EQ_INT(att_wden_pending(&s), 0);
    return k + got;
}

static void test_stream_passes_lines(void)
{
    static const size_t edges[][2] = { { 0, 0 }, { 5, 5 }, { 24, 8 }, { 8, 24 }, { 40, 20 } };
    att_wden_config cfg;
    size_t w, e, n;
    for (w = 0; w < 3; w++) {
        for (e = 0; e < sizeof edges / sizeof edges[0]; e++) {
            small_config(&cfg);
            cfg.wavelet = wavelets[w];
            cfg.edge_start = edges[e][0];
            cfg.edge_end = edges[e][1];
            cfg.mode = (int)(e & 1u);
            line(sin_, SLEN, 2.0, 0.01, 0); /* a ramp from 2 to 8 */
            n = run_stream(&cfg, SLEN - (size_t)e * 7, sout);
            CHECK_EQ_INT(n, SLEN - e * 7);
            CHECK(max_abs_diff(sin_, sout, n) <= TOL_RT * 8 * 4); /* + the per-segment constant */
        }
    }
}

static void test_stream_segments(void)
{
    att_wden_config cfg;
    att_wden s;
    size_t i, k = 0, burst = 0, first = 1;
    small_config(&cfg); /* N = 64, Es = 24, Ee = 8, H = 32 */
    line(sin_, SLEN, 0.2, 0.0005, 0.05);
    CHECK_EQ_INT(att_wden_init(&s, &cfg, ring1, 64, scratch, 128), ATT_OK);
    for (i = 0; i < SLEN; i++) {
        int r = att_wden_push(&s, sin_[i], sout + k);
        if (r > 0) {
            double sx = 0, sy = 0, sa = 0;
            size_t j;
            /* the burst: window ending at sample i; it outputs [i+1−N+Es, i+1−Ee) (first: from 0) */
            CHECK_EQ_INT(r, first ? 56 : 32);
            CHECK_EQ_INT(k, first ? 0 : i + 1 - 64 + 24);
            CHECK_EQ_INT(i + 1 - (k + (size_t)r), 8); /* Ee samples stay pending */
            for (j = k; j < k + (size_t)r; j++) {
                sx += (double)sin_[j];
                sy += (double)sout[j];
                sa += fabs((double)sin_[j]);
            }
            /* the segment's sum is restored: the two sums of r ≤ 56 terms and the r
             * corrected outputs each err by ≤ r·EPS·Σ|x| */
            CHECK_CLOSE(sy, sx, 4 * (double)r * EPS * sa);
            /* latency: the segment's first sample waited N − 1 − Es samples (N − 1 for window 0) */
            CHECK_EQ_INT(i - k, first ? 63 : 39);
            first = 0;
            burst++;
            k += (size_t)r;
        }
    }
    CHECK_EQ_INT(s.windows, burst);
    CHECK_EQ_INT(burst, 1 + (SLEN - 64) / 32);
    CHECK(s.sigma > 0.01 && s.sigma < 0.05); /* uniform ±0.05: σ = 0.029 */
}

static void test_stream_batch_and_errors(void)
{
    att_wden_config cfg;
    att_wden a, b, c3[3];
    size_t n1 = 0, n2 = 0, err = 0, i, k, got;
    int r;
    small_config(&cfg);
    cfg.wavelet = ATT_WDEN_DB2;
    cfg.edge_start = 8;
    cfg.edge_end = 8;
    line(sin_, SLEN, -0.1, 0.0002, 0.02);
    /* push_n in uneven chunks == one push at a time, bit for bit */
    n1 = run_stream(&cfg, SLEN, sout);
    CHECK_EQ_INT(att_wden_init(&b, &cfg, ring2, 64, scratch, 128), ATT_OK);
    k = 0;
    for (i = 0; i < SLEN;) {
        size_t m = i + 37 <= SLEN ? 37 : SLEN - i;
        size_t want = att_wden_outputs(&b, m);
        CHECK_EQ_INT(att_wden_push_n(&b, sin_ + i, m, sout2 + k, want, &n2, &err), ATT_OK);
        CHECK_EQ_INT(n2, want);
        k += n2;
        i += m;
    }
    CHECK_EQ_INT(att_wden_flush(&b, sout2 + k, 64, &got), ATT_OK);
    CHECK_EQ_INT(k + got, n1);
    CHECK(max_abs_diff(sout, sout2, n1) == 0);
    /* three streams sharing one scratch == each alone */
    for (i = 0; i < 3; i++)
        CHECK_EQ_INT(att_wden_init(&c3[i], &cfg,
                                   i == 0   ? ring1
                                   : i == 1 ? ring2
                                            : ring3,
                                   64, scratch, 128),
                     ATT_OK);
    k = 0;
    for (i = 0; i < SLEN; i++) {
        att_real o[3][64];
        int r0 = att_wden_push(&c3[0], sin_[i], o[0]);
        int r1 = att_wden_push(&c3[1], -sin_[i], o[1]);
        int r2 = att_wden_push(&c3[2], sin_[i], o[2]);
        CHECK(r0 == r1 && r1 == r2);
        if (r0 > 0) {
            CHECK(max_abs_diff(o[0], sout + k, (size_t)r0) == 0);
            CHECK(max_abs_diff(o[2], sout + k, (size_t)r0) == 0);
            for (n2 = 0; n2 < (size_t)r0; n2++)
                CHECK(o[1][n2] == -o[0][n2]); /* the denoiser is odd: D(−x) = −D(x) */
            k += (size_t)r0;
        }
    }
    /* NaN/Inf: rejected, nothing consumed */
    CHECK_EQ_INT(att_wden_init(&a, &cfg, ring1, 64, scratch, 128), ATT_OK);
    CHECK_EQ_INT(att_wden_push(&a, (att_real)NAN, sout), ATT_E_NONFINITE);
    CHECK_EQ_INT(att_wden_pending(&a), 0);
    sin_[50] = (att_real)INFINITY;
    CHECK_EQ_INT(att_wden_push_n(&a, sin_, 100, sout, 100, &n2, &err), ATT_E_NONFINITE);
    CHECK_EQ_INT(err, 50);
    CHECK_EQ_INT(n2, 0);
    CHECK_EQ_INT(att_wden_pending(&a), 0);
    sin_[50] = 0;
    /* output room */
    CHECK_EQ_INT(att_wden_push_n(&a, sin_, 100, sout, att_wden_outputs(&a, 100) - 1, &n2, &err),
                 ATT_E_BUFFER);
    CHECK_EQ_INT(att_wden_pending(&a), 0);
    CHECK_EQ_INT(att_wden_push_n(&a, sin_, 10, NULL, 0, &n2, &err), ATT_OK); /* no output due */
    CHECK_EQ_INT(att_wden_pending(&a), 10);
    /* flush too early, then buffers */
    CHECK_EQ_INT(att_wden_flush(&a, sout, 64, &got), ATT_E_WDEN_SHORT);
    CHECK_EQ_INT(att_wden_pending(&a), 10);
    CHECK_EQ_INT(att_wden_reset(&a), ATT_OK);
    CHECK_EQ_INT(att_wden_flush(&a, NULL, 0, &got), ATT_OK); /* nothing pending */
    CHECK_EQ_INT(got, 0);
    CHECK_EQ_INT(att_wden_init(&a, &cfg, ring1, 63, scratch, 128), ATT_E_BUFFER);
    CHECK_EQ_INT(att_wden_init(&a, &cfg, ring1, 64, scratch, 127), ATT_E_BUFFER);
    CHECK_EQ_INT(att_wden_init(&a, &cfg, NULL, 64, scratch, 128), ATT_E_NULL);
    CHECK_EQ_INT(att_wden_push(NULL, 0, sout), ATT_E_NULL);
    /* overflow: the sample that completes a window is rejected with the state
     * unchanged; the stream then goes on as if it had never been offered */
    CHECK_EQ_INT(att_wden_init(&a, &cfg, ring1, 64, scratch, 128), ATT_OK);
    CHECK_EQ_INT(att_wden_init(&b, &cfg, ring2, 64, scratch, 128), ATT_OK);
    for (i = 0; i < 63; i++) {
        CHECK_EQ_INT(att_wden_push(&a, sin_[i], sout), 0);
        CHECK_EQ_INT(att_wden_push(&b, sin_[i], sout2), 0);
    }
    CHECK_EQ_INT(att_wden_push(&a, HUGEV, sout), ATT_E_WDEN_OVERFLOW); /* τ = 31.5: τ·x overflows */
    CHECK_EQ_INT(att_wden_pending(&a), 63);
    CHECK_EQ_INT(a.windows, 0);
    r = att_wden_push(&a, sin_[63], sout);
    CHECK_EQ_INT(r, 56);
    CHECK_EQ_INT(att_wden_push(&b, sin_[63], sout2), r);
    CHECK(max_abs_diff(sout, sout2, 56) == 0);
    /* batch: stops at the overflowing sample, earlier outputs kept */
    CHECK_EQ_INT(att_wden_init(&a, &cfg, ring1, 64, scratch, 128), ATT_OK);
    for (i = 0; i < 200; i++)
        sout2[i] = sin_[i];
    sout2[64 + 48 - 1] = HUGEV; /* completes window 1 (hop 48) */
    CHECK_EQ_INT(att_wden_push_n(&a, sout2, 200, sout, 200, &n2, &err), ATT_E_WDEN_OVERFLOW);
    CHECK_EQ_INT(err, 64 + 48 - 1);
    CHECK_EQ_INT(n2, 56); /* window 0 output N − Ee = 56 samples */
    CHECK_EQ_INT(att_wden_pending(&a), 64 + 48 - 1 - 56);
}

int main(void)
{
    test_config();
    test_filters();
    test_transform();
    test_threshold();
    test_median();
    test_sigma();
    test_block();
    test_stream_passes_lines();
    test_stream_segments();
    test_stream_batch_and_errors();
    return ATT_TEST_REPORT();
}
