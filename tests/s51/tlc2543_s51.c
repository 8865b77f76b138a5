/*
 * TLC2543 driver on the 8051 (s51): cycle counts for the benchmark and a
 * smoke check of the SDCC build. In s51 nothing drives P1, so its pins read
 * the port latch (1): EOC is "conversion done" at once and DATA OUT reads
 * all ones, so every word is all ones — which this program checks, together
 * with the pin levels the driver leaves behind (CS high, CLOCK low).
 *
 * Built with -DTLC2543_LOOPBACK -DTLC2543_PIN_DOUT=P1_2 (DATA OUT read back
 * from the DATA INPUT latch), every clock receives the bit just sent, so
 * each word is a known function of the input byte: that checks the bit
 * order, the clock count and the B-register shift register of the SDCC
 * build in every mode.
 */
#include "s51_sif.h"
#include "attitude/tlc2543.h"

static tlc2543 adc;
static const uint8_t xyz[3] = { TLC2543_CH_X, TLC2543_CH_Y, TLC2543_CH_Z };

static void check(unsigned char ok, const char *what)
{
    if (!ok) {
        s51_puts("FAIL ");
        s51_puts(what);
        s51_putc('\n');
        s51_exit(1);
    }
}

#ifdef TLC2543_LOOPBACK
/* Expected loopback word: the 8 input bits, then DATA INPUT stays at D0 for
 * the remaining clocks; LSB-first words are reversed by the driver. */
static uint16_t expected(uint8_t in)
{
    uint8_t nclk = ((in & 0x0C) == 0x04) ? 8 : ((in & 0x0C) == 0x0C) ? 16 : 12;
    uint16_t w = in, r = 0;
    uint8_t i;
    for (i = 8; i < nclk; i++) {
        w = (uint16_t)((w << 1) | (in & 1u));
    }
    if (in & 0x02) {
        for (i = 0; i < nclk; i++) {
            r = (uint16_t)((r << 1) | (w & 1u));
            w >>= 1;
        }
        w = r;
    }
    return w;
}

void main(void)
{
    uint8_t mode, addr;
    uint16_t w;
    tlc2543_settings s;
    P1 = 0xFF;
    for (mode = 0; mode < 16; mode++) {
        if ((mode & 0x0C) == 0x08) {
            continue; /* 10 = 12 bits too, but init only takes the 00 code */
        }
        s.length = (uint8_t)(mode >> 2);
        s.lsb_first = (uint8_t)((mode >> 1) & 1u);
        s.bipolar = (uint8_t)(mode & 1u);
        s.eoc_polls = 0;
        check(tlc2543_init(&adc, 0, &s) == ATT_OK, "init");
        for (addr = 0; addr <= TLC2543_POWER_DOWN; addr++) {
            check(tlc2543_cycle(&adc, addr, &w) == ATT_OK, "cycle");
            if (w != expected((uint8_t)((addr << 4) | mode))) {
                s51_puts("word ");
                s51_puthex(w);
                s51_puts(" for input byte ");
                s51_puthex((uint16_t)((addr << 4) | mode));
                s51_putc('\n');
                s51_exit(2);
            }
        }
    }
    s51_puts("LOOPBACK OK\n");
    s51_exit(0);
}
#else
void main(void)
{
    uint16_t w, codes[3];
    int st;
    tlc2543_settings s;

    P1 = 0xFF;
    check(tlc2543_init(&adc, 0, 0) == ATT_OK, "init");

    S51_CYCLES_BEGIN();
    st = tlc2543_cycle(&adc, TLC2543_CH_X, &w);
    S51_CYCLES_END();
    s51_report_cycles("cycle12");
    check(st == ATT_OK && w == 0x0FFFu, "cycle12");
    check(P1_4 == 1 && P1_1 == 0, "pins idle");

    S51_CYCLES_BEGIN();
    st = tlc2543_scan(&adc, xyz, 3, codes, TLC2543_CH_X);
    S51_CYCLES_END();
    s51_report_cycles("scan_xyz_steady");
    check(st == ATT_OK && codes[0] == 0x0FFFu && codes[2] == 0x0FFFu, "scan steady");

    adc.pending |= TLC2543_NO_RESULT;
    S51_CYCLES_BEGIN();
    st = tlc2543_scan(&adc, xyz, 3, codes, TLC2543_CH_X);
    S51_CYCLES_END();
    s51_report_cycles("scan_xyz_first");
    check(st == ATT_OK, "scan first");

    /* DATA OUT all ones: the self-test must fail on the mid-scale code */
    check(tlc2543_self_test(&adc) == TLC2543_E_SELFTEST_MID, "self-test detects stuck DOUT");

    s.length = TLC2543_LEN_8;
    s.lsb_first = 0;
    s.bipolar = 0;
    s.eoc_polls = 0;
    check(tlc2543_init(&adc, 0, &s) == ATT_OK, "init8");
    S51_CYCLES_BEGIN();
    st = tlc2543_cycle(&adc, TLC2543_CH_X, &w);
    S51_CYCLES_END();
    s51_report_cycles("cycle8");
    check(st == ATT_OK && w == 0xFFu, "cycle8");

    s.length = TLC2543_LEN_16;
    s.lsb_first = 1;
    check(tlc2543_init(&adc, 0, &s) == ATT_OK, "init16");
    S51_CYCLES_BEGIN();
    st = tlc2543_cycle(&adc, TLC2543_CH_X, &w);
    S51_CYCLES_END();
    s51_report_cycles("cycle16_lsbf");
    check(st == ATT_OK && w == 0xFFFFu, "cycle16");

    /* EOC held low: a bounded wait, then the timeout code */
    check(tlc2543_init(&adc, 0, 0) == ATT_OK, "init eoc");
    P1_0 = 0;
    check(tlc2543_cycle(&adc, TLC2543_CH_X, &w) == TLC2543_E_EOC_TIMEOUT, "eoc timeout");
    P1_0 = 1;

    s51_puts("OK\n");
    s51_exit(0);
}
#endif
