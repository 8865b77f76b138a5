/*
 * s51_sif.h — helpers for 8051 programs run under the s51 harness
 * (toolchain/s51.py). SDCC only; link toolchain/s51_sif.c (the harness
 * does it for you).
 *
 * The simulator interface of uCsim sits on SFR 0xFF (s51 -I if=sfr[0xff]):
 * the program writes a one-character command there. The harness uses
 *   'w' c  : write character c to the interface output file (program text),
 *   's'    : stop the simulation (s51 -G then exits).
 *
 * Cycle counting uses Timer 0 in 16-bit mode: in the 12-clock C51 core it
 * counts one per machine cycle. S51_CYCLES_BEGIN() starts it and
 * S51_CYCLES_END() stops it; s51_cycles() returns the machine cycles spent
 * between the two (the 1-cycle CLR TR0 of the END macro is subtracted), or
 * 0xFFFF when the 16-bit timer overflowed (region longer than 65534 cycles).
 * The program must not use Timer 0 itself while measuring.
 */
#ifndef S51_SIF_H
#define S51_SIF_H

#include <8051.h>

__sfr __at(0xff) S51_SIF;

#define S51_CYCLES_BEGIN()                            \
    do {                                              \
        TR0 = 0;                                      \
        TMOD = (unsigned char)((TMOD & 0xF0) | 0x01); \
        TH0 = 0;                                      \
        TL0 = 0;                                      \
        TF0 = 0;                                      \
        TR0 = 1;                                      \
    } while (0)
#define S51_CYCLES_END() \
    do {                 \
        TR0 = 0;         \
    } while (0)

/* Machine cycles between BEGIN and END (0xFFFF on overflow). */
unsigned int s51_cycles(void);

void s51_putc(char c);
void s51_puts(const char *s);
/* Unsigned decimal / 4-digit hex (no newline). */
void s51_putu(unsigned long v);
void s51_puthex(unsigned int v);
/* Print "CYCLES <label> <n>\n" with n = s51_cycles(); the harness
 * collects these into S51Result.cycles. */
void s51_report_cycles(const char *label);
/* Print "EXIT <code>\n" and stop the simulation; never returns. */
void s51_exit(unsigned char code);

#endif
