/* libattitude — wavelet threshold denoiser: configuration, block transform,
 * selection, thresholding and the block denoiser (see denoise.h,
 * docs/denoise.md). */
#include "attitude/denoise.h"

#include "att_math.h"
#include "denoise_internal.h"

#if defined(ATT_REAL_F32)
#define att_log logf
#else
#define att_log log
#endif

/* Extremal-phase Daubechies scaling filters, Σh = √2 (PyWavelets' rec_lo).
 * 25 digits from Newton's method on the defining equations in 50-digit
 * arithmetic: python -m toolchain.wavelet_constants. */
static const att_real haar_h[2] = { ATT_R(7.0710678118654752440084436e-1),
                                    ATT_R(7.0710678118654752440084436e-1) };
static const att_real db2_h[4] = { ATT_R(4.8296291314453414337487160e-1),
                                   ATT_R(8.3651630373780790557529378e-1),
                                   ATT_R(2.2414386804201338102597276e-1),
                                   ATT_R(-1.2940952255126038117444942e-1) };
static const att_real db4_h[8] = {
    ATT_R(2.3037781330889650086329118e-1),  ATT_R(7.1484657055291564708992196e-1),
    ATT_R(6.3088076792985890788171634e-1),  ATT_R(-2.7983769416859854211413747e-2),
    ATT_R(-1.8703481171909308407957067e-1), ATT_R(3.0841381835560763627219363e-2),
    ATT_R(3.2883011666885199735407514e-2),  ATT_R(-1.0597401785069032104883209e-2)
};

/* Φ⁻¹(3/4): the median of |N(0, σ²)| is σ·Φ⁻¹(3/4). */
#define ATT_WDEN_MAD_NORMAL ATT_R(0.67448975019608174320)

typedef struct {
    const att_real *h;
    att_real g[ATT_WDEN_MAX_TAPS];
    size_t f;
} bank;

static int load_bank(int wavelet, bank *b)
{
    size_t m;
    switch (wavelet) {
    case ATT_WDEN_HAAR:
        b->h = haar_h;
        b->f = 2;
        break;
    case ATT_WDEN_DB2:
        b->h = db2_h;
        b->f = 4;
        break;
    case ATT_WDEN_DB4:
        b->h = db4_h;
        b->f = 8;
        break;
    default:
        return 0;
    }
    for (m = 0; m < b->f; m++) /* g[m] = (−1)^m h[F−1−m] */
        b->g[m] = (m & 1u) ? -b->h[b->f - 1 - m] : b->h[b->f - 1 - m];
    return 1;
}

static int all_finite(const att_real *x, size_t n)
{
    size_t i;
    for (i = 0; i < n; i++)
        if (!isfinite(x[i]))
            return 0;
    return 1;
}

/* ---- configuration ---------------------------------------------------------- */

int att_wden_config_default(att_wden_config *cfg)
{
    if (cfg == NULL)
        return ATT_E_NULL;
    cfg->wavelet = ATT_WDEN_DEFAULT_WAVELET;
    cfg->mode = ATT_WDEN_DEFAULT_MODE;
    cfg->levels = ATT_WDEN_DEFAULT_LEVELS;
    cfg->block = ATT_WDEN_DEFAULT_BLOCK;
    cfg->edge_start = ATT_WDEN_DEFAULT_EDGE_START;
    cfg->edge_end = ATT_WDEN_DEFAULT_EDGE_END;
    cfg->detrend = ATT_WDEN_DEFAULT_DETREND;
    return ATT_OK;
}

static int check_shape(unsigned int levels, size_t n)
{
    if (levels < 1 || levels > ATT_WDEN_MAX_LEVELS)
        return ATT_E_WDEN_LEVELS;
    if (n < 2 || n > ATT_WDEN_MAX_BLOCK || (n & (((size_t)1 << levels) - 1)) != 0)
        return ATT_E_WDEN_BLOCK;
    return ATT_OK;
}

int att_wden_config_check(const att_wden_config *cfg)
{
    int st;
    if (cfg == NULL)
        return ATT_E_NULL;
    if (cfg->wavelet < 0 || cfg->wavelet >= ATT_WDEN_WAVELET_COUNT)
        return ATT_E_WDEN_WAVELET;
    if (cfg->mode < 0 || cfg->mode >= ATT_WDEN_MODE_COUNT)
        return ATT_E_WDEN_MODE;
    st = check_shape(cfg->levels, cfg->block);
    if (st != ATT_OK)
        return st;
    if (cfg->edge_start >= cfg->block || cfg->edge_end >= cfg->block - cfg->edge_start) /* Es + Ee < N */
        return ATT_E_WDEN_EDGE;
    if (cfg->detrend != 0 && cfg->detrend != 1)
        return ATT_E_ARG;
    return ATT_OK;
}

size_t att_wden_state_len(const att_wden_config *cfg)
{
    return att_wden_config_check(cfg) == ATT_OK ? cfg->block : 0;
}

size_t att_wden_scratch_len(const att_wden_config *cfg)
{
    return att_wden_config_check(cfg) == ATT_OK ? 2 * cfg->block : 0;
}

size_t att_wden_max_out(const att_wden_config *cfg)
{
    return att_wden_config_check(cfg) == ATT_OK ? cfg->block - cfg->edge_end : 0;
}

size_t att_wden_latency(const att_wden_config *cfg)
{
    return att_wden_config_check(cfg) == ATT_OK ? cfg->block - 1 - cfg->edge_start : 0;
}

int att_wden_filters(int wavelet, att_real h[ATT_WDEN_MAX_TAPS], att_real g[ATT_WDEN_MAX_TAPS], size_t *taps)
{
    bank b;
    size_t m;
    if (h == NULL || g == NULL || taps == NULL)
        return ATT_E_NULL;
    if (!load_bank(wavelet, &b))
        return ATT_E_WDEN_WAVELET;
    for (m = 0; m < b.f; m++) {
        h[m] = b.h[m];
        g[m] = b.g[m];
    }
    *taps = b.f;
    return ATT_OK;
}

/* ---- one level of the periodized transform ------------------------------------- */

/* Index of x where the filter of output i starts: (2i + 1 − F/2) mod n. */
static size_t first_index(size_t i, size_t f, size_t n)
{
    size_t back = f / 2 - 1, j; /* F/2 − 1 ≥ 0 samples before 2i */
    while (back >= n)
        back -= n;
    j = 2 * i + (back ? n - back : 0);
    return j >= n ? j - n : j;
}

/* lo[i], hi[i] for i < n/2 from x[0..n). */
static void analyze(const bank *b, const att_real *x, size_t n, att_real *lo, att_real *hi)
{
    const size_t half = n / 2, f = b->f;
    size_t i, m;
    for (i = 0; i < half; i++) {
        size_t j = first_index(i, f, n);
        att_real a = ATT_R(0.0), d = ATT_R(0.0);
        if (j + f <= n) { /* no wrap: the common case */
            const att_real *xp = x + j;
            for (m = 0; m < f; m++) {
                a += b->h[m] * xp[m];
                d += b->g[m] * xp[m];
            }
        } else {
            for (m = 0; m < f; m++) {
                a += b->h[m] * x[j];
                d += b->g[m] * x[j];
                if (++j == n)
                    j = 0;
            }
        }
        lo[i] = a;
        hi[i] = d;
    }
}

/* y[0..n) = Σ_i lo[i] φ_i + hi[i] ψ_i (the transpose of analyze). */
static void synthesize(const bank *b, const att_real *lo, const att_real *hi, size_t n, att_real *y)
{
    const size_t half = n / 2, f = b->f;
    size_t i, m;
    for (i = 0; i < n; i++)
        y[i] = ATT_R(0.0);
    for (i = 0; i < half; i++) {
        size_t j = first_index(i, f, n);
        const att_real a = lo[i], d = hi[i];
        if (j + f <= n) {
            att_real *yp = y + j;
            if (d == ATT_R(0.0)) { /* a thresholded detail: half the work (most of them, on noise) */
                for (m = 0; m < f; m++)
                    yp[m] += a * b->h[m];
            } else {
                for (m = 0; m < f; m++)
                    yp[m] += a * b->h[m] + d * b->g[m];
            }
        } else {
            for (m = 0; m < f; m++) {
                y[j] += a * b->h[m] + d * b->g[m];
                if (++j == n)
                    j = 0;
            }
        }
    }
}

static void copy(att_real *dst, const att_real *src, size_t n)
{
    size_t i;
    for (i = 0; i < n; i++)
        dst[i] = src[i];
}

/* The transforms on validated arguments (c may be x, y may be c). */
static void dwt(const bank *b, unsigned int levels, const att_real *x, size_t n, att_real *c, att_real *tmp)
{
    size_t m = n;
    unsigned int l;
    for (l = 0; l < levels; l++) {
        analyze(b, l == 0 ? x : c, m, tmp, tmp + m / 2);
        copy(c, tmp, m);
        m /= 2;
    }
}

static void idwt(const bank *b, unsigned int levels, const att_real *c, size_t n, att_real *y, att_real *tmp)
{
    size_t m = n >> levels;
    unsigned int l;
    if (y != c)
        copy(y, c, n); /* details of every level first; the levels below rebuild y[0..2m) */
    for (l = 0; l < levels; l++) {
        synthesize(b, y, y + m, 2 * m, tmp);
        copy(y, tmp, 2 * m);
        m *= 2;
    }
}

/* The checks both transforms share, then one of them. */
static int transform(int inverse, int wavelet, unsigned int levels, const att_real *in, size_t n,
                     att_real *out, att_real *tmp)
{
    bank b;
    int st;
    if (in == NULL || out == NULL || tmp == NULL)
        return ATT_E_NULL;
    if (!load_bank(wavelet, &b))
        return ATT_E_WDEN_WAVELET;
    st = check_shape(levels, n);
    if (st != ATT_OK)
        return st;
    if (!all_finite(in, n))
        return ATT_E_NONFINITE;
    if (inverse)
        idwt(&b, levels, in, n, out, tmp);
    else
        dwt(&b, levels, in, n, out, tmp);
    return all_finite(out, n) ? ATT_OK : ATT_E_WDEN_OVERFLOW;
}

int att_wden_dwt(int wavelet, unsigned int levels, const att_real *x, size_t n, att_real *c, att_real *tmp)
{
    return transform(0, wavelet, levels, x, n, c, tmp);
}

int att_wden_idwt(int wavelet, unsigned int levels, const att_real *c, size_t n, att_real *y, att_real *tmp)
{
    return transform(1, wavelet, levels, c, n, y, tmp);
}

/* ---- thresholding ---------------------------------------------------------------- */

static void threshold(att_real *c, size_t n, att_real lambda, int mode)
{
    size_t i;
    if (mode == ATT_WDEN_SOFT) {
        for (i = 0; i < n; i++) {
            const att_real v = c[i];
            c[i] = v > lambda ? v - lambda : (v < -lambda ? v + lambda : ATT_R(0.0));
        }
    } else {
        for (i = 0; i < n; i++)
            if (att_fabs(c[i]) < lambda)
                c[i] = ATT_R(0.0);
    }
}

int att_wden_threshold(att_real *c, size_t n, att_real lambda, int mode)
{
    if (c == NULL)
        return ATT_E_NULL;
    if (mode < 0 || mode >= ATT_WDEN_MODE_COUNT)
        return ATT_E_WDEN_MODE;
    if (!isfinite(lambda))
        return ATT_E_NONFINITE;
    if (lambda < ATT_R(0.0))
        return ATT_E_ARG;
    if (!all_finite(c, n))
        return ATT_E_NONFINITE;
    threshold(c, n, lambda, mode);
    return ATT_OK;
}

/* ---- selection ----------------------------------------------------------------------- */

static void swap(att_real *a, long i, long j)
{
    att_real t = a[i];
    a[i] = a[j];
    a[j] = t;
}

static void sift_down(att_real *a, long root, long end) /* max-heap on a[0..end) */
{
    for (;;) {
        long child = 2 * root + 1;
        if (child >= end)
            return;
        if (child + 1 < end && a[child] < a[child + 1])
            child++;
        if (!(a[root] < a[child]))
            return;
        swap(a, root, child);
        root = child;
    }
}

static void heapsort(att_real *a, long n)
{
    long i;
    for (i = n / 2 - 1; i >= 0; i--)
        sift_down(a, i, n);
    for (i = n - 1; i > 0; i--) {
        swap(a, 0, i);
        sift_down(a, 0, i);
    }
}

unsigned int att__wden_depth(size_t n)
{
    unsigned int d = 2;
    while (n > 1) {
        n >>= 1;
        d += 2;
    }
    return d;
}

att_real att__wden_select(att_real *a, size_t n, size_t k, unsigned int depth)
{
    long lo = 0, hi = (long)n - 1;
    const long kk = (long)k;
    while (hi > lo) {
        long mid, i, j;
        att_real pivot;
        if (depth == 0) {
            heapsort(a + lo, hi - lo + 1);
            break;
        }
        depth--;
        mid = lo + (hi - lo) / 2; /* median of three: a[lo] ≤ a[mid] ≤ a[hi] */
        if (a[mid] < a[lo])
            swap(a, mid, lo);
        if (a[hi] < a[lo])
            swap(a, hi, lo);
        if (a[hi] < a[mid])
            swap(a, hi, mid);
        pivot = a[mid];
        i = lo;
        j = hi;
        while (i <= j) { /* Hoare: a[lo..j] ≤ pivot ≤ a[i..hi] at the end */
            while (a[i] < pivot)
                i++;
            while (pivot < a[j])
                j--;
            if (i <= j) {
                swap(a, i, j);
                i++;
                j--;
            }
        }
        if (kk <= j)
            hi = j;
        else if (kk >= i)
            lo = i;
        else
            break; /* j < k < i: a[k] == pivot, in place */
    }
    return a[k];
}

int att_wden_median(att_real *a, size_t n, att_real *median)
{
    size_t k, i;
    att_real lower, upper;
    if (a == NULL || median == NULL)
        return ATT_E_NULL;
    if (n == 0)
        return ATT_E_ARG;
    if (!all_finite(a, n))
        return ATT_E_NONFINITE;
    k = (n - 1) / 2;
    lower = att__wden_select(a, n, k, att__wden_depth(n));
    if (n & 1u) {
        *median = lower;
        return ATT_OK;
    }
    upper = a[k + 1]; /* the upper middle value: the smallest of a[k+1..n) */
    for (i = k + 2; i < n; i++)
        if (a[i] < upper)
            upper = a[i];
    /* mean of the two without overflow: the difference for equal signs, the sum otherwise */
    if ((lower < ATT_R(0.0)) == (upper < ATT_R(0.0)))
        *median = lower + (upper - lower) * ATT_R(0.5);
    else
        *median = (lower + upper) * ATT_R(0.5);
    return ATT_OK;
}

int att_wden_mad_sigma(const att_real *d, size_t n, att_real *work, att_real *sigma)
{
    size_t i;
    att_real med;
    int st;
    if (d == NULL || work == NULL || sigma == NULL)
        return ATT_E_NULL;
    if (n == 0)
        return ATT_E_ARG;
    if (!all_finite(d, n))
        return ATT_E_NONFINITE;
    for (i = 0; i < n; i++)
        work[i] = att_fabs(d[i]);
    st = att_wden_median(work, n, &med);
    if (st != ATT_OK)
        return st;
    *sigma = med / ATT_WDEN_MAD_NORMAL;
    return isfinite(*sigma) ? ATT_OK : ATT_E_WDEN_OVERFLOW;
}

int att_wden_universal(att_real sigma, size_t n, att_real *lambda)
{
    if (lambda == NULL)
        return ATT_E_NULL;
    if (!isfinite(sigma))
        return ATT_E_NONFINITE;
    if (sigma < ATT_R(0.0) || n == 0)
        return ATT_E_ARG;
    *lambda = sigma * att_sqrt(ATT_R(2.0) * att_log((att_real)n));
    return isfinite(*lambda) ? ATT_OK : ATT_E_WDEN_OVERFLOW;
}

/* ---- the block denoiser ------------------------------------------------------------- */

/* τ_i = i − (n − 1)/2, exact (integers and halves below 2^24) */
static att_real centred(size_t i, size_t n)
{
    return ATT_R(0.5) * ((att_real)(2 * i + 1) - (att_real)n);
}

int att__wden_block_core(const att_wden_config *cfg, att_real *c, att_real *tmp, att_real *sigma)
{
    const size_t n = cfg->block;
    size_t i;
    att_real mean = ATT_R(0.0), slope = ATT_R(0.0), s, lambda;
    int st;
    bank b;
    load_bank(cfg->wavelet, &b);
    if (cfg->detrend) {
        /* least-squares line mean + slope·τ, τ_i = i − (n−1)/2 (exact halves):
         * slope = Σ τ_i x_i / Σ τ_i², Σ τ_i² = n(n² − 1)/12 */
        att_real st_x = ATT_R(0.0);
        for (i = 0; i < n; i++) {
            const att_real tau = centred(i, n);
            mean += c[i];
            st_x += tau * c[i];
        }
        mean /= (att_real)n;
        slope = st_x / ((att_real)n * ((att_real)n * (att_real)n - ATT_R(1.0)) / ATT_R(12.0));
        for (i = 0; i < n; i++)
            c[i] -= mean + slope * centred(i, n);
    }
    dwt(&b, cfg->levels, c, n, c, tmp);
    st = att_wden_mad_sigma(c + n / 2, n / 2, tmp, &s); /* cD_1: the finest details */
    if (st == ATT_OK)
        st = att_wden_universal(s, n, &lambda);
    if (st != ATT_OK)
        return ATT_E_WDEN_OVERFLOW; /* the only way here: finite input, overflowing sums */
    threshold(c + (n >> cfg->levels), n - (n >> cfg->levels), lambda, cfg->mode);
    idwt(&b, cfg->levels, c, n, c, tmp);
    if (cfg->detrend)
        for (i = 0; i < n; i++)
            c[i] += mean + slope * centred(i, n);
    if (sigma != NULL)
        *sigma = s;
    return all_finite(c, n) ? ATT_OK : ATT_E_WDEN_OVERFLOW;
}

int att_wden_block(const att_wden_config *cfg, const att_real *x, att_real *y, att_real *scratch,
                   att_real *sigma)
{
    int st;
    if (cfg == NULL || x == NULL || y == NULL || scratch == NULL)
        return ATT_E_NULL;
    st = att_wden_config_check(cfg);
    if (st != ATT_OK)
        return st;
    if (!all_finite(x, cfg->block))
        return ATT_E_NONFINITE;
    copy(scratch, x, cfg->block);
    st = att__wden_block_core(cfg, scratch, scratch + cfg->block, sigma);
    if (st == ATT_OK)
        copy(y, scratch, cfg->block);
    return st;
}
