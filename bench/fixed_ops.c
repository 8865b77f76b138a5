/*
 * Instruction-count driver for bench/fixed.py: runs K attitude updates of
 * one kind and exits; bench/fixed.py runs it under qemu-arm (ti925t) with
 * K and 2K and takes the difference, so start-up cancels.
 *
 *   fixed_ops MODE K
 *   MODE: fx-rv3        K rv3 updates, fixed point, integrator API (3 increments each)
 *         fx-rv3-kernel K calls of att_fx_update_rv3 (9 increments each)
 *         fx-reuse      K rv3-reuse updates, fixed point (1 increment each)
 *         fx-reuse-poly K rv3-reuse-poly updates, fixed point
 *         fx-reuse-kernel, fx-reuse-poly-kernel
 *                       K calls of att_fx_update_reuse (a sliding window of 9 increments)
 *         fx-rv3-batch  K rv3 updates through att_fx_integ_batch (64 updates per call)
 *         fx-loop-kernel  the fx-rv3-kernel loop calling an empty function instead
 *                       (the driver's own share of the fx-rv3-kernel figure)
 *         fx-reuse-batch, fx-reuse-poly-batch  the same for the reuse forms
 *         fl-rv3        K rv3 updates, att_real build (float or double), 3 increments each
 *         fl-reuse, fl-reuse-poly  K updates of a reuse form, att_real build
 * The increments cycle through a table of 64 made once at start-up
 * (about 1 rad/s at 1 kHz: 1e-3 rad per increment).
 */
#include <stdlib.h>
#include <string.h>

#include "attitude/attitude.h"

#define NTAB 64

static att_q30 tab_fx[NTAB][3];

/* stand-in for att_fx_update_rv3 in loop-kernel mode (not inlined) */
__attribute__((noinline)) static att_status no_update(att_q30 q[4], const att_q30 d[9])
{
    __asm__ volatile("" : : "r"(q), "r"(d) : "memory");
    return ATT_OK;
}
static att_real tab_fl[NTAB][3];

static void make_tables(void)
{
    /* integer LCG → ±1.1e-3 rad in Q2.30, the float tables from the same integers */
    uint32_t x = 12345u;
    int i, k;
    for (i = 0; i < NTAB; ++i) {
        for (k = 0; k < 3; ++k) {
            x = x * 1664525u + 1013904223u;
            tab_fx[i][k] = (att_q30)((int32_t)(x >> 11) - (1 << 20)) + (k == 2 ? 1000000 : 0);
            tab_fl[i][k] = (att_real)tab_fx[i][k] / (att_real)1073741824.0;
        }
    }
}

int main(int argc, char **argv)
{
    long n, i;
    const char *mode;
    if (argc < 3) {
        return 2;
    }
    mode = argv[1];
    n = atol(argv[2]);
    make_tables();
    if (mode[0] == 'f' && mode[1] == 'x') {
        att_fx_integ s;
        att_q30 q[4] = { ATT_FX_Q30_ONE, 0, 0, 0 };
        /* the reuse form of the mode, if any */
        att_fx_method rm = strncmp(mode, "fx-reuse-poly", 13) == 0 ? ATT_FX_RV3_REUSE_POLY : ATT_FX_RV3_REUSE;
        int reuse = (strcmp(mode, "fx-reuse") == 0) || (strcmp(mode, "fx-reuse-poly") == 0);
        int kernel = (strcmp(mode, "fx-rv3-kernel") == 0) || (strcmp(mode, "fx-loop-kernel") == 0);
        int empty = (strcmp(mode, "fx-loop-kernel") == 0);
        size_t len = strlen(mode);
        if (len > 6 && strcmp(mode + len - 6, "-batch") == 0) {
            static att_q30 big[192][3];
            static att_q30 qo[192][4];
            size_t no, per = (strncmp(mode, "fx-reuse", 8) == 0) ? 64u : 192u;
            for (i = 0; i < 192; ++i) {
                big[i][0] = tab_fx[i & (NTAB - 1)][0];
                big[i][1] = tab_fx[i & (NTAB - 1)][1];
                big[i][2] = tab_fx[i & (NTAB - 1)][2];
            }
            att_fx_integ_init(&s, per == 64u ? rm : ATT_FX_RV3, 0);
            for (i = 0; i < n; i += 64) {
                if (att_fx_integ_batch(&s, &big[0][0], per, &qo[0][0], &no, 0) != ATT_OK) {
                    return 1;
                }
            }
            return 0;
        }
        if (len > 7 && strcmp(mode + len - 7, "-kernel") == 0 && strncmp(mode, "fx-reuse", 8) == 0) {
            att_q30 d[9];
            int k;
            for (k = 0; k < 6; ++k) {
                d[3 + k] = tab_fx[k / 3][k % 3];
            }
            for (i = 0; i < n; ++i) {
                const att_q30 *e = tab_fx[(i + 2) & (NTAB - 1)];
                for (k = 0; k < 6; ++k) {
                    d[k] = d[k + 3];
                }
                d[6] = e[0];
                d[7] = e[1];
                d[8] = e[2];
                if (att_fx_update_reuse(q, d, rm) != ATT_OK) {
                    return 1;
                }
            }
            return q[0] == 0 ? 3 : 0;
        }
        if (kernel) {
            att_q30 d[9];
            for (i = 0; i < n; ++i) {
                int j = (int)(i & (NTAB - 4));
                d[0] = tab_fx[j][0];
                d[1] = tab_fx[j][1];
                d[2] = tab_fx[j][2];
                d[3] = tab_fx[j + 1][0];
                d[4] = tab_fx[j + 1][1];
                d[5] = tab_fx[j + 1][2];
                d[6] = tab_fx[j + 2][0];
                d[7] = tab_fx[j + 2][1];
                d[8] = tab_fx[j + 2][2];
                if ((empty ? no_update(q, d) : att_fx_update_rv3(q, d)) != ATT_OK) {
                    return 1;
                }
            }
            return q[0] == 0 ? 3 : 0;
        }
        att_fx_integ_init(&s, reuse ? rm : ATT_FX_RV3, 0);
        for (i = 0; i < n; ++i) {
            if (reuse) {
                if (att_fx_integ_update(&s, tab_fx[i & (NTAB - 1)], q) < 0) {
                    return 1;
                }
            } else {
                int j = (int)((3 * i) & (NTAB - 1));
                att_fx_integ_update(&s, tab_fx[j], q);
                att_fx_integ_update(&s, tab_fx[(j + 1) & (NTAB - 1)], q);
                if (att_fx_integ_update(&s, tab_fx[(j + 2) & (NTAB - 1)], q) != ATT_FX_UPDATED) {
                    return 1;
                }
            }
        }
        return q[0] == 0 ? 3 : 0;
    } else {
        att_integ s;
        att_real q[4];
        int reuse = (strncmp(mode, "fl-reuse", 8) == 0);
        att_integ_init(
            &s,
            reuse ? (strcmp(mode, "fl-reuse-poly") == 0 ? ATT_METHOD_RV3_REUSE_POLY : ATT_METHOD_RV3_REUSE)
                  : ATT_METHOD_RV3,
            0);
        for (i = 0; i < n; ++i) {
            if (reuse) {
                if (att_integ_update(&s, tab_fl[i & (NTAB - 1)], q) < 0) {
                    return 1;
                }
            } else {
                int j = (int)((3 * i) & (NTAB - 1));
                att_integ_update(&s, tab_fl[j], q);
                att_integ_update(&s, tab_fl[(j + 1) & (NTAB - 1)], q);
                if (att_integ_update(&s, tab_fl[(j + 2) & (NTAB - 1)], q) != ATT_INTEG_UPDATED) {
                    return 1;
                }
            }
        }
        return 0;
    }
}
