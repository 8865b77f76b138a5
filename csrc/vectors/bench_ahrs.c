/*
 * Instruction-count harness of the attitude filters (bench/broad.py,
 * docs/ahrs.md): N samples through one filter, one update call each with
 * gyro, specific force and field (the full per-sample path). The motion is
 * a steady turn about the vertical, one turn per TABLE samples at 200 Hz,
 * tabulated at start-up (start-up cancels out in toolchain/qemu_count.py's
 * difference of two N; bench/broad.py takes both N past the filter's own
 * start, the reported inclination's running mean over tilt_tau).
 *
 * The filter is chosen at compile time, so that each build calls its
 * filter directly (the counts are those of the filter alone):
 *   (default)          att_ahrs_update (ahrs.h): propagation, accelerometer
 *                      and magnetometer updates;
 *   -DBENCH_AHRS_TEKF  att_tekf_update (ahrs_thesis.h), the UAV thesis's
 *                      EKF: time update, Gauss–Newton solve, measurement
 *                      update;
 *   -DBENCH_AHRS_DELAYS att_ahrs_update with acc_delay = 5 ms and
 *                      mag_delay = 13 ms (the time-skew compensation of
 *                      both aiding vectors, ahrs.h).
 *
 *   bench_ahrs N
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "attitude/attitude.h"

#ifdef BENCH_AHRS_TEKF
typedef att_tekf bench_filter;
#define BENCH_INIT   att_tekf_init
#define BENCH_UPDATE att_tekf_update
#else
typedef att_ahrs bench_filter;
#define BENCH_INIT   att_ahrs_init
#define BENCH_UPDATE att_ahrs_update
#endif

#define TABLE 256

static att_real mag[TABLE][3], gyr[TABLE][3], acc[TABLE][3];

int main(int argc, char **argv)
{
    bench_filter s;
    att_real q[4];
    att_real dt = (att_real)(1.0 / 200.0);
    unsigned long n, i;
    double w = 2.0 * 3.14159265358979 / (TABLE * (1.0 / 200.0));
    if (argc != 2) {
        return 2;
    }
    n = strtoul(argv[1], NULL, 10);
    for (i = 0; i < TABLE; i++) { /* m_b = R_z(−ψ) m_n, m_n = (0, 20, −40) µT */
        double psi = w * (double)i / 200.0, k = (double)i;
        mag[i][0] = (att_real)(20.0 * sin(psi) + 0.3 * sin(1.7 * k));
        mag[i][1] = (att_real)(20.0 * cos(psi) + 0.3 * sin(2.3 * k));
        mag[i][2] = (att_real)(-40.0 + 0.3 * sin(3.1 * k));
        /* sensor-like noise on every axis (none of the inputs exactly 0: soft-float's
         * fast paths for zero operands would flatter the count) */
        gyr[i][0] = (att_real)(0.002 * sin(1.3 * k));
        gyr[i][1] = (att_real)(0.002 * sin(2.9 * k));
        gyr[i][2] = (att_real)(w + 0.002 * sin(3.7 * k));
        acc[i][0] = (att_real)(0.03 * sin(1.1 * k));
        acc[i][1] = (att_real)(0.03 * sin(2.7 * k));
        acc[i][2] = (att_real)(9.81 + 0.03 * sin(3.3 * k));
    }
#ifdef BENCH_AHRS_DELAYS
    {
        att_ahrs_settings set;
        att_ahrs_default_settings(&set);
        set.acc_delay = (att_real)0.005;
        set.mag_delay = (att_real)0.013;
        if (att_ahrs_init(&s, &set, NULL) != ATT_OK) {
            return 3;
        }
    }
#else
    if (BENCH_INIT(&s, NULL, NULL) != ATT_OK) {
        return 3;
    }
#endif
    for (i = 0; i < n; i++) {
        if (BENCH_UPDATE(&s, gyr[i & (TABLE - 1)], acc[i & (TABLE - 1)], mag[i & (TABLE - 1)], dt, q)
            != ATT_OK) {
            return 4;
        }
    }
    printf("q = %g %g %g %g, flags %d\n", (double)q[0], (double)q[1], (double)q[2], (double)q[3], s.flags);
    return 0;
}
