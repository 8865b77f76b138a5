/*
 * AD7927 driver. See attitude/ad7927.h for the API and docs/ad7927.md for
 * the frame, the pipeline, the sequencer and what was interpreted from the
 * datasheet.
 *
 * The driver works on 16-bit frames only: every call builds the DIN words
 * of its frames, sends them in one HAL transfer where the datasheet allows
 * (only the t_POWER-UP wait splits a call in two), then checks every output
 * word against the channel the pipeline says it holds.
 */
#include "attitude/ad7927.h"

enum {
    F_POWERED = 1u,  /* ad7927_power_up done */
    F_SHUTDOWN = 2u, /* the last control write was a full shutdown */
    F_DIRTY = 4u     /* ctrl changed since the last control write */
};

/* take(): check the leading zero only (the converted channel is not named
 * by the datasheet for that frame). */
#define LEAD_ONLY 0x80u

/* Bit-banged frame timing (ns), datasheet timing specifications (the 3 V
 * column where the two differ). */
enum {
    T_CS_SCLK_NS = 35,   /* CS low -> first DOUT read / SCLK fall: t2 >= 10, t3 <= 35 (DOUT enabled) */
    T_DIN_SETUP_NS = 10, /* DIN stable -> SCLK falling edge: t9 */
    T_SCLK_LOW_NS = 40,  /* SCLK low: t5 >= 0.4 t_SCLK; the next DOUT bit is valid t4 <= 40 after the fall */
    T_SCLK_HIGH_NS = 20  /* SCLK high before the next DIN change: t6 (with the setup wait: 30 high) */
};

/* Pin access of the bit-banged HAL. Define AD7927_HAL_CUSTOM and these
 * five macros (p = the const ad7927_pins * passed to ad7927_pins_transfer,
 * may be ignored) to drive GPIO registers directly. */
#ifndef AD7927_HAL_CUSTOM
#define AD7927_CS(p, v)        ((p)->set_cs((p)->ctx, (v)))
#define AD7927_SCLK(p, v)      ((p)->set_sclk((p)->ctx, (v)))
#define AD7927_DIN(p, v)       ((p)->set_din((p)->ctx, (v)))
#define AD7927_DOUT(p)         ((p)->get_dout((p)->ctx))
#define AD7927_DELAY_NS(p, ns) ((p)->delay_ns((p)->ctx, (ns)))
#endif

int ad7927_pins_transfer(void *pins, const uint16_t *tx, uint16_t *rx, uint8_t n, uint32_t hold_ns)
{
    const ad7927_pins *p = (const ad7927_pins *)pins;
    uint8_t i, k;
    if (p == 0 || tx == 0 || rx == 0) {
        return ATT_E_NULL;
    }
    (void)p;
    AD7927_SCLK(p, 1); /* idle level: the first edge of a frame is a falling one */
    for (i = 0u; i < n; i++) {
        uint16_t w = tx[i];
        uint16_t r = 0u;
        AD7927_CS(p, 0); /* samples the input, drives the leading zero */
        AD7927_DELAY_NS(p, T_CS_SCLK_NS);
        for (k = 0u; k < 16u; k++) {
            /* the part latches DIN and shifts DOUT on the falling edge: set
             * DIN and read the current DOUT bit while SCLK is high */
            AD7927_DIN(p, (w & 0x8000u) != 0u);
            w = (uint16_t)(w << 1);
            AD7927_DELAY_NS(p, T_DIN_SETUP_NS);
            r = (uint16_t)(((unsigned)r << 1) | (AD7927_DOUT(p) ? 1u : 0u));
            AD7927_SCLK(p, 0);
            AD7927_DELAY_NS(p, T_SCLK_LOW_NS);
            AD7927_SCLK(p, 1);
            AD7927_DELAY_NS(p, T_SCLK_HIGH_NS);
        }
        AD7927_CS(p, 1); /* >= 60 ns after the 16th fall: t11 >= 20 */
        rx[i] = r;
        AD7927_DELAY_NS(p, (i + 1u == n && hold_ns > AD7927_T_QUIET_NS) ? hold_ns : AD7927_T_QUIET_NS);
    }
    return 0;
}

uint16_t ad7927_din_word(uint16_t control_bits)
{
    return (uint16_t)((AD7927_CR_WRITE | (control_bits & 0x7FFu)) << AD7927_DIN_SHIFT);
}

/* DIN word of a control write of this driver's mode bits. */
static uint16_t control(const ad7927 *dev, uint16_t seq_bits, uint8_t add)
{
    return ad7927_din_word((uint16_t)(dev->ctrl | seq_bits | ((unsigned)add << AD7927_CR_ADD_SHIFT)));
}

static int settings_bits(const ad7927_settings *s, uint16_t *bits)
{
    uint16_t b = (uint16_t)(AD7927_PM_NORMAL << AD7927_CR_PM_SHIFT);
    if (s == 0) {
        *bits = (uint16_t)(b | AD7927_CR_CODING); /* 0..2*REFIN, straight binary */
        return ATT_OK;
    }
    if (s->range_double > 1u || s->twos_complement > 1u) {
        return ATT_E_ARG;
    }
    if (!s->range_double) {
        b |= AD7927_CR_RANGE;
    }
    if (!s->twos_complement) {
        b |= AD7927_CR_CODING;
    }
    *bits = b;
    return ATT_OK;
}

int ad7927_init(ad7927 *dev, const ad7927_hal *hal, const ad7927_settings *settings)
{
    uint16_t bits;
    uint8_t i;
    if (dev == 0 || hal == 0 || hal->transfer == 0) {
        return ATT_E_NULL;
    }
    if (settings_bits(settings, &bits) != ATT_OK) {
        return ATT_E_ARG;
    }
    dev->hal = hal;
    dev->ctrl = bits;
    dev->pending = AD7927_NO_CHANNEL;
    dev->out_coding = (uint8_t)(bits & AD7927_CR_CODING);
    dev->flags = 0u;
    dev->seq_len = 0u;
    dev->seq_pos = 0u;
    for (i = 0u; i < 16u; i++) {
        dev->seq[i] = 0u;
    }
    dev->last_word = 0u;
    dev->last_expect = AD7927_NO_CHANNEL;
    return ATT_OK;
}

int ad7927_configure(ad7927 *dev, const ad7927_settings *settings)
{
    uint16_t bits;
    if (dev == 0) {
        return ATT_E_NULL;
    }
    if (settings_bits(settings, &bits) != ATT_OK) {
        return ATT_E_ARG;
    }
    if (bits != dev->ctrl) {
        dev->ctrl = bits;
        dev->flags |= F_DIRTY;
    }
    return ATT_OK;
}

/* Send n frames; on a HAL failure nothing is known about the part any more. */
static int xfer(ad7927 *dev, const uint16_t *tx, uint16_t *rx, uint8_t n, uint32_t hold_ns)
{
    if (dev->hal->transfer(dev->hal->ctx, tx, rx, n, hold_ns) != 0) {
        dev->pending = AD7927_NO_CHANNEL;
        dev->seq_len = 0u;
        return AD7927_E_TRANSFER;
    }
    return ATT_OK;
}

/*
 * Check one output word. expect: the channel the frame converted (0..7),
 * LEAD_ONLY, or AD7927_NO_CHANNEL (nothing to check: the output is not a
 * conversion the driver can name). coding: AD7927_CR_CODING bit in effect
 * for that conversion. Stores the code (sign-extended in two's complement)
 * if `code` is not NULL.
 */
static int take(ad7927 *dev, uint16_t word, uint8_t expect, uint8_t coding, int16_t *code)
{
    uint16_t data;
    if (expect == AD7927_NO_CHANNEL) {
        return ATT_OK;
    }
    if ((word & AD7927_OUT_LEAD) != 0u
        || (expect != LEAD_ONLY && ((word >> AD7927_OUT_ADDR_SHIFT) & 7u) != expect)) {
        dev->last_word = word;
        dev->last_expect = expect;
        dev->pending = AD7927_NO_CHANNEL;
        dev->seq_len = 0u;
        return (word & AD7927_OUT_LEAD) ? AD7927_E_FRAME : AD7927_E_CHANNEL;
    }
    if (code != 0) {
        data = (uint16_t)(word & AD7927_OUT_DATA_MASK);
        /* two's complement: 12-bit field, sign bit 0x800 */
        *code = coding ? (int16_t)data : (int16_t)((int16_t)(data ^ 0x800u) - 2048);
    }
    return ATT_OK;
}

/* Leave full shutdown with this control write (PM = normal) in its own
 * transfer, CS held high t_POWER-UP after it. The frame converted nothing
 * valid: its output is not checked. */
static int wake(ad7927 *dev, uint16_t tx)
{
    uint16_t rx;
    int st = xfer(dev, &tx, &rx, 1u, AD7927_T_POWER_UP_NS);
    if (st == ATT_OK) {
        dev->flags &= (uint8_t) ~(F_SHUTDOWN | F_DIRTY);
        dev->out_coding = (uint8_t)(dev->ctrl & AD7927_CR_CODING);
    }
    return st;
}

int ad7927_power_up(ad7927 *dev)
{
    uint16_t tx[1], rx[1];
    int st;
    if (dev == 0) {
        return ATT_E_NULL;
    }
    dev->flags = 0u;
    dev->seq_len = 0u;
    dev->pending = AD7927_NO_CHANNEL;
    /* Two frames with DIN high. Whatever the part woke in, one of them is
     * a control write of 0xFFF (the first may go to a pending shadow-register
     * load): normal power, range 0..REFIN, straight binary, consecutive
     * sequence VIN0..VIN7. If the part was shut down it powers up on the CS
     * rising edge of that write: each frame is followed by t_POWER-UP. */
    tx[0] = 0xFFFFu;
    st = xfer(dev, tx, rx, 1u, AD7927_T_POWER_UP_NS);
    if (st == ATT_OK) {
        st = xfer(dev, tx, rx, 1u, AD7927_T_POWER_UP_NS);
    }
    if (st != ATT_OK) {
        return st;
    }
    /* The first write of the configured mode (sequencer off, VIN0 next).
     * This frame converts VIN0, the head of that all-ones sequence. */
    tx[0] = control(dev, 0u, 0u);
    st = xfer(dev, tx, rx, 1u, AD7927_T_QUIET_NS);
    if (st != ATT_OK) {
        return st;
    }
    st = take(dev, rx[0], 0u, 1u, 0);
    if (st != ATT_OK) {
        return st;
    }
    dev->flags = F_POWERED;
    dev->pending = 0u;
    dev->out_coding = (uint8_t)(dev->ctrl & AD7927_CR_CODING);
    return ATT_OK;
}

int ad7927_scan(ad7927 *dev, const uint8_t *channels, uint8_t n, int16_t *codes, uint8_t next)
{
    uint16_t tx[AD7927_MAX_FRAMES], rx[AD7927_MAX_FRAMES];
    uint8_t i, f = 0u, prime, coding;
    int st;
    if (dev == 0 || channels == 0 || codes == 0) {
        return ATT_E_NULL;
    }
    if (n == 0u || n > AD7927_MAX_SCAN || next >= AD7927_CHANNELS) {
        return ATT_E_ARG;
    }
    for (i = 0u; i < n; i++) { /* all checked first: the frames go out in one batch */
        if (channels[i] >= AD7927_CHANNELS) {
            return ATT_E_ARG;
        }
    }
    if ((dev->flags & F_POWERED) == 0u) {
        return ATT_E_STATE;
    }
    if ((dev->flags & F_SHUTDOWN) != 0u) {
        st = wake(dev, control(dev, 0u, channels[0]));
        if (st != ATT_OK) {
            return st;
        }
        dev->seq_len = 0u;
        dev->pending = channels[0];
    }
    /* A priming frame unless the next conversion is already channels[0] in
     * the configured mode (its output: whatever was pending, discarded). */
    prime = (uint8_t)(dev->pending != channels[0] || dev->seq_len != 0u || (dev->flags & F_DIRTY) != 0u);
    if (prime) {
        tx[f++] = control(dev, 0u, channels[0]);
    }
    for (i = 1u; i < n; i++) {
        tx[f++] = control(dev, 0u, channels[i]);
    }
    tx[f++] = control(dev, 0u, next);
    st = xfer(dev, tx, rx, f, AD7927_T_QUIET_NS);
    if (st != ATT_OK) {
        return st;
    }
    coding = (uint8_t)(dev->ctrl & AD7927_CR_CODING);
    f = 0u;
    if (prime) {
        st = take(dev, rx[0], dev->pending, dev->out_coding, 0);
        if (st != ATT_OK) {
            return st;
        }
        f = 1u;
    }
    for (i = 0u; i < n; i++, f++) {
        /* the first output of the batch still has the coding written before it */
        st = take(dev, rx[f], channels[i], (f == 0u) ? dev->out_coding : coding, &codes[i]);
        if (st != ATT_OK) {
            dev->flags &= (uint8_t)~F_DIRTY;
            return st;
        }
    }
    dev->pending = next;
    dev->out_coding = coding;
    dev->seq_len = 0u;
    dev->flags &= (uint8_t)~F_DIRTY;
    return ATT_OK;
}

/* One control write starting a sequence: woken from full shutdown, or
 * checked against what was pending. */
static int sequence_write(ad7927 *dev, uint16_t tx)
{
    uint16_t rx;
    int st;
    if ((dev->flags & F_SHUTDOWN) != 0u) {
        return wake(dev, tx);
    }
    st = xfer(dev, &tx, &rx, 1u, AD7927_T_QUIET_NS);
    if (st == ATT_OK) {
        st = take(dev, rx, dev->pending, dev->out_coding, 0);
    }
    dev->flags &= (uint8_t)~F_DIRTY;
    dev->out_coding = (uint8_t)(dev->ctrl & AD7927_CR_CODING);
    return st;
}

int ad7927_seq_start(ad7927 *dev, uint8_t last)
{
    uint8_t i;
    int st;
    if (dev == 0) {
        return ATT_E_NULL;
    }
    if (last >= AD7927_CHANNELS) {
        return ATT_E_ARG;
    }
    if ((dev->flags & F_POWERED) == 0u) {
        return ATT_E_STATE;
    }
    st = sequence_write(dev, control(dev, AD7927_CR_SEQ | AD7927_CR_SHADOW, last));
    if (st != ATT_OK) {
        return st;
    }
    for (i = 0u; i <= last; i++) {
        dev->seq[i] = i;
    }
    dev->seq_len = (uint8_t)(last + 1u);
    dev->seq_pos = 0u;
    dev->pending = 0u;
    return ATT_OK;
}

int ad7927_shadow_start(ad7927 *dev, uint8_t seq_one, uint8_t seq_two)
{
    uint16_t shadow = 0u;
    uint16_t rx;
    uint8_t c, len = 0u;
    int st;
    if (dev == 0) {
        return ATT_E_NULL;
    }
    if (seq_one == 0u) {
        return ATT_E_ARG;
    }
    if ((dev->flags & F_POWERED) == 0u) {
        return ATT_E_STATE;
    }
    /* shadow word, MSB first: sequence one VIN0..VIN7, sequence two VIN0..VIN7 */
    for (c = 0u; c < AD7927_CHANNELS; c++) {
        if ((seq_one >> c) & 1u) {
            shadow |= (uint16_t)(0x8000u >> c);
        }
        if ((seq_two >> c) & 1u) {
            shadow |= (uint16_t)(0x0080u >> c);
        }
    }
    st = sequence_write(dev, control(dev, AD7927_CR_SHADOW, 0u));
    if (st != ATT_OK) {
        return st;
    }
    st = xfer(dev, &shadow, &rx, 1u, AD7927_T_QUIET_NS);
    if (st == ATT_OK) {
        st = take(dev, rx, LEAD_ONLY, 1u, 0);
    }
    if (st != ATT_OK) {
        return st;
    }
    for (c = 0u; c < AD7927_CHANNELS; c++) {
        if ((seq_one >> c) & 1u) {
            dev->seq[len++] = c;
        }
    }
    for (c = 0u; c < AD7927_CHANNELS; c++) {
        if ((seq_two >> c) & 1u) {
            dev->seq[len++] = c;
        }
    }
    dev->seq_len = len;
    dev->seq_pos = 0u;
    dev->pending = dev->seq[0];
    return ATT_OK;
}

int ad7927_seq_read(ad7927 *dev, int16_t *codes, uint8_t *channels, uint8_t n)
{
    uint16_t tx[AD7927_MAX_SCAN], rx[AD7927_MAX_SCAN];
    uint8_t i, coding, ch;
    int st;
    if (dev == 0 || codes == 0) {
        return ATT_E_NULL;
    }
    if (n == 0u || n > AD7927_MAX_SCAN) {
        return ATT_E_ARG;
    }
    if (dev->seq_len == 0u || (dev->flags & F_SHUTDOWN) != 0u) {
        return ATT_E_STATE;
    }
    for (i = 0u; i < n; i++) {
        tx[i] = 0u; /* WRITE = 0: the control register and the sequence run on */
    }
    if ((dev->flags & F_DIRTY) != 0u) {
        /* SEQ = 1, SHADOW = 0: new range/coding without interrupting the sequence */
        tx[0] = control(dev, AD7927_CR_SEQ, 0u);
    }
    st = xfer(dev, tx, rx, n, AD7927_T_QUIET_NS);
    if (st != ATT_OK) {
        return st;
    }
    coding = (uint8_t)(dev->ctrl & AD7927_CR_CODING);
    for (i = 0u; i < n; i++) {
        ch = dev->seq[dev->seq_pos];
        st = take(dev, rx[i], ch, (i == 0u) ? dev->out_coding : coding, &codes[i]);
        if (st != ATT_OK) {
            dev->flags &= (uint8_t)~F_DIRTY;
            return st;
        }
        if (channels != 0) {
            channels[i] = ch;
        }
        dev->seq_pos = (uint8_t)((dev->seq_pos + 1u == dev->seq_len) ? 0u : dev->seq_pos + 1u);
    }
    dev->pending = dev->seq[dev->seq_pos];
    dev->out_coding = coding;
    dev->flags &= (uint8_t)~F_DIRTY;
    return ATT_OK;
}

int ad7927_power_down(ad7927 *dev)
{
    uint16_t tx, rx;
    int st;
    if (dev == 0) {
        return ATT_E_NULL;
    }
    if ((dev->flags & F_POWERED) == 0u) {
        return ATT_E_STATE;
    }
    if ((dev->flags & F_SHUTDOWN) != 0u) {
        return ATT_OK;
    }
    tx = ad7927_din_word((uint16_t)((dev->ctrl & (AD7927_CR_RANGE | AD7927_CR_CODING))
                                    | (AD7927_PM_FULL_SHUTDOWN << AD7927_CR_PM_SHIFT)));
    st = xfer(dev, &tx, &rx, 1u, AD7927_T_QUIET_NS);
    if (st == ATT_OK) {
        st = take(dev, rx, dev->pending, dev->out_coding, 0);
    }
    /* whatever the check said, the write may have gone out: treat the part
     * as shut down (the next call wakes it, which is harmless if it is not) */
    dev->flags = (uint8_t)((dev->flags & (uint8_t)~F_DIRTY) | F_SHUTDOWN);
    dev->pending = AD7927_NO_CHANNEL;
    dev->seq_len = 0u;
    return st;
}
