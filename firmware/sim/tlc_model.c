/*
 * firmware/sim/tlc_model.c — behavioural model of a TLC2543 with three
 * gyros, compiled into simulation images of the firmware (8051 C, integer
 * only). The firmware's real driver (csrc/src/tlc2543.c, unchanged, with
 * its production 8051 HAL) reaches it through the pin assignment of
 * tlc_hal_sim.h, which holds the chip side (the I/O cycle, conversion,
 * EOC, the checks). This file holds the analog side and the reports.
 *
 * Analog inputs (Vref+ = 5 V, Vref- = 0 V; a 16-bit value v stands for
 * v / 65536 * Vref): AIN0..AIN2 are the X, Y, Z gyros,
 *     v_c(k) = OFF_c + (round(32767 sin(2 pi (PH_c + k STEP_c) / 256)) >> SH_c)
 * where k is the simulated time in sampling periods since the first
 * sample, rounded to the nearest period: k = round((fw_ticks - t_first) /
 * FW_PERIOD_TICKS). The firmware's main loop calls fw_sim_model_step()
 * right before each scan (the analog world advances to "now"), so the
 * inputs are sinusoidal angular rates read at the instants the scans
 * really happen (Timer 0 time): a sample taken at the wrong time, a stale
 * pipeline result or a mislabelled channel shows up as a wrong value.
 * The 12-bit code is v >> 4 (ideal quantizer, no offset or gain error).
 * AIN3..AIN10 are grounded (code 0) on the gyro board; on the aided board
 * (FW_AIDED) AIN3..AIN8 are its accelerometer and magnetometer, the same
 * form with the parameters FW_SIM_AUX_OFF, _SH, _PH, _STEP (comma lists of
 * six: toolchain/firmware.py AUX), evaluated when converted (the time k is
 * the one the scan's step set). The test inputs give 0x800, 0x000, 0xFFF. FW_SIM_DOUT_STUCK=0/1 ties DATA OUT low/high, FW_SIM_EOC_STUCK
 * keeps EOC low: the faults of the self-test and EOC-timeout tests.
 * FW_SIM_EOC_STUCK_AT=K keeps EOC low in one scan only, that of sample K
 * (or of the first sample scanned after it; K < 256): the driver times
 * out, the firmware sends an ADC_ERROR report in that sample's place and
 * samples on (a deterministic loss report).
 *
 * FW_SIM_DATA (aided board only): the inputs come from a recording instead,
 * the simulator interface's input file (s51 -I ...,in=FILE), read in the
 * order the firmware converts them: per sample, the three gyro codes when
 * the scan's step runs, then each accelerometer or magnetometer code when
 * its conversion ends (so only the groups' due channels are in the file:
 * n % FW_ACC_EVERY, n % FW_MAG_EVERY, as the firmware decides). A code is
 * two bytes, big-endian, 0..4095 (toolchain/firmware.py data_file). The
 * scan of the sample at time k gets the file's group k: the groups of
 * samples the firmware never scanned (lost to an OVERRUN) are read and
 * dropped first, so a loss does not shift the recording.
 *
 * Gyro oversampling (FW_GYRO_OVERSAMPLE = N > 1, the aided board): the
 * scan is sub-scan s (0..N-1) of its sample, the firmware's fw_sub (main.c;
 * the sub-scans are only 1/N of a period apart, and the main loop can be late
 * by more than half of that, so the model takes s from the firmware and k
 * from the time of the sample's first sub-scan, fw_ticks - s x period / N);
 * the inputs' phase index is k N + s, so the accelerometer and
 * magnetometer, converted in the last sub-scan, are read at k N + N - 1.
 * With FW_SIM_DATA the file's group k holds N gyro triples (one per
 * sub-scan, in time order), then the accelerometer's and magnetometer's
 * codes; a group the firmware started and did not finish (a sample it lost
 * at its last sub-scan) is read to its end before the next one.
 */
#include "attitude/tlc2543.h"
#include "config.h"
#include "fw_sim.h"
#include "sim_io.h"
#include "tlc_hal_sim.h"

extern uint16_t fw_ticks; /* firmware's Timer 0 tick counter (main.c) */

/* Gyro signals (see above). */
#ifndef FW_SIM_X_OFF
#define FW_SIM_X_OFF  32768u
#define FW_SIM_X_SH   1
#define FW_SIM_X_PH   0
#define FW_SIM_X_STEP 3
#endif
#ifndef FW_SIM_Y_OFF
#define FW_SIM_Y_OFF  24576u
#define FW_SIM_Y_SH   2
#define FW_SIM_Y_PH   64
#define FW_SIM_Y_STEP 5
#endif
#ifndef FW_SIM_Z_OFF
#define FW_SIM_Z_OFF  40960u
#define FW_SIM_Z_SH   3
#define FW_SIM_Z_PH   128
#define FW_SIM_Z_STEP 7
#endif

static const int16_t quarter_sine[65] = {
    0,     804,   1608,  2410,  3212,  4011,  4808,  5602,  6393,  7179,  7962,  8739,  9512,
    10278, 11039, 11793, 12539, 13279, 14010, 14732, 15446, 16151, 16846, 17530, 18204, 18868,
    19519, 20159, 20787, 21403, 22005, 22594, 23170, 23731, 24279, 24811, 25329, 25832, 26319,
    26790, 27245, 27683, 28105, 28510, 28898, 29268, 29621, 29956, 30273, 30571, 30852, 31113,
    31356, 31580, 31785, 31971, 32137, 32285, 32412, 32521, 32609, 32678, 32728, 32757, 32767,
};

#if FW_AIDED
#define FW_SIM_NCH 9 /* gyros, accelerometer, magnetometer: AIN0..AIN8 */
#else
#define FW_SIM_NCH 3
#endif
#if FW_AIDED
#define AUX(list) , list /* the six more inputs' parameters after the gyros' */
#else
#define AUX(list)
#endif
static const uint16_t gyro_off[FW_SIM_NCH] = { FW_SIM_X_OFF, FW_SIM_Y_OFF, FW_SIM_Z_OFF AUX(FW_SIM_AUX_OFF) };
static const uint8_t gyro_sh[FW_SIM_NCH] = { FW_SIM_X_SH, FW_SIM_Y_SH, FW_SIM_Z_SH AUX(FW_SIM_AUX_SH) };
static const uint8_t gyro_step[FW_SIM_NCH] = { FW_SIM_X_STEP, FW_SIM_Y_STEP,
                                               FW_SIM_Z_STEP AUX(FW_SIM_AUX_STEP) };
static const uint8_t gyro_phase[FW_SIM_NCH] = { FW_SIM_X_PH, FW_SIM_Y_PH, FW_SIM_Z_PH AUX(FW_SIM_AUX_PH) };

/* Model state beyond tlc_hal_sim.h's cells: SFR cells too, no RAM. */
__sfr __at(0xBD) m_started; /* fw_sim_model_step() ran once (a byte: SFR 0xC8 holds fwm_word) */
__sfr __at(0xC7) m_k;       /* sampling periods since the first step (mod 256) */
__sfr __at(0xF5) m_next;    /* FW_SIM_DATA: the file's next group (sample number mod 256) */
#if defined(FW_SIM_C52)     /* 0xC8-0xCD are Timer 2's on the C52 core */
__sfr16 __at(0x9493) m_bound;
__sfr16 __at(0x9695) m_conversions;
#else
__sfr16 __at(0xCAC9) m_bound;             /* fw_ticks at which m_k next increments */
__sfr16 __at(0xCCCB) m_conversions;       /* gyro input evaluations so far */
#endif
__sfr __at(0xAF) m_fault_done; /* FW_SIM_EOC_STUCK_AT: the one failed scan happened */
#if FW_AIDED && FW_GYRO_OVERSAMPLE > 1
#define OVS FW_GYRO_OVERSAMPLE
extern uint8_t fw_sub;   /* the firmware's sub-scan (main.c) */
__sfr __at(0xF7) m_left; /* FW_SIM_DATA: codes of the group being read still in the file */
#define M_T          ((uint8_t)(m_k * (uint8_t)OVS + fw_sub)) /* the inputs' phase index */
#define M_SUB_TICKS  ((uint16_t)fw_sub * (uint16_t)(FW_PERIOD_TICKS / OVS))
#define M_NEW_SAMPLE (fw_sub == 0u) /* the step of a sample's first sub-scan */
#else
#define OVS          1
#define M_T          m_k
#define M_SUB_TICKS  0u
#define M_NEW_SAMPLE 1
#endif

void fw_sim_model_init(void)
{
    fwm_cs_pin = 1;
    fwm_clk_pin = 0;
    fwm_din_pin = 0;
    fwm_bad_count = 0;
    fwm_bad_format = 0;
    fwm_bad_cs = 0;
    fwm_bad_abort = 0;
    fwm_nclk = 0;
    fwm_in = 0;
    fwm_word = 0;
    fwm_eoc_wait = 0;
    m_started = 0;
    m_k = 0;
    m_bound = 0;
    m_conversions = 0;
    m_fault_done = 0;
#if defined(FW_SIM_DATA)
    m_next = 0;
#endif
#if OVS > 1
    m_left = 0;
#endif
#if defined(FW_SIM_DOUT_STUCK)
    fwm_stuck_dout = FW_SIM_DOUT_STUCK;
#endif
}

#if defined(FW_SIM_DATA)
#if FW_MAG_SR
#error "FW_SIM_DATA serves one code per magnetometer conversion: not with FW_MAG_SR"
#endif
/* The input file's next code, << 4. */
static uint16_t next_code(void)
{
    uint16_t hi = fw_sim_getc();
#if OVS > 1
    m_left--;
#endif
    return (uint16_t)(((hi << 8) | fw_sim_getc()) << 4);
}

/* The codes of group m_next in the file. */
static uint8_t group_codes(void)
{
    uint8_t n = 3u * OVS;
#if FW_ACC_EVERY == 1
    n += 3u;
#elif FW_ACC_EVERY != 0
    if ((m_next & (uint8_t)(FW_ACC_EVERY - 1)) == 0u) {
        n += 3u;
    }
#endif
#if FW_MAG_EVERY == 1
    n += 3u;
#elif FW_MAG_EVERY != 0
    if ((m_next & (uint8_t)(FW_MAG_EVERY - 1)) == 0u) {
        n += 3u;
    }
#endif
    return n;
}

/* Read and drop group m_next (a sample the firmware did not scan). */
static void skip_group(void)
{
    uint8_t n = group_codes();
    while (n-- != 0u) {
        (void)next_code();
    }
    m_next++;
}
#endif

/* Input c now: on the aided board analog() gives the 16-bit fraction of
 * Vref before the quantizer (mag() below adds the bridge offset first);
 * on the gyro board gyro() gives the 12-bit code << 4 directly (that
 * image's code as it was). */
#if FW_AIDED
#define INPUT_FN analog
#define QUANT(v) (v)
#define gyro(c)  ((uint16_t)(analog(c) & 0xFFF0u))
#else
#define INPUT_FN gyro
#define QUANT(v) ((v)&0xFFF0u)
#endif
static uint16_t INPUT_FN(uint8_t c)
{
    uint8_t p = (uint8_t)(gyro_phase[c] + (uint8_t)(M_T * gyro_step[c]));
    uint8_t i = (uint8_t)(p & 63u);
    uint8_t q = (uint8_t)(p >> 6);
    uint16_t v;
    if (q & 1u) {
        i = (uint8_t)(64u - i);
    }
    v = (uint16_t)(quarter_sine[i] >> gyro_sh[c]);
    if (q & 2u) {
        v = (uint16_t)-v;
    }
    return (uint16_t)QUANT((uint16_t)(gyro_off[c] + v));
}

#if FW_AIDED
/* The magnetometer's bridges (AIN6-AIN8): the field's sign follows the
 * set/reset straps' last pulse (P3.4, as the firmware drives it: high =
 * set, low = reset), the bridge offset FW_SIM_BRIDGE (toolchain/firmware.py
 * BRIDGE: 256 LSB) does not, as
 * in attitude_c's hmc1043-ad623 front end; (c_set + 4095 - c_reset) / 2 is
 * then within 1 LSB of the field's code (docs/firmware.md). */
__sbit __at(0xB4) m_sr_pin; /* P3.4 reads its latch in s51: 1 until driven low */
static uint16_t mag(uint8_t c)
{
    uint16_t v = analog(c);
    if (!m_sr_pin) {
        v = (uint16_t)(0u - v);
    }
    return (uint16_t)((uint16_t)(v + FW_SIM_BRIDGE) & 0xFFF0u);
}
#endif

#ifndef FW_SIM_CONV_POLLS
#define FW_SIM_CONV_POLLS 2 /* EOC reads low after a conversion starts */
#endif

unsigned char fwm_end_cycle(void)
{
    uint8_t a = (uint8_t)(fwm_in >> 4);
    if (fwm_nclk != 12u) {
        fwm_bad_count = 1;
    }
    if ((fwm_in & 0x0Fu) != 0u) {
        fwm_bad_format = 1;
    }
    if (fwm_clk_pin) {
        fwm_bad_cs = 1;
    }
    fwm_nclk = 0;
    fwm_eoc_wait = 0;
    if (a == TLC2543_POWER_DOWN) {
        fwm_word = 0u; /* output register undefined after power-down; the model gives 0 */
        return 1u;
    }
    if (a == TLC2543_CH_X) {
        fwm_word = fwm_vx;
    } else if (a == TLC2543_CH_Y) {
        fwm_word = fwm_vy;
    } else if (a == TLC2543_CH_Z) {
        fwm_word = fwm_vz;
#if FW_AIDED
    } else if (a < FW_SIM_NCH) {
#if defined(FW_SIM_DATA)
        fwm_word = next_code(); /* accelerometer, magnetometer: the recording's next code */
#else
        fwm_word = a >= (uint8_t)FW_AIN_MAG ? mag(a) : gyro(a); /* at the scan's time k */
#endif
#endif
    } else if (a == TLC2543_TEST_MID) {
        fwm_word = 0x8000u;
    } else if (a == TLC2543_TEST_REFP) {
        fwm_word = 0xFFF0u;
    } else {
        fwm_word = 0u; /* Vref-, grounded inputs */
    }
#if defined(FW_SIM_EOC_STUCK)
    fwm_eoc_wait = 255u; /* fault: EOC stays low past the driver's bound */
#else
    fwm_eoc_wait = FW_SIM_CONV_POLLS - 1; /* this read is the first low one */
#if defined(FW_SIM_EOC_STUCK_AT)
    if (m_started && !m_fault_done && m_k >= (uint8_t)FW_SIM_EOC_STUCK_AT) {
        m_fault_done = 1;
        fwm_eoc_wait = 255u; /* past the driver's bound: this scan times out */
    }
#endif
#endif
    return 0u;
}

void fw_sim_model_step(void)
{
    uint16_t t = (uint16_t)(fw_ticks - M_SUB_TICKS); /* oversampling: the sample's first sub-scan */
    if (!m_started) {
        m_started = 1;
        m_bound = (uint16_t)(t + (uint16_t)(FW_PERIOD_TICKS - FW_PERIOD_TICKS / 2));
    }
    /* k = round((fw_ticks - t_first) / period), kept incrementally:
     * m_bound is the next half-period boundary. */
    while ((int16_t)(t - m_bound) >= 0) {
        m_k++;
        m_bound += (uint16_t)FW_PERIOD_TICKS;
    }
#if defined(FW_SIM_DATA)
    if (M_NEW_SAMPLE) {
#if OVS > 1
        while (m_left != 0u) { /* the rest of a group the firmware did not finish */
            (void)next_code();
        }
#endif
        while (m_next != m_k) {
            skip_group();
        }
#if OVS > 1
        m_left = group_codes();
#endif
        m_next++; /* this group: its gyros now, its other codes as they are converted */
    }
    fwm_vx = next_code();
    fwm_vy = next_code();
    fwm_vz = next_code();
#else
    fwm_vx = gyro(0);
    fwm_vy = gyro(1);
    fwm_vz = gyro(2);
#endif
    m_conversions++;
}

static void violation(const char *what)
{
    fw_sim_puts("MODEL ERROR ");
    fw_sim_puts(what);
    fw_sim_putc('\n');
    fw_sim_stop(2);
}

void fw_sim_model_check(void)
{
    if (fwm_bad_count) {
        violation("I/O cycle without exactly 12 clocks");
    }
    if (fwm_bad_format) {
        violation("format is not 12-bit MSB-first unipolar");
    }
    if (fwm_bad_cs) {
        violation("DATA OUT read with CS high");
    }
    if (fwm_bad_abort) {
        violation("I/O cycle during a conversion (EOC low)");
    }
}

uint16_t fw_sim_conversions(void)
{
    return m_conversions;
}
