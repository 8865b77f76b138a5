/*
 * firmware/sim/tlc_hal_sim.h — simulation pins of the TLC2543 driver.
 *
 * Force-included (SDCC -Wp-include) into every file of a simulation image.
 * The driver csrc/src/tlc2543.c is compiled unchanged, with its production
 * 8051 HAL (pins as bit variables, the B-register shift register); only
 * its pin assignment (TLC2543_PIN_*, which the HAL lets a board override)
 * points at a TLC2543 + gyro device model instead of port P1:
 *
 *  - CS, I/O CLOCK and DATA INPUT are bits of SFR 0xC0, an address the C51
 *    core does not implement (uCsim keeps it as plain memory);
 *  - reading DATA OUT evaluates the model inline (no call, no stack, no
 *    RAM: its state lives in unused SFR cells 0xC0-0xC8, 0xA9-0xAE);
 *    the first EOC read after CS rose calls it (fwm_end_cycle).
 *
 * The model is driven by the reads: the driver reads DATA OUT once per
 * clock, just before the rising edge, after setting DATA INPUT, so each
 * read shifts DATA INPUT in (first 8 clocks) and the previous result out
 * (MSB first); the first EOC read after CS rose ends the I/O cycle:
 * clock count and format are checked, the addressed input is converted
 * (from the values tlc_model.c computed for the current time) and EOC
 * stays low for FW_SIM_CONV_POLLS reads. Violations set sticky bits that
 * fw_sim_model_check() reports (MODEL ERROR ...) and stops on: a cycle
 * without exactly 12 clocks, another format, CS rising with the clock
 * high, a new cycle (DATA OUT read) while a conversion still runs.
 */
#ifndef FW_TLC_HAL_SIM_H
#define FW_TLC_HAL_SIM_H

__sbit __at(0xC0) fwm_cs_pin;     /* CS as last driven (reset: 1) */
__sbit __at(0xC1) fwm_clk_pin;    /* I/O CLOCK as last driven */
__sbit __at(0xC2) fwm_din_pin;    /* DATA INPUT as last driven */
__sbit __at(0xC3) fwm_t;          /* DATA OUT bit being returned */
__sbit __at(0xC4) fwm_bad_count;  /* a cycle without exactly 12 clocks */
__sbit __at(0xC5) fwm_bad_format; /* a format other than 12-bit MSB-first unipolar */
__sbit __at(0xC6) fwm_bad_cs;     /* CS rose with the clock high */
__sbit __at(0xC7) fwm_bad_abort;  /* a cycle ended before its conversion did */
__sfr __at(0xC1) fwm_nclk;        /* clocks (DATA OUT reads) in this cycle */
__sfr __at(0xC2) fwm_in;          /* input byte shifted in */
#if defined(FW_SIM_C52)
/* the C52 core (the aided AT89S52) has Timer 2 at 0xC8-0xCD: the word's high
 * byte moves to 0xD8, another bit-addressable cell that core leaves free */
__sfr16 __at(0xD8C3) fwm_word; /* result being shifted out, code << 4 */
__sbit __at(0xDF) fwm_msb;     /* its bit 15 */
#else
__sfr16 __at(0xC8C3) fwm_word; /* result being shifted out, code << 4 */
__sbit __at(0xCF) fwm_msb;     /* its bit 15 (SFR 0xC8 is bit-addressable) */
#endif
__sfr __at(0xC5) fwm_eoc_wait; /* EOC reads that still return low */
__sfr __at(0xC6) fwm_a;        /* address of the cycle being ended */
__sfr16 __at(0xAAA9) fwm_vx;   /* inputs AIN0..AIN2 now, code << 4 */
__sfr16 __at(0xACAB) fwm_vy;
__sfr16 __at(0xAEAD) fwm_vz;

#define TLC2543_PIN_CS    fwm_cs_pin
#define TLC2543_PIN_CLOCK fwm_clk_pin
#define TLC2543_PIN_DIN   fwm_din_pin

/* One DATA OUT read = one clock: shift DATA INPUT in (first 8 clocks),
 * count, and return the next bit of the previous result, MSB first. */
#define FWM_DOUT_READ                                                                           \
    ((fwm_nclk < 8u ? (fwm_in = (unsigned char)((fwm_in << 1) | fwm_din_pin)) : 0), fwm_nclk++, \
     fwm_t = fwm_msb, fwm_word <<= 1)
#if defined(FW_SIM_DOUT_STUCK)
/* fault: DATA OUT tied to the level in this cell (set by fw_sim_model_init;
 * a cell rather than a constant, so the compiler keeps the driver's code) */
__sfr __at(0xBF) fwm_stuck_dout;
#define TLC2543_PIN_DOUT (FWM_DOUT_READ, (fwm_stuck_dout != 0u))
#else
#define TLC2543_PIN_DOUT (FWM_DOUT_READ, fwm_t)
#endif

/* End of an I/O cycle (first EOC read with CS high, tlc_model.c): checks
 * it, converts; returns the EOC level (1 if no conversion: power-down). */
unsigned char fwm_end_cycle(void);
#define TLC2543_PIN_EOC \
    ((fwm_cs_pin && fwm_nclk != 0u) ? fwm_end_cycle() : (fwm_eoc_wait != 0u ? (fwm_eoc_wait--, 0) : 1))

#endif /* FW_TLC_HAL_SIM_H */
