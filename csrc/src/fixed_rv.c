/*
 * libattitude fixed point: the update kernel (rotation vector → quaternion,
 * quaternion product with folded renormalization, the rotation vectors of
 * rv3 and of the reuse forms). This file alone is what an rv3 update or a
 * reuse-form update needs (its 8051 flash size with -DATT_FX_RV3_ONLY is
 * the "rv3 alone" figure of docs/fixed-point.md, with -DATT_FX_REUSE_ONLY
 * the "reuse alone" one). Integer-only.
 */
#include "attitude/fixed.h"

#include "fixed_internal.h"
#if !defined(__SDCC) && !defined(ATT_FX_COMPACT) /* the compact build has its own */
#include "fixed_prim.h"
#endif

/* Series coefficients in Q2.30 for v = φ²/8 (φ = |Φ|):
 *   cos(φ/2)          = Σ (−v)^n · 2^n/(2n)!
 *   sin(φ/2) / (φ/2)  = Σ (−v)^n · 2^n/(2n+1)!
 * (the n-th power of φ²/4 = 2v). */
static const int32_t fx_cs_k[2][8] = {
    { 1073741824L, 1073741824L, 178956971L, 11930465L, 426088L, 9469L, 143L, 2L },
    { 1073741824L, 357913941L, 35791394L, 1704352L, 47343L, 861L, 11L, 0L }
};
#define fx_cos_k fx_cs_k[0]
#define fx_sin_k fx_cs_k[1]
/* Largest v (Q2.30) for which degree n+1 suffices: the first omitted term
 * v^(n+2)·2^(n+2)/(2n+4)! of the cosine series is below 2^-33 (the sine
 * series converges faster). Degree 7 covers v ≤ 1.2 (φ ≤ 3.1). */
static const int32_t fx_deg_vmax[6] = { 28378L, 2349547L, 24989211L, 113507487L, 331839229L, 747556367L };

/* -DATT_FX_RV3_ONLY / -DATT_FX_REUSE_ONLY: in the compact build, leave only
 * att_fx_update_rv3 / att_fx_update_reuse (the 8051 flash figures) */
#if (defined(__SDCC) || defined(ATT_FX_COMPACT)) && (defined(ATT_FX_RV3_ONLY) || defined(ATT_FX_REUSE_ONLY))
#define FX_KERNEL_ONLY 1
#endif

#ifndef FX_KERNEL_ONLY
uint32_t att__fx_dither_seed(const att_q30 q[4])
{
    uint32_t x = (uint32_t)q[0] ^ (uint32_t)q[1] ^ (uint32_t)q[2] ^ (uint32_t)q[3];
    x ^= x >> 16;
    x *= 0x85EBCA6Bul;
    x ^= x >> 13;
    x *= 0xC2B2AE35ul;
    x ^= x >> 16;
    return (x != 0u) ? x : 1u; /* 0 would mean "no dither" */
}

int att__fx_dtheta_ok(const att_q30 *d, uint8_t n)
{
    uint8_t i;
    for (i = 0; i < n; ++i) {
        if (FX_DBAD(d[i])) {
            return 0;
        }
    }
    return 1;
}
#endif

#if defined(__SDCC) || defined(ATT_FX_COMPACT)
/*
 * Compact build (the 8051: AT89S51, 4 KB flash, 128 bytes of RAM; on a
 * host with -DATT_FX_COMPACT for testing): the same arithmetic, bit for
 * bit, written for code size and RAM. The working values live in a
 * register file of eight 32-bit words (fxr, in directly addressed RAM),
 * addressed by one-byte indices, so that every step is a short call with
 * constant arguments; each phase's use of the registers is documented at
 * the phase. Every product — the dither hash's included — goes through
 * one multiply-accumulate routine on byte limbs (fxa_mac: sixteen 8 × 8 →
 * 16-bit products, the 8051's MUL AB, into an 8-byte accumulator); no
 * 32-bit multiply routine of the compiler's library is linked. Products
 * to subtract use a negated copy of an operand (exact). Two register
 * indices are packed into one byte argument (FX_M): one-parameter
 * functions take it in a register, with no static parameter block. The
 * caller's arrays are read through one loader (fx_ld7; generic pointers
 * are costly on the 8051). Not reentrant: no interrupt handler may call
 * these functions.
 *
 * Words are read as their little-endian bytes through unions (SDCC's
 * mcs51 port and the test hosts are little-endian).
 */
#if defined(__BYTE_ORDER__) && defined(__ORDER_LITTLE_ENDIAN__)
#if __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
#error "the compact fixed-point build reads words as little-endian bytes"
#endif
#endif
#ifdef __SDCC
#define FX_DATA __data
#else
#define FX_DATA
#endif

typedef union {
    int32_t s;
    uint32_t u;
    uint8_t b[4];
} fx_word;

enum {
    FX_R7 = 7, /* the operand register */
    FX_NREG = 8,
    FX_Q = 0x10,    /* fx_ld7: load from Q (else from the increments) */
    FX_ADD = 0x20,  /* fx_ld7: R7 += value */
    FX_SUB = 0x40,  /* fx_ld7: R7 −= value */
    FX_NEGL = 0x60, /* fx_ld7: R7 = −value */
    FX_SH30 = 0x10  /* fxa_out: shift 30 (else 31) */
};
/* fxa_mac argument: x register in the high nibble, y in the low one */
#define FX_M(x, y) ((uint8_t)(((x) << 4) | (y)))
static FX_DATA fx_word fxr[FX_NREG];
static FX_DATA union {
    struct {
        uint32_t lo;
        uint32_t hi;
    } w;
    uint8_t b[8];
} fxa;                           /* accumulator (hi:lo), two's complement */
static const att_q30 *fx_dp;     /* increments of the update */
static att_q30 *fx_qp;           /* attitude being updated */
static uint32_t fx_t;            /* dither seed of the update (0: plain rounding) */
static uint8_t fx_i, fx_j, fx_k; /* loop indices of the phases */

/* R7 = / += / −= / = − (op & 0x60) the value d[op & 15] or, with FX_Q, q[op & 15] */
static void fx_ld7(uint8_t op)
{
    fx_word v;
    uint8_t i = (uint8_t)(op & 15u);
    v.s = (op & FX_Q) ? fx_qp[i] : fx_dp[i];
    op &= 0x60u;
    if (op == 0u) {
        fxr[FX_R7].s = v.s;
    } else if (op == FX_ADD) {
        fxr[FX_R7].u += v.u;
    } else {
        if (op == FX_NEGL) {
            fxr[FX_R7].u = 0;
        }
        fxr[FX_R7].u -= v.u;
    }
}

/* fxa += fxr[xy >> 4] · fxr[xy & 15], signed 32 × 32 → 64 bits, modulo
 * 2^64: the unsigned product row by row from 8 × 8 → 16-bit products
 * (product + accumulator byte + carry ≤ 0xFE01 + 0xFF + 0xFF = 0xFFFF; the
 * row's carry then rippled into the upper bytes), then the two's-complement
 * correction x·y = ux·uy − 2^32·((x < 0 ? uy : 0) + (y < 0 ? ux : 0)). */
static void fxa_mac(uint8_t xy)
{
    uint8_t i, j, c, xi;
    uint16_t s;
    FX_DATA fx_word *x = &fxr[xy >> 4];
    FX_DATA fx_word *y = &fxr[xy & 15u];
    FX_DATA uint8_t *a;
    for (i = 0; i < 4u; ++i) {
        xi = x->b[i];
        a = &fxa.b[i];
        c = 0;
        for (j = 0; j < 4u; ++j) {
            s = (uint16_t)(xi * y->b[j]);
            s += *a;
            s += c;
            *a++ = (uint8_t)s;
            c = (uint8_t)(s >> 8);
        }
        /* propagate the carry into bytes i + 4 .. 7 */
        for (j = (uint8_t)(i + 4u); c != 0u && j < 8u; ++j) {
            s = (uint16_t)(*a + c);
            *a++ = (uint8_t)s;
            c = (uint8_t)(s >> 8);
        }
    }
    if (x->s < 0) {
        fxa.w.hi -= y->u;
    }
    if (y->s < 0) {
        fxa.w.hi -= x->u;
    }
}

static void fxa_set(uint32_t lo)
{
    fxa.w.lo = lo;
    fxa.w.hi = 0;
}

/* fxr[dn & 15] = floor(fxa / 2^31), or 2^30 with FX_SH30 (low 32 bits);
 * fxa is consumed */
static void fxa_out(uint8_t dn)
{
    uint8_t k, c, t;
    for (;;) {
        c = 0;
        for (k = 0; k < 8u; ++k) {
            t = fxa.b[k];
            fxa.b[k] = (uint8_t)((t << 1) | c);
            c = (uint8_t)(t >> 7);
        }
        if (!(dn & FX_SH30)) {
            break;
        }
        dn &= 15u;
    }
    fxr[dn].u = fxa.w.hi;
}

/* fxr[dst] = round(fxr[R7] · fxr[dst] / 2^30) */
static void fxa_mul30(uint8_t dst)
{
    fxa_set(0x20000000ul);
    fxa_mac(FX_M(FX_R7, dst));
    fxa_out((uint8_t)(dst | FX_SH30));
}

/* fx_t *= m (low 32 bits of the product; uses R6, R7) */
static void fxc_tmul(uint32_t m)
{
    fxr[6].u = fx_t;
    fxr[FX_R7].u = m;
    fxa_set(0);
    fxa_mac(FX_M(6, FX_R7));
    fx_t = fxa.w.lo;
}

/* fx_t = fx_dither_seed(Q) (the same MurmurHash3 finalizer) */
static void fxc_seed(void)
{
    fx_t = 0;
    for (fx_i = 0; fx_i < 4u; ++fx_i) {
        fx_ld7((uint8_t)(fx_i | FX_Q));
        fx_t ^= fxr[FX_R7].u;
    }
    fx_t ^= fx_t >> 16;
    fxc_tmul(0x85EBCA6Bul);
    fx_t ^= fx_t >> 13;
    fxc_tmul(0xC2B2AE35ul);
    fx_t ^= fx_t >> 16;
    if (fx_t == 0u) {
        fx_t = 1u;
    }
}

/* fxa = D of FX_DITHER30(fx_t, k): fx_t rotated right by k, top 30 bits */
static void fxa_dither(uint8_t k)
{
    fxa_set(0x20000000ul);
    if (fx_t != 0u) {
        fxa.w.lo = fx_t;
        while (k-- != 0u) {
            uint8_t c = (uint8_t)(fxa.b[0] & 1u);
            fxa.w.lo >>= 1;
            if (c != 0u) {
                fxa.b[3] |= 0x80u;
            }
        }
        fxa.w.lo >>= 2;
    }
}

/* cross-product index pairs: component i uses j = (i+1)%3, k = (i+2)%3;
 * fx_jk and fx_phid repeat from index 4 (fxc_phi_reuse's poly pass) */
#ifdef ATT_FX_RV3_ONLY
static const uint8_t fx_jk[4] = { 1, 2, 0, 1 };
static const uint8_t fx_phid[3] = { 6, 2, 5 };
#else
static const uint8_t fx_jk[8] = { 1, 2, 0, 1, 1, 2, 0, 1 };
static const uint8_t fx_phid[7] = { 6, 2, 5, 0, 6, 2, 5 };
#endif
static const uint8_t fx_rot[6] = { 1, 11, 22, 6, 17, 27 };

/* End of component fx_i of a Φ routine, the integer sum of its increments
 * in R7: Φ_i = floor(fxa / 2^30) + R7 into register fx_phid[fx_i] (6, 2,
 * 5: the ones free at that point of both routines). */
static void fxc_phi_out(void)
{
    fx_j = fx_phid[fx_i];
    fxa_out((uint8_t)(fx_j | FX_SH30));
    fxr[fx_j].u += fxr[FX_R7].u;
}

#ifndef ATT_FX_REUSE_ONLY
/*
 * Φ of the increments at fx_dp into fxr[0..2], coefficients k13, k23 in
 * fxr[6], fxr[5] on entry. Registers: a = k13 Δθ1 in R0..R2, b = k23 Δθ2
 * in R3..R5, operand in R7; Φ_0 goes to R6, Φ_1 over a2 (component 2 uses
 * a0, a1, b0, b1 only), Φ_2 over b2. Subtracted products use a negated
 * increment: −a_k e_j = a_k·(−e_j), −b_k w_j = b_k·(Δθ1_j − e_j).
 */
static void fxc_phi_rv3(void)
{
    for (fx_i = 0; fx_i < 6u; ++fx_i) {
        /* R_i = k13 for i < 3, k23 after (R5 is b2, written last); R7 = Δθ */
        fxr[fx_i].u = fxr[fx_i < 3u ? 6u : 5u].u;
        fx_ld7(fx_i);
        fxa_mul30(fx_i);
    }
    for (fx_i = 0; fx_i < 3u; ++fx_i) {
        fx_j = fx_jk[fx_i];
        fx_k = fx_jk[fx_i + 1u];
        fxa_dither(fx_rot[fx_i]);
        fx_ld7((uint8_t)(6u + fx_k));
        fxa_mac(FX_M(fx_j, FX_R7)); /* a_j e_k */
        fx_ld7((uint8_t)((6u + fx_j) | FX_NEGL));
        fxa_mac(FX_M(fx_k, FX_R7)); /* − a_k e_j */
        fx_ld7((uint8_t)(6u + fx_k));
        fx_ld7((uint8_t)(fx_k | FX_SUB));
        fxa_mac(FX_M(3u + fx_j, FX_R7)); /* b_j w_k */
        fx_ld7(fx_j);
        fx_ld7((uint8_t)((6u + fx_j) | FX_SUB));
        fxa_mac(FX_M(3u + fx_k, FX_R7)); /* − b_k w_j */
        fx_ld7(fx_i);
        fx_ld7((uint8_t)((3u + fx_i) | FX_ADD));
        fx_ld7((uint8_t)((6u + fx_i) | FX_ADD));
        fxc_phi_out();
    }
    fxr[0].u = fxr[6].u;
    fxr[1].u = fxr[2].u;
    fxr[2].u = fxr[5].u;
}

#ifndef FX_KERNEL_ONLY
void att__fx_phi_rv3(const att_q30 d[9], int32_t k13, int32_t k23, uint32_t t, att_q30 phi[3])
{
    fx_dp = d;
    fx_t = t;
    fxr[6].s = k13;
    fxr[5].s = k23;
    fxc_phi_rv3();
    phi[0] = fxr[0].s;
    phi[1] = fxr[1].s;
    phi[2] = fxr[2].s;
}
#endif
#endif /* !ATT_FX_REUSE_ONLY */

#ifndef ATT_FX_RV3_ONLY
/*
 * Φ of a reuse form from d = [Δθ1, Δθ2, Δθ3] at fx_dp (Δθ3 the newest) into
 * fxr[0..2]: Φ = Δθ3 + u × Δθ3 (+ p × Δθ2 with poly), u = k13 Δθ1 + k23 Δθ2
 * (one rounding of the exact two-term sum), p = k12 Δθ1 (the arithmetic of
 * the fast att__fx_phi_reuse). Registers: k13, k23 in R6, R2; p to R3..R5
 * (poly only); u to R0..R2 (u2 over k23 once its sum is formed); operand
 * in R7; Φ_0 goes to R6, Φ_1 over u2 (component 2 uses u0, u1, p0, p1
 * only), Φ_2 over R5. The form is kept in fx_k (0 or 4) until the
 * component loop and there in bit 2 of its index fx_i (0..2 or 4..6; the
 * index tables repeat), so it needs no byte of RAM of its own (the
 * update's static RAM is at the AT89S51's limit). Subtracted products use
 * a negated increment.
 */
static void fxc_phi_reuse(uint8_t poly)
{
    if (poly) {
        fx_k = 4;
        fxr[6].s = ATT_FX_K_RV3RP_13;
        fxr[2].s = ATT_FX_K_RV3RP_23;
    } else {
        fx_k = 0;
        fxr[6].s = ATT_FX_K_RV3R_13;
        fxr[2].s = ATT_FX_K_RV3R_23;
    }
    if (fx_k) {
        for (fx_i = 3; fx_i < 6u; ++fx_i) {
            fxr[fx_i].s = ATT_FX_K_RV3RP_12;
            fx_ld7((uint8_t)(fx_i - 3u));
            fxa_mul30(fx_i);
        }
    }
    for (fx_i = 0; fx_i < 3u; ++fx_i) {
        fxa_set(0x20000000ul); /* round to nearest: + 2^29, then floor */
        fx_ld7(fx_i);
        fxa_mac(FX_M(6, FX_R7));
        fx_ld7((uint8_t)(3u + fx_i));
        fxa_mac(FX_M(2, FX_R7));
        fxa_out((uint8_t)(fx_i | FX_SH30));
    }
    for (fx_i = fx_k; (uint8_t)(fx_i & 3u) != 3u; ++fx_i) {
        fx_j = fx_jk[fx_i];
        fx_k = fx_jk[fx_i + 1u];
        fxa_dither(fx_rot[(uint8_t)(fx_i & 3u)]);
        fx_ld7((uint8_t)(6u + fx_k));
        fxa_mac(FX_M(fx_j, FX_R7)); /* u_j Δθ3_k */
        fx_ld7((uint8_t)((6u + fx_j) | FX_NEGL));
        fxa_mac(FX_M(fx_k, FX_R7)); /* − u_k Δθ3_j */
        if (fx_i & 4u) {
            fx_ld7((uint8_t)(3u + fx_k));
            fxa_mac(FX_M(3u + fx_j, FX_R7)); /* p_j Δθ2_k */
            fx_ld7((uint8_t)((3u + fx_j) | FX_NEGL));
            fxa_mac(FX_M(3u + fx_k, FX_R7)); /* − p_k Δθ2_j */
        }
        fx_ld7((uint8_t)(6u + (uint8_t)(fx_i & 3u)));
        fxc_phi_out();
    }
    fxr[0].u = fxr[6].u;
    fxr[1].u = fxr[2].u;
    fxr[2].u = fxr[5].u;
}
#endif

#ifndef FX_KERNEL_ONLY
void att__fx_phi_reuse(const att_q30 d1[3], const att_q30 d2[3], const att_q30 d3[3], uint8_t poly,
                       uint32_t t, att_q30 phi[3])
{
    att_q30 w[9]; /* the three increments in one array for fx_ld7 */
    for (fx_i = 0; fx_i < 3u; ++fx_i) {
        w[fx_i] = d1[fx_i];
        w[3u + fx_i] = d2[fx_i];
        w[6u + fx_i] = d3[fx_i];
    }
    fx_dp = w;
    fx_t = t;
    fxc_phi_reuse(poly);
    phi[0] = fxr[0].s;
    phi[1] = fxr[1].s;
    phi[2] = fxr[2].s;
}
#endif

/* Horner step on c (R3, mn = 0x3n) or s (R4, mn = 0x4n): R = k_n − R, or
 * with bit 3 set R = k_(n & 7) (fx_cos_k / fx_sin_k) */
static void fxc_k(uint8_t mn)
{
    FX_DATA fx_word *r = &fxr[mn >> 4];
    if (mn & 8u) {
        r->s = 0;
    } else {
        r->u = 0u - r->u;
    }
    r->u += (uint32_t)fx_cs_k[(mn >> 4) - 3u][mn & 7u];
}

/* c, s into R3, R4 for Φ in R0..R2 (v in R7). Degree 1 (c = 1 − v·1,
 * s = 1 − v·(1/6)) is the Horner loop's first step. */
static void fxc_cs(void)
{
    uint8_t n;
    fxa_set(0);
    for (n = 0; n < 3u; ++n) {
        fxa_mac(FX_M(n, n));
    }
    fxr[FX_R7].u = (fxa.w.hi + 1u) >> 1; /* v = round(Σ/2^33): the half is 2^32 */
    n = 0;
    while (n < 6u && fxr[FX_R7].s > fx_deg_vmax[n]) {
        ++n;
    }
    ++n; /* degree */
    fxc_k((uint8_t)(0x38u | n));
    fxc_k((uint8_t)(0x48u | n));
    do {
        --n;
        fxa_mul30(3);
        fxc_k((uint8_t)(0x30u | n));
        fxa_mul30(4);
        fxc_k((uint8_t)(0x40u | n));
    } while (n != 0u);
}

#ifndef FX_KERNEL_ONLY
void att__fx_cs(const att_q30 phi[3], int32_t *cp, int32_t *sp)
{
    fxr[0].s = phi[0];
    fxr[1].s = phi[1];
    fxr[2].s = phi[2];
    fxc_cs();
    *cp = fxr[3].s;
    *sp = fxr[4].s;
}
#endif

/* rows of Q ⊗ [c, h] besides the 2·q_i·c term: output i adds
 * sign · q[fx_pq] · h[fx_ph] (signs as in the fast version) */
static const uint8_t fx_pq[4][3] = { { 1, 2, 3 }, { 0, 2, 3 }, { 0, 1, 3 }, { 0, 1, 2 } };
static const uint8_t fx_ph[4][3] = { { 0, 1, 2 }, { 0, 2, 1 }, { 1, 2, 0 }, { 2, 1, 0 } };
static const uint8_t fx_pneg[4] = { 7, 4, 2, 4 }; /* bit k set: subtract term k */
static const uint8_t fx_res[4] = { 4, 5, 6, 7 };

/* q_i = result i */
static void fx_st(uint8_t i)
{
    fx_qp[i] = fxr[fx_res[i]].s;
}

/* Q ← Q ⊗ q(Φ) for Q at fx_qp, Φ in R0..R2. Registers: h in R0..R2 (over
 * Φ), c then c2 in R3, s in R4, then the results r0..r3 in R4..R7 (r3:
 * the operand register, free after the last product), operand in R7. */
static att_status fxc_apply(void)
{
    fxc_cs();
    fxa_set(0);
    for (fx_i = 0; fx_i < 4u; ++fx_i) {
        fx_ld7((uint8_t)(fx_i | FX_Q));
        fxa_mac(FX_M(FX_R7, FX_R7));
    }
    fxa.w.hi -= 0x10000000ul;                      /* − 2^60 */
    if ((uint32_t)(fxa.w.hi + 0x100u) >= 0x200u) { /* |e| ≥ 2^-20 */
        return (att_status)ATT_FX_E_RANGE;
    }
    /* e/2 = round(Σ/2^31): add 2^30 then floor */
    fxa.w.lo += 0x40000000ul;
    if (fxa.w.lo < 0x40000000ul) {
        fxa.w.hi++;
    }
    fxa_out(FX_R7);
    fxr[3].u -= fxr[FX_R7].u;
    /* c2 = 2c − 2^31 (mod 2^32; fits int32: 0 ≤ c < 2^31) */
    fxr[3].u <<= 1;
    fxr[3].b[3] ^= 0x80u;
    for (fx_i = 0; fx_i < 3u; ++fx_i) {
        fxa_dither(fx_rot[3u + fx_i]);
        fxa_mac(FX_M(4, fx_i));
        fxa_out((uint8_t)(fx_i | FX_SH30));
    }
    for (fx_i = 0; fx_i < 4u; ++fx_i) {
        /* q_i·2^31 + 2^30, then + q_i·c2 (= 2·q_i·c) */
        fx_ld7((uint8_t)(fx_i | FX_Q));
        fxa.w.lo = 0x40000000ul;
        if (fxr[FX_R7].b[0] & 1u) {
            fxa.b[3] = 0xC0u;
        }
        fxa.w.hi = fxr[FX_R7].u >> 1;
        if (fxr[FX_R7].b[3] & 0x80u) {
            fxa.b[7] |= 0x80u;
        }
        fxa_mac(FX_M(FX_R7, 3));
        for (fx_k = 0; fx_k < 3u; ++fx_k) {
            /* − q·h as (−q)·h */
            fx_ld7((uint8_t)(fx_pq[fx_i][fx_k] | FX_Q | (((fx_pneg[fx_i] >> fx_k) & 1u) ? FX_NEGL : 0u)));
            fxa_mac(FX_M(FX_R7, fx_ph[fx_i][fx_k]));
        }
        fxa_out(fx_res[fx_i]);
    }
    for (fx_i = 0; fx_i < 4u; ++fx_i) {
        fx_st(fx_i);
    }
    return ATT_OK;
}

#ifndef FX_KERNEL_ONLY
att_status att__fx_apply(att_q30 q[4], const att_q30 phi[3], uint32_t t)
{
    fxr[0].s = phi[0];
    fxr[1].s = phi[1];
    fxr[2].s = phi[2];
    fx_qp = q;
    fx_t = t;
    return fxc_apply();
}

att_status att_fx_update_phi(att_q30 q[4], const att_q30 phi[3])
{
    uint8_t n;
    if (q == 0 || phi == 0) {
        return ATT_E_NULL;
    }
    fxa_set(0);
    for (n = 0; n < 3u; ++n) {
        fxr[n].s = phi[n];
        fxa_mac(FX_M(n, n));
    }
    /* |Φ|² ≤ 9.6: round(Σ/2^36) ≤ FX_PHI2_MAX_Q24, i.e. (hi + 8) >> 4 */
    if (((fxa.w.hi + 8u) >> 4) > FX_PHI2_MAX_Q24) {
        return (att_status)ATT_FX_E_RANGE;
    }
    return att__fx_apply(q, phi, fx_dither_seed(q));
}
#endif

/* Checks Q at fx_qp and the 9 increments at fx_dp: ATT_E_NULL or
 * ATT_FX_E_RANGE (|Δθ| > 0.4), else ATT_OK with the dither seed in fx_t */
static att_status fxc_begin(void)
{
    if (fx_qp == 0 || fx_dp == 0) {
        return ATT_E_NULL;
    }
    for (fx_i = 0; fx_i < 9u; ++fx_i) {
        fx_ld7(fx_i);
        if (FX_DBAD(fxr[FX_R7].s)) {
            return (att_status)ATT_FX_E_RANGE;
        }
    }
    fxc_seed();
    return ATT_OK;
}

#ifndef ATT_FX_REUSE_ONLY
att_status att_fx_update_rv3(att_q30 q[4], const att_q30 d[9])
{
    att_status st;
    fx_qp = q;
    fx_dp = d;
    st = fxc_begin();
    if (st != ATT_OK) {
        return st;
    }
    fxr[6].s = ATT_FX_K_RV3_13;
    fxr[5].s = ATT_FX_K_RV3_23;
    fxc_phi_rv3();
    return fxc_apply();
}
#endif

#ifndef ATT_FX_RV3_ONLY
att_status att_fx_update_reuse(att_q30 q[4], const att_q30 d[9], att_fx_method method)
{
    att_status st;
    if (method != ATT_FX_RV3_REUSE && method != ATT_FX_RV3_REUSE_POLY) {
        return (att_status)ATT_FX_E_METHOD;
    }
    fx_qp = q;
    fx_dp = d;
    st = fxc_begin();
    if (st != ATT_OK) {
        return st;
    }
    fxc_phi_reuse(method == ATT_FX_RV3_REUSE_POLY);
    return fxc_apply();
}
#endif

#else /* fast build: unrolled, 64-bit or halves primitive from fixed_prim.h */

/*
 * Three-sample rotation vector with k12 = k23 (rv3, rv3-coning):
 *   Φ = Δθ1 + Δθ2 + Δθ3 + a × Δθ3 + b × w,  a = k13 Δθ1, b = k23 Δθ2, w = Δθ3 − Δθ1
 * Inputs Q2.30 with |Δθ| ≤ 0.4: a, b rounded to Q2.30 (|a|, |b| ≤ 0.29),
 * w exact (|w| ≤ 0.8). Per component the four cross-product terms are
 * accumulated exactly in Q4.60 and rounded once to Q2.30 (shift 30), then
 * the exact integer sum is added (= one rounding of the exact total); |Φ_i| ≤ 3·0.4 + 2·0.29·0.4 + 2·0.29·0.8 = 1.9 < 2,
 * so no saturation is needed. Subtracted products use a negated operand
 * (one multiply-accumulate each).
 */
void att__fx_phi_rv3(const att_q30 d[9], int32_t k13, int32_t k23, uint32_t t, att_q30 phi[3])
{
    int32_t a0, a1, a2, b0, b1, b2, w0, w1, w2, e0, e1, e2;
    fx_acc acc;
    a0 = fx_mul(k13, d[0], 30);
    a1 = fx_mul(k13, d[1], 30);
    a2 = fx_mul(k13, d[2], 30);
    b0 = fx_mul(k23, d[3], 30);
    b1 = fx_mul(k23, d[4], 30);
    b2 = fx_mul(k23, d[5], 30);
    e0 = d[6];
    e1 = d[7];
    e2 = d[8];
    w0 = e0 - d[0];
    w1 = e1 - d[1];
    w2 = e2 - d[2];

    /* round(S·2^30 + X) / 2^30 = S + round(X / 2^30) for an integer sum S
     * (dithered: floor((X + D) / 2^30), see FX_DITHER30) */
    fx_init_u(&acc, FX_DITHER30(t, 1u));
    fx_mac(&acc, a1, e2);
    fx_mac(&acc, -a2, e1);
    fx_mac(&acc, b1, w2);
    fx_mac(&acc, -b2, w1);
    phi[0] = d[0] + d[3] + e0 + fx_floor(&acc, 30);

    fx_init_u(&acc, FX_DITHER30(t, 11u));
    fx_mac(&acc, a2, e0);
    fx_mac(&acc, -a0, e2);
    fx_mac(&acc, b2, w0);
    fx_mac(&acc, -b0, w2);
    phi[1] = d[1] + d[4] + e1 + fx_floor(&acc, 30);

    fx_init_u(&acc, FX_DITHER30(t, 22u));
    fx_mac(&acc, a0, e1);
    fx_mac(&acc, -a1, e0);
    fx_mac(&acc, b0, w1);
    fx_mac(&acc, -b1, w0);
    phi[2] = d[2] + d[5] + e2 + fx_floor(&acc, 30);
}

/*
 * Reuse forms, two previous increments (d1 older, d2, d3 newest):
 *   Φ = d3 + u × d3 (+ p × d2),  u = k13 d1 + k23 d2,  p = k12 d1
 *   rv3-reuse:      k13 = −1/60, k23 = 7/60 (k12 = 0: no p term)
 *   rv3-reuse-poly: k12 = 1/720, k13 = −31/720, k23 = 121/720
 * u one rounding of an exact two-term Q4.60 sum, p rounded to Q2.30 (shift
 * 30); per component the cross terms accumulated exactly and rounded once
 * (shift 30, dithered), the integer d3 added. With |Δθ| ≤ 0.4:
 * rv3-reuse |u_i| ≤ (8/60)·0.4, |Φ_i| ≤ 0.4 + 2·0.053·0.4 < 0.45;
 * poly |u_i| ≤ (152/720)·0.4, |Φ_i| ≤ 0.4 + 2·(0.084 + 0.0006)·0.4 < 0.47.
 */
void att__fx_phi_reuse(const att_q30 d1[3], const att_q30 d2[3], const att_q30 d3[3], uint8_t poly,
                       uint32_t t, att_q30 phi[3])
{
    int32_t p0 = 0, p1 = 0, p2 = 0, u0, u1, u2, k13, k23;
    fx_acc acc;
    if (poly) {
        p0 = fx_mul(ATT_FX_K_RV3RP_12, d1[0], 30);
        p1 = fx_mul(ATT_FX_K_RV3RP_12, d1[1], 30);
        p2 = fx_mul(ATT_FX_K_RV3RP_12, d1[2], 30);
        k13 = ATT_FX_K_RV3RP_13;
        k23 = ATT_FX_K_RV3RP_23;
    } else {
        k13 = ATT_FX_K_RV3R_13;
        k23 = ATT_FX_K_RV3R_23;
    }
#define FX_U(u, i)            \
    fx_zero(&acc);            \
    fx_mac(&acc, k13, d1[i]); \
    fx_mac(&acc, k23, d2[i]); \
    u = fx_round(&acc, 30)
    FX_U(u0, 0);
    FX_U(u1, 1);
    FX_U(u2, 2);
#undef FX_U
    /* component i (j, k the next two, cyclic); the p × d2 terms are exact
     * zeros for rv3-reuse (p = 0): skipped. Unrolled (a loop costs ARM ~20 %) */
#define FX_PHI(i, j, k, uj, uk, pj, pk, ROT) \
    fx_init_u(&acc, FX_DITHER30(t, ROT));    \
    fx_mac(&acc, uj, d3[k]);                 \
    fx_mac(&acc, -(uk), d3[j]);              \
    if (poly) {                              \
        fx_mac(&acc, pj, d2[k]);             \
        fx_mac(&acc, -(pk), d2[j]);          \
    }                                        \
    phi[i] = d3[i] + fx_floor(&acc, 30)
    FX_PHI(0, 1, 2, u1, u2, p1, p2, 1u);
    FX_PHI(1, 2, 0, u2, u0, p2, p0, 11u);
    FX_PHI(2, 0, 1, u0, u1, p0, p1, 22u);
#undef FX_PHI
}

/*
 * c = cos(φ/2), s = sin(φ/2)/(φ/2) (both Q2.30) for |Φ|² ≤ 9.6:
 *  1. v = |Φ|²/8: exact Q4.60 sum of squares (< 9.6·2^60 < 2^64, unsigned),
 *     rounded to Q2.30 (shift 33); v ≤ 1.2.
 *  2. Horner in v, Q2.30, one rounding per step (|partial sums| ≤ 1),
 *     degree from fx_deg_vmax (degree 1, v ≤ 2.6e-5 i.e. φ ≤ 0.0145 rad,
 *     is the common case and has a short path: c = 1 − v exactly).
 */
void att__fx_cs(const att_q30 phi[3], int32_t *cp, int32_t *sp)
{
    fx_acc acc;
    int32_t v, c, s;
    int8_t n, deg;

    fx_zero(&acc);
    fx_mac(&acc, phi[0], phi[0]);
    fx_mac(&acc, phi[1], phi[1]);
    fx_mac(&acc, phi[2], phi[2]);
    v = (int32_t)fx_round_u(&acc, 33);

    if (v <= fx_deg_vmax[0]) {
        *cp = (int32_t)ATT_FX_Q30_ONE - v;
        *sp = (int32_t)ATT_FX_Q30_ONE - fx_mul(v, fx_sin_k[1], 30);
        return;
    }
    deg = 7;
    for (n = 1; n < 6; ++n) {
        if (v <= fx_deg_vmax[n]) {
            deg = (int8_t)(n + 1);
            break;
        }
    }
    c = fx_cos_k[deg];
    s = fx_sin_k[deg];
    for (n = (int8_t)(deg - 1); n >= 0; --n) {
        c = fx_cos_k[n] - fx_mul(v, c, 30);
        s = fx_sin_k[n] - fx_mul(v, s, 30);
    }
    *cp = c;
    *sp = s;
}

/*
 * Q ← Q ⊗ q(Φ), renormalization folded into q:
 *  1-2. c, s from att__fx_cs.
 *  3. e = |Q|² − 1: exact Q4.60 sum minus 2^60; |e| < 2^-20 is required
 *     (else ATT_FX_E_RANGE, Q untouched: Q was not a unit quaternion of
 *     this module); e/2 rounded to Q2.30 (shift 31).
 *  4. c ← c − e/2, so that |Q ⊗ q|² = (1 + e)(c² − c·e + |h|²) = 1 + O(e·(1 − c))
 *     + rounding: the norm error is removed at every update, without a
 *     separate normalization pass and without a second rounding of Q.
 *  5. h = s·Φ/2 in Q1.31 (|h| ≤ sin(1.55) < 1): Q2.30 × Q2.30 → shift 30,
 *     dithered rounding h = floor((s·Φ + D)/2^30) with D ∈ [0, 2^30) a
 *     hash of the low bits of Q (Knuth's multiplicative hash). Plain
 *     rounding of h is biased for smooth motion: h differs from the
 *     integer Φ by the tiny, slowly varying (s − 1)·Φ/2, so its rounding
 *     error repeats update after update and the attitude drifts linearly.
 *     With D uniform, E[h] = s·Φ/2 exactly and the error is white.
 *     Deterministic: the same bits on every target.
 *  6. Q ⊗ [c, h] in Q3.61: Q·h terms (Q2.30 × Q1.31) and Q·c twice
 *     (Q2.30 × Q2.30 = Q60, doubled); the exact sum of each component is
 *     bounded by |Q||q| ≈ 2^61 and rounded once to Q2.30 (shift 31).
 */
att_status att__fx_apply(att_q30 q[4], const att_q30 phi[3], uint32_t t)
{
    fx_acc acc;
    int32_t c, c2, s, e, h1, h2, h3, q0, q1, q2, q3;

    att__fx_cs(phi, &c, &s);
    q0 = q[0];
    q1 = q[1];
    q2 = q[2];
    q3 = q[3];

    fx_zero(&acc);
    fx_mac(&acc, q0, q0);
    fx_mac(&acc, q1, q1);
    fx_mac(&acc, q2, q2);
    fx_mac(&acc, q3, q3);
    fx_add_shl(&acc, -(int32_t)ATT_FX_Q30_ONE, 30);
    if (!fx_small(&acc, 40)) {
        return (att_status)ATT_FX_E_RANGE;
    }
    e = fx_round(&acc, 31);
    c -= e;

#define FX_H(hk, ROT, pk)                 \
    fx_init_u(&acc, FX_DITHER30(t, ROT)); \
    fx_mac(&acc, s, pk);                  \
    hk = fx_floor(&acc, 30)
    FX_H(h1, 6u, phi[0]);
    FX_H(h2, 17u, phi[1]);
    FX_H(h3, 27u, phi[2]);
#undef FX_H

    /* 2·Q_i·c = Q_i·2^31 + Q_i·c2 with c2 = 2c − 2^31 (fits int32: 0 ≤ c < 2^31);
     * the accumulator starts at Q_i·2^31 + 2^30 (the rounding half). */
    c2 = fx_u2s((uint32_t)c * 2u - 0x80000000ul);
    fx_init_shl31(&acc, q0);
    fx_mac(&acc, q0, c2);
    fx_mac(&acc, q1, -h1);
    fx_mac(&acc, q2, -h2);
    fx_mac(&acc, q3, -h3);
    q[0] = fx_floor(&acc, 31);

    fx_init_shl31(&acc, q1);
    fx_mac(&acc, q0, h1);
    fx_mac(&acc, q1, c2);
    fx_mac(&acc, q2, h3);
    fx_mac(&acc, q3, -h2);
    q[1] = fx_floor(&acc, 31);

    fx_init_shl31(&acc, q2);
    fx_mac(&acc, q0, h2);
    fx_mac(&acc, q1, -h3);
    fx_mac(&acc, q2, c2);
    fx_mac(&acc, q3, h1);
    q[2] = fx_floor(&acc, 31);

    fx_init_shl31(&acc, q3);
    fx_mac(&acc, q0, h3);
    fx_mac(&acc, q1, h2);
    fx_mac(&acc, q2, -h1);
    fx_mac(&acc, q3, c2);
    q[3] = fx_floor(&acc, 31);
    return ATT_OK;
}

att_status att_fx_update_phi(att_q30 q[4], const att_q30 phi[3])
{
    if (q == 0 || phi == 0) {
        return ATT_E_NULL;
    }
    if (!fx_phi_in_range(phi, FX_PHI2_MAX_Q24)) {
        return (att_status)ATT_FX_E_RANGE;
    }
    {
        uint32_t t = fx_dither_seed(q);
        return att__fx_apply(q, phi, t);
    }
}

att_status att_fx_update_rv3(att_q30 q[4], const att_q30 d[9])
{
    att_q30 phi[3];
    uint32_t t;
    if (q == 0 || d == 0) {
        return ATT_E_NULL;
    }
    if (FX_DBAD(d[0]) || FX_DBAD(d[1]) || FX_DBAD(d[2]) || FX_DBAD(d[3]) || FX_DBAD(d[4]) || FX_DBAD(d[5])
        || FX_DBAD(d[6]) || FX_DBAD(d[7]) || FX_DBAD(d[8])) {
        return (att_status)ATT_FX_E_RANGE;
    }
    t = fx_dither_seed(q);
    att__fx_phi_rv3(d, ATT_FX_K_RV3_13, ATT_FX_K_RV3_23, t, phi);
    return att__fx_apply(q, phi, t);
}

att_status att_fx_update_reuse(att_q30 q[4], const att_q30 d[9], att_fx_method method)
{
    att_q30 phi[3];
    uint32_t t;
    if (method != ATT_FX_RV3_REUSE && method != ATT_FX_RV3_REUSE_POLY) {
        return (att_status)ATT_FX_E_METHOD;
    }
    if (q == 0 || d == 0) {
        return ATT_E_NULL;
    }
    if (!att__fx_dtheta_ok(d, 9u)) {
        return (att_status)ATT_FX_E_RANGE;
    }
    t = fx_dither_seed(q);
    att__fx_phi_reuse(d, d + 3, d + 6, method == ATT_FX_RV3_REUSE_POLY, t, phi);
    return att__fx_apply(q, phi, t);
}

#endif /* compact / fast */
