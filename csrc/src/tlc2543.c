/*
 * TLC2543 bit-banging driver. See attitude/tlc2543.h for the API and
 * docs/tlc2543.md for the I/O cycle, the pipeline and the timing budget.
 *
 * Written for SDCC's small model as much as for the host: 8-bit state and
 * loop variables, no float, no 64-bit, no recursion, the hot loop on
 * bytes so that each I/O clock is a handful of bit instructions.
 */
#include "attitude/tlc2543.h"

/* Datasheet timing limits the driver must respect, in ns. On the host the
 * HAL delays are real calls (a simulated-time model checks them); on the
 * 8051 TLC2543_DELAY_NS() expands to nothing because each instruction
 * takes >= 1 machine cycle (1.085 us at 11.0592 MHz) — see docs/tlc2543.md. */
enum {
    T_CS_SETUP_NS = 1425,   /* CS low -> first I/O CLOCK rise (also DATA OUT enable) */
    T_DIN_SETUP_NS = 100,   /* DATA INPUT stable -> I/O CLOCK rise */
    T_CLK_HIGH_NS = 122,    /* I/O CLOCK high: half of 1/4.1 MHz */
    T_DOUT_VALID_NS = 240,  /* I/O CLOCK fall -> next DATA OUT bit valid (>= 122 low) */
    T_EOC_FALL_NS = 2200,   /* last I/O CLOCK fall -> EOC low (EOC meaningless before) */
    T_EOC_POLL_NS = 1000,   /* spacing of EOC samples */
    T_CS_REASSERT_NS = 5000 /* last I/O CLOCK fall -> CS may fall again */
};

#define TLC2543_MODE_MASK 0x0Fu
#define TLC2543_LSBF      0x02u
#define TLC2543_BIP       0x01u
#define TLC2543_LEN_MASK  0x0Cu

static uint8_t mode_clocks(uint8_t mode)
{
    uint8_t len = (uint8_t)((mode >> 2) & 3u);
    if (len == TLC2543_LEN_8) {
        return 8u;
    }
    if (len == TLC2543_LEN_16) {
        return 16u;
    }
    return 12u;
}

int tlc2543_init(tlc2543 TLC2543_DATA *dev, const tlc2543_hal *hal,
                 const tlc2543_settings *settings) TLC2543_COLD
{
    uint8_t mode = 0u;
    uint8_t polls = TLC2543_EOC_POLLS_DEFAULT;
    if (dev == 0) {
        return ATT_E_NULL;
    }
#if !defined(__SDCC) || defined(TLC2543_HAL_CUSTOM)
    if (hal == 0) {
        return ATT_E_NULL;
    }
    dev->hal = hal;
#else
    (void)hal;
#endif
    if (settings != 0) {
        if ((settings->length != TLC2543_LEN_8 && settings->length != TLC2543_LEN_12
             && settings->length != TLC2543_LEN_16)
            || settings->lsb_first > 1u || settings->bipolar > 1u) {
            return ATT_E_ARG;
        }
        mode = (uint8_t)((settings->length << 2) | (settings->lsb_first << 1) | settings->bipolar);
        if (settings->eoc_polls != 0u) {
            polls = settings->eoc_polls;
        }
    }
    dev->pending = (uint8_t)(TLC2543_NO_RESULT | mode);
    dev->eoc_polls = polls;
    return ATT_OK;
}

/*
 * One I/O clock. DATA INPUT and DATA OUT both change only while the clock
 * is low: DATA INPUT is set (when the clock carries an input bit), DATA OUT
 * is sampled just before the rising edge (the chip shifts it on falling
 * edges; the previous fall was >= T_DOUT_VALID_NS ago), then the clock
 * pulse. The first 8 clocks use the one-byte shift register of the HAL
 * (bit k out, then DATA OUT into bit k: 8 machine cycles on the 8051); the
 * others shift DATA OUT into a byte (`rx <<= 1; if (DOUT) rx |= 1;` becomes
 * MOV C,P1.3 / ADDC A,rx: 6 machine cycles with the clock pulse).
 */
#define CLOCK_PULSE(dev)                        \
    do {                                        \
        TLC2543_CLOCK(dev, 1);                  \
        TLC2543_DELAY_NS(dev, T_CLK_HIGH_NS);   \
        TLC2543_CLOCK(dev, 0);                  \
        TLC2543_DELAY_NS(dev, T_DOUT_VALID_NS); \
    } while (0)
#define CLOCK_SR(dev, sr, k)                      \
    do {                                          \
        TLC2543_DIN(dev, TLC2543_SR_BIT(sr, k));  \
        TLC2543_DELAY_NS(dev, T_DIN_SETUP_NS);    \
        TLC2543_SR_PUT(sr, k, TLC2543_DOUT(dev)); \
        CLOCK_PULSE(dev);                         \
    } while (0)
#define CLOCK_RX(dev, rx)                      \
    do {                                       \
        TLC2543_DELAY_NS(dev, T_DIN_SETUP_NS); \
        rx <<= 1;                              \
        if (TLC2543_DOUT(dev)) {               \
            rx |= 1u;                          \
        }                                      \
        CLOCK_PULSE(dev);                      \
    } while (0)
#define CLOCK_SR_RX(dev, sr, k)                   \
    do {                                          \
        TLC2543_DELAY_NS(dev, T_DIN_SETUP_NS);    \
        TLC2543_SR_PUT(sr, k, TLC2543_DOUT(dev)); \
        CLOCK_PULSE(dev);                         \
    } while (0)

/* n receive-only clocks (1..8) off the fast path: not unrolled. */
static uint8_t clock_rx(tlc2543 TLC2543_DATA *dev, uint8_t n)
{
    uint8_t rx = 0u;
    (void)dev;
    do {
        CLOCK_RX(dev, rx);
    } while (--n);
    return rx;
}

/* Put an L-bit word clocked LSB first back in natural order. */
static uint16_t reverse_bits(uint16_t w, uint8_t nbits)
{
    uint16_t r = 0u;
    do {
        r = (uint16_t)(((unsigned)r << 1) | (w & 1u));
        w >>= 1;
    } while (--nbits);
    return r;
}

/*
 * End of an I/O cycle in the modes off the fast path (8 or 16 bits, or LSB
 * first): the remaining clocks, CS high, and the word put back in natural
 * order. What was clocked out is the previous request's result in the
 * previous request's bit order, which equals the current mode whenever
 * the word is meaningful (a mode change makes the pending result stale:
 * tlc2543_scan discards it). Stores the word if `word` is not NULL.
 */
static void finish_other_modes(tlc2543 TLC2543_DATA *dev, uint8_t in, uint8_t hi, uint16_t TLC2543_DATA *word)
{
    uint8_t nclk = mode_clocks(in);
    uint16_t w;
    (void)dev;
    if (nclk == 8u) {
        w = hi;
    } else if (nclk == 16u) {
        w = (uint16_t)(((uint16_t)hi << 8) | clock_rx(dev, 8u));
    } else {
        w = (uint16_t)(((uint16_t)hi << 4) | clock_rx(dev, 4u));
    }
    TLC2543_CS(dev, 1);
    if ((in & TLC2543_LSBF) != 0u) {
        w = reverse_bits(w, nclk);
    }
    if (word != 0) {
        *word = w;
    }
}

/*
 * One I/O cycle: CS low, the input byte MSB first on DATA INPUT while DATA
 * OUT shifts the previous result out, the remaining clocks of the
 * programmed length (DATA INPUT is a don't-care there and left as is), CS
 * high, then the bounded wait for EOC. Kept in one function (no helper
 * call) because it is the hot path on the 8051.
 */
int tlc2543_cycle(tlc2543 TLC2543_DATA *dev, uint8_t address, uint16_t TLC2543_DATA *word)
{
    uint8_t in, hi, polls;
    uint8_t sr = 0u; /* the shift register on the host (the B register on SDCC) */

    (void)sr;
    if (dev == 0) {
        return ATT_E_NULL;
    }
    if (address > TLC2543_POWER_DOWN) {
        return ATT_E_ARG;
    }
    in = (uint8_t)(dev->pending & TLC2543_MODE_MASK);
    in |= (uint8_t)(address << 4);
    TLC2543_SR_LOAD(sr, in);
    TLC2543_CS(dev, 0);
    TLC2543_DELAY_NS(dev, T_CS_SETUP_NS);
    CLOCK_SR(dev, sr, 7);
    CLOCK_SR(dev, sr, 6);
    CLOCK_SR(dev, sr, 5);
    CLOCK_SR(dev, sr, 4);
    CLOCK_SR(dev, sr, 3);
    CLOCK_SR(dev, sr, 2);
    CLOCK_SR(dev, sr, 1);
    CLOCK_SR(dev, sr, 0);
    hi = TLC2543_SR_GET(sr);
    if ((in & (TLC2543_LEN_MASK | TLC2543_LSBF)) != 0u) {
        finish_other_modes(dev, in, hi, word);
    } else {
        /* Fast path, 12 bits MSB first: move the low nibble of the shift
         * register up and clock the last 4 bits into its low nibble; it
         * then holds the low byte of the word, and hi >> 4 is the high byte. */
        TLC2543_SR_SHL4(sr);
        CLOCK_SR_RX(dev, sr, 3);
        CLOCK_SR_RX(dev, sr, 2);
        CLOCK_SR_RX(dev, sr, 1);
        CLOCK_SR_RX(dev, sr, 0);
        TLC2543_CS(dev, 1);
        if (word != 0) {
            TLC2543_STORE_WORD(word, (uint8_t)(hi >> 4), TLC2543_SR_GET(sr));
        }
    }
    /* EOC is meaningless until T_EOC_FALL_NS after the last clock; then it
     * stays low for the conversion (<= 10 us). A power-down cycle starts no
     * conversion (EOC stays high), so its wait is only the CS re-assert
     * limit. The bound is read only while EOC is low, off the fast path. */
    TLC2543_DELAY_NS(dev, (address == TLC2543_POWER_DOWN) ? T_CS_REASSERT_NS : T_EOC_FALL_NS);
    if (!TLC2543_EOC(dev)) {
        polls = dev->eoc_polls;
        do {
            if (--polls == 0u) {
                dev->pending = (uint8_t)(in | TLC2543_NO_RESULT);
                return TLC2543_E_EOC_TIMEOUT;
            }
            TLC2543_DELAY_NS(dev, T_EOC_POLL_NS);
        } while (!TLC2543_EOC(dev));
    }
    dev->pending = in;
    return ATT_OK;
}

int tlc2543_scan(tlc2543 TLC2543_DATA *dev, const uint8_t *channels, uint8_t n, uint16_t TLC2543_DATA *codes,
                 uint8_t next)
{
    uint8_t ch;
    int st;
    if (dev == 0 || channels == 0 || codes == 0) {
        return ATT_E_NULL;
    }
    if (n == 0u || next > TLC2543_POWER_DOWN) {
        return ATT_E_ARG;
    }
    ch = *channels;
    if (ch >= TLC2543_POWER_DOWN) {
        return ATT_E_ARG;
    }
    if (dev->pending != (uint8_t)(((unsigned)ch << 4) | (dev->pending & TLC2543_MODE_MASK))) {
        st = tlc2543_cycle(dev, ch, 0); /* its output word is stale: discarded */
        if (st != ATT_OK) {
            return st;
        }
    }
    /* channels are checked as they come (each before its cycle), so a bad
     * entry stops the scan with the codes before it already stored */
    while (--n != 0u) {
        ch = *++channels;
        if (ch >= TLC2543_POWER_DOWN) {
            return ATT_E_ARG;
        }
        st = tlc2543_cycle(dev, ch, codes);
        if (st != ATT_OK) {
            return st;
        }
        codes++;
    }
    return tlc2543_cycle(dev, next, codes);
}

/* Check one self-test code; returns ATT_OK or the error naming it. */
static int check_test_code(uint8_t index, uint16_t code)
{
    if (index == 0u) {
        if (code < 0x800u - TLC2543_SELFTEST_TOL || code > 0x800u + TLC2543_SELFTEST_TOL) {
            return TLC2543_E_SELFTEST_MID;
        }
    } else if (index == 1u) {
        if (code > TLC2543_SELFTEST_TOL) {
            return TLC2543_E_SELFTEST_REFM;
        }
    } else if (code < 0xFFFu - TLC2543_SELFTEST_TOL) {
        return TLC2543_E_SELFTEST_REFP;
    }
    return ATT_OK;
}

/*
 * The same I/O cycles as tlc2543_scan({MID, REFM, REFP}, next = MID) from a
 * stale output register, but each code is checked as it arrives, so only
 * one word of RAM is needed (the AT89S51 has 128 bytes). All four cycles
 * always run; the first failing check is returned.
 */
int tlc2543_self_test_codes(tlc2543 TLC2543_DATA *dev, uint16_t TLC2543_DATA *codes) TLC2543_COLD
{
    uint16_t w;
    uint8_t saved, i;
    int st, result = ATT_OK;
    if (dev == 0) {
        return ATT_E_NULL;
    }
    saved = (uint8_t)(dev->pending & TLC2543_MODE_MASK);
    dev->pending = TLC2543_NO_RESULT; /* mode 0: 12-bit, MSB first, unipolar */
    st = tlc2543_cycle(dev, TLC2543_TEST_MID, 0);
    for (i = 0u; st == ATT_OK && i < 3u; i++) {
        /* request REFM, REFP, then MID again while reading MID, REFM, REFP */
        st = tlc2543_cycle(dev, (uint8_t)((i == 2u) ? TLC2543_TEST_MID : TLC2543_TEST_MID + 1u + i), &w);
        if (st == ATT_OK) {
            if (codes != 0) {
                codes[i] = w;
            }
            if (result == ATT_OK) {
                result = check_test_code(i, w);
            }
        }
    }
    /* the pending conversion has the self-test's format: mark it stale */
    dev->pending = (uint8_t)(TLC2543_NO_RESULT | saved);
    return (st != ATT_OK) ? st : result;
}

int tlc2543_self_test(tlc2543 TLC2543_DATA *dev) TLC2543_COLD
{
    return tlc2543_self_test_codes(dev, 0);
}

int tlc2543_power_down(tlc2543 TLC2543_DATA *dev) TLC2543_COLD
{
    return tlc2543_cycle(dev, TLC2543_POWER_DOWN, 0);
}

int16_t tlc2543_signed(const tlc2543 TLC2543_DATA *dev, uint16_t word) TLC2543_COLD
{
    uint16_t sign = (uint16_t)(1u << (mode_clocks(dev->pending) - 1u));
    uint16_t mag = (uint16_t)(word & (sign - 1u));
    /* mag - sign without leaving 16 bits: mag - (sign - 1) - 1 >= -32768 */
    return (word & sign) ? (int16_t)((int16_t)mag - (int16_t)(sign - 1u) - 1) : (int16_t)mag;
}

uint8_t tlc2543_clocks(const tlc2543 TLC2543_DATA *dev) TLC2543_COLD
{
    return mode_clocks(dev->pending);
}
