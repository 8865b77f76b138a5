/*
 * ad7927.h — Analog Devices AD7927 8-channel 12-bit SAR ADC driver (portable C99).
 *
 * One source (csrc/src/ad7927.c) for every target. The driver speaks in
 * 16-clock *frames* (one CS-low period): it builds the words to send, hands
 * a batch of frames to a frame-transfer HAL (struct ad7927_hal) and checks
 * every word that comes back. Two HALs fit under it:
 *
 *  - a hardware SPI controller: fill ad7927_hal.transfer yourself; on
 *    embedded Linux that is spidev (csrc/platform/linux/ad7927_spidev.h,
 *    SPI_IOC_MESSAGE: one spi_ioc_transfer per frame);
 *  - bit-banged GPIO: ad7927_pins_transfer() below is a frame-transfer HAL
 *    over five pin operations (struct ad7927_pins), the way the TLC2543 is
 *    driven (set AD7927_HAL_CUSTOM and the AD7927_CS/... macros of
 *    ad7927.c to inline GPIO accesses on a bare-metal port).
 *
 * The device (datasheet Rev. D; docs/ad7927.md lists what was interpreted):
 *
 *  - Frame: CS falls (the input is sampled, the conversion starts), 16 SCLK
 *    falling edges, CS rises. DIN is latched on falling edges 1..12 (the
 *    12-bit control word, MSB first = bits 15..4 of the 16-bit DIN word;
 *    bits 3..0 are don't-cares) — or on all 16 when the frame loads the
 *    shadow register. DOUT gives a leading zero, ADD2..ADD0 of the channel
 *    converted in this frame, then the 12 data bits MSB first.
 *  - Pipeline: the channel written in frame k is converted (sampled at the
 *    CS falling edge) and clocked out in frame k + 1. The driver state
 *    remembers which channel the next frame converts (`pending`) and checks
 *    the channel address of every output word against it:
 *    AD7927_E_CHANNEL on a mismatch, AD7927_E_FRAME when the leading bit
 *    is 1 (DOUT stuck high, floating bus).
 *  - Power-up: two frames with DIN high, then the first control write
 *    (ad7927_power_up); the part may power up in any mode, even full
 *    shutdown or waiting for a shadow-register word.
 *  - Modes: single channel per write (ad7927_scan), consecutive sequence
 *    VIN0..VINn (ad7927_seq_start), shadow-register sequences
 *    (ad7927_shadow_start), both read with WRITE = 0 frames
 *    (ad7927_seq_read); coding and range can change inside a sequence
 *    (ad7927_configure, SEQ = 1 / SHADOW = 0 write).
 *  - Codes: straight binary 0..4095, or two's complement -2048..2047 about
 *    the middle of the range (returned sign-extended in int16_t).
 *
 * How to use (Linux, the thesis's board: SPI0, 9.26 MHz, REFIN 2.5 V, 0-5 V):
 *
 *     #include "attitude/ad7927.h"
 *     #include "ad7927_spidev.h"
 *     static const uint8_t ch[7] = { 0, 1, 2, 3, 4, 5, 6 };
 *     ad7927_spidev bus;  ad7927_hal hal;  ad7927 adc;  int16_t codes[7];
 *     ad7927_settings s = { 1, 0 };         // 0..2*REFIN = 0..5 V, straight binary
 *     if (ad7927_spidev_open(&bus, "/dev/spidev0.0", 9260000u, &hal) != ATT_OK
 *         || ad7927_init(&adc, &hal, &s) != ATT_OK || ad7927_power_up(&adc) != ATT_OK) ...
 *     for (;;) {
 *         if (ad7927_scan(&adc, ch, 7, codes, ch[0]) != ATT_OK) ...   // 7 frames per scan
 *     }
 *
 * All functions return ATT_OK (0) or a negative att_status / AD7927_E_*.
 * No allocation, no global state; the driver state is caller-owned.
 */
#ifndef ATTITUDE_AD7927_H
#define ATTITUDE_AD7927_H

#include "attitude/common.h"

ATT_API_BEGIN

/* Sizes and special values. */
enum {
    AD7927_CHANNELS = 8,     /* analog inputs VIN0..VIN7 */
    AD7927_MAX_SCAN = 16,    /* channels per ad7927_scan / frames per ad7927_seq_read */
    AD7927_MAX_FRAMES = 17,  /* frames per HAL transfer call (a scan of 16 + 1) */
    AD7927_NO_CHANNEL = 0xFF /* ad7927.pending: the next frame's output is not a
                                conversion the driver can name (after init, an
                                error, a shutdown) */
};

/* Control register (12 bits; sent in bits 15..4 of the DIN word: shift by
 * AD7927_DIN_SHIFT). Datasheet Table 5/6. */
enum {
    AD7927_CR_WRITE = 0x800,  /* 1: load the other 11 bits; 0: register unchanged */
    AD7927_CR_SEQ = 0x400,    /* with SHADOW: sequencer mode (Table 9) */
    AD7927_CR_ADD_SHIFT = 6,  /* ADD2..ADD0: bits 8..6 */
    AD7927_CR_PM_SHIFT = 4,   /* PM1..PM0: bits 5..4 */
    AD7927_CR_SHADOW = 0x008, /* with SEQ: sequencer mode */
    AD7927_CR_RANGE = 0x002,  /* 1: 0..REFIN; 0: 0..2*REFIN (needs AVDD 4.75..5.25 V) */
    AD7927_CR_CODING = 0x001, /* 1: straight binary; 0: two's complement */
    AD7927_DIN_SHIFT = 4      /* DIN word = control << 4 (bits 3..0 don't care, sent 0) */
};

/* Power modes (PM1 PM0). PM = 00 is not a documented mode: never written. */
enum {
    AD7927_PM_NORMAL = 3,
    AD7927_PM_FULL_SHUTDOWN = 2,
    AD7927_PM_AUTO_SHUTDOWN = 1
};

/* Output word (DOUT, 16 bits MSB first). */
enum {
    AD7927_OUT_LEAD = 0x8000,     /* always 0 */
    AD7927_OUT_ADDR_SHIFT = 12,   /* bits 14..12: ADD2..ADD0 of the converted channel */
    AD7927_OUT_DATA_MASK = 0x0FFF /* bits 11..0: the conversion, MSB first */
};

/* Timing the HALs must keep (ns; datasheet timing specifications). */
enum {
    AD7927_T_QUIET_NS = 50,     /* CS high between frames (t_QUIET, min) */
    AD7927_T_POWER_UP_NS = 1000 /* CS rising edge of the write that leaves full
                                   shutdown -> next CS falling edge (t_POWER-UP) */
};

/* Status codes of this module (range -180..-199 of common.h). */
enum {
    AD7927_E_CHANNEL = -180, /* an output word names another channel than the one the driver
                                wrote for that frame (wrong address, missed write, wiring) */
    AD7927_E_FRAME = -181,   /* an output word's leading bit is 1 (DOUT stuck high, no part) */
    AD7927_E_TRANSFER = -182 /* the frame HAL reported a failure (e.g. an ioctl error) */
};

/*
 * Frame-transfer HAL. transfer() runs n frames (1..AD7927_MAX_FRAMES): for
 * frame i, CS low, 16 SCLK cycles shifting tx[i] out on DIN MSB first while
 * rx[i] receives DOUT MSB first, CS high. SCLK and the data edges as in the
 * datasheet's serial-interface timing (SPI mode 2: SCLK idles high, both
 * devices latch on the falling edge; see docs/ad7927.md), SCLK <= 20 MHz,
 * CS high >= AD7927_T_QUIET_NS between frames. After the last frame CS stays
 * high at least hold_ns (>= AD7927_T_QUIET_NS) before any later frame
 * starts. Returns 0, or a negative value (the driver returns
 * AD7927_E_TRANSFER; the HAL keeps its own error detail).
 */
typedef struct ad7927_hal {
    void *ctx; /* passed to transfer */
    int (*transfer)(void *ctx, const uint16_t *tx, uint16_t *rx, uint8_t n, uint32_t hold_ns);
} ad7927_hal;

/* Pin operations for the bit-banged HAL (levels 0/1). */
typedef struct ad7927_pins {
    void *ctx;                                /* passed to every callback */
    void (*set_cs)(void *ctx, int level);     /* CS (active low) */
    void (*set_sclk)(void *ctx, int level);   /* SCLK (idles high) */
    void (*set_din)(void *ctx, int level);    /* DIN, to the ADC */
    int (*get_dout)(void *ctx);               /* DOUT, from the ADC */
    void (*delay_ns)(void *ctx, uint32_t ns); /* wait at least ns nanoseconds */
} ad7927_pins;

/*
 * The bit-banged frame-transfer HAL: `pins` is a const ad7927_pins *. Use
 * it as { .ctx = &pins, .transfer = ad7927_pins_transfer }. Per frame: SCLK
 * high (idle), CS low, wait 35 ns (t2, t3), then 16 times: DIN = next bit,
 * wait 10 ns (t9), read DOUT, SCLK low, wait 40 ns (t5, t4), SCLK high, wait
 * 20 ns (t6); CS high, wait 50 ns (t_QUIET; hold_ns after the last frame).
 * A 70 ns SCLK period: 14.3 MHz when the pin operations take no time.
 * Always returns 0.
 */
int ad7927_pins_transfer(void *pins, const uint16_t *tx, uint16_t *rx, uint8_t n, uint32_t hold_ns);

/* Settings. NULL settings = { 1, 0 }: 0..2*REFIN, straight binary. */
typedef struct {
    uint8_t range_double;    /* 1: 0..2*REFIN (RANGE = 0); 0: 0..REFIN (RANGE = 1) */
    uint8_t twos_complement; /* 1: two's complement (CODING = 0); 0: straight binary */
} ad7927_settings;

/* Driver state: caller-owned, passed by pointer. Treat as opaque. */
typedef struct {
    const ad7927_hal *hal;
    uint16_t ctrl;       /* PM | RANGE | CODING bits of every control write */
    uint8_t pending;     /* channel the next frame converts, or AD7927_NO_CHANNEL */
    uint8_t out_coding;  /* AD7927_CR_CODING bit in effect for that conversion */
    uint8_t flags;       /* AD7927_F_* (private) */
    uint8_t seq_len;     /* 0: no sequence running; else entries of seq[] */
    uint8_t seq_pos;     /* index in seq[] of the channel the next frame converts */
    uint8_t seq[16];     /* the running sequence, in conversion order */
    uint16_t last_word;  /* the output word that failed the last check (diagnostics) */
    uint8_t last_expect; /* the channel that word should have named */
} ad7927;

/* Initialise the state (no bus activity). ATT_E_NULL without hal or
 * hal->transfer, ATT_E_ARG on a settings field other than 0/1. */
int ad7927_init(ad7927 *dev, const ad7927_hal *hal, const ad7927_settings *settings);

/* The power-up sequence (datasheet "Powering up the AD7927"): two frames
 * with DIN high (all ones: whatever state the part woke in, one of them is
 * a control write of 0xFFF: normal power, consecutive sequence 0..7), each
 * followed by t_POWER-UP with CS high (that write may be the one that
 * leaves full shutdown), then the control write of the configured mode
 * selecting VIN0. The third frame's output must be the VIN0 conversion of
 * that all-ones sequence (checked: AD7927_E_FRAME / AD7927_E_CHANNEL); the
 * next frame converts VIN0 in the configured mode. 3 frames, 3 transfers. */
int ad7927_power_up(ad7927 *dev);

/* Read channels[0..n-1] (0..7, n = 1..AD7927_MAX_SCAN) into codes[0..n-1]
 * in one HAL transfer: each frame writes the next channel while clocking
 * out the previous one, the last frame writes `next` (0..7). Pass
 * next = channels[0] and the following scan of the same list needs only n
 * frames (its first conversion is sampled at its own first CS fall); the
 * first scan, or one after a sequence or a configure(), takes n + 1. A
 * running sequence is stopped. After a full shutdown the first frame wakes
 * the part in its own transfer (hold t_POWER-UP). Every output word is
 * checked; on an error the codes before the bad frame are kept and
 * `pending` becomes AD7927_NO_CHANNEL. ATT_E_STATE before ad7927_power_up. */
int ad7927_scan(ad7927 *dev, const uint8_t *channels, uint8_t n, int16_t *codes, uint8_t next);

/* Start the consecutive sequence VIN0..VIN`last` (SEQ = 1, SHADOW = 1,
 * ADD = last; last = 0..7). One frame; its output (the conversion written
 * before) is checked and discarded. ad7927_seq_read then returns VIN0,
 * VIN1, ..., VIN`last`, VIN0, ... */
int ad7927_seq_start(ad7927 *dev, uint8_t last);

/* Program the shadow register (SEQ = 0, SHADOW = 1 write, then the 16-bit
 * shadow word: sequence one then sequence two, each VIN0..VIN7 from the
 * MSB). Masks: bit c = VINc; seq_one != 0. Two frames; the first output is
 * checked and discarded, the second (the shadow-load frame's conversion)
 * is discarded after the leading-zero check. ad7927_seq_read then returns
 * the channels of seq_one in ascending order, then those of seq_two, and
 * around again. */
int ad7927_shadow_start(ad7927 *dev, uint8_t seq_one, uint8_t seq_two);

/* n frames (1..AD7927_MAX_SCAN) of a running sequence, in one transfer:
 * WRITE = 0 frames (DIN low), or a SEQ = 1 / SHADOW = 0 control write as
 * the first frame when ad7927_configure() changed the mode. codes[i] is the
 * conversion of channels[i] (may be NULL), both checked against the
 * sequence. ATT_E_STATE when no sequence runs. */
int ad7927_seq_read(ad7927 *dev, int16_t *codes, uint8_t *channels, uint8_t n);

/* Change range/coding (no bus activity): the next frame written carries
 * them; they apply from the conversion after it. Inside a sequence the
 * next ad7927_seq_read sends them without interrupting the sequence. */
int ad7927_configure(ad7927 *dev, const ad7927_settings *settings);

/* Full shutdown (a PM = 10 write; one frame, its output checked and
 * discarded). The next scan or sequence start wakes the part. */
int ad7927_power_down(ad7927 *dev);

/* The 16-bit DIN word of a control write (WRITE = 1), for HAL tests and
 * transcripts: (AD7927_CR_WRITE | bits) << AD7927_DIN_SHIFT. */
uint16_t ad7927_din_word(uint16_t control_bits);

ATT_API_END

#endif /* ATTITUDE_AD7927_H */
