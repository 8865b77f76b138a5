/*
 * Baseline for bench/tlc2543.py: the "textbook" TLC2543 read loop (one
 * 12-clock cycle, 16-bit accumulator shifted every clock) as commonly
 * written for the 8051, on the same pins. Timed like the real driver.
 */
#include "s51_sif.h"
#include <stdint.h>

static uint16_t naive_read(uint8_t ch)
{
    uint8_t i;
    uint16_t ad = 0;
    uint8_t in = (uint8_t)(ch << 4);
    P1_1 = 0;
    P1_4 = 0;
    for (i = 0; i < 12; i++) {
        if (P1_3) {
            ad |= 1;
        }
        P1_2 = (in & 0x80) ? 1 : 0;
        P1_1 = 1;
        P1_1 = 0;
        in <<= 1;
        ad <<= 1;
    }
    P1_4 = 1;
    while (!P1_0) {
    }
    return ad >> 1;
}

void main(void)
{
    volatile uint16_t w;
    P1 = 0xFF;
    S51_CYCLES_BEGIN();
    w = naive_read(0);
    S51_CYCLES_END();
    s51_report_cycles("naive_cycle12");
    (void)w;
    s51_exit(0);
}
