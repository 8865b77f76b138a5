/*
 * C twin of attitude_c/ad7927/model.py (host only). Keep the two in step:
 * the tests compare their pin traces and frame logs event by event.
 */
#include "ad7927_model.h"

#include <math.h>
#include <stdarg.h>
#include <string.h>

enum {
    PM_AUTO = 1,
    PM_FULL = 2,
    PM_NORMAL = 3
};

void ad7927m_default_timing(ad7927m_timing *tm)
{
    tm->t_cs_sclk = 10;
    tm->t_dout_enable = 35;
    tm->t_dout_access = 40;
    tm->t_sclk_period = 50;
    tm->t_sclk_period_max = 100000;
    tm->t_din_setup = 10;
    tm->t_din_hold = 5;
    tm->t_cs_hold = 20;
    tm->t_quiet = 50;
    tm->t_power_up = 1000;
}

uint16_t ad7927m_quantize(double v, double refin, int range_double)
{
    double span = range_double ? 2.0 * refin : refin;
    double c = floor(v / span * 4096.0);
    if (c < 0.0) {
        return 0u;
    }
    if (c > 4095.0) {
        return 4095u;
    }
    return (uint16_t)c;
}

static void log_event(ad7927m *m, uint8_t signal, uint8_t value)
{
    devm_log(m->trace, m->trace_cap, &m->trace_len, &m->trace_dropped, m->t, signal, value);
}

static void log_frame(ad7927m *m, uint16_t din)
{
    if (m->frames == 0) {
        return;
    }
    if (m->frames_len < m->frames_cap) {
        ad7927m_frame *f = &m->frames[m->frames_len++];
        f->t = m->t_cs_fall;
        f->din = din;
        f->dout = m->out_word;
        f->channel = m->converting;
        f->valid = m->valid;
    } else {
        m->frames_dropped++;
    }
}

/* Latch the first violation. */
static void fail(ad7927m *m, int code, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    devm_vfail(&m->violation, &m->violation_t, m->message, sizeof m->message, m->t, code, fmt, ap);
    va_end(ap);
}

static void set_dout(ad7927m *m, uint8_t level)
{
    if (m->stuck_dout >= 0 && level != AD7927M_HIGH_Z) {
        level = (uint8_t)m->stuck_dout;
    }
    if (level != m->dout_level) {
        m->dout_level = level;
        log_event(m, AD7927M_SIG_DOUT, level);
    }
}

/* CS falling edge: sample and start converting; set out_word. */
static void begin_frame(ad7927m *m)
{
    const ad7927m_timing *tm = &m->timing;
    uint16_t word;
    uint8_t ch;
    if (m->has_cs_rise && m->t - m->t_cs_rise < tm->t_quiet) {
        fail(m, AD7927M_V_QUIET_TIME, "CS fell %lld ns after it rose (min %d ns)",
             (long long)(m->t - m->t_cs_rise), (int)tm->t_quiet);
    }
    if (!m->powered) {
        m->valid = 0u;
        if (m->pm == PM_AUTO) { /* this edge wakes the part; the conversion is a dummy */
            m->powered = 1u;
            m->has_ready = 1u;
            m->ready_at = m->t + tm->t_power_up;
        }
    } else {
        if (m->has_ready && m->t < m->ready_at) {
            fail(m, AD7927M_V_POWER_UP_TIME,
                 "conversion started %lld ns before the part is powered up (t_power_up %d ns)",
                 (long long)(m->ready_at - m->t), (int)tm->t_power_up);
        }
        m->has_ready = 0u;
        m->valid = 1u;
    }
    ch = m->next_ch;
    m->converting = ch;
    if (m->valid) {
        uint16_t code = ad7927m_quantize(m->inputs[ch], m->refin, m->range_bit == 0u);
        word = (uint16_t)(((unsigned)ch << 12) | (m->coding ? code : (uint16_t)(code ^ 0x800u)));
        m->conversions++;
    } else {
        word = (uint16_t)(m->garbage & 0x7FFFu);
    }
    word = (uint16_t)(word ^ ((unsigned)(m->address_xor & 7u) << 12));
    if (m->stuck_dout >= 0) {
        word = m->stuck_dout ? 0xFFFFu : 0u;
    }
    m->out_word = word;
    m->t_cs_fall = m->t;
}

static void advance(ad7927m *m)
{
    m->seq_pos = (uint8_t)((m->seq_pos + 1u) % m->seq_len);
    m->next_ch = m->seq[m->seq_pos];
}

/* CS rising edge after 16 falling edges: the DIN word takes effect. */
static void end_frame(ad7927m *m, uint16_t din)
{
    uint8_t was_valid = m->valid;
    uint8_t c;
    if (m->stuck_din >= 0) {
        din = m->stuck_din ? 0xFFFFu : 0u;
    }
    log_frame(m, din);
    if (m->shadow_pending) {
        m->shadow_pending = 0u;
        m->seq_len = 0u;
        for (c = 0u; c < 8u; c++) { /* sequence one: bits 15..8 = VIN0..VIN7 */
            if ((din >> (15u - c)) & 1u) {
                m->seq[m->seq_len++] = c;
            }
        }
        for (c = 0u; c < 8u; c++) { /* sequence two: bits 7..0 */
            if ((din >> (7u - c)) & 1u) {
                m->seq[m->seq_len++] = c;
            }
        }
        m->seq_pos = 0u;
        m->next_ch = m->seq_len ? m->seq[0] : m->add;
    } else if (din & 0x8000u) {
        uint16_t cw = (uint16_t)(din >> 4);
        uint8_t pm = (uint8_t)((cw >> 4) & 3u);
        uint8_t seq = (uint8_t)((cw >> 10) & 1u), shadow = (uint8_t)((cw >> 3) & 1u);
        uint8_t add = (uint8_t)((cw >> 6) & 7u);
        if (pm == 0u) {
            fail(m, AD7927M_V_INVALID_POWER_MODE, "control word 0x%03X has PM1 PM0 = 00", (unsigned)cw);
        }
        m->add = add;
        m->range_bit = (uint8_t)((cw >> 1) & 1u);
        m->coding = (uint8_t)(cw & 1u);
        if (seq && shadow) {
            for (c = 0u; c <= add; c++) {
                m->seq[c] = c;
            }
            m->seq_len = (uint8_t)(add + 1u);
            m->seq_pos = 0u;
            m->next_ch = 0u;
        } else if (seq) {
            if (m->seq_len) {
                advance(m);
            } else {
                m->next_ch = add;
            }
        } else {
            m->seq_len = 0u;
            m->next_ch = add;
            m->shadow_pending = shadow;
        }
        m->pm = pm;
    } else if (m->seq_len) {
        advance(m);
    }
    /* power, from this CS rising edge */
    if (m->pm == PM_NORMAL && !m->powered) {
        m->powered = 1u;
        m->has_ready = 1u;
        m->ready_at = m->t + m->timing.t_power_up;
    } else if (m->pm == PM_FULL) {
        m->powered = 0u;
    } else if (m->pm == PM_AUTO && was_valid) {
        m->powered = 0u;
    }
}

int ad7927m_init(ad7927m *m, double refin, uint16_t powerup_control, int powerup_shadow)
{
    uint8_t c;
    if (m == 0) {
        return ATT_E_NULL;
    }
    if (!isfinite(refin)) {
        return ATT_E_NONFINITE;
    }
    if (!(refin > 0.0) || powerup_control > 0xFFFu || ((powerup_control >> 4) & 3u) == 0u) {
        return ATT_E_ARG;
    }
    memset(m, 0, sizeof *m);
    m->refin = refin;
    ad7927m_default_timing(&m->timing);
    m->sclk_period_ns = AD7927M_SCLK_PERIOD_NS;
    m->stuck_dout = -1;
    m->stuck_din = -1;
    m->garbage = AD7927M_GARBAGE & 0x7FFFu;
    m->cs = 1u;
    m->dout_level = AD7927M_HIGH_Z;
    m->t_din = -1000000000LL;
    m->add = (uint8_t)((powerup_control >> 6) & 7u);
    m->range_bit = (uint8_t)((powerup_control >> 1) & 1u);
    m->coding = (uint8_t)(powerup_control & 1u);
    m->pm = (uint8_t)((powerup_control >> 4) & 3u);
    m->powered = (uint8_t)(m->pm == PM_NORMAL);
    m->shadow_pending = (uint8_t)(powerup_shadow != 0);
    if (((powerup_control >> 10) & 1u) && ((powerup_control >> 3) & 1u)) {
        for (c = 0u; c <= m->add; c++) {
            m->seq[c] = c;
        }
        m->seq_len = (uint8_t)(m->add + 1u);
    }
    m->next_ch = m->seq_len ? m->seq[0] : m->add;
    m->pins.ctx = m;
    m->pins.set_cs = ad7927m_set_cs;
    m->pins.set_sclk = ad7927m_set_sclk;
    m->pins.set_din = ad7927m_set_din;
    m->pins.get_dout = ad7927m_get_dout;
    m->pins.delay_ns = ad7927m_delay_ns;
    m->pin_hal.ctx = &m->pins;
    m->pin_hal.transfer = ad7927_pins_transfer;
    m->frame_hal.ctx = m;
    m->frame_hal.transfer = ad7927m_transfer;
    return ATT_OK;
}

int ad7927m_set_inputs(ad7927m *m, const double *volts, size_t n)
{
    return m == 0 ? ATT_E_NULL : devm_set_inputs(m->inputs, 8u, volts, n);
}

void ad7927m_delay_ns(void *ctx, uint32_t ns)
{
    ad7927m *m = (ad7927m *)ctx;
    m->t += (int64_t)ns;
}

void ad7927m_set_cs(void *ctx, int level)
{
    ad7927m *m = (ad7927m *)ctx;
    uint8_t lv = level ? 1u : 0u;
    if (lv == m->cs) {
        return;
    }
    if (lv == 0u) {
        begin_frame(m);
        m->cs = 0u;
        log_event(m, AD7927M_SIG_CS, 0u);
        m->n_fall = 0u;
        m->din_word = 0u;
        m->has_fall = 0u;
        m->has_rise = 0u;
        set_dout(m, (uint8_t)(m->out_word >> 15));
    } else {
        if (m->n_fall < 16u) {
            fail(m, AD7927M_V_CS_EARLY,
                 "CS raised after %u SCLK falling edges of 16 (the conversion is aborted)",
                 (unsigned)m->n_fall);
        } else if (m->t - m->t_fall < m->timing.t_cs_hold) {
            fail(m, AD7927M_V_CS_HOLD, "CS raised %lld ns after the 16th falling edge (min %d ns)",
                 (long long)(m->t - m->t_fall), (int)m->timing.t_cs_hold);
        }
        m->cs = 1u;
        log_event(m, AD7927M_SIG_CS, 1u);
        set_dout(m, AD7927M_HIGH_Z);
        m->t_cs_rise = m->t;
        m->has_cs_rise = 1u;
        if (m->n_fall >= 16u) { /* an aborted frame changes nothing */
            end_frame(m, m->din_word);
        }
    }
}

void ad7927m_set_sclk(void *ctx, int level)
{
    ad7927m *m = (ad7927m *)ctx;
    const ad7927m_timing *tm = &m->timing;
    uint8_t lv = level ? 1u : 0u;
    uint8_t bit;
    if (lv == m->sclk) {
        return;
    }
    m->sclk = lv;
    if (m->cs) { /* SCLK is ignored while CS is high */
        log_event(m, AD7927M_SIG_SCLK, lv);
        return;
    }
    if (lv == 1u) {
        m->t_rise = m->t;
        m->has_rise = 1u;
        log_event(m, AD7927M_SIG_SCLK, 1u);
        return;
    }
    if (m->n_fall < 255u) {
        m->n_fall++;
    }
    if (m->n_fall > 16u) {
        fail(m, AD7927M_V_CLOCK_COUNT, "SCLK falling edge %u in a 16-clock frame", (unsigned)m->n_fall);
    }
    if (m->n_fall == 1u) {
        if (m->t - m->t_cs_fall < tm->t_cs_sclk) {
            fail(m, AD7927M_V_CS_SETUP, "first SCLK falling edge %lld ns after CS fell (min %d ns)",
                 (long long)(m->t - m->t_cs_fall), (int)tm->t_cs_sclk);
        }
    } else if (m->has_fall && m->has_rise) {
        int64_t period = m->t - m->t_fall, high = m->t - m->t_rise, low = m->t_rise - m->t_fall;
        if (period < tm->t_sclk_period || 5 * high < 2 * period || 5 * low < 2 * period) {
            fail(m, AD7927M_V_CLOCK_TOO_FAST,
                 "SCLK period %lld ns (low %lld, high %lld; min %d ns, each phase >= 40 %%)",
                 (long long)period, (long long)low, (long long)high, (int)tm->t_sclk_period);
        }
        if (period > tm->t_sclk_period_max) {
            fail(m, AD7927M_V_CLOCK_TOO_SLOW, "SCLK period %lld ns (max %d ns: f_SCLK >= 10 kHz)",
                 (long long)period, (int)tm->t_sclk_period_max);
        }
    }
    if (m->t - m->t_din < tm->t_din_setup) {
        fail(m, AD7927M_V_DIN_SETUP, "DIN changed %lld ns before the falling edge (min %d ns)",
             (long long)(m->t - m->t_din), (int)tm->t_din_setup);
    }
    bit = (m->stuck_din >= 0) ? (uint8_t)m->stuck_din : m->din;
    m->din_word = (uint16_t)(((unsigned)m->din_word << 1) | bit);
    m->t_fall = m->t;
    m->has_fall = 1u;
    log_event(m, AD7927M_SIG_SCLK, 0u);
    if (m->n_fall >= 16u) {
        set_dout(m, AD7927M_HIGH_Z);
    } else {
        set_dout(m, (uint8_t)((m->out_word >> (15u - m->n_fall)) & 1u));
    }
}

void ad7927m_set_din(void *ctx, int level)
{
    ad7927m *m = (ad7927m *)ctx;
    uint8_t lv = level ? 1u : 0u;
    if (lv == m->din) {
        return;
    }
    if (!m->cs && m->has_fall && m->t - m->t_fall < m->timing.t_din_hold) {
        fail(m, AD7927M_V_DIN_HOLD, "DIN changed %lld ns after the falling edge (min %d ns)",
             (long long)(m->t - m->t_fall), (int)m->timing.t_din_hold);
    }
    m->din = lv;
    m->t_din = m->t;
    log_event(m, AD7927M_SIG_DIN, lv);
}

int ad7927m_get_dout(void *ctx)
{
    ad7927m *m = (ad7927m *)ctx;
    const ad7927m_timing *tm = &m->timing;
    if (m->cs || m->n_fall >= 16u) {
        fail(m, AD7927M_V_DOUT_THREE_STATE,
             m->cs ? "DOUT read while it is three-state (CS high)"
                   : "DOUT read while it is three-state (after the 16th falling edge)");
    } else if (m->n_fall == 0u) {
        if (m->t - m->t_cs_fall < tm->t_dout_enable) {
            fail(m, AD7927M_V_DOUT_EARLY, "DOUT read %lld ns after CS fell (valid after %d ns)",
                 (long long)(m->t - m->t_cs_fall), (int)tm->t_dout_enable);
        }
    } else if (m->t - m->t_fall < tm->t_dout_access) {
        fail(m, AD7927M_V_DOUT_EARLY,
             "DOUT read %lld ns after an SCLK falling edge (next bit valid after %d ns)",
             (long long)(m->t - m->t_fall), (int)tm->t_dout_access);
    }
    log_event(m, AD7927M_SIG_READ_DOUT, m->dout_level);
    return m->dout_level == 1u;
}

int ad7927m_transfer(void *ctx, const uint16_t *tx, uint16_t *rx, uint8_t n, uint32_t hold_ns)
{
    ad7927m *m = (ad7927m *)ctx;
    uint8_t i;
    if (m == 0 || (n != 0u && (tx == 0 || rx == 0))) {
        return ATT_E_NULL;
    }
    if (!m->cs) {
        return ATT_E_STATE;
    }
    for (i = 0u; i < n; i++) {
        begin_frame(m);
        m->t += 16 * (int64_t)m->sclk_period_ns;
        m->t_cs_rise = m->t;
        m->has_cs_rise = 1u;
        rx[i] = m->out_word;
        end_frame(m, tx[i]);
        if (i + 1u == n) {
            m->t += (hold_ns > (uint32_t)m->timing.t_quiet) ? (int64_t)hold_ns : m->timing.t_quiet;
        } else {
            m->t += m->timing.t_quiet;
        }
    }
    return 0;
}

int ad7927m_convert(ad7927m *m, ad7927 *dev, const uint8_t *channels, uint8_t nch, const double *volts,
                    size_t n, int32_t *codes, int sequence, int power_up, size_t *rows_done)
{
    size_t row;
    uint8_t k;
    int16_t words[AD7927_MAX_SCAN];
    int st;
    if (rows_done != 0) {
        *rows_done = 0u;
    }
    if (m == 0 || dev == 0 || channels == 0 || (n != 0u && (volts == 0 || codes == 0))) {
        return ATT_E_NULL;
    }
    if (nch == 0u || nch > AD7927_CHANNELS) {
        return ATT_E_ARG;
    }
    for (k = 0u; k < nch; k++) {
        if (channels[k] >= AD7927_CHANNELS || (sequence && channels[k] != k)) {
            return ATT_E_ARG;
        }
    }
    if (power_up) {
        st = ad7927_power_up(dev);
        if (m->violation != AD7927M_V_NONE) {
            return AD7927M_E_VIOLATION;
        }
        if (st != ATT_OK) {
            return st;
        }
    }
    if (sequence) { /* restarted at every call: row 0 begins with VIN0 */
        st = ad7927_seq_start(dev, (uint8_t)(nch - 1u));
        if (m->violation != AD7927M_V_NONE) {
            return AD7927M_E_VIOLATION;
        }
        if (st != ATT_OK) {
            return st;
        }
    }
    for (row = 0u; row < n; row++) {
        const double *v = volts + row * nch;
        for (k = 0u; k < nch; k++) {
            if (!isfinite(v[k])) {
                return ATT_E_NONFINITE;
            }
            m->inputs[channels[k]] = v[k];
        }
        if (sequence) {
            st = ad7927_seq_read(dev, words, 0, nch);
        } else {
            st = ad7927_scan(dev, channels, nch, words, channels[0]);
        }
        if (m->violation != AD7927M_V_NONE) {
            return AD7927M_E_VIOLATION;
        }
        if (st != ATT_OK) {
            return st;
        }
        for (k = 0u; k < nch; k++) {
            codes[row * nch + k] = words[k];
        }
        if (rows_done != 0) {
            *rows_done = row + 1u;
        }
    }
    return ATT_OK;
}
