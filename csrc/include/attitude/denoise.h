/*
 * libattitude — wavelet threshold denoiser for a stream of samples (prefix att_wden_).
 *
 * The gyro denoising of the FPGA+DSP paper (sec. 3.4): per block, a
 * discrete wavelet decomposition, the noise level from the median absolute
 * deviation of the finest details, the universal threshold σ√(2 ln N),
 * soft or hard thresholding of every detail level, reconstruction.
 * docs/denoise.md gives the method, the choices below and their reasons,
 * and what the denoiser does and does not do to an attitude solution.
 *
 * Block transform. Orthonormal periodized DWT (PyWavelets' "periodization"
 * mode, same phase): one level maps a block x of n samples (n even) to
 *     cA[i] = Σ_m h[m] x[(2i + m + 1 − F/2) mod n],
 *     cD[i] = Σ_m g[m] x[(2i + m + 1 − F/2) mod n],   i = 0 … n/2 − 1,
 * h the F-tap Daubechies scaling filter (Σh = √2), g[m] = (−1)^m h[F−1−m].
 * L levels give the coefficients in PyWavelets' wavedec order
 *     [cA_L | cD_L | cD_{L−1} | … | cD_1]   (lengths n/2^L, n/2^L, …, n/2).
 * Periodization keeps the transform orthonormal: white noise of level σ
 * gives detail coefficients of level σ (what the MAD estimate and the
 * universal threshold assume), Parseval holds, and the block's sum lives
 * in cA_L alone, so thresholding details never changes a block's mean.
 *
 * Block denoiser (att_wden_block). With detrend on, the least-squares line
 * through the block is removed first and added back last: a constant or a
 * ramp then passes exactly (to rounding) for every wavelet — Haar's single
 * vanishing moment would otherwise turn a ramp into a staircase, and the
 * periodic wrap of a ramp is a jump that thresholding would shrink.
 *
 * Stream (att_wden_push). Windows of N = block samples advance by the hop
 * H = N − Es − Ee. Window k covers stream samples [kH, kH + N) and outputs
 * [kH + Es, kH + N − Ee) (window 0 outputs from sample 0: the stream's start
 * is a true edge): the Es oldest and the Ee newest samples of each window,
 * where the periodic wrap and the line fit disturb the estimate, are
 * discarded. The disturbed stretch is not symmetric: the extremal-phase
 * filters put the wrap's error mostly at the window's start (docs/denoise.md
 * gives the measured profile), hence Es = 56, Ee = 24 for the default db4,
 * L = 4, N = 128. Each output segment gets the constant that makes its sum
 * equal the input's sum over the same samples: the integral of the signal
 * over every segment (the angle, for a gyro rate) is preserved, the mean
 * exactly. att_wden_flush() ends the stream with a last window over the
 * final N samples, outputting what is left.
 *
 * Latency: a sample leaves at the latest ATT_WDEN_LATENCY = N − 1 − Es
 * samples after it arrived (N − 1 for the first Es samples of the stream);
 * outputs come in bursts of H samples (N − Ee for the first window). With
 * the defaults (N = 128, Es = 56, Ee = 24, H = 48) that is 71 samples:
 * 0.355 s at 200 Hz.
 *
 * Caller-owned memory: the state struct, a state buffer of
 * att_wden_state_len() samples (the window ring, one per stream) and a
 * scratch buffer of att_wden_scratch_len() samples (used only inside a
 * call: several streams run one after the other, e.g. the three gyro axes,
 * may share one). No malloc, no global state, no I/O.
 *
 * Errors: every function returns ATT_OK (0) or a negative status code, the
 * generic ones of common.h or this module's ATT_E_WDEN_*, as an int (as
 * tlc2543.h does): att_status is a one-byte enum where enums are short
 * (arm-none-eabi, SDCC) and cannot hold codes below -128. Inputs and outputs
 * are checked (NaN/Inf in → ATT_E_NONFINITE, finite in but non-finite out →
 * ATT_E_WDEN_OVERFLOW).
 */
#ifndef ATTITUDE_DENOISE_H
#define ATTITUDE_DENOISE_H

#include "attitude/common.h"

ATT_API_BEGIN

/* Wavelets (Daubechies, extremal phase; names as in PyWavelets). */
typedef enum {
    ATT_WDEN_HAAR = 0, /* 2 taps, 1 vanishing moment (= db1) */
    ATT_WDEN_DB2 = 1,  /* 4 taps, 2 vanishing moments ("D4") */
    ATT_WDEN_DB4 = 2,  /* 8 taps, 4 vanishing moments */
    ATT_WDEN_WAVELET_COUNT = 3
} att_wden_wavelet;

/* Thresholding rules for a coefficient c and threshold λ. */
typedef enum {
    ATT_WDEN_SOFT = 0, /* sign(c)·max(|c| − λ, 0) */
    ATT_WDEN_HARD = 1, /* c if |c| ≥ λ, else 0 */
    ATT_WDEN_MODE_COUNT = 2
} att_wden_mode;

/* Limits and the default configuration (att_wden_config_default). */
enum {
    ATT_WDEN_MAX_TAPS = 8,        /* longest filter (db4) */
    ATT_WDEN_MAX_LEVELS = 16,     /* decomposition levels 1..16 */
    ATT_WDEN_MAX_BLOCK = 16384,   /* block length N, 2..16384, a multiple of 2^levels */
    ATT_WDEN_DEFAULT_WAVELET = 2, /* ATT_WDEN_DB4 */
    ATT_WDEN_DEFAULT_MODE = 0,    /* ATT_WDEN_SOFT */
    ATT_WDEN_DEFAULT_LEVELS = 4,
    ATT_WDEN_DEFAULT_BLOCK = 128,
    ATT_WDEN_DEFAULT_EDGE_START = 56,
    ATT_WDEN_DEFAULT_EDGE_END = 24,
    ATT_WDEN_DEFAULT_DETREND = 1
};

/* Status codes of this module (range -160..-179 of common.h). */
enum {
    ATT_E_WDEN_WAVELET = -160, /* unknown wavelet */
    ATT_E_WDEN_MODE = -161,    /* unknown thresholding rule */
    ATT_E_WDEN_LEVELS = -162,  /* levels outside 1..ATT_WDEN_MAX_LEVELS */
    ATT_E_WDEN_BLOCK = -163,   /* block length outside 2..ATT_WDEN_MAX_BLOCK or not a multiple of 2^levels */
    ATT_E_WDEN_EDGE = -164,    /* edge_start + edge_end ≥ block (no sample left to output) */
    ATT_E_WDEN_SHORT = -165,   /* flush before one full block was received */
    ATT_E_WDEN_OVERFLOW = -166 /* finite input, non-finite result (|x| near the type's maximum) */
};

/* Configuration. */
typedef struct {
    int wavelet;         /* att_wden_wavelet */
    int mode;            /* att_wden_mode */
    unsigned int levels; /* L, 1..ATT_WDEN_MAX_LEVELS */
    size_t block;        /* N (samples per window), 2..ATT_WDEN_MAX_BLOCK, N mod 2^L = 0 */
    size_t edge_start;   /* Es: oldest samples of a window not output */
    size_t edge_end;     /* Ee: newest samples of a window not output; Es + Ee < N;
                            Es = Ee = 0: non-overlapping blocks */
    int detrend;         /* 1: remove and restore the least-squares line per block; 0: not */
} att_wden_config;

/* Stream state. Caller-owned; treat as opaque. */
typedef struct {
    att_wden_config cfg;
    att_real *ring;        /* the last `block` samples (state buffer) */
    att_real *scratch;     /* 2·block samples, used only inside a call */
    size_t head;           /* ring index of the next sample to write (= the oldest once full) */
    size_t fill;           /* samples in the ring (≤ block) */
    size_t since;          /* samples since the last window (started streams) */
    size_t pending;        /* samples received and not yet output */
    int started;           /* 1 once the first window was processed */
    unsigned long windows; /* windows processed since init/reset (wraps) */
    att_real sigma;        /* noise level σ of the last window (0 before the first) */
} att_wden;

/* ---- configuration ------------------------------------------------------ */

/* Fill cfg with the defaults: db4, soft, L = 4, N = 128, Es = 56, Ee = 24, detrend on
 * (docs/denoise.md: why). ATT_E_NULL if cfg is NULL. */
int att_wden_config_default(att_wden_config *cfg);

/* ATT_OK if cfg is valid, else the status naming the first bad field
 * (checked in the order wavelet, mode, levels, block, edges, detrend
 * (ATT_E_ARG unless 0 or 1)). */
int att_wden_config_check(const att_wden_config *cfg);

/* Buffer sizes in att_real elements for a valid cfg (0 if cfg is invalid):
 * state = N (per stream), scratch = 2N (shareable), and the most samples a
 * single att_wden_push() call can output, N − Ee. */
size_t att_wden_state_len(const att_wden_config *cfg);
size_t att_wden_scratch_len(const att_wden_config *cfg);
size_t att_wden_max_out(const att_wden_config *cfg);

/* Largest delay in samples from a sample's arrival to its output in the
 * steady state, N − 1 − Es (0 if cfg is invalid). */
size_t att_wden_latency(const att_wden_config *cfg);

/* ---- block transform (pure functions) -------------------------------------
 * Cost per block of n samples with an F-tap filter and L levels:
 * dwt and idwt each 2F·n·(1 − 2^−L) multiply-adds plus 2n copies;
 * median: expected ~3n comparisons, worst case O(n log n) (introselect);
 * threshold: n; block denoiser: dwt + idwt + median of n/2 + ~8n. */

/* The F-tap scaling filter h and wavelet filter g of wavelet w (F ≤
 * ATT_WDEN_MAX_TAPS values each; *taps = F). h is PyWavelets' rec_lo, g its
 * rec_hi. */
int att_wden_filters(int wavelet, att_real h[ATT_WDEN_MAX_TAPS], att_real g[ATT_WDEN_MAX_TAPS], size_t *taps);

/* L-level periodized DWT of x[0..n) into c[0..n) in wavedec order. n is a
 * multiple of 2^L (ATT_E_WDEN_BLOCK otherwise), 1 ≤ L ≤ ATT_WDEN_MAX_LEVELS.
 * tmp: n samples of scratch. c may be x (in place). Any filter length works
 * for any n (a filter longer than a level wraps around it several times, as
 * in PyWavelets). ATT_E_NONFINITE if x holds NaN/Inf (c untouched). */
int att_wden_dwt(int wavelet, unsigned int levels, const att_real *x, size_t n, att_real *c, att_real *tmp);

/* Inverse of att_wden_dwt (the transpose: perfect reconstruction to
 * rounding). Same arguments and rules; y may be c. */
int att_wden_idwt(int wavelet, unsigned int levels, const att_real *c, size_t n, att_real *y, att_real *tmp);

/* Threshold c[0..n) in place with λ ≥ 0 (finite; ATT_E_ARG otherwise). */
int att_wden_threshold(att_real *c, size_t n, att_real lambda, int mode);

/* Median of a[0..n) (n ≥ 1; even n: the mean of the two middle values, as
 * numpy.median). Selection in place: a is permuted. NaN or Inf in a:
 * ATT_E_NONFINITE, a untouched. */
int att_wden_median(att_real *a, size_t n, att_real *median);

/* Noise level σ = median(|d|) / Φ⁻¹(3/4) (Φ⁻¹(3/4) = 0.6744897501960817)
 * of detail coefficients d[0..n) (n ≥ 1); work: n samples of scratch. */
int att_wden_mad_sigma(const att_real *d, size_t n, att_real *work, att_real *sigma);

/* Universal threshold λ = σ √(2 ln n) (σ ≥ 0 finite, n ≥ 1). */
int att_wden_universal(att_real sigma, size_t n, att_real *lambda);

/* Denoise one block x[0..N) into y[0..N) (y may be x) with cfg (the edges are
 * not used): detrend (optional), dwt, σ from cD_1 by MAD, universal
 * threshold on every detail level, idwt, the line back. scratch: 2N
 * samples. *sigma (may be NULL) receives σ. The sum of y equals the sum of x
 * to rounding. */
int att_wden_block(const att_wden_config *cfg, const att_real *x, att_real *y, att_real *scratch,
                   att_real *sigma);

/* ---- stream ------------------------------------------------------------------ */

/* Start a stream with cfg (copied). state: state_len ≥ att_wden_state_len()
 * samples owned by this stream; scratch: scratch_len ≥ att_wden_scratch_len()
 * samples (ATT_E_BUFFER if smaller), may be shared with other streams that
 * are not used concurrently. */
int att_wden_init(att_wden *s, const att_wden_config *cfg, att_real *state, size_t state_len,
                  att_real *scratch, size_t scratch_len);

/* Drop every sample received; start a new stream with the same buffers. */
int att_wden_reset(att_wden *s);

/* Number of samples that n more att_wden_push() calls would output. */
size_t att_wden_outputs(const att_wden *s, size_t n);

/* Samples received and not yet output (what att_wden_flush() would output). */
size_t att_wden_pending(const att_wden *s);

/* Feed one sample. Returns the number of denoised samples written to out
 * (0, H, or N − Ee for the first window; room for att_wden_max_out()), in
 * stream order, or a negative status with the state unchanged:
 * ATT_E_NONFINITE, ATT_E_WDEN_OVERFLOW. Cost: one block denoiser run and
 * 2N copies every H samples, O(1) otherwise. */
int att_wden_push(att_wden *s, att_real x, att_real *out);

/* n samples in one call, exactly as n att_wden_push() calls: outputs
 * appended to out (out_cap ≥ att_wden_outputs(s, n), else ATT_E_BUFFER and
 * nothing consumed), their number in *n_out. A NaN/Inf anywhere is found
 * before anything is consumed (ATT_E_NONFINITE, *err_index = its index,
 * state unchanged). On ATT_E_WDEN_OVERFLOW the samples before *err_index
 * were consumed and their outputs are in out (*n_out). n_out and err_index
 * may be NULL. */
int att_wden_push_n(att_wden *s, const att_real *x, size_t n, att_real *out, size_t out_cap, size_t *n_out,
                    size_t *err_index);

/* End the stream: output the att_wden_pending() samples left (room in out,
 * ≤ N − 1 samples) from a last window over the final N samples (no edge
 * discarded at the end), then reset. ATT_E_WDEN_SHORT (state unchanged) if
 * fewer than N samples were received and some are pending; 0 outputs if
 * none are pending. */
int att_wden_flush(att_wden *s, att_real *out, size_t out_cap, size_t *n_out);

#ifndef ATT_CDEF
/* Compile-time buffer sizes for static arrays (same values as the
 * functions above for a valid configuration). */
#define ATT_WDEN_STATE_LEN(block)           (block)
#define ATT_WDEN_SCRATCH_LEN(block)         (2 * (block))
#define ATT_WDEN_LATENCY(block, edge_start) ((block)-1 - (edge_start))
#endif

ATT_API_END

#endif /* ATTITUDE_DENOISE_H */
