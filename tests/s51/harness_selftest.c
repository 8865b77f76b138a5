/* Self-test program for toolchain/s51.py (run by tests/test_s51_harness.py). */
#include "s51_sif.h"

void main(void)
{
    unsigned char c;

    s51_puts("hello 8051\n");
    s51_putu(4000000000UL);
    s51_putc(' ');
    s51_puthex(0xBEEFu);
    s51_putc('\n');

    S51_CYCLES_BEGIN();
    S51_CYCLES_END();
    s51_report_cycles("empty");

    S51_CYCLES_BEGIN();
    /* clang-format off */
    __asm
        nop
        nop
        nop
        nop
        nop
        nop
        nop
        nop
        nop
        nop
    __endasm;
    /* clang-format on */
    S51_CYCLES_END();
    s51_report_cycles("ten_nops");

    /* NOP = 1, DJNZ = 2 cycles: 100 iterations = 300 cycles + MOV (1). */
    S51_CYCLES_BEGIN();
    /* clang-format off */
    __asm
        mov r7,#100
    00001$:
        nop
        djnz r7,00001$
    __endasm;
    /* clang-format on */
    S51_CYCLES_END();
    s51_report_cycles("nop_djnz100");

    /* echo the UART input, upper-cased, until a newline */
    SCON = 0x50;
    TMOD = (unsigned char)((TMOD & 0x0F) | 0x20);
    TH1 = 0xFD;
    TR1 = 1;
    for (;;) {
        while (!RI) {
        }
        RI = 0;
        c = SBUF;
        if (c >= 'a' && c <= 'z') {
            c = (unsigned char)(c - 32);
        }
        TI = 0;
        SBUF = c;
        while (!TI) {
        }
        if (c == '\n') {
            break;
        }
    }
    s51_exit(3);
}
