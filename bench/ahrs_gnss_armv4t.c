/*
 * Instruction-count harness for bench/gnss9.py's att_ahrs rows: the library's
 * filter (attitude/ahrs.h) with a magnetometer on a level vehicle turning at
 * 0.2 rad/s and 10 m/s, 100 samples/s, default settings but gnss_window 0
 * (every velocity compared, so each one is an update).
 *
 *   ahrs_gnss_armv4t MODE N
 *     MODE = imu    : N samples (att_ahrs_update), no velocity
 *            gnss10 : the same, a GNSS velocity (valid 50 ms before the
 *                     clock: the history is interpolated) after every 10th
 *            gnss20 : after every 20th
 *     N    = samples (a multiple of 20 keeps the modes aligned)
 *
 * toolchain/qemu_count.py's difference of two N cancels start-up (the first
 * velocities arm the history and set the anchor); with m10, m20 the
 * per-sample means, an update costs 20 (m10 − m20) and an aided sample
 * without one 2 m20 − m10.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "attitude/attitude.h"

static volatile int sink;

static void sensors(double psi, double r, double speed, double g, att_real gyr[3], att_real acc[3],
                    att_real mag[3])
{
    gyr[0] = gyr[1] = 0;
    gyr[2] = (att_real)r;            /* a left turn: heading −psi, the body y along the velocity */
    acc[0] = (att_real)(-speed * r); /* centripetal, toward the centre on the left (body −x) */
    acc[1] = 0;
    acc[2] = (att_real)g;
    mag[0] = (att_real)(20.0 * sin(psi)); /* the field (0, 20, −40) µT ENU seen by the body */
    mag[1] = (att_real)(20.0 * cos(psi));
    mag[2] = (att_real)-40.0;
}

int main(int argc, char **argv)
{
    const double h = 0.01, r = 0.2, speed = 10.0, g = 9.81;
    att_ahrs s;
    att_ahrs_settings set;
    att_ahrs_vel v;
    att_real q0[4] = { 1, 0, 0, 0 }, gyr[3], acc[3], mag[3], q[4];
    long n, k;
    int every;
    if (argc != 3) {
        return 2;
    }
    every = strcmp(argv[1], "gnss10") == 0 ? 10 : strcmp(argv[1], "gnss20") == 0 ? 20 : 0;
    n = atol(argv[2]);
    att_ahrs_default_settings(&set);
    set.gnss_window = 0;
    if (att_ahrs_init(&s, &set, q0) != ATT_OK) {
        return 1;
    }
    memset(&v, 0, sizeof v);
    v.fix_type = ATT_GNSS_FIX_3D;
    for (k = 1; k <= n; ++k) {
        double psi = r * (double)k * h, tv = (double)k * h - 0.05, pv = r * tv;
        sensors(psi, r, speed, g, gyr, acc, mag);
        if (att_ahrs_update(&s, gyr, acc, mag, (att_real)h, q) != ATT_OK) {
            return 1;
        }
        if (every && k % every == 0) {
            v.t = att_ahrs_time(&s) - (att_real)0.05;
            v.vel[0] = (att_real)(-speed * sin(pv)); /* velocity along the track, heading −pv */
            v.vel[1] = (att_real)(speed * cos(pv));
            sink += att_ahrs_update_vel(&s, &v);
        }
    }
    return sink == 0 && (every == 0 || (att_ahrs_flags(&s) & ATT_AHRS_F_GNSS_AIDED)) ? 0 : 1;
}
