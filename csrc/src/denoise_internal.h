/*
 * libattitude — private parts of the wavelet denoiser shared by denoise.c
 * and denoise_stream.c (and exercised directly by csrc/tests/test_denoise.c).
 */
#ifndef ATT_SRC_DENOISE_INTERNAL_H
#define ATT_SRC_DENOISE_INTERNAL_H

#include "attitude/denoise.h"

/* Rearrange a[0..n) (n ≥ 1, no NaN) so that a[k] is the k-th smallest,
 * a[0..k) ≤ a[k] ≤ a[k+1..n); return a[k]. Quickselect (median-of-three
 * pivot, Hoare partition) that falls back to heapsort on the remaining range
 * after `depth` partitions (introselect: expected O(n), worst O(n log n)). */
att_real att__wden_select(att_real *a, size_t n, size_t k, unsigned int depth);

/* Depth limit used by the library: 2·floor(log2 n) + 2 partitions. */
unsigned int att__wden_depth(size_t n);

/* The block denoiser on a block already in c[0..N) (cfg valid, c finite):
 * c ← denoised block, tmp: N samples of scratch. ATT_E_WDEN_OVERFLOW if
 * the result is not finite. */
int att__wden_block_core(const att_wden_config *cfg, att_real *c, att_real *tmp, att_real *sigma);

#endif /* ATT_SRC_DENOISE_INTERNAL_H */
