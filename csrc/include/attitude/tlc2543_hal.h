/*
 * tlc2543_hal.h — pin-level HAL of the TLC2543 driver (csrc/src/tlc2543.c).
 *
 * Two implementations of the same seven operations:
 *
 *  - SDCC / 8051 (`__SDCC` defined): macros on the bits of port P1, wired as
 *    in the paper (Fig. 5): P1.0 = EOC (in), P1.1 = I/O CLOCK, P1.2 = DATA
 *    INPUT (to the ADC), P1.3 = DATA OUT (from the ADC), P1.4 = CS. Each
 *    operation is one bit instruction (SETB/CLR/MOV C,bit), no call. The
 *    timing delays expand to nothing: see "8051 timing" in docs/tlc2543.md
 *    (one machine cycle is 1.085 us at 11.0592 MHz, longer than every
 *    sub-microsecond limit; the longer limits are covered by the
 *    instructions the driver executes anyway). Define TLC2543_HAL_CUSTOM and
 *    provide the TLC2543_* macros yourself to use other pins or another MCU.
 *
 *  - Host: every operation is a call through a caller-owned context
 *    (struct tlc2543_hal, pointed to by the driver state). No global state.
 *    The delays are real calls, so a host model with simulated time can
 *    check that the driver never violates a timing limit.
 *
 * Only plain declarations are visible to CFFI (ATT_CDEF).
 */
#ifndef ATTITUDE_TLC2543_HAL_H
#define ATTITUDE_TLC2543_HAL_H

#include "attitude/common.h"

/* Host HAL: pin callbacks on a caller-owned context. Levels are 0/1. */
typedef struct tlc2543_hal {
    void *ctx;                                /* passed to every callback */
    void (*set_cs)(void *ctx, int level);     /* CS (active low) */
    void (*set_clock)(void *ctx, int level);  /* I/O CLOCK */
    void (*set_din)(void *ctx, int level);    /* DATA INPUT, to the ADC */
    int (*get_dout)(void *ctx);               /* DATA OUT, from the ADC */
    int (*get_eoc)(void *ctx);                /* EOC (high = conversion done) */
    void (*delay_ns)(void *ctx, uint32_t ns); /* wait at least ns nanoseconds */
} tlc2543_hal;

#ifndef ATT_CDEF
#if defined(__SDCC) && !defined(TLC2543_HAL_CUSTOM)
#include <8051.h>
/* Pin assignment (bit-addressable port bits); override with -D to rewire.
 * `d` (the driver state) is unused on the 8051. */
#ifndef TLC2543_PIN_EOC
#define TLC2543_PIN_EOC P1_0
#endif
#ifndef TLC2543_PIN_CLOCK
#define TLC2543_PIN_CLOCK P1_1
#endif
#ifndef TLC2543_PIN_DIN
#define TLC2543_PIN_DIN P1_2
#endif
#ifndef TLC2543_PIN_DOUT
#define TLC2543_PIN_DOUT P1_3
#endif
#ifndef TLC2543_PIN_CS
#define TLC2543_PIN_CS P1_4
#endif
#define TLC2543_CS(d, v)        (TLC2543_PIN_CS = (v))
#define TLC2543_CLOCK(d, v)     (TLC2543_PIN_CLOCK = (v))
#define TLC2543_DIN(d, v)       (TLC2543_PIN_DIN = (v))
#define TLC2543_DOUT(d)         (TLC2543_PIN_DOUT)
#define TLC2543_EOC(d)          (TLC2543_PIN_EOC)
#define TLC2543_DELAY_NS(d, ns) ((void)0)
/* The input byte and the received byte share one shift register: the
 * bit-addressable B register. Clock k sends B.k and then overwrites it with
 * DATA OUT (MOV C,B.k / MOV P1.2,C / MOV C,P1.3 / MOV B.k,C), so no shift
 * instruction is needed. Nothing between SR_LOAD and SR_GET uses B (the s51
 * loopback test, DATA OUT read from the DATA INPUT latch, checks every bit
 * sent and received in every mode). */
__sbit __at(0xF0) TLC2543_B0;
__sbit __at(0xF1) TLC2543_B1;
__sbit __at(0xF2) TLC2543_B2;
__sbit __at(0xF3) TLC2543_B3;
__sbit __at(0xF4) TLC2543_B4;
__sbit __at(0xF5) TLC2543_B5;
__sbit __at(0xF6) TLC2543_B6;
__sbit __at(0xF7) TLC2543_B7;
#define TLC2543_SR_LOAD(sr, byte) (B = (byte))
#define TLC2543_SR_BIT(sr, k)     (TLC2543_B##k)
#define TLC2543_SR_PUT(sr, k, v)  (TLC2543_B##k = (v))
#define TLC2543_SR_GET(sr)        (B)
#define TLC2543_SR_SHL4(sr)       (B = (uint8_t)(B << 4))
/* Store a 16-bit word from its two bytes (SDCC's mcs51 port is little
 * endian): two MOV @R0 instead of building the word in registers. */
#define TLC2543_STORE_WORD(p, whi, wlo)             \
    do {                                            \
        uint8_t __data *q_ = (uint8_t __data *)(p); \
        *q_ = (wlo);                                \
        q_++;                                       \
        *q_ = (whi);                                \
    } while (0)
/* Driver state and result words live in internal RAM (small model). */
#define TLC2543_DATA __data
/* Cold functions keep their parameters and locals on the stack (only while
 * they run) instead of in static internal RAM: the AT89S51 has 128 bytes. */
#define TLC2543_COLD __reentrant
#elif !defined(TLC2543_HAL_CUSTOM)
#define TLC2543_CS(d, v)        ((d)->hal->set_cs((d)->hal->ctx, (v)))
#define TLC2543_CLOCK(d, v)     ((d)->hal->set_clock((d)->hal->ctx, (v)))
#define TLC2543_DIN(d, v)       ((d)->hal->set_din((d)->hal->ctx, (v)))
#define TLC2543_DOUT(d)         ((d)->hal->get_dout((d)->hal->ctx))
#define TLC2543_EOC(d)          ((d)->hal->get_eoc((d)->hal->ctx))
#define TLC2543_DELAY_NS(d, ns) ((d)->hal->delay_ns((d)->hal->ctx, (ns)))
#endif
/* Defaults (host, and custom HALs that do not define them). */
/* Shift register of one byte in a local variable `sr`. */
#ifndef TLC2543_SR_LOAD
#define TLC2543_SR_LOAD(sr, byte) ((sr) = (uint8_t)(byte))
#define TLC2543_SR_BIT(sr, k)     (((sr) >> (k)) & 1u)
#define TLC2543_SR_PUT(sr, k, v) \
    ((sr) = (uint8_t)(((sr) & (uint8_t) ~(1u << (k))) | ((v) ? (1u << (k)) : 0u)))
#define TLC2543_SR_GET(sr)  (sr)
#define TLC2543_SR_SHL4(sr) ((sr) = (uint8_t)((sr) << 4))
#endif
#ifndef TLC2543_STORE_WORD
#define TLC2543_STORE_WORD(p, whi, wlo) (*(p) = (uint16_t)(((uint16_t)(whi) << 8) | (wlo)))
#endif
#endif
#ifndef TLC2543_DATA
#define TLC2543_DATA
#endif
#ifndef TLC2543_COLD
#define TLC2543_COLD
#endif

#endif /* ATTITUDE_TLC2543_HAL_H */
