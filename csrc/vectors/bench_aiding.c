/*
 * Instruction-count harness for bench/aiding.py: runs one aiding operation
 * N times on a table of 64 precomputed static attitudes (start-up, the
 * table included, cancels in the difference of two runs; see
 * toolchain/qemu_count.py). Run under `qemu-arm -cpu ti925t` with two N.
 *
 *   bench_aiding OP N
 *     OP = align | triad | gn | gn_simplified | window_add | magcal_add | magcal_solve
 *   gn: warm start, the truth turned by 0.1 rad about each axis (a filter's
 *   previous attitude); magcal_solve: the full model over 64 samples.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "attitude/attitude.h"

#define TABLE 64

static att_real F[TABLE][3], M[TABLE][3], Q0[TABLE][4];

static void make_table(void)
{
    unsigned long lcg = 12345u;
    att_real mn[3] = { 0.0, 20.0, -40.0 }, fn[3] = { 0.0, 0.0, 9.81 }, C[9], e[3], qt[4],
             d[3] = { 0.1, 0.1, 0.1 }, dq[4];
    int i, k, j;
    att_rotvec_to_quat(d, dq);
    for (i = 0; i < TABLE; i++) {
        for (k = 0; k < 3; k++) {
            lcg = (lcg * 1664525u + 1013904223u) & 0xFFFFFFFFu;
            e[k] = (att_real)(((double)lcg / 4294967296.0 - 0.5) * (k == 1 ? 2.8 : 6.2));
        }
        att_euler_to_dcm(e, C);
        for (k = 0; k < 3; k++) {
            F[i][k] = 0;
            M[i][k] = 0;
            for (j = 0; j < 3; j++) {
                F[i][k] += C[3 * j + k] * fn[j];
                M[i][k] += C[3 * j + k] * mn[j];
            }
        }
        att_euler_to_quat(e, qt);
        att_quat_mul(qt, dq, Q0[i]);
    }
}

int main(int argc, char **argv)
{
    unsigned long n, i;
    att_real q[4];
    att_gn_settings gs;
    att_align_window w;
    att_magcal mc;
    att_magcal_result r;
    att_real gyr[3] = { 0.001, -0.002, 0.0005 };
    static const char *ops[7] = { "align",      "triad",      "gn",          "gn_simplified",
                                  "window_add", "magcal_add", "magcal_solve" };
    const char *op;
    int st = 0, code;
    if (argc != 3)
        return 2;
    op = argv[1];
    n = strtoul(argv[2], NULL, 10);
    make_table();
    att_gn_defaults(&gs);
    if (strcmp(op, "gn_simplified") == 0) {
        gs.method = ATT_GN_SIMPLIFIED;
        gs.max_iter = 200;
    }
    att_align_window_init(&w, NULL);
    att_magcal_init(&mc, NULL);
    if (strcmp(op, "magcal_solve") == 0)
        for (i = 0; i < TABLE; i++)
            att_magcal_add(&mc, M[i]);
    for (code = 0; code < 7; code++)
        if (strcmp(op, ops[code]) == 0)
            break;
    if (code == 7)
        return 3;
    for (i = 0; i < n; i++) { /* the op is decoded once: the loop adds a few instructions only */
        unsigned long k = i & (TABLE - 1);
        switch (code) {
        case 0:
            st |= att_align_accmag(F[k], M[k], (att_real)0.1, q);
            break;
        case 1:
            st |= att_triad(F[k], M[k], (att_real)0.1, q);
            break;
        case 2:
        case 3:
            st |= att_gn_solve(F[k], M[k], (att_real)0.1, Q0[k], &gs, q, NULL);
            break;
        case 4:
            st |= att_align_window_add(&w, gyr, F[k], M[k]);
            break;
        case 5:
            st |= att_magcal_add(&mc, M[k]);
            break;
        default:
            st |= att_magcal_solve(&mc, ATT_MAGCAL_FULL, &r);
            break;
        }
    }
    printf("%s %lu: status %d\n", op, n, st);
    return st != 0 ? 4 : 0;
}
