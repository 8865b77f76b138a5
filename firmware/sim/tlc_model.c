/*
 * firmware/sim/tlc_model.c — behavioural model of a TLC2543 with three
 * gyros, compiled into simulation images of the firmware (8051 C, integer
 * only). The firmware's real driver (csrc/src/tlc2543.c, unchanged) drives
 * it through the macros of tlc_hal_sim.h.
 *
 * The chip, as the driver must see it:
 *  - CS falling edge starts an I/O cycle; DATA OUT presents the MSB of the
 *    previous result and moves to the next bit after each clock;
 *  - I/O CLOCK rising edge: DATA INPUT is shifted in (first 8 clocks);
 *  - CS rising edge after exactly 12 clocks: the addressed input is
 *    converted; EOC reads low for FW_SIM_CONV_POLLS reads, then high.
 * Only the firmware's format is modelled (12 bits, MSB first, unipolar:
 * input byte low nibble 0). Anything else — another clock count, another
 * format, CS falling while a conversion runs or with the clock high,
 * clocking with CS high — is a protocol violation: the model prints
 * "MODEL ERROR <what>" and stops the simulation (EXIT 2).
 *
 * Analog inputs (Vref+ = 5 V, Vref- = 0 V; a 16-bit value v stands for
 * v / 65536 * Vref): AIN0..AIN2 are the X, Y, Z gyros,
 *     v_c(k) = OFF_c + (round(32767 sin(2 pi (PH_c + k STEP_c) / 256)) >> SH_c)
 * where k is the simulated time of the conversion in sampling periods
 * since the first gyro conversion, rounded to the nearest period:
 * k = round((fw_ticks - t_first) / FW_PERIOD_TICKS). So the inputs are
 * sinusoidal angular rates read at the instants the conversions really
 * happen (Timer 0 time), and a sample taken at the wrong time, a stale
 * pipeline result or a mislabelled channel shows up as a wrong value.
 * The 12-bit code is v >> 4 (ideal quantizer, no offset or gain error).
 * AIN3..AIN10 are grounded (code 0); the test inputs give 0x800, 0x000,
 * 0xFFF. FW_SIM_DOUT_STUCK=0/1 ties DATA OUT low/high, FW_SIM_EOC_STUCK
 * keeps EOC low: the faults of the self-test and EOC-timeout tests.
 */
#include "attitude/tlc2543.h"
#include "config.h"
#include "fw_sim.h"
#include "sim_io.h"

extern uint16_t fw_ticks; /* firmware's Timer 0 tick counter (main.c) */

#ifndef FW_SIM_CONV_POLLS
#define FW_SIM_CONV_POLLS 2
#endif

/* Gyro signals (see above). */
#ifndef FW_SIM_X_OFF
#define FW_SIM_X_OFF 32768u
#define FW_SIM_X_SH 1
#define FW_SIM_X_PH 0
#define FW_SIM_X_STEP 3
#endif
#ifndef FW_SIM_Y_OFF
#define FW_SIM_Y_OFF 24576u
#define FW_SIM_Y_SH 2
#define FW_SIM_Y_PH 64
#define FW_SIM_Y_STEP 5
#endif
#ifndef FW_SIM_Z_OFF
#define FW_SIM_Z_OFF 40960u
#define FW_SIM_Z_SH 3
#define FW_SIM_Z_PH 128
#define FW_SIM_Z_STEP 7
#endif

static const int16_t quarter_sine[65] = {
    0, 804, 1608, 2410, 3212, 4011, 4808, 5602,
    6393, 7179, 7962, 8739, 9512, 10278, 11039, 11793,
    12539, 13279, 14010, 14732, 15446, 16151, 16846, 17530,
    18204, 18868, 19519, 20159, 20787, 21403, 22005, 22594,
    23170, 23731, 24279, 24811, 25329, 25832, 26319, 26790,
    27245, 27683, 28105, 28510, 28898, 29268, 29621, 29956,
    30273, 30571, 30852, 31113, 31356, 31580, 31785, 31971,
    32137, 32285, 32412, 32521, 32609, 32678, 32728, 32757,
    32767,
};

static const uint16_t gyro_off[3] = {FW_SIM_X_OFF, FW_SIM_Y_OFF, FW_SIM_Z_OFF};
static const uint8_t gyro_sh[3] = {FW_SIM_X_SH, FW_SIM_Y_SH, FW_SIM_Z_SH};
static const uint8_t gyro_step[3] = {FW_SIM_X_STEP, FW_SIM_Y_STEP, FW_SIM_Z_STEP};
static const uint8_t gyro_phase[3] = {FW_SIM_X_PH, FW_SIM_Y_PH, FW_SIM_Z_PH};

/* Model state beyond tlc_hal_sim.h's pins: SFR cells, no RAM (see there). */
__sfr __at(0xC6) m_k;             /* sampling periods since the first conversion (mod 256) */
__sfr16 __at(0xCAC9) m_bound;     /* fw_ticks at which m_k next increments */
__sfr16 __at(0xCCCB) m_conversions; /* gyro conversions so far */

static void violation(const char *what)
{
    fw_sim_puts("MODEL ERROR ");
    fw_sim_puts(what);
    fw_sim_putc('\n');
    fw_sim_stop(2);
}

void fw_sim_model_init(void)
{
    fwm_cs_pin = 1;
    fwm_clk_pin = 0;
    fwm_din_pin = 0;
    fwm_bad = 0;
    fwm_started = 0;
    fwm_nclk = 0;
    fwm_in = 0;
    fwm_word = 0;
    fwm_eoc_wait = 0;
    m_k = 0;
    m_bound = 0;
    m_conversions = 0;
}

/* CS edges: falling starts an I/O cycle, rising ends it: check it, then
 * convert the addressed input (EOC low for FW_SIM_CONV_POLLS reads). */
void fwm_cs(unsigned char level)
{
    uint16_t v;
    uint8_t a, p, i, q;
    if (level == 0u) {
        if (fwm_cs_pin == 0) {
            return;
        }
        fwm_cs_pin = 0;
        if (fwm_eoc_wait != 0u) {
            violation("CS low during a conversion");
        }
        if (fwm_clk_pin) {
            violation("CS fell with I/O CLOCK high");
        }
        fwm_nclk = 0;
        fwm_in = 0;
        return;
    }
    if (fwm_cs_pin) {
        return;
    }
    fwm_cs_pin = 1;
    if (fwm_bad) {
        violation("I/O CLOCK toggled with CS high");
    }
    if (fwm_nclk != 12u) {
        violation("clock count is not 12");
    }
    if ((fwm_in & 0x0Fu) != 0u) {
        violation("format is not 12-bit MSB-first unipolar");
    }
    a = (uint8_t)(fwm_in >> 4);
    if (a >= TLC2543_POWER_DOWN) {
        fwm_word = 0u; /* power-down: output register undefined, model gives 0 */
        return;
    }
    fwm_eoc_wait = FW_SIM_CONV_POLLS;
    if (a > TLC2543_CH_Z) {
        fwm_word = a == TLC2543_TEST_MID ? 0x800u : (a == TLC2543_TEST_REFP ? 0xFFFu : 0u);
        return; /* test inputs; AIN3..AIN10 grounded, Vref- */
    }
    /* k = round((fw_ticks - t_first) / period), kept incrementally:
     * m_bound is the next half-period boundary. */
    v = fw_ticks;
    if (!fwm_started) {
        fwm_started = 1;
        m_bound = (uint16_t)(v + (uint16_t)(FW_PERIOD_TICKS - FW_PERIOD_TICKS / 2));
    }
    while ((int16_t)(v - m_bound) >= 0) {
        m_k++;
        m_bound += (uint16_t)FW_PERIOD_TICKS;
    }
    m_conversions++;
    /* sine of phase p (256 steps per turn) from the quarter-wave table */
    p = (uint8_t)(gyro_phase[a] + (uint8_t)(m_k * gyro_step[a]));
    i = (uint8_t)(p & 63u);
    q = (uint8_t)(p >> 6);
    if (q & 1u) {
        i = (uint8_t)(64u - i);
    }
    v = (uint16_t)(quarter_sine[i] >> gyro_sh[a]);
    if (q & 2u) {
        v = (uint16_t)-v;
    }
    fwm_word = (uint16_t)((uint16_t)(gyro_off[a] + v) >> 4);
}

static const tlc2543_hal dummy_hal = {0, 0, 0, 0, 0, 0, 0};

const tlc2543_hal *fw_sim_adc_hal(void)
{
    return &dummy_hal;
}

uint16_t fw_sim_conversions(void)
{
    return m_conversions;
}
