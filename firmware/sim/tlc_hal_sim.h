/*
 * firmware/sim/tlc_hal_sim.h — simulation HAL of the TLC2543 driver.
 *
 * Force-included (SDCC -Wp-include) into every file of a simulation image,
 * together with -DTLC2543_HAL_CUSTOM: the driver csrc/src/tlc2543.c is
 * compiled unchanged, but its pin operations act on a TLC2543 + gyro
 * device model (tlc_model.c) instead of port P1. The pins and the model's
 * shift state live in SFR addresses the C51 core does not implement
 * (0xC0-0xCC; uCsim keeps them as plain memory), so the model takes no
 * RAM from the firmware. Clock edges, DATA IN, DATA OUT and EOC are inline
 * expressions like the production HAL's bit instructions (no call, no
 * stack); only the CS edges call the model, which checks the cycle and
 * converts.
 *
 * DATA OUT is computed when read: before the k-th rising clock edge of a
 * cycle (k = 0..11) the chip presents bit 11-k of the previous result.
 */
#ifndef FW_TLC_HAL_SIM_H
#define FW_TLC_HAL_SIM_H

__sbit __at(0xC0) fwm_cs_pin;     /* CS as last driven */
__sbit __at(0xC1) fwm_clk_pin;    /* I/O CLOCK as last driven */
__sbit __at(0xC2) fwm_din_pin;    /* DATA INPUT as last driven */
__sbit __at(0xC3) fwm_bad;        /* a violation seen inline, reported at CS high */
__sbit __at(0xC4) fwm_started;    /* a gyro conversion happened */
__sfr __at(0xC1) fwm_nclk;        /* rising clock edges in this cycle */
__sfr __at(0xC2) fwm_in;          /* input byte shifted in */
__sfr16 __at(0xC4C3) fwm_word;    /* result being shifted out / last result */
__sfr __at(0xC5) fwm_eoc_wait;    /* EOC reads that still return low */

void fwm_cs(unsigned char level);

#define TLC2543_CS(d, v) fwm_cs((unsigned char)(v))
/* rising edge: count it, shift DATA INPUT in during the first 8 clocks;
 * clocking with CS high is a violation */
#define TLC2543_CLOCK(d, v)                                                   \
    ((v) ? (fwm_clk_pin = 1, fwm_bad |= fwm_cs_pin,                            \
            fwm_in = (fwm_nclk < 8u) ? (unsigned char)((fwm_in << 1) | fwm_din_pin) : fwm_in, \
            fwm_nclk++)                                                       \
         : (fwm_clk_pin = 0, 0))
#define TLC2543_DIN(d, v) (fwm_din_pin = (v))
#if defined(FW_SIM_DOUT_STUCK)
#define TLC2543_DOUT(d) (FW_SIM_DOUT_STUCK)
#else
#define TLC2543_DOUT(d) \
    ((fwm_nclk < 12u) ? (unsigned char)((fwm_word >> (11u - fwm_nclk)) & 1u) : 0u)
#endif
#if defined(FW_SIM_EOC_STUCK)
#define TLC2543_EOC(d) 0
#else
#define TLC2543_EOC(d) ((fwm_eoc_wait != 0u) ? (fwm_eoc_wait--, 0) : 1)
#endif
#define TLC2543_DELAY_NS(d, ns) ((void)0)
/* Same memory space for the driver state as the real 8051 build. */
#define TLC2543_DATA __data

#endif /* FW_TLC_HAL_SIM_H */
