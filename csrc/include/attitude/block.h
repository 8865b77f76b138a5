/*
 * libattitude — block format of the acquisition link: what the bytes of a
 * link block mean (prefix att_block_). The AT89S51 firmware encodes with
 * it, attitude-rx and the Python host ends (through the bindings) decode
 * with it: this header is the one description of the format.
 *
 * Records. A link block (attitude/link.h) of N bytes carries N / 6
 * records of ATT_BLOCK_SIZE = 6 bytes (the firmware sends N = 6: one
 * record per block). Multi-byte fields are big-endian.
 *
 * Sample record: one sample of the three gyro channels,
 *
 *     bytes 0-1  X code   bytes 2-3  Y code   bytes 4-5  Z code
 *
 * each the TLC2543's 12-bit code, 0..ATT_BLOCK_CODE_MAX (4095), so byte 0
 * is 0x00..0x0F. A record whose byte 0 is not ATT_BLOCK_MARK and that
 * holds a code above 4095 is no sample: the decoder rejects it
 * (ATT_BLOCK_E_CODE) and a receiver must never integrate it.
 *
 * Report record: byte 0 = ATT_BLOCK_MARK (0xFE, never byte 0 of a sample),
 * byte 1 = kind, bytes 2-5 by kind (widths in bits):
 *
 *     kind         byte 2        bytes 3-4        byte 5        sent
 *     0 BOOT       version (8)   link + period    baud_div (8)  once at power-up, first
 *                                (1 + 15)
 *     1 SELFTEST   status (8)    bad_code (16)    attempt (8)   each failed ADC self-test
 *
 *     kind         bytes 2-3     bytes 4-5                      sent
 *     2 GAVE_UP    first (16)    count (16)                     the link gave up on samples
 *     3 OVERRUN    first (16)    count (16)                     samples lost to a full queue
 *     4 ADC_ERROR  first (16)    status (8), then 0 (8)         a scan that failed: 1 sample
 *
 *     kind         byte 2        bytes 3-5                      sent
 *     5 OVERSAMPLE n (8)         0 (24)                         by a board that sums n
 *                                                               conversions per word, right
 *                                                               after BOOT
 *
 *     kind         byte 2     byte 3        byte 4      byte 5     sent
 *     6 CHANNELS   board (8)  channels (8)  acc_every   mag_every  by a board whose stream is
 *                                           (8)         (8)        not gyro-only, right after
 *                                                                  BOOT (after OVERSAMPLE when
 *                                                                  both)
 *
 * Fields (the decoder checks every range; a report outside them is
 * rejected with ATT_BLOCK_E_FIELD, an unknown kind with ATT_BLOCK_E_KIND):
 *   version   ATT_BLOCK_VERSION (1), the format this header describes; a
 *             receiver decodes only version 1.
 *   period    sampling period in ticks of 1/ATT_BLOCK_TICK_HZ s (1/3600 s:
 *             Timer 0 of the AT89S51 at 11.0592 MHz), 1..ATT_BLOCK_PERIOD_MAX.
 *             72 = 20 ms. The low 15 bits of bytes 3-4.
 *   link      the top bit of bytes 3-4 (ATT_BLOCK_BOOT_LINK2): the board's
 *             link protocol, 0 = the paper's AA/BB handshake (attitude/link.h;
 *             every BOOT before this bit existed), 1 = link v2
 *             (attitude/link2.h). Decoded as att_block.link 0 or 2.
 *   baud_div  line rate / ATT_BLOCK_BAUD_UNIT (1200), 1..255: 8 = 9600 baud.
 *   status    the att_status of the failure, -128..-1: a TLC2543_E_* code
 *             (attitude/tlc2543.h: -40 EOC timeout, -41/-42/-43 a self-test
 *             input read wrong) or another negative library status.
 *   bad_code  SELFTEST: the 12-bit code read from the failed test input
 *             (0..4095; 0 when there was none, e.g. an EOC timeout).
 *   attempt   SELFTEST: number of the self-test attempt, from 1, mod 256.
 *   first     number of the first lost sample (mod 2^16).
 *   count     GAVE_UP, OVERRUN: samples lost, 1..65535: first .. first +
 *             count - 1. ADC_ERROR always loses one sample (count 1).
 *   n         OVERSAMPLE: conversions summed into each word of the sample
 *             records that follow, 1..ATT_BLOCK_OVERSAMPLE_MAX (16).
 *   board     CHANNELS: the board type (att_block_board): ATT_BLOCK_BOARD_GYRO3
 *             (1: the paper's AT89S51 board, three gyros) or
 *             ATT_BLOCK_BOARD_AIDED9 (2: the AT89S52 board, nine channels of
 *             its TLC2543: three gyros, accelerometer, magnetometer).
 *   channels  CHANNELS: the channel set (att_block_channel bits): ATT_BLOCK_CH_GYR
 *             (bit 0, always set), ATT_BLOCK_CH_ACC (bit 1: three-axis
 *             accelerometer), ATT_BLOCK_CH_MAG (bit 2: three-axis
 *             magnetometer); bits 3-7 are 0. A GYRO3 board's set is GYR alone.
 *   acc_every CHANNELS: the accelerometer's decimation, 1..255 when ACC is in
 *             the set (sample n carries an accelerometer record when
 *             n % acc_every == 0), 0 when it is not.
 *   mag_every CHANNELS: the same for the magnetometer (MAG).
 *
 * Oversampled streams. A board that converts each channel n times per
 * sample period and sends the sums (the paper's increment formation, the
 * simulator's modeled board) keeps the sums' resolution (1/n of a code)
 * in the same 6-byte sample record: it announces n with an OVERSAMPLE
 * report right after BOOT, and its sample records then carry per channel
 * the sum of n codes, 0..min(n x 4095, ATT_BLOCK_SUM_MAX). The limit
 * ATT_BLOCK_SUM_MAX = 0xFDFF keeps byte 0 of every sample below the
 * report mark; it only matters for n = 16, whose sums above 65023 (a mean
 * code above 4063.9, the top 0.8 % of the ADC range) cannot be sent: the
 * encoder refuses them (ATT_BLOCK_E_CODE) and a board reports an
 * ADC_ERROR in their place, as for any code it cannot encode. (No 6-byte
 * record can do better: three words of 0..65520 and the reports need
 * more than 2^48 values.) The AT89S51 firmware sends one conversion per
 * channel and no OVERSAMPLE report (n = 1). A BOOT restarts a stream as a
 * plain one (n = 1). Which limit applies to a sample is therefore a
 * property of the stream: att_block_decode checks a record alone against
 * the plain limit (4095); att_block_seq_decode checks it against its
 * stream's. A receiver that joins after the OVERSAMPLE report reads the
 * sums as plain codes: those above 4095 are rejected, never integrated.
 *
 * Aided streams. A board that sends more than the gyros announces its
 * channel set with a CHANNELS report right after BOOT (after OVERSAMPLE
 * when both); a stream with no CHANNELS after its BOOT is gyro-only (every
 * board before this report), and a BOOT makes a stream gyro-only again.
 * Sample n of a stream with CHANNELS is a group of sample records, in this
 * order: its gyro record (X, Y, Z angular rate channels), then, if ACC is in
 * the set and n % acc_every == 0, an accelerometer record (X, Y, Z), then,
 * if MAG is in the set and n % mag_every == 0, a magnetometer record
 * (X, Y, Z). Each is an ordinary sample record, plain codes or sums as the
 * stream's OVERSAMPLE says (the same limit for every record), so a link
 * carries them unchanged; the records themselves do not say which sensor
 * they hold: their place in the group does. A board never puts a report
 * inside a group (loss reports count whole samples: groups).
 *
 * Loss accounting by sequence number. Samples are numbered from 0, the
 * first sample after BOOT (the self-test runs before sampling starts);
 * sample records carry no number. Every sample that will never be sent
 * is announced by exactly one GAVE_UP, OVERRUN or ADC_ERROR report placed
 * in the stream where the lost samples would have been. A receiver that
 * numbers the sample records it gets and advances by `count` at each loss
 * report therefore knows the number (and so the time, number x period)
 * of every sample, and how many are missing where; a loss report whose
 * `first` disagrees with that count shows that the numbering slipped (a
 * record lost or duplicated on the way: the link's known duplicate, a
 * receiver started after BOOT). att_block_seq_feed keeps that count,
 * reports a slip (ATT_BLOCK_E_SEQ) and resynchronizes on the report.
 * In an aided stream it numbers the samples by their gyro records and
 * tells which record of its group each sample record is
 * (att_block_span.part). A report that arrives inside a group, before
 * the group's accelerometer or magnetometer record (records lost on the
 * way), cuts the group short: that sample keeps only the records already
 * received (a receiver uses it gyro-only, or with the accelerometer alone),
 * the tracker reports ATT_BLOCK_E_SEQ (span.part says which record was
 * due) and handles the report as in a gyro-only stream; a BOOT simply
 * starts a new stream. A record lost or duplicated inside a group's
 * records cannot be seen in the bytes (samples carry no sensor tag): the
 * records are read one place off until the next report, as a lost sample
 * shifts the numbering until the next loss report. A receiver that joins
 * after the CHANNELS report reads the stream as gyro-only (as one that
 * joins after OVERSAMPLE reads it as plain): its sample records are not
 * all gyro records, so such a receiver must wait for a BOOT.
 *
 * Encoders (block.c) are what the firmware links: portable C99 that SDCC
 * compiles for the AT89S51 (leaf functions, 8/16-bit arithmetic, buffers
 * in __data memory there: ATT_LINK_MEM). The encoders of oversampled
 * streams (block_sums.c), the CHANNELS encoder (block_channels.c: the aided
 * AT89S52 image links it, the AT89S51 gyro-only image does not), the
 * decoder and the sequence tracker (block_decode.c) are kept in their own
 * translation units so that an 8051 image carries only what it sends.
 */
#ifndef ATTITUDE_BLOCK_H
#define ATTITUDE_BLOCK_H

#include "attitude/common.h"
#include "attitude/link.h"

ATT_API_BEGIN

/* Format constants. */
enum {
    ATT_BLOCK_SIZE = 6,            /* bytes of one record (= ATT_LINK_BLOCK_DEFAULT) */
    ATT_BLOCK_CODE_MAX = 4095,     /* largest sample code (12-bit ADC) */
    ATT_BLOCK_MARK = 0xFE,         /* byte 0 of every report record */
    ATT_BLOCK_VERSION = 1,         /* format version carried by BOOT */
    ATT_BLOCK_TICK_HZ = 3600,      /* BOOT period unit: ticks per second */
    ATT_BLOCK_PERIOD_MAX = 32767,  /* largest BOOT period (ticks) */
    ATT_BLOCK_BAUD_UNIT = 1200,    /* BOOT baud_div unit (baud per count) */
    ATT_BLOCK_OVERSAMPLE_MAX = 16, /* largest OVERSAMPLE n (conversions per word) */
    ATT_BLOCK_SUM_MAX = 0xFDFF,    /* largest word of an oversampled sample (byte 0 below the mark) */
    ATT_BLOCK_BOOT_LINK2 = 0x8000  /* BOOT period word: the board speaks link v2 (or-ed into period_ticks) */
};

/* Record kinds: byte 1 of a report record, or ATT_BLOCK_SAMPLE. */
typedef enum {
    ATT_BLOCK_BOOT = 0,
    ATT_BLOCK_SELFTEST = 1,
    ATT_BLOCK_GAVE_UP = 2,
    ATT_BLOCK_OVERRUN = 3,
    ATT_BLOCK_ADC_ERROR = 4,
    ATT_BLOCK_OVERSAMPLE = 5,
    ATT_BLOCK_CHANNELS = 6,
    ATT_BLOCK_SAMPLE = 0x100 /* a sample record (not a byte value: never a report kind) */
} att_block_kind;

/* CHANNELS: board types (byte 2). 0 and other values: ATT_BLOCK_E_FIELD. */
typedef enum {
    ATT_BLOCK_BOARD_GYRO3 = 1, /* AT89S51, three gyros: the paper's board (channel set GYR alone) */
    ATT_BLOCK_BOARD_AIDED9 = 2 /* AT89S52, nine TLC2543 channels: gyros, accelerometer, magnetometer */
} att_block_board;

/* CHANNELS: the channel set (byte 3), bits of these values; other bits 0. */
typedef enum {
    ATT_BLOCK_CH_GYR = 1, /* three gyros: always in the set (the first record of every group) */
    ATT_BLOCK_CH_ACC = 2, /* three-axis accelerometer: a record every acc_every samples */
    ATT_BLOCK_CH_MAG = 4  /* three-axis magnetometer: a record every mag_every samples */
} att_block_channel;

/* Which record of its sample's group a sample record is (att_block_span.part). */
typedef enum {
    ATT_BLOCK_PART_GYR = 0, /* the gyro record: the first of the group, numbers the sample */
    ATT_BLOCK_PART_ACC = 1, /* the accelerometer record */
    ATT_BLOCK_PART_MAG = 2  /* the magnetometer record */
} att_block_part;

/* Status codes of this module (range -100..-119 of common.h). */
enum {
    ATT_BLOCK_E_CODE = -100,  /* a sample code above its stream's limit (ATT_BLOCK_CODE_MAX, or
                                 n x ATT_BLOCK_CODE_MAX capped at ATT_BLOCK_SUM_MAX) */
    ATT_BLOCK_E_KIND = -101,  /* a report kind this format does not define */
    ATT_BLOCK_E_FIELD = -102, /* a report field outside its range (see above) */
    ATT_BLOCK_E_SEQ = -103    /* a loss report's first disagrees with the sample count, or a
                                 report cut a group short (aided streams) */
};

/* ------------------------------------------------------------------ */
/* Encoders (block.c): each fills the ATT_BLOCK_SIZE bytes at blk.     */
/* All return ATT_OK, ATT_E_NULL (blk NULL) or the code named; on an   */
/* error blk holds unspecified bytes and must not be sent as is.       */
/* ------------------------------------------------------------------ */

/* Sample record from codes[0..2] = X, Y, Z (each 0..4095, else
 * ATT_BLOCK_E_CODE). codes may be the same memory as blk: the firmware
 * scans the ADC's words into the block and converts them in place. */
int att_block_encode_sample(uint8_t ATT_LINK_MEM *blk, const uint16_t ATT_LINK_MEM *codes);

/* BOOT: version ATT_BLOCK_VERSION, period_ticks 1..32767, or-ed with
 * ATT_BLOCK_BOOT_LINK2 by a board that speaks link v2, baud_div 1..255
 * (else ATT_BLOCK_E_FIELD). */
int att_block_encode_boot(uint8_t ATT_LINK_MEM *blk, uint16_t period_ticks, uint8_t baud_div);

/* SELFTEST: status -128..-1, bad_code 0..4095, attempt (else ATT_BLOCK_E_FIELD). */
int att_block_encode_selftest(uint8_t ATT_LINK_MEM *blk, int8_t status, uint16_t bad_code, uint8_t attempt);

/* GAVE_UP or OVERRUN (kind; another kind: ATT_BLOCK_E_KIND): samples
 * first .. first + count - 1 lost, count >= 1 (else ATT_BLOCK_E_FIELD). */
int att_block_encode_loss(uint8_t ATT_LINK_MEM *blk, uint8_t kind, uint16_t first, uint16_t count);

/* ADC_ERROR: sample `first` lost to a scan that failed with status -128..-1
 * (else ATT_BLOCK_E_FIELD). */
int att_block_encode_adc_error(uint8_t ATT_LINK_MEM *blk, uint16_t first, int8_t status);

/* CHANNELS (block_channels.c: what the aided firmware adds): board
 * ATT_BLOCK_BOARD_GYRO3 or _AIDED9; channels a set of ATT_BLOCK_CH_* bits
 * with GYR, GYR alone for GYRO3; acc_every 1..255 when ACC is in the set,
 * else 0; mag_every likewise for MAG (else ATT_BLOCK_E_FIELD). */
int att_block_encode_channels(uint8_t ATT_LINK_MEM *blk, uint8_t board, uint8_t channels, uint8_t acc_every,
                              uint8_t mag_every);

/* Oversampled streams (block_sums.c: host-side boards, and the aided firmware with gyro
 * oversampling; not the AT89S51 image). */

/* OVERSAMPLE: the sample records that follow carry sums of n conversions,
 * n = 1..ATT_BLOCK_OVERSAMPLE_MAX (else ATT_BLOCK_E_FIELD). */
int att_block_encode_oversample(uint8_t ATT_LINK_MEM *blk, uint8_t n);

/* Sample record of an oversampled stream from sums[0..2] = X, Y, Z, each
 * the sum of n codes: 0..min(n x ATT_BLOCK_CODE_MAX, ATT_BLOCK_SUM_MAX)
 * (else ATT_BLOCK_E_CODE); n 1..ATT_BLOCK_OVERSAMPLE_MAX (else
 * ATT_BLOCK_E_FIELD). n = 1 gives att_block_encode_sample's bytes. */
int att_block_encode_sums(uint8_t ATT_LINK_MEM *blk, const uint16_t ATT_LINK_MEM *sums, uint8_t n);

/* ------------------------------------------------------------------ */
/* Decoder (block_decode.c)                                           */
/* ------------------------------------------------------------------ */

/* One decoded record. Fields a kind does not use are 0. */
typedef struct {
    uint16_t code[3];      /* SAMPLE: X, Y, Z codes */
    uint16_t first;        /* GAVE_UP, OVERRUN, ADC_ERROR: first lost sample (mod 2^16) */
    uint16_t count;        /* GAVE_UP, OVERRUN: samples lost; ADC_ERROR: 1 */
    uint16_t period_ticks; /* BOOT: sampling period, ticks of 1/ATT_BLOCK_TICK_HZ s */
    uint16_t bad_code;     /* SELFTEST: code of the failed test input */
    uint16_t kind;         /* att_block_kind, or an unknown report kind byte (ATT_BLOCK_E_KIND) */
    uint8_t version;       /* BOOT: format version */
    uint8_t baud_div;      /* BOOT: line rate / ATT_BLOCK_BAUD_UNIT */
    uint8_t link;          /* BOOT: the board's link protocol: 0 legacy (AA/BB), 2 link v2 */
    uint8_t attempt;       /* SELFTEST: attempt number (from 1, mod 256) */
    uint8_t oversample;    /* OVERSAMPLE: conversions per word of the samples that follow */
    int8_t status;         /* SELFTEST, ADC_ERROR: the failure's att_status */
    uint8_t board;         /* CHANNELS: board type (att_block_board) */
    uint8_t channels;      /* CHANNELS: channel set (ATT_BLOCK_CH_* bits) */
    uint8_t acc_every;     /* CHANNELS: accelerometer record every acc_every samples (0: none) */
    uint8_t mag_every;     /* CHANNELS: magnetometer record every mag_every samples (0: none) */
} att_block;

/* Decode the ATT_BLOCK_SIZE bytes at raw into *out, a record read alone
 * (a sample's words checked against the plain limit, 4095). Returns ATT_OK,
 * ATT_E_NULL, ATT_BLOCK_E_CODE (out->kind = ATT_BLOCK_SAMPLE and the codes
 * as received, for the caller's log: never integrate them),
 * ATT_BLOCK_E_KIND (out->kind = the unknown kind byte) or
 * ATT_BLOCK_E_FIELD (a report field out of range, a BOOT of another
 * version; out->kind = the report's kind). */
int att_block_decode(const uint8_t *raw, att_block *out);

/* Sequence tracker: numbers the samples of a record stream. A tracker of
 * all-zero bytes is an unsynced, plain, gyro-only one. */
typedef struct {
    uint32_t next;      /* number of the next sample expected (since the last BOOT; not wrapped):
                           its gyro record is the next record with part ATT_BLOCK_PART_GYR */
    uint8_t synced;     /* the numbering was fixed by a BOOT or a loss report */
    uint8_t oversample; /* conversions per sample word: 1, or the last OVERSAMPLE's n */
    uint8_t channels;   /* channel set: ATT_BLOCK_CH_GYR until a CHANNELS report (BOOT: again) */
    uint8_t acc_every;  /* CHANNELS' acc_every (0: no accelerometer records) */
    uint8_t mag_every;  /* CHANNELS' mag_every (0: no magnetometer records) */
    uint8_t part;       /* the record the next sample record is (att_block_part): GYR, the
                           gyro record of sample next; ACC or MAG, a record of the group of
                           sample next - 1. GYR after a feed: that group is complete */
} att_block_seq;

/* Where one record falls in the numbering. */
typedef struct {
    uint32_t first; /* SAMPLE: its number; loss report: first sample lost;
                       BOOT, SELFTEST: the number the next sample will have */
    uint32_t count; /* SAMPLE: 1; loss report: samples missing here (its count,
                       plus an unreported gap when slip > 0); BOOT, SELFTEST: 0 */
    int32_t slip;   /* loss report: its first minus the number expected, -32768..32767:
                       > 0 samples vanished without a report (they are included in
                       first/count), < 0 that many records were numbered twice;
                       0 otherwise */
    uint8_t part;   /* SAMPLE: which record of the group of sample `first` it is
                       (att_block_part; always GYR in a gyro-only stream); a report
                       that cut a group short (ATT_BLOCK_E_SEQ): the record that was
                       due (ACC or MAG); other reports: GYR */
} att_block_span;

/* Start unsynced, plain (oversample 1), gyro-only: samples are numbered
 * from 0 until a BOOT (numbering restarts at 0, the stream is plain and
 * gyro-only again) or a loss report (its first and count are adopted as
 * they are, no slip) fixes the numbering; an OVERSAMPLE report sets the
 * stream's n, a CHANNELS report its channel set and decimations (for the
 * samples after it, numbered as always from BOOT). */
void att_block_seq_init(att_block_seq *s);

/* Place the decoded record b (also a SAMPLE that failed with
 * ATT_BLOCK_E_CODE: it still took its place) and advance. A sample record
 * is the gyro record of sample s->next (which it takes), or the
 * accelerometer or magnetometer record of the group of sample s->next - 1,
 * as s->part says (span->part: which). Returns ATT_OK, ATT_E_NULL,
 * ATT_BLOCK_E_KIND (b->kind unknown: nothing changes), ATT_BLOCK_E_FIELD
 * (a loss report with count 0, an OVERSAMPLE or CHANNELS report with a
 * field out of range: nothing changes) or ATT_BLOCK_E_SEQ (synced, and a
 * loss report disagrees with the count: *span says how; the numbering
 * follows the report from now on; or a report other than BOOT cut a group
 * short: span->part is the record that was due, the group is closed and
 * the report placed as usual). */
int att_block_seq_feed(att_block_seq *s, const att_block *b, att_block_span *span);

/* What a receiver calls for each record: decode the ATT_BLOCK_SIZE bytes
 * at raw into *out with the stream's limit for sample words (4095, or
 * n x 4095 capped at ATT_BLOCK_SUM_MAX after an OVERSAMPLE report) and
 * place the record (att_block_seq_feed). Returns ATT_OK, ATT_E_NULL,
 * ATT_BLOCK_E_CODE (a sample above the stream's limit: it took its
 * number, *span is valid; never integrate it), ATT_BLOCK_E_KIND or
 * ATT_BLOCK_E_FIELD (as att_block_decode; not placed, the stream is
 * unchanged) or ATT_BLOCK_E_SEQ (as att_block_seq_feed). */
int att_block_seq_decode(att_block_seq *s, const uint8_t *raw, att_block *out, att_block_span *span);

ATT_API_END

#endif /* ATTITUDE_BLOCK_H */
