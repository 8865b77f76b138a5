/*
 * firmware/config.h — build-time configuration of the AT89S51 acquisition
 * firmware. Every FW_* value can be overridden on the SDCC command line
 * (`invoke firmware.build --baud 19200 --period-ticks 36`, or -DFW_...=...).
 *
 * Time base: Timer 0 free-running in mode 1 counts machine cycles; its high
 * byte TH0 advances every 256 machine cycles. At 11.0592 MHz a machine
 * cycle is 12 clocks, so one tick is 256 * 12 / 11059200 s = 1/3600 s =
 * 277.8 us, exactly.
 * All periods and timeouts below are in those ticks.
 */
#ifndef FW_CONFIG_H
#define FW_CONFIG_H

/* Crystal (Hz). The baud-rate table and the tick length follow from it. */
#ifndef FW_XTAL_HZ
#define FW_XTAL_HZ 11059200L
#endif

/* UART speed (8N1). Allowed: the rates Timer 1 in mode 2 makes exactly
 * from FW_XTAL_HZ: at 11.0592 MHz 1200, 2400, 4800, 9600, 14400, 19200,
 * 28800 and 57600 (the fastest: SMOD = 1, TH1 = 0xFF). */
#ifndef FW_BAUD
#define FW_BAUD 9600L
#endif

/* Sampling period in ticks (72 ticks = 20 ms = 50 samples/s). One block
 * exchange at 9600 baud takes 10 byte times = 10.4 ms = 37.5 ticks, so 72
 * leaves room for one resend per sample. */
#ifndef FW_PERIOD_TICKS
#define FW_PERIOD_TICKS 72
#endif

/* Link sender timeouts (ticks) and attempts per block: 0xAA + 0xBB on the
 * wire are 2 byte times (2.1 ms at 9600 baud), the checksum + answer 2
 * more; the rest is the host's latency. 180 ticks = 50 ms. */
#ifndef FW_SYN_TIMEOUT_TICKS
#define FW_SYN_TIMEOUT_TICKS 180
#endif
#ifndef FW_ANSWER_TIMEOUT_TICKS
#define FW_ANSWER_TIMEOUT_TICKS 180
#endif
#ifndef FW_MAX_ATTEMPTS
#define FW_MAX_ATTEMPTS 5
#endif

/* Link protocol: 0 = the paper's AA/BB handshake (attitude/link.h,
 * csrc/src/link_sender.c), 1 = link v2 (attitude/link2.h,
 * csrc/src/link2_sender.c built as the single instance: every source is
 * compiled with -DATT_LINK2_ONE=1 and its settings ATT_LINK2_ONE_RTO,
 * _SAMPLES, _RING; toolchain/firmware.py passes them). */
#ifndef FW_LINK_V2
#define FW_LINK_V2 0
#endif
#if FW_LINK_V2 && !defined(ATT_LINK2_ONE)
#error "the link v2 build needs -DATT_LINK2_ONE=1 on every source (toolchain/firmware.py passes it)"
#endif

/* Retry interval of a failed ADC self-test (ticks; 3600 = 1 s). */
#ifndef FW_SELFTEST_RETRY_TICKS
#define FW_SELFTEST_RETRY_TICKS 3600
#endif

/* ---- derived values and checks --------------------------------------- */

#define FW_TICK_HZ (FW_XTAL_HZ / 3072L) /* 12 clocks x 256 counts */
#if (FW_XTAL_HZ % 3072L) != 0
#error "FW_XTAL_HZ must be a multiple of 3072 Hz for an exact tick"
#endif

/* Timer 1 mode 2: baud = 2^SMOD * XTAL / (384 * (256 - TH1)). */
#if ((FW_XTAL_HZ / 384L) % FW_BAUD) == 0 && (FW_XTAL_HZ / 384L / FW_BAUD) <= 255
#define FW_SMOD 0
#define FW_TH1  (256 - (FW_XTAL_HZ / 384L / FW_BAUD))
#elif ((FW_XTAL_HZ / 192L) % FW_BAUD) == 0 && (FW_XTAL_HZ / 192L / FW_BAUD) <= 255
#define FW_SMOD 1
#define FW_TH1  (256 - (FW_XTAL_HZ / 192L / FW_BAUD))
#else
#error "FW_BAUD cannot be made exactly from FW_XTAL_HZ with Timer 1 in mode 2"
#endif

#if FW_PERIOD_TICKS < 1 || FW_PERIOD_TICKS > 32767
#error "FW_PERIOD_TICKS must be 1..32767"
#endif
#if FW_SYN_TIMEOUT_TICKS < 1 || FW_SYN_TIMEOUT_TICKS > 32767 || FW_ANSWER_TIMEOUT_TICKS < 1 \
    || FW_ANSWER_TIMEOUT_TICKS > 32767
#error "link timeouts must be 1..32767 ticks"
#endif
#if FW_MAX_ATTEMPTS < 1 || FW_MAX_ATTEMPTS > 255
#error "FW_MAX_ATTEMPTS must be 1..255"
#endif

#endif /* FW_CONFIG_H */
