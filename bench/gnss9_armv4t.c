/*
 * Instruction-count harness for bench/gnss9.py: the nine-state filter
 * (attitude/ahrs_gnss9.h) on a level vehicle turning at 0.2 rad/s and
 * 10 m/s, 100 samples/s, default settings (kf_period 5).
 *
 *   gnss9_armv4t MODE N
 *     MODE = imu     : N IMU samples (att_g9_update), no aiding
 *            gnss    : the same, a GNSS velocity after every 5th sample
 *            heading : the same, a magnetic heading after every 5th sample
 *     N    = samples (a multiple of 5 keeps the predictions aligned)
 *
 * toolchain/qemu_count.py's difference of two N cancels start-up; the
 * per-update cost is 5 × (mode's per-sample count − imu's).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "attitude/attitude.h"

static volatile int sink;

int main(int argc, char **argv)
{
    const double h = 0.01, r = 0.2, speed = 10.0, g = 9.80665;
    att_g9 s;
    att_real q0[4] = { 1, 0, 0, 0 }, v0[2] = { 0, 10 }, gyr[3], acc[3], v[2];
    long n, k;
    int mode;
    if (argc != 3) {
        return 2;
    }
    mode = strcmp(argv[1], "gnss") == 0 ? 1 : strcmp(argv[1], "heading") == 0 ? 2 : 0;
    n = atol(argv[2]);
    if (att_g9_init(&s, NULL, q0, v0) != ATT_OK) {
        return 1;
    }
    gyr[0] = gyr[1] = 0;
    gyr[2] = (att_real)-r;
    acc[0] = (att_real)(speed * r); /* centripetal, body x to the turn's centre */
    acc[1] = 0;
    acc[2] = (att_real)g;
    for (k = 1; k <= n; ++k) {
        double psi = r * (double)k * h;
        if (att_g9_update(&s, gyr, acc, (att_real)h) != ATT_OK) {
            return 1;
        }
        if (k % 5 == 0 && mode == 1) {
            v[0] = (att_real)(speed * sin(psi));
            v[1] = (att_real)(speed * cos(psi));
            sink += att_g9_gnss(&s, v, 0);
        } else if (k % 5 == 0 && mode == 2) {
            sink += att_g9_heading(&s, (att_real)fmod(psi, 6.283185307179586));
        }
    }
    return sink == 0 ? 0 : 1;
}
