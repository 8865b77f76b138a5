/*
 * 8051 run of a fixed-point update kernel (tests/test_fixed_targets.py):
 * att_fx_update_rv3, or att_fx_update_reuse for one of the reuse forms.
 *
 * K = NUPD updates Q ← Q ⊗ q(Φ) from the increments of the generated
 * header fixed_kernel_inc.h (tests/test_fixed_targets.py writes it from a
 * 32-bit LCG, with FX_UPDATE naming the kernel, and replays the same
 * increments on the host, comparing every quaternion bit for bit). Prints one line per update: the four Q2.30
 * components as 8 hex digits. The last two updates are timed in machine
 * cycles with Timer 0 plus an overflow interrupt (the few cycles of each
 * ISR entry are inside the count: < 0.1 %), one with small increments
 * (≈ ±4.9e-4 rad: the degree-1 series) and one with large ones (±0.25 rad:
 * up to degree 4).
 *
 * Built for the AT89S51 (s51 -t C51): small model, 128 bytes of internal
 * RAM, no external RAM, 4 KB of code. The increments sit in code memory
 * (the update reads them through a generic pointer), so the program's own
 * RAM is Q (16 bytes) beside the update's static RAM and the stack.
 */
#include <8051.h>

#include "attitude/fixed.h"
#include "s51_sif.h"

#include "fixed_kernel_inc.h" /* NUPD, fx_inc[NUPD][9], FX_UPDATE (generated) */

static volatile unsigned char ovf;

/* Timer 0 overflow: ovf++ with no register saved, so the interrupt takes
 * only its return address (2 bytes) from the update's stack — the reuse
 * kernel leaves 13 bytes of stack, its deepest call chain needs 10. */
void t0_isr(void) __interrupt(1) __naked
{
    /* clang-format off */
    __asm
        inc _ovf
        reti
    __endasm;
    /* clang-format on */
}

static void put32(int32_t v)
{
    uint32_t u = (uint32_t)v;
    s51_puthex((unsigned int)(u >> 16));
    s51_puthex((unsigned int)(u & 0xFFFFu));
}

static att_q30 q[4];

void main(void)
{
    unsigned char k;
    unsigned int lo;
    int st;
    q[0] = ATT_FX_Q30_ONE;
    q[1] = 0;
    q[2] = 0;
    q[3] = 0;
    for (k = 0; k < NUPD; ++k) {
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
        st = FX_UPDATE(q, fx_inc[k]);
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
