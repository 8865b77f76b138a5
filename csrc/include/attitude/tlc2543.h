/*
 * tlc2543.h — TI TLC2543 12-bit serial ADC driver (bit-banged, portable C99).
 *
 * One source (csrc/src/tlc2543.c) for the AT89S51 (SDCC) and the host.
 * The pins are reached through tlc2543_hal.h: P1 bit macros on SDCC, calls
 * through a caller-owned struct tlc2543_hal on the host.
 *
 * How to use from firmware (SDCC, AT89S51, P1.0 EOC, P1.1 CLOCK, P1.2 DIN,
 * P1.3 DOUT, P1.4 CS; compile csrc/src/tlc2543.c unchanged):
 *
 *     #include "attitude/tlc2543.h"
 *     static tlc2543 adc;                        // 2 bytes of RAM
 *     static const uint8_t xyz[3] = {TLC2543_CH_X, TLC2543_CH_Y, TLC2543_CH_Z};
 *     uint16_t codes[3];
 *     if (tlc2543_init(&adc, 0, 0) != ATT_OK) ...      // 12-bit, MSB first, unipolar
 *     if (tlc2543_self_test(&adc) != ATT_OK) ...       // test voltages 0x800/0x000/0xFFF
 *     for (;;) {
 *         if (tlc2543_scan(&adc, xyz, 3, codes, TLC2543_CH_X) != ATT_OK) ...
 *         // codes[0..2] = X, Y, Z; with next = xyz[0], every scan after the
 *         // first takes 3 I/O cycles (the X conversion is started at the end
 *         // of the previous scan).
 *     }
 *
 * Pipeline: the word clocked out in an I/O cycle is the conversion requested
 * by the previous cycle. The driver state remembers which address (and
 * format) that was, so results are never mislabelled and the undefined
 * output register after power-up/power-down/mode change is discarded.
 *
 * Words returned are the bits as clocked out, put back in natural order
 * (bit L-1 = MSB) for the output length L: 8-bit mode = the 8 MSBs of the
 * 12-bit result, 12-bit mode = the result, 16-bit mode = result << 4.
 * Bipolar mode: two's complement in L bits (sign-extend with
 * tlc2543_signed()).
 *
 * All functions return ATT_OK (0) or a negative att_status / TLC2543_E_*.
 *
 * On SDCC the state and the result words are `__data` (internal RAM, the
 * small model's default for variables): TLC2543_DATA below. Elsewhere it is
 * empty.
 */
#ifndef ATTITUDE_TLC2543_H
#define ATTITUDE_TLC2543_H

#include "attitude/common.h"
#include "attitude/tlc2543_hal.h"

ATT_API_BEGIN

/* Input byte fields and addresses (datasheet "input data byte"). */
enum {
    TLC2543_CH_X = 0,        /* board wiring: gyro X on AIN0 */
    TLC2543_CH_Y = 1,        /* gyro Y on AIN1 */
    TLC2543_CH_Z = 2,        /* gyro Z on AIN2 */
    TLC2543_AIN_COUNT = 11,  /* analog inputs AIN0..AIN10 */
    TLC2543_TEST_MID = 11,   /* test input (Vref+ + Vref-)/2 -> 0x800 */
    TLC2543_TEST_REFM = 12,  /* test input Vref- -> 0x000 */
    TLC2543_TEST_REFP = 13,  /* test input Vref+ -> 0xFFF */
    TLC2543_POWER_DOWN = 14, /* software power-down address */
    TLC2543_NO_RESULT = 0xF0 /* tlc2543.pending >= this: output register
                                 undefined (address 15 is never sent) */
};

/* Output data length field (D3-D2 of the input byte). */
enum {
    TLC2543_LEN_12 = 0, /* 12 clocks (D3-D2 = 00 or 10) */
    TLC2543_LEN_8 = 1,  /* 8 clocks: the 8 MSBs */
    TLC2543_LEN_16 = 3  /* 16 clocks: result followed by four 0 bits */
};

/* Status codes of this module (range -40..-59 of common.h). */
enum {
    TLC2543_E_EOC_TIMEOUT = -40,   /* EOC did not rise within eoc_polls samples */
    TLC2543_E_SELFTEST_MID = -41,  /* (Vref+ + Vref-)/2 test code not 0x800 +- tol */
    TLC2543_E_SELFTEST_REFM = -42, /* Vref- test code not 0x000 + tol */
    TLC2543_E_SELFTEST_REFP = -43  /* Vref+ test code not 0xFFF - tol */
};

/* Self-test tolerance in 12-bit LSB (see docs/tlc2543.md: datasheet total
 * unadjusted error +-1 LSB, plus 1 LSB for noise on the reference). */
enum {
    TLC2543_SELFTEST_TOL = 2
};

/* Default bound of the EOC wait when settings->eoc_polls is 0. */
enum {
    TLC2543_EOC_POLLS_DEFAULT = 40
};

/* Settings (Fusion style). NULL settings = 12-bit, MSB first, unipolar. */
typedef struct {
    uint8_t length;    /* TLC2543_LEN_8 / _12 / _16 */
    uint8_t lsb_first; /* 0: MSB first, 1: LSB first */
    uint8_t bipolar;   /* 0: unipolar straight binary, 1: bipolar two's complement */
    uint8_t eoc_polls; /* EOC samples before TLC2543_E_EOC_TIMEOUT; samples are
                          >= 1 us apart (host: 1000 ns delay; 8051: >= 4 machine
                          cycles). 0 = TLC2543_EOC_POLLS_DEFAULT (40 us > 10 us
                          conversion time) */
} tlc2543_settings;

/* Driver state: caller-owned, passed by pointer. Treat as opaque. */
typedef struct {
#if !defined(__SDCC) || defined(TLC2543_HAL_CUSTOM)
    const tlc2543_hal *hal; /* host: pin callbacks (unused on the 8051) */
#endif
    uint8_t pending;   /* input byte (address << 4 | mode) of the last request:
                          the output register holds that conversion; address
                          field 15 (>= TLC2543_NO_RESULT): it holds nothing
                          usable. The low nibble is always the mode (D3..D0). */
    uint8_t eoc_polls; /* bound of the EOC wait */
} tlc2543;

/* Initialise the state (no pin activity). `hal` is required on the host and
 * ignored on the 8051; `settings` may be NULL. ATT_E_ARG on a bad field. */
int tlc2543_init(tlc2543 TLC2543_DATA *dev, const tlc2543_hal *hal,
                 const tlc2543_settings *settings) TLC2543_COLD;

/* One I/O cycle: send `address` (0..14) with the configured mode and read
 * the word clocked out (the conversion requested by the previous cycle;
 * meaningful only if dev->pending < TLC2543_NO_RESULT before the call),
 * then wait (bounded) for the end of the new conversion. `word` may be NULL.
 * Power-down (address 14) starts no conversion and does not wait for EOC. */
int tlc2543_cycle(tlc2543 TLC2543_DATA *dev, uint8_t address, uint16_t TLC2543_DATA *word);

/* Read channels[0..n-1] (addresses 0..13) into codes[0..n-1] in the
 * minimum number of I/O cycles: each cycle addresses the next channel while
 * clocking out the previous one. The last cycle requests `next` (0..14):
 * pass channels[0] so that the following scan of the same list needs only
 * n cycles (its first result is already converted); the first cycle is
 * skipped whenever the pending conversion is channels[0] in the configured
 * mode. n = 1..255. On error, codes already read are kept. */
int tlc2543_scan(tlc2543 TLC2543_DATA *dev, const uint8_t *channels, uint8_t n, uint16_t TLC2543_DATA *codes,
                 uint8_t next);

/* Convert the three internal test voltages (12-bit, MSB first, unipolar)
 * and check them against 0x800 / 0x000 / 0xFFF within TLC2543_SELFTEST_TOL.
 * Returns TLC2543_E_SELFTEST_* naming the first bad one. The configured mode
 * is kept; the output register is left holding nothing usable. `codes` (may
 * be NULL) receives the three 12-bit codes (MID, REFM, REFP). */
int tlc2543_self_test_codes(tlc2543 TLC2543_DATA *dev, uint16_t TLC2543_DATA *codes) TLC2543_COLD;
int tlc2543_self_test(tlc2543 TLC2543_DATA *dev) TLC2543_COLD;

/* Software power-down (one I/O cycle with address 14). Any later cycle
 * wakes the chip; its output word is discarded by tlc2543_scan. */
int tlc2543_power_down(tlc2543 TLC2543_DATA *dev) TLC2543_COLD;

/* Sign-extend a bipolar word of the configured length (two's complement). */
int16_t tlc2543_signed(const tlc2543 TLC2543_DATA *dev, uint16_t word) TLC2543_COLD;

/* Number of I/O clocks of one cycle in the configured mode (8, 12, 16). */
uint8_t tlc2543_clocks(const tlc2543 TLC2543_DATA *dev) TLC2543_COLD;

ATT_API_END

#endif /* ATTITUDE_TLC2543_H */
