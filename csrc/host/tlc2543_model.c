/*
 * C twin of attitude_c/tlc2543/model.py (host only). Keep the two in step:
 * the tests compare their traces event by event.
 */
#include "tlc2543_model.h"

#include <math.h>
#include <stdarg.h>
#include <string.h>

#define FAR_PAST (-1000000000LL)

void tlc2543m_default_timing(tlc2543m_timing *tm)
{
    tm->t_cs_setup = 1425;
    tm->t_dout_enable = 1425;
    tm->t_din_setup = 100;
    tm->t_din_hold = 5;
    tm->t_clk_high = 122;
    tm->t_clk_low = 122;
    tm->t_dout_valid = 240;
    tm->t_eoc_fall = 2200;
    tm->t_conv = 10000;
    tm->t_cs_reassert = 5000;
}

uint16_t tlc2543m_quantize(double v, double vref_plus, double vref_minus)
{
    double x = (v - vref_minus) / (vref_plus - vref_minus);
    double c = floor(x * 4096.0 + 0.5);
    if (c < 0.0) {
        return 0u;
    }
    if (c > 4095.0) {
        return 4095u;
    }
    return (uint16_t)c;
}

static void format_bits(tlc2543m *m, uint16_t code12, uint8_t mode)
{
    uint16_t code = (mode & 1u) ? (uint16_t)(code12 ^ 0x800u) : code12;
    uint8_t len = (uint8_t)((mode >> 2) & 3u);
    uint8_t nbits, i;
    uint32_t word;
    if (len == 1u) {
        nbits = 8u;
        word = (uint32_t)code >> 4;
    } else if (len == 3u) {
        nbits = 16u;
        word = (uint32_t)code << 4;
    } else {
        nbits = 12u;
        word = code;
    }
    for (i = 0u; i < nbits; i++) {
        uint8_t bit = (uint8_t)((word >> (nbits - 1u - i)) & 1u);
        if (mode & 2u) {
            m->out_bits[nbits - 1u - i] = bit;
        } else {
            m->out_bits[i] = bit;
        }
    }
    m->out_len = nbits;
}

static uint8_t clocks_of(uint8_t in_byte)
{
    uint8_t len = (uint8_t)((in_byte >> 2) & 3u);
    return (len == 1u) ? 8u : (len == 3u) ? 16u : 12u;
}

static void log_event(tlc2543m *m, uint8_t signal, uint8_t value)
{
    devm_log(m->trace, m->trace_cap, &m->trace_len, &m->trace_dropped, m->t, signal, value);
}

/* Latch the first violation; returns 1 (so callers can `if (fail(...)) return;`). */
static int fail(tlc2543m *m, int code, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    devm_vfail(&m->violation, &m->violation_t, m->message, sizeof m->message, m->t, code, fmt, ap);
    va_end(ap);
    return 1;
}

static void set_dout(tlc2543m *m, uint8_t level)
{
    if (m->stuck_dout >= 0 && level != TLC2543M_HIGH_Z) {
        level = (uint8_t)m->stuck_dout;
    }
    if (level != m->dout_level) {
        m->dout_level = level;
        log_event(m, TLC2543M_SIG_DOUT, level);
    }
}

static void set_eoc(tlc2543m *m, uint8_t level)
{
    if (m->stuck_eoc >= 0) {
        level = (uint8_t)m->stuck_eoc;
    }
    if (level != m->eoc_level) {
        m->eoc_level = level;
        log_event(m, TLC2543M_SIG_EOC, level);
    }
}

static uint8_t out_bit(const tlc2543m *m, uint8_t index)
{
    return (index < m->out_len) ? m->out_bits[index] : 0u;
}

static void finish_conversion(tlc2543m *m)
{
    double v;
    uint8_t a = m->pending_address;
    m->pending_active = 0u;
    if (a <= 10u) {
        v = m->inputs[a];
    } else if (a == 11u) {
        v = (m->vref_plus + m->vref_minus) / 2.0;
    } else if (a == 12u) {
        v = m->vref_minus;
    } else {
        v = m->vref_plus;
    }
    format_bits(m, tlc2543m_quantize(v, m->vref_plus, m->vref_minus), m->pending_mode);
    m->conversions++;
    set_eoc(m, 1u);
}

static void advance_to(tlc2543m *m, int64_t t_new)
{
    for (;;) {
        int have_fall = m->eoc_fall_pending && m->eoc_fall_at <= t_new;
        int have_end = m->pending_active && m->conv_end <= t_new;
        if (!have_fall && !have_end) {
            break;
        }
        /* earliest first; at equal times the EOC fall comes first (as in
         * Python's min() over (t, kind) with kind 0 = fall, 1 = end) */
        if (have_fall && (!have_end || m->eoc_fall_at <= m->conv_end)) {
            m->t = m->eoc_fall_at;
            m->eoc_fall_pending = 0u;
            set_eoc(m, 0u);
        } else {
            m->t = m->conv_end;
            finish_conversion(m);
        }
    }
    m->t = t_new;
}

static void reset_cycle(tlc2543m *m)
{
    m->n_rise = 0u;
    m->n_fall = 0u;
    m->in_byte = 0u;
    m->nclk = 0u;
    m->t_cs_fall = 0;
    m->t_rise = FAR_PAST;
    m->t_fall = FAR_PAST;
}

static void end_of_cycle(tlc2543m *m)
{
    uint8_t address = (uint8_t)(m->in_byte >> 4);
    m->t_last_clock = m->t;
    m->has_last_clock = 1u;
    if (address == 15u) {
        fail(m, TLC2543M_V_RESERVED_ADDRESS, "address 15 is reserved (factory test)");
        return;
    }
    if (address == 14u) { /* power-down: no conversion, output undefined */
        format_bits(m, 0xA5Au, 0u);
        m->pending_active = 0u;
        return;
    }
    m->pending_active = 1u;
    m->pending_address = address;
    m->pending_mode = (uint8_t)(m->in_byte & 0x0Fu);
    m->conv_end = m->t + m->timing.t_conv;
    m->eoc_fall_pending = 1u;
    m->eoc_fall_at = m->t + m->timing.t_eoc_fall;
}

int tlc2543m_init(tlc2543m *m, double vref_plus, double vref_minus, uint16_t powerup_word)
{
    if (m == 0) {
        return ATT_E_NULL;
    }
    if (!isfinite(vref_plus) || !isfinite(vref_minus)) {
        return ATT_E_NONFINITE;
    }
    if (!(vref_plus > vref_minus)) {
        return ATT_E_ARG;
    }
    memset(m, 0, sizeof *m);
    m->vref_plus = vref_plus;
    m->vref_minus = vref_minus;
    tlc2543m_default_timing(&m->timing);
    m->stuck_eoc = -1;
    m->stuck_dout = -1;
    m->cs = 1u;
    m->t_din = FAR_PAST;
    m->dout_level = TLC2543M_HIGH_Z;
    m->eoc_level = 1u;
    format_bits(m, (uint16_t)(powerup_word & 0xFFFu), 0u);
    reset_cycle(m);
    m->hal.ctx = m;
    m->hal.set_cs = tlc2543m_set_cs;
    m->hal.set_clock = tlc2543m_set_clock;
    m->hal.set_din = tlc2543m_set_din;
    m->hal.get_dout = tlc2543m_get_dout;
    m->hal.get_eoc = tlc2543m_get_eoc;
    m->hal.delay_ns = tlc2543m_delay_ns;
    return ATT_OK;
}

int tlc2543m_set_inputs(tlc2543m *m, const double *volts, size_t n)
{
    return m == 0 ? ATT_E_NULL : devm_set_inputs(m->inputs, 11u, volts, n);
}

void tlc2543m_delay_ns(void *ctx, uint32_t ns)
{
    tlc2543m *m = (tlc2543m *)ctx;
    advance_to(m, m->t + (int64_t)ns);
}

void tlc2543m_set_cs(void *ctx, int level)
{
    tlc2543m *m = (tlc2543m *)ctx;
    const tlc2543m_timing *tm = &m->timing;
    uint8_t lv = level ? 1u : 0u;
    if (lv == m->cs) {
        return;
    }
    if (m->clock) {
        fail(m, TLC2543M_V_CLOCK_HIGH_AT_CS, "CS changed while I/O CLOCK is high");
    }
    if (lv == 0u) {
        if (m->has_last_clock && m->t - m->t_last_clock < tm->t_cs_reassert) {
            fail(m, TLC2543M_V_CS_TOO_EARLY,
                 "CS fell %lld ns after the last I/O clock (min %d ns): the conversion would abort",
                 (long long)(m->t - m->t_last_clock), (int)tm->t_cs_reassert);
        }
        if (m->pending_active) {
            fail(m, TLC2543M_V_CS_DURING_CONVERSION,
                 "CS fell %lld ns before the conversion ends (it would abort)",
                 (long long)(m->conv_end - m->t));
        }
        m->cs = 0u;
        log_event(m, TLC2543M_SIG_CS, 0u);
        reset_cycle(m);
        m->t_cs_fall = m->t;
        set_dout(m, out_bit(m, 0u));
    } else {
        if (m->nclk == 0u || m->n_fall < m->nclk) {
            fail(m, TLC2543M_V_CS_MID_CYCLE, "CS raised after %u I/O clocks of %u", (unsigned)m->n_fall,
                 (unsigned)m->nclk);
        }
        m->cs = 1u;
        log_event(m, TLC2543M_SIG_CS, 1u);
        set_dout(m, TLC2543M_HIGH_Z);
    }
}

void tlc2543m_set_clock(void *ctx, int level)
{
    tlc2543m *m = (tlc2543m *)ctx;
    const tlc2543m_timing *tm = &m->timing;
    uint8_t lv = level ? 1u : 0u;
    if (lv == m->clock) {
        return;
    }
    if (m->cs) {
        fail(m, TLC2543M_V_CLOCK_CS_HIGH, "I/O CLOCK toggled while CS is high");
    }
    if (lv == 1u) {
        if (m->n_rise == 0u) {
            if (m->t - m->t_cs_fall < tm->t_cs_setup) {
                fail(m, TLC2543M_V_CS_SETUP, "first I/O clock %lld ns after CS fell (min %d ns)",
                     (long long)(m->t - m->t_cs_fall), (int)tm->t_cs_setup);
            }
        } else if (m->t - m->t_fall < tm->t_clk_low) {
            fail(m, TLC2543M_V_CLOCK_TOO_FAST, "I/O CLOCK low for %lld ns (min %d ns: 4.1 MHz)",
                 (long long)(m->t - m->t_fall), (int)tm->t_clk_low);
        }
        if (m->nclk != 0u && m->n_rise >= m->nclk) {
            fail(m, TLC2543M_V_CLOCK_COUNT, "I/O clock %u in a %u-clock cycle", (unsigned)m->n_rise + 1u,
                 (unsigned)m->nclk);
        }
        if (m->n_rise < 8u) {
            if (m->t - m->t_din < tm->t_din_setup) {
                fail(m, TLC2543M_V_DIN_SETUP, "DATA INPUT changed %lld ns before the rising edge (min %d ns)",
                     (long long)(m->t - m->t_din), (int)tm->t_din_setup);
            }
            m->in_byte = (uint8_t)((m->in_byte << 1) | m->din);
        }
        if (m->n_rise < 255u) {
            m->n_rise++;
        }
        if (m->n_rise == 8u) {
            m->nclk = clocks_of(m->in_byte);
        }
        m->clock = 1u;
        m->t_rise = m->t;
        log_event(m, TLC2543M_SIG_CLOCK, 1u);
    } else {
        if (m->t - m->t_rise < tm->t_clk_high) {
            fail(m, TLC2543M_V_CLOCK_TOO_FAST, "I/O CLOCK high for %lld ns (min %d ns: 4.1 MHz)",
                 (long long)(m->t - m->t_rise), (int)tm->t_clk_high);
        }
        m->clock = 0u;
        if (m->n_fall < 255u) {
            m->n_fall++;
        }
        m->t_fall = m->t;
        log_event(m, TLC2543M_SIG_CLOCK, 0u);
        if (m->nclk != 0u && m->n_fall == m->nclk) {
            end_of_cycle(m);
        } else {
            set_dout(m, out_bit(m, m->n_fall));
        }
    }
}

void tlc2543m_set_din(void *ctx, int level)
{
    tlc2543m *m = (tlc2543m *)ctx;
    uint8_t lv = level ? 1u : 0u;
    if (lv == m->din) {
        return;
    }
    if (m->clock && m->t - m->t_rise < m->timing.t_din_hold) {
        fail(m, TLC2543M_V_DIN_HOLD, "DATA INPUT changed %lld ns after the rising edge (min %d ns)",
             (long long)(m->t - m->t_rise), (int)m->timing.t_din_hold);
    }
    m->din = lv;
    m->t_din = m->t;
    log_event(m, TLC2543M_SIG_DIN, lv);
}

int tlc2543m_get_dout(void *ctx)
{
    tlc2543m *m = (tlc2543m *)ctx;
    const tlc2543m_timing *tm = &m->timing;
    if (m->cs) {
        fail(m, TLC2543M_V_DOUT_CS_HIGH, "DATA OUT read while CS is high (high impedance)");
    } else if (m->n_fall == 0u) {
        if (m->t - m->t_cs_fall < tm->t_dout_enable) {
            fail(m, TLC2543M_V_DOUT_EARLY, "DATA OUT read %lld ns after CS fell (valid after %d ns)",
                 (long long)(m->t - m->t_cs_fall), (int)tm->t_dout_enable);
        }
    } else if (m->t - m->t_fall < tm->t_dout_valid) {
        fail(m, TLC2543M_V_DOUT_EARLY,
             "DATA OUT read %lld ns after I/O CLOCK fell (next bit valid after %d ns)",
             (long long)(m->t - m->t_fall), (int)tm->t_dout_valid);
    }
    if (!m->cs && m->nclk != 0u && m->n_fall >= m->nclk) {
        fail(m, TLC2543M_V_DOUT_EARLY, "DATA OUT read after the last bit of the cycle");
    }
    log_event(m, TLC2543M_SIG_READ_DOUT, m->dout_level);
    return m->dout_level == 1u;
}

int tlc2543m_get_eoc(void *ctx)
{
    tlc2543m *m = (tlc2543m *)ctx;
    if (m->has_last_clock && m->pending_active && m->t - m->t_last_clock < m->timing.t_eoc_fall) {
        fail(m, TLC2543M_V_EOC_EARLY, "EOC sampled %lld ns after the last I/O clock (undefined until %d ns)",
             (long long)(m->t - m->t_last_clock), (int)m->timing.t_eoc_fall);
    }
    log_event(m, TLC2543M_SIG_READ_EOC, m->eoc_level);
    return m->eoc_level;
}

int tlc2543m_convert(tlc2543m *m, tlc2543 *dev, const uint8_t *channels, uint8_t nch, const double *volts,
                     size_t n, int32_t *codes, int self_test, size_t *rows_done)
{
    size_t row;
    uint8_t k;
    uint16_t words[11];
    int st;
    if (rows_done != 0) {
        *rows_done = 0u;
    }
    if (m == 0 || dev == 0 || channels == 0 || (n != 0u && (volts == 0 || codes == 0))) {
        return ATT_E_NULL;
    }
    if (nch == 0u || nch > 11u) {
        return ATT_E_ARG;
    }
    for (k = 0u; k < nch; k++) {
        if (channels[k] > 10u) {
            return ATT_E_ARG;
        }
    }
    if (self_test) {
        st = tlc2543_self_test(dev);
        if (m->violation != TLC2543M_V_NONE) {
            return TLC2543M_E_VIOLATION;
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
        st = tlc2543_scan(dev, channels, nch, words, TLC2543_TEST_MID);
        if (m->violation != TLC2543M_V_NONE) {
            return TLC2543M_E_VIOLATION;
        }
        if (st != ATT_OK) {
            return st;
        }
        for (k = 0u; k < nch; k++) {
            codes[row * nch + k] = (dev->pending & 1u) ? tlc2543_signed(dev, words[k]) : words[k];
        }
        if (rows_done != 0) {
            *rows_done = row + 1u;
        }
    }
    return ATT_OK;
}
