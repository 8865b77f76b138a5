/*
 * firmware/report.h — the blocks the acquisition board sends over the link.
 *
 * Every block is ATT_LINK_BLOCK_DEFAULT = 6 bytes (the protocol's N).
 *
 * Sample block: X, Y, Z as 16-bit big-endian words holding the 12-bit ADC
 * code (0..4095), so byte 0 is always 0x00..0x0F.
 *
 * Report block: byte 0 = FW_REPORT_MARK (0xFE, impossible in a sample
 * block), byte 1 = kind, bytes 2..5 by kind (multi-byte fields big-endian):
 *
 *   BOOT       version, period_ticks (16), baud / 1200      once at power-up
 *   SELFTEST   status (int8), bad code (16), attempt (8)    each failed self-test
 *   GAVE_UP    first seq (16), count (16)                   a sample the link
 *                                                           gave up on
 *   OVERRUN    first seq (16), count (16)                   samples dropped
 *                                                           because the queue
 *                                                           was full
 *   ADC_ERROR  seq (16), status (int8), 0                   a scan that failed
 *
 * Samples are numbered from 0 at power-up (seq, modulo 2^16). Sample blocks
 * carry no number: the receiver counts them. Every sample that will never
 * be sent is announced by exactly one GAVE_UP / OVERRUN / ADC_ERROR report,
 * placed in the stream exactly where the lost samples would have been, so
 * a receiver that counts sample blocks and adds `count` for each loss
 * report always knows the seq of the next sample.
 */
#ifndef FW_REPORT_H
#define FW_REPORT_H

enum {
    FW_VERSION = 1,
    FW_BLOCK_SIZE = 6,
    FW_REPORT_MARK = 0xFE,
    FW_REPORT_BOOT = 0x00,
    FW_REPORT_SELFTEST = 0x01,
    FW_REPORT_GAVE_UP = 0x02,
    FW_REPORT_OVERRUN = 0x03,
    FW_REPORT_ADC_ERROR = 0x04
};

#endif /* FW_REPORT_H */
