/*
 * 8051 run of the fixed-point rv3 update (tests/test_fixed_targets.py).
 *
 * K = NUPD updates Q ← Q ⊗ q(Φ_rv3) from increments made by a 32-bit LCG
 * (the test replays the same LCG on the host and compares every
 * quaternion bit for bit). Prints one line per update: the four Q2.30
 * components as 8 hex digits. The last update is timed in machine cycles
 * with Timer 0 plus an overflow interrupt (the ~20 cycles of each ISR
 * entry are inside the count: < 0.1 %); the last two updates are timed,
 * one with small increments (≈ ±4.9e-4 rad: the degree-1 series) and one
 * with large ones (±0.25 rad: up to degree 4).
 *
 * RAM: the update needs ~60 bytes of its own plus the caller's 52-byte Q and
 * Δθ: more than an AT89S51 (128 bytes) can spare beside a stack, so the test
 * builds with --stack-auto for 256 bytes of internal RAM and runs on s51's
 * 8052 core (AT89S52); see docs/fixed-point.md.
 */
#include <8051.h>

#include "attitude/fixed.h"
#include "s51_sif.h"

#ifndef NUPD
#define NUPD 6
#endif

static volatile unsigned char ovf;

void t0_isr(void) __interrupt(1)
{
    ovf++;
}

static uint32_t x = 12345ul;

static int32_t next_inc(unsigned char big)
{
    x = x * 1664525ul + 1013904223ul;
    /* big: [-2^28, 2^28) = ±0.25 rad; small: [-2^19, 2^19) ≈ ±4.9e-4 rad */
    return big ? (int32_t)(x >> 3) - 268435456L : (int32_t)(x >> 12) - 524288L;
}

static void put32(int32_t v)
{
    uint32_t u = (uint32_t)v;
    s51_puthex((unsigned int)(u >> 16));
    s51_puthex((unsigned int)(u & 0xFFFFu));
}

static att_q30 q[4];
static att_q30 d[9];

void main(void)
{
    unsigned char k, i;
    unsigned int lo;
    int st;
    q[0] = ATT_FX_Q30_ONE;
    q[1] = 0;
    q[2] = 0;
    q[3] = 0;
    for (k = 0; k < NUPD; ++k) {
        for (i = 0; i < 9; ++i) {
            d[i] = next_inc((unsigned char)(k & 1u));
        }
        if (k >= NUPD - 2) {
            ovf = 0;
            TR0 = 0;
            TMOD = (unsigned char)((TMOD & 0xF0) | 0x01);
            TH0 = 0;
            TL0 = 0;
            TF0 = 0;
            ET0 = 1;
            EA = 1;
            TR0 = 1;
        }
        st = att_fx_update_rv3(q, d);
        if (k >= NUPD - 2) {
            TR0 = 0;
            EA = 0;
            lo = ((unsigned int)TH0 << 8) | TL0;
            s51_puts((k & 1u) ? "CYC big " : "CYC small ");
            s51_putu((unsigned long)ovf * 65536ul + lo);
            s51_putc('\n');
        }
        if (st != 0) {
            s51_exit(1);
        }
        put32(q[0]);
        s51_putc(' ');
        put32(q[1]);
        s51_putc(' ');
        put32(q[2]);
        s51_putc(' ');
        put32(q[3]);
        s51_putc('\n');
    }
    s51_exit(0);
}
