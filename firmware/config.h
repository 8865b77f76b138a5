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

/* The aided board (FW_AIDED = 1; docs/firmware.md "The aided board"): an
 * AT89S52 (8 KB flash, 256 bytes of RAM, Timer 2) that samples nine TLC2543
 * inputs: the gyros on AIN0-AIN2 as on the paper's board, the
 * accelerometer's X, Y, Z on AIN3-AIN5 (FW_AIN_ACC) and the magnetometer's
 * on AIN6-AIN8 (FW_AIN_MAG); AIN9 and AIN10 stay free. It speaks link v2
 * only, announces itself with a CHANNELS report after BOOT
 * (attitude/block.h), and sends sample n's accelerometer record when
 * n % FW_ACC_EVERY == 0 and its magnetometer record when n % FW_MAG_EVERY
 * == 0: powers of two 1..128 (a mask, no division), or 0 for a sensor it
 * does not send. Its UART runs on Timer 2: baud = XTAL / (32 x (65536 -
 * RCAP2)), exact at 11.0592 MHz for 115200 (RCAP2 = 0xFFFD), 57600
 * (0xFFFA), 38400, 28800, 19200, 14400, 9600 (0xFFDC) and below; received
 * bytes go through a small interrupt-driven FIFO (at 115200 baud a byte
 * comes every 80 machine cycles, less than one poll of the sender). */
#ifndef FW_AIDED
#define FW_AIDED 0
#endif
#if FW_AIDED
#ifndef FW_ACC_EVERY
#define FW_ACC_EVERY 1
#endif
#ifndef FW_MAG_EVERY
#define FW_MAG_EVERY 1
#endif
#define FW_AIN_ACC 3 /* accelerometer X, Y, Z: AIN3, AIN4, AIN5 */
#define FW_AIN_MAG 6 /* magnetometer X, Y, Z: AIN6, AIN7, AIN8 */
/* FW_MAG_SR = 1: each magnetometer sample is converted after a set pulse
 * and again after a reset pulse of its straps (P3.4, main.c SR_PIN), and
 * the combination (c_set + 4095 - c_reset) / 2 is sent: the bridge offset
 * cancels. Three more conversions per magnetometer sample (about 5.7 points
 * of CPU at the default plan: docs/firmware.md); 0 (default): one
 * conversion, P3.4 untouched, the offset left to `attitude calibrate`. */
#ifndef FW_MAG_SR
#define FW_MAG_SR 0
#endif
/* FW_GYRO_OVERSAMPLE = N (1, 2, 4 or 8; default 1): the gyros are converted N times per
 * sample period, FW_PERIOD_TICKS / N ticks apart, the last one at the sample's instant t
 * with the accelerometer and magnetometer (the midpoints of the N sub-intervals of the
 * period (t - P + P/2N, t + P/2N]), and
 * their sum is sent: an OVERSAMPLE n = N report after BOOT (attitude/block.h), the gyro
 * words sums of N codes, the accelerometer's and magnetometer's (one conversion each)
 * their code times N, so a receiver's division by n gives them back exactly (docs/firmware.md
 * "Gyro oversampling"). 1: one scan per sample, no OVERSAMPLE report (the image as before). */
#ifndef FW_GYRO_OVERSAMPLE
#define FW_GYRO_OVERSAMPLE 1
#endif
/* FW_GYRO_MEAN = 1 (with FW_GYRO_OVERSAMPLE > 1): send each gyro word as the rounded mean
 * of its N codes, (sum + N/2) / N, and the accelerometer's and magnetometer's codes as they
 * are: a plain 12-bit stream, no OVERSAMPLE report, which link v2 packs into its DATA frames
 * (sums above 4095 travel one record per RAW frame). 0 (default): the sums. */
#ifndef FW_GYRO_MEAN
#define FW_GYRO_MEAN 0
#endif
#if FW_GYRO_OVERSAMPLE != 1 && FW_GYRO_OVERSAMPLE != 2 && FW_GYRO_OVERSAMPLE != 4 && FW_GYRO_OVERSAMPLE != 8
#error "FW_GYRO_OVERSAMPLE must be 1, 2, 4 or 8"
#endif
#if FW_PERIOD_TICKS % FW_GYRO_OVERSAMPLE != 0
#error "FW_PERIOD_TICKS must be a multiple of FW_GYRO_OVERSAMPLE (sub-intervals of whole ticks)"
#endif
#ifndef FW_RXQ
/* received bytes the FIFO holds (a power of two <= 128): an ACK frame is
 * 10 bytes with its delimiters, and one frame is answered at a time */
#define FW_RXQ 16
#endif
#if !FW_LINK_V2
#error "the aided board speaks link v2 only: build it with FW_LINK_V2=1 (toolchain/firmware.py does)"
#endif
#if FW_ACC_EVERY < 0 || FW_ACC_EVERY > 128 || (FW_ACC_EVERY & (FW_ACC_EVERY - 1)) != 0 || FW_MAG_EVERY < 0 \
    || FW_MAG_EVERY > 128 || (FW_MAG_EVERY & (FW_MAG_EVERY - 1)) != 0
#error "FW_ACC_EVERY and FW_MAG_EVERY must be 0 (not sent) or a power of two 1..128"
#endif
#if FW_RXQ < 2 || FW_RXQ > 128 || (FW_RXQ & (FW_RXQ - 1)) != 0
#error "FW_RXQ must be a power of two 2..128"
#endif
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

#if FW_AIDED
/* Timer 2 as baud generator (RCLK = TCLK = 1): baud = XTAL / (32 * (65536 - RCAP2)). */
#if ((FW_XTAL_HZ / 32L) % FW_BAUD) != 0 || (FW_XTAL_HZ / 32L / FW_BAUD) > 65535L
#error "FW_BAUD cannot be made exactly from FW_XTAL_HZ with Timer 2"
#endif
#define FW_RCAP2 (65536L - FW_XTAL_HZ / 32L / FW_BAUD)
/* Timer 1 mode 2: baud = 2^SMOD * XTAL / (384 * (256 - TH1)). */
#elif ((FW_XTAL_HZ / 384L) % FW_BAUD) == 0 && (FW_XTAL_HZ / 384L / FW_BAUD) <= 255
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
