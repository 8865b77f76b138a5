/*
 * Instruction-count harness for bench/rx_filter.py: attitude-rx's per-sample
 * path on an aided stream (csrc/app/attitude_rx.c), made of the library
 * calls attitude-rx makes for one sample: its group's records decoded and
 * numbered (att_block_seq_decode: the gyro record, and the accelerometer and
 * magnetometer records when due), converted (att_sensor_convert; the
 * accelerometer and magnetometer with a correction matrix and bias), one
 * att_ahrs_update (NULL aiding when the sample has none), then what its
 * output line needs: Euler angles, heading, bias, flags (att_quat_to_euler,
 * att_quat_heading, att_ahrs_bias, att_ahrs_flags). With MODE line, also the
 * line itself formatted as attitude-rx's JSON Lines print it (snprintf, the
 * same numbers with 17 digits). The thread hand-over, the link and the
 * write(2) are not counted.
 *
 * The stream: BOOT and CHANNELS, then a steady turn about the vertical at
 * 200 samples/s, one turn per TABLE samples, as 12-bit codes (tabulated at
 * start-up; toolchain/qemu_count.py's difference of two N cancels it).
 *
 *   rx_filter_armv4t MODE EVERY N
 *     MODE  = path | line
 *     EVERY = 1..255: accelerometer and magnetometer records in sample n
 *             when n % EVERY == 0 (1: every sample; 2: the aided board's plan)
 *     N     = samples
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "attitude/attitude.h"

#define TABLE 1024
#define RATE  200.0

static uint8_t rec[TABLE][3][ATT_BLOCK_SIZE]; /* gyro, acc, mag records of sample i */
static char line[1024];
static volatile int sink;

static uint16_t code(double v, double zero, double scale)
{
    return (uint16_t)floor(zero + v / scale + 0.5);
}

/* The records of a steady turn: rate w about z, specific force (0, 0, g), field
 * R_z(-psi) (0, 20, -40) uT, in the codes of the sensors below. */
static void tabulate(void)
{
    const double w = 2.0 * 3.14159265358979 / (TABLE / RATE);
    uint16_t c[3];
    int i;
    for (i = 0; i < TABLE; i++) {
        double psi = w * (double)i / RATE;
        c[0] = 2048;
        c[1] = 2048;
        c[2] = code(w, 2048.0, 7.67e-4);
        att_block_encode_sample(rec[i][0], c);
        c[2] = code(9.80665, 2048.0, 9.80665 / 409.6);
        att_block_encode_sample(rec[i][1], c);
        c[0] = code(20.0 * sin(psi), 2047.5, 100.0 / 819.2);
        c[1] = code(20.0 * cos(psi), 2047.5, 100.0 / 819.2);
        c[2] = code(-40.0, 2047.5, 100.0 / 819.2);
        att_block_encode_sample(rec[i][2], c);
    }
}

/* The three converters, the accelerometer's and magnetometer's with a correction. */
static int sensors(att_sensor s[3])
{
    static const att_real gz[3] = { 2048, 2048, 2048 }, gk[3] = { 7.67e-4, 7.67e-4, 7.67e-4 };
    static const att_real az[3] = { 2048, 2048, 2048 }, ak[3] = { 0.02394, 0.02394, 0.02394 };
    static const att_real mz[3] = { 2047.5, 2047.5, 2047.5 }, mk[3] = { 0.12207, 0.12207, 0.12207 };
    static const att_real am[9] = { 1.01, 0.002, -0.003, 0.001, 0.99, 0.004, 0.002, -0.001, 1.005 };
    static const att_real ab[3] = { 0.05, -0.03, 0.1 };
    /* small enough (< 1 %) that the field stays within the filter's norm tolerance: the path
     * measured is the accepted magnetometer update's */
    static const att_real mm[9] = { 1.005, 0.002, 0.001, 0.002, 0.996, -0.001, 0.001, -0.001, 0.999 };
    static const att_real mb[3] = { 0.2, -0.1, 0.15 };
    return att_sensor_init(&s[0], gz, gk, NULL, NULL) != ATT_OK
           || att_sensor_init(&s[1], az, ak, NULL, NULL) != ATT_OK
           || att_sensor_init(&s[2], mz, mk, NULL, NULL) != ATT_OK
           || att_sensor_set_correction(&s[1], am, ab) != ATT_OK
           || att_sensor_set_correction(&s[2], mm, mb) != ATT_OK;
}

/* The JSON line of attitude-rx's print_filter, with these numbers. */
static void format_line(unsigned long n, const att_block *g, const att_real q[4], const att_real e[3],
                        att_real h, att_real v[4][3], int flags, int aided)
{
    const double d = 180.0 / 3.14159265358979323846;
    int k = snprintf(
        line, sizeof line,
        "{\"t\":%.9g,\"n\":%lu,\"codes\":[%u,%u,%u],\"q\":[%.17g,%.17g,%.17g,%.17g],\"yaw_deg\":%.17g,"
        "\"pitch_deg\":%.17g,\"roll_deg\":%.17g,\"heading_deg\":%.17g,\"held\":0,\"rate_dps\":[%.17g,"
        "%.17g,%.17g],\"bias_dps\":[%.17g,%.17g,%.17g],\"flags\":[%s]",
        (double)n / RATE, n, g->code[0], g->code[1], g->code[2], (double)q[0], (double)q[1], (double)q[2],
        (double)q[3], (double)e[0] * d, (double)e[1] * d, (double)e[2] * d, (double)h * d,
        (double)v[0][0] * d, (double)v[0][1] * d, (double)v[0][2] * d, (double)v[3][0] * d,
        (double)v[3][1] * d, (double)v[3][2] * d, (flags & ATT_AHRS_F_REST) ? "\"rest\"" : "");
    if (aided)
        k += snprintf(line + k, sizeof line - (size_t)k,
                      ",\"acc_ms2\":[%.17g,%.17g,%.17g],\"mag_ut\":[%.17g,%.17g,%.17g]}\n", (double)v[1][0],
                      (double)v[1][1], (double)v[1][2], (double)v[2][0], (double)v[2][1], (double)v[2][2]);
    sink += k;
}

int main(int argc, char **argv)
{
    static att_ahrs f;
    att_block_seq seq;
    att_block b, g;
    att_block_span span;
    att_sensor s[3];
    uint8_t head[2][ATT_BLOCK_SIZE];
    att_real v[4][3], q[4], e[3], h;
    unsigned long n, i, every;
    int line_mode, aided, p;
    if (argc != 4)
        return 2;
    every = strtoul(argv[2], NULL, 10);
    if (every < 1 || every > 255)
        return 2;
    line_mode = strcmp(argv[1], "line") == 0;
    n = strtoul(argv[3], NULL, 10);
    tabulate();
    if (sensors(s) || att_ahrs_init(&f, NULL, NULL) != ATT_OK)
        return 3;
    att_block_seq_init(&seq);
    att_block_encode_boot(head[0], 18, 96);
    att_block_encode_channels(head[1], ATT_BLOCK_BOARD_AIDED9,
                              ATT_BLOCK_CH_GYR | ATT_BLOCK_CH_ACC | ATT_BLOCK_CH_MAG, (uint8_t)every,
                              (uint8_t)every);
    if (att_block_seq_decode(&seq, head[0], &b, &span) != ATT_OK
        || att_block_seq_decode(&seq, head[1], &b, &span))
        return 4;
    for (i = 0; i < n; i++) {
        aided = i % every == 0;
        for (p = 0; p < (aided ? 3 : 1); p++) {
            if (att_block_seq_decode(&seq, rec[i % TABLE][p], p ? &b : &g, &span) != ATT_OK
                || att_sensor_convert(&s[p], (p ? &b : &g)->code, seq.oversample, v[p]) != ATT_OK)
                return 5;
        }
        if (att_ahrs_update(&f, v[0], aided ? v[1] : NULL, aided ? v[2] : NULL, (att_real)(1.0 / RATE), q)
                != ATT_OK
            || att_quat_to_euler(q, e) != ATT_OK || att_quat_heading(q, &h) != ATT_OK
            || att_ahrs_bias(&f, v[3]) != ATT_OK)
            return 6;
        if (line_mode)
            format_line(i, &g, q, e, h, v, att_ahrs_flags(&f), aided);
        else
            sink += att_ahrs_flags(&f);
    }
    return 0;
}
