/*
 * Private: the widening-multiply primitive of the fixed-point module and
 * the 64-bit accumulator built on it.
 *
 * An accumulator holds a 64-bit two's-complement value (an exact sum of
 * 32×32-bit products, e.g. Q4.60 for Q2.30 × Q2.30). Two implementations
 * with identical results:
 *
 *   - "wide"   (fxw_*): uint64_t arithmetic; the product is one
 *              (int64_t)a * b, i.e. SMULL/SMLAL on ARMv4T. Hosts and ARM.
 *   - "halves" (fxh_*): two uint32_t words; the product is built from four
 *              16×16→32-bit partial products. No 64-bit type at all: this
 *              is the 8051 (SDCC) path, and the host test compiles it too
 *              and compares it bit for bit with the wide one.
 *
 * fx_* names select one of them: halves under SDCC or when
 * ATT_FX_FORCE_HALVES is defined, wide otherwise.
 *
 * All arithmetic is done on unsigned types (wraps modulo 2^64, never
 * undefined); signed results are converted back with fx_u2s (no
 * implementation-defined conversion). Callers guarantee the exact sums fit
 * in 64 bits (documented in each caller: 4 products of |x| ≤ 1.25·2^30).
 *
 * Extraction: fx_round(acc, sh) = floor(acc / 2^sh + 1/2) (round to
 * nearest, ties toward +inf), 0 ≤ sh ≤ 62, returning the low 32 bits of
 * the result, as int32: exact when the caller has proven the result fits;
 * fx_round_sat() checks that and reports overflow, for any 0 ≤ sh ≤ 62.
 */
#ifndef ATT_FIXED_PRIM_H
#define ATT_FIXED_PRIM_H

#include <stdint.h>

#if defined(__SDCC)
#define FX_STATIC  static
#define FX_NO_WIDE 1
#else
#define FX_STATIC static inline
#endif

#if defined(__SDCC) || defined(ATT_FX_FORCE_HALVES)
#define FX_USE_HALVES 1
#endif

/* uint32 → int32 without implementation-defined conversion. */
FX_STATIC int32_t fx_u2s(uint32_t u)
{
    if (u <= 0x7FFFFFFFul) {
        return (int32_t)u;
    }
    return -(int32_t)(~u) - 1;
}

#ifndef FX_PRIM_MINIMAL /* the compact kernel (fixed_rv.c on the 8051) needs only the above */

/* Arithmetic shift right (floor division by 2^n), 0 ≤ n ≤ 31, no
 * implementation-defined right shift of a negative value. */
FX_STATIC int32_t fx_asr(int32_t x, uint8_t n)
{
    return (x < 0) ? ~(~x >> n) : (x >> n);
}

/* ---- halves: 2×32-bit words, 16×16 partial products ------------------ */
typedef struct {
    uint32_t lo;
    uint32_t hi;
} fxh_acc;

FX_STATIC void fxh_zero(fxh_acc *a)
{
    a->lo = 0;
    a->hi = 0;
}

/* a = u (a non-negative 32-bit value) */
FX_STATIC void fxh_init_u(fxh_acc *a, uint32_t u)
{
    a->lo = u;
    a->hi = 0;
}

/* a = x·2^31 + 2^30 (start of a sum rounded by floor(a / 2^31)) */
FX_STATIC void fxh_init_shl31(fxh_acc *a, int32_t x)
{
    uint32_t ux = (uint32_t)x;
    a->lo = (ux << 31) | 0x40000000ul;
    a->hi = (ux >> 1) | (ux & 0x80000000ul);
}

/* (hi:lo) = ux * uy, unsigned 32 × 32 → 64 bits, from four 16 × 16 → 32-bit
 * partial products (MUL-friendly on the 8051: no 64-bit type). */
FX_STATIC void fxh_uprod(uint32_t ux, uint32_t uy, uint32_t *hi, uint32_t *lo)
{
    uint16_t x0 = (uint16_t)(ux & 0xFFFFu), x1 = (uint16_t)(ux >> 16);
    uint16_t y0 = (uint16_t)(uy & 0xFFFFu), y1 = (uint16_t)(uy >> 16);
    uint32_t p0 = (uint32_t)x0 * y0;
    uint32_t p1 = (uint32_t)x0 * y1;
    uint32_t p2 = (uint32_t)x1 * y0;
    uint32_t p3 = (uint32_t)x1 * y1;
    uint32_t mid = p1 + p2;
    uint32_t c1 = (mid < p1) ? 0x10000ul : 0u; /* carry out of the middle sum */
    uint32_t l = p0 + (mid << 16);
    uint32_t c2 = (l < p0) ? 1u : 0u;
    *hi = p3 + (mid >> 16) + c1 + c2;
    *lo = l;
}

/* (hi:lo) = x * y, signed 32 × 32 → 64 bits (two's complement). */
FX_STATIC void fxh_prod(int32_t x, int32_t y, uint32_t *hi, uint32_t *lo)
{
    uint32_t ux = (uint32_t)x, uy = (uint32_t)y;
    fxh_uprod(ux, uy, hi, lo);
    /* unsigned → signed product: subtract 2^32·uy if x < 0, 2^32·ux if y < 0 */
    if (x < 0) {
        *hi -= uy;
    }
    if (y < 0) {
        *hi -= ux;
    }
}

FX_STATIC void fxh_add(fxh_acc *a, uint32_t hi, uint32_t lo)
{
    uint32_t l = a->lo + lo;
    a->hi += hi + ((l < lo) ? 1u : 0u);
    a->lo = l;
}

/* a += x * y */
FX_STATIC void fxh_mac(fxh_acc *a, int32_t x, int32_t y)
{
    uint32_t hi, lo;
    fxh_prod(x, y, &hi, &lo);
    fxh_add(a, hi, lo);
}

/* a += 2 * x * y */
FX_STATIC void fxh_mac2(fxh_acc *a, int32_t x, int32_t y)
{
    uint32_t hi, lo;
    fxh_prod(x, y, &hi, &lo);
    hi = (hi << 1) | (lo >> 31);
    lo <<= 1;
    fxh_add(a, hi, lo);
}

/* a -= x * y */
FX_STATIC void fxh_msc(fxh_acc *a, int32_t x, int32_t y)
{
    uint32_t hi, lo;
    fxh_prod(x, y, &hi, &lo);
    /* negate (hi:lo) */
    lo = ~lo + 1u;
    hi = ~hi + ((lo == 0u) ? 1u : 0u);
    fxh_add(a, hi, lo);
}

/* a += x · 2^sh, 0 ≤ sh ≤ 31 (sign-extended) */
FX_STATIC void fxh_add_shl(fxh_acc *a, int32_t x, uint8_t sh)
{
    uint32_t ux = (uint32_t)x;
    uint32_t hi = (x < 0) ? 0xFFFFFFFFul : 0u;
    uint32_t lo = ux << sh;
    if (sh != 0u) {
        hi = (hi << sh) | (ux >> (32u - sh));
    }
    fxh_add(a, hi, lo);
}

/* (hi:lo) + 2^(sh-1) for sh ≥ 1 */
FX_STATIC void fxh_add_half(uint32_t *hi, uint32_t *lo, uint8_t sh)
{
    if (sh == 0u) {
        return;
    }
    if (sh <= 32u) {
        uint32_t h = 1ul << (sh - 1u);
        uint32_t l = *lo + h;
        *hi += (l < h) ? 1u : 0u;
        *lo = l;
    } else {
        *hi += 1ul << (sh - 33u);
    }
}

/* Round-to-nearest extraction, 0 ≤ sh ≤ 62, low 32 bits of the result. */
FX_STATIC int32_t fxh_round(const fxh_acc *a, uint8_t sh)
{
    uint32_t hi = a->hi, lo = a->lo;
    fxh_add_half(&hi, &lo, sh);
    if (sh == 0u) {
        return fx_u2s(lo);
    }
    if (sh >= 32u) {
        return fx_asr(fx_u2s(hi), (uint8_t)(sh - 32u));
    }
    return fx_u2s((lo >> sh) | (hi << (32u - sh)));
}

/* floor(a / 2^sh), 1 ≤ sh ≤ 31, low 32 bits */
FX_STATIC int32_t fxh_floor(const fxh_acc *a, uint8_t sh)
{
    return fx_u2s((a->lo >> sh) | (a->hi << (32u - sh)));
}

/* Unsigned extraction of a non-negative sum < 2^64, 0 < sh ≤ 63; the
 * caller guarantees the result < 2^32. */
FX_STATIC uint32_t fxh_round_u(const fxh_acc *a, uint8_t sh)
{
    uint32_t hi = a->hi, lo = a->lo;
    fxh_add_half(&hi, &lo, sh);
    if (sh < 32u) {
        return (lo >> sh) | (hi << (32u - sh));
    }
    return hi >> (sh - 32u);
}

/* 1 if the accumulated value v satisfies −2^b ≤ v < 2^b (33 ≤ b ≤ 62):
 * the high word of v + 2^b is below 2^(b−31). */
FX_STATIC int fxh_small(const fxh_acc *a, uint8_t b)
{
    return (uint32_t)(a->hi + (1ul << (b - 32u))) < (1ul << (b - 31u));
}

/* Round-to-nearest extraction with range check, 0 ≤ sh ≤ 62: returns 0
 * and *out on success, -1 if the rounded value is outside int32. */
FX_STATIC int fxh_round_sat(const fxh_acc *a, uint8_t sh, int32_t *out)
{
    uint32_t hi = a->hi, lo = a->lo;
    uint32_t neg = hi & 0x80000000ul;
    uint32_t sign, rhi, rlo;
    fxh_add_half(&hi, &lo, sh);
    /* t = v + half is exact as unsigned when v ≥ 0 and as signed when v < 0 */
    sign = (neg && (hi & 0x80000000ul)) ? 0xFFFFFFFFul : 0u;
    if (sh == 0u) {
        rlo = lo;
        rhi = hi;
    } else if (sh < 32u) {
        rlo = (lo >> sh) | (hi << (32u - sh));
        rhi = (hi >> sh) | (sign << (32u - sh));
    } else if (sh == 32u) {
        rlo = hi;
        rhi = sign;
    } else {
        rlo = (hi >> (sh - 32u)) | (sign << (64u - sh));
        rhi = sign;
    }
    if (rhi != ((rlo & 0x80000000ul) ? 0xFFFFFFFFul : 0u)) {
        return -1;
    }
    *out = fx_u2s(rlo);
    return 0;
}

/* ---- wide: uint64_t --------------------------------------------------- */
#ifndef FX_NO_WIDE
typedef struct {
    uint64_t v;
} fxw_acc;

FX_STATIC void fxw_zero(fxw_acc *a)
{
    a->v = 0;
}

FX_STATIC void fxw_init_u(fxw_acc *a, uint32_t u)
{
    a->v = u;
}

FX_STATIC void fxw_init_shl31(fxw_acc *a, int32_t x)
{
    a->v = ((uint64_t)(int64_t)x << 31) | 0x40000000u;
}

FX_STATIC int32_t fxw_floor(const fxw_acc *a, uint8_t sh)
{
    return fx_u2s((uint32_t)(a->v >> sh));
}

FX_STATIC void fxw_mac(fxw_acc *a, int32_t x, int32_t y)
{
    a->v += (uint64_t)((int64_t)x * (int64_t)y);
}

FX_STATIC void fxw_uprod(uint32_t x, uint32_t y, uint32_t *hi, uint32_t *lo)
{
    uint64_t p = (uint64_t)x * y;
    *hi = (uint32_t)(p >> 32);
    *lo = (uint32_t)p;
}

FX_STATIC void fxw_mac2(fxw_acc *a, int32_t x, int32_t y)
{
    a->v += (uint64_t)((int64_t)x * (int64_t)y) << 1;
}

FX_STATIC void fxw_msc(fxw_acc *a, int32_t x, int32_t y)
{
    a->v -= (uint64_t)((int64_t)x * (int64_t)y);
}

FX_STATIC void fxw_add_shl(fxw_acc *a, int32_t x, uint8_t sh)
{
    a->v += (uint64_t)(int64_t)x << sh;
}

FX_STATIC int32_t fxw_round(const fxw_acc *a, uint8_t sh)
{
    uint64_t v = a->v;
    if (sh != 0u) {
        v += (uint64_t)1 << (sh - 1u);
    }
    if (sh > 32u) {
        return fx_asr(fx_u2s((uint32_t)(v >> 32)), (uint8_t)(sh - 32u));
    }
    return fx_u2s((uint32_t)(v >> sh));
}

FX_STATIC uint32_t fxw_round_u(const fxw_acc *a, uint8_t sh)
{
    return (uint32_t)((a->v + ((uint64_t)1 << (sh - 1u))) >> sh);
}

FX_STATIC int fxw_small(const fxw_acc *a, uint8_t b)
{
    return (uint32_t)((uint32_t)(a->v >> 32) + (1ul << (b - 32u))) < (1ul << (b - 31u));
}

FX_STATIC int fxw_round_sat(const fxw_acc *a, uint8_t sh, int32_t *out)
{
    uint64_t v = a->v;
    uint64_t neg = v >> 63;
    uint64_t sign, r;
    if (sh != 0u) {
        v += (uint64_t)1 << (sh - 1u);
    }
    /* t = v + half is exact as unsigned when v ≥ 0 and as signed when v < 0 */
    sign = (neg && (v >> 63)) ? ~(uint64_t)0 : 0u;
    r = v >> sh;
    if (sh != 0u) {
        r |= sign << (64u - sh);
    }
    /* fits int32 iff bits 31..63 are all equal */
    if ((r >> 31) != 0u && (r >> 31) != (~(uint64_t)0 >> 31)) {
        return -1;
    }
    *out = fx_u2s((uint32_t)r);
    return 0;
}
#endif /* FX_NO_WIDE */

/* ---- selection -------------------------------------------------------- */
#if defined(FX_USE_HALVES)
typedef fxh_acc fx_acc;
#define fx_zero       fxh_zero
#define fx_init_u     fxh_init_u
#define fx_init_shl31 fxh_init_shl31
#define fx_floor      fxh_floor
#define fx_uprod      fxh_uprod
#define fx_mac        fxh_mac
#define fx_mac2       fxh_mac2
#define fx_msc        fxh_msc
#define fx_add_shl    fxh_add_shl
#define fx_round      fxh_round
#define fx_round_u    fxh_round_u
#define fx_round_sat  fxh_round_sat
#define fx_small      fxh_small
#else
typedef fxw_acc fx_acc;
#define fx_zero       fxw_zero
#define fx_init_u     fxw_init_u
#define fx_init_shl31 fxw_init_shl31
#define fx_floor      fxw_floor
#define fx_uprod      fxw_uprod
#define fx_mac        fxw_mac
#define fx_mac2       fxw_mac2
#define fx_msc        fxw_msc
#define fx_add_shl    fxw_add_shl
#define fx_round      fxw_round
#define fx_round_u    fxw_round_u
#define fx_round_sat  fxw_round_sat
#define fx_small      fxw_small
#endif

/* round(x · y / 2^sh), the caller guarantees the result fits (0 ≤ sh ≤ 62) */
FX_STATIC int32_t fx_mul(int32_t x, int32_t y, uint8_t sh)
{
    fx_acc a;
    fx_zero(&a);
    fx_mac(&a, x, y);
    return fx_round(&a, sh);
}

/* 1 if |Φ|² ≤ FX_PHI2_MAX_Q24 / 2^24 (the domain of q(Φ), see
 * fixed_internal.h): exact sum of squares rounded once. */
FX_STATIC int fx_phi_in_range(const int32_t phi[3], uint32_t max_q24)
{
    fx_acc acc;
    fx_zero(&acc);
    fx_mac(&acc, phi[0], phi[0]);
    fx_mac(&acc, phi[1], phi[1]);
    fx_mac(&acc, phi[2], phi[2]);
    return fx_round_u(&acc, 36) <= max_q24;
}

#endif /* FX_PRIM_MINIMAL */

#endif /* ATT_FIXED_PRIM_H */
