/* Helpers for 8051 programs run under toolchain/s51.py; see s51_sif.h. */
#include "s51_sif.h"

unsigned int s51_cycles(void)
{
    unsigned int t;
    if (TF0) {
        return 0xFFFFu;
    }
    t = ((unsigned int)TH0 << 8) | TL0;
    return t ? (unsigned int)(t - 1u) : 0u; /* minus the CLR TR0 of END */
}

void s51_putc(char c)
{
    S51_SIF = 'w';
    S51_SIF = (unsigned char)c;
}

void s51_puts(const char *s)
{
    while (*s) {
        s51_putc(*s++);
    }
}

void s51_putu(unsigned long v)
{
    char buf[11];
    unsigned char n = 0;
    do {
        buf[n++] = (char)('0' + (unsigned char)(v % 10u));
        v /= 10u;
    } while (v != 0u);
    while (n != 0u) {
        s51_putc(buf[--n]);
    }
}

void s51_puthex(unsigned int v)
{
    static const char digits[] = "0123456789ABCDEF";
    signed char sh;
    for (sh = 12; sh >= 0; sh -= 4) {
        s51_putc(digits[(v >> sh) & 0xFu]);
    }
}

void s51_report_cycles(const char *label)
{
    unsigned int c = s51_cycles();
    s51_puts("CYCLES ");
    s51_puts(label);
    s51_putc(' ');
    if (c == 0xFFFFu) {
        s51_puts("overflow");
    } else {
        s51_putu(c);
    }
    s51_putc('\n');
}

void s51_exit(unsigned char code)
{
    s51_puts("EXIT ");
    s51_putu(code);
    s51_putc('\n');
    S51_SIF = 's';
    for (;;) {
    }
}
