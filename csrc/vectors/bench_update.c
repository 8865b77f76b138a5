/*
 * Instruction-count harness for bench/armv4t.py: feeds N increments (or
 * rate samples for rk4) to the integrator one call at a time, like the
 * attitude thread of attitude-rx does. Run under
 * `qemu-arm -cpu ti925t -singlestep -d nochain,exec` (toolchain/qemu_count.py)
 * with two values of N; the difference divided by the number of updates is
 * the cost of one update (start-up cancels out). The increments come from a
 * small precomputed table, so the per-sample overhead is a few loads.
 *
 *   bench_update METHOD N     METHOD = rv1|rv2|rv3|rv3-coning|rv3-reuse|rv3-reuse-poly|rk4
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "attitude/attitude.h"

#define TABLE 16

int main(int argc, char **argv)
{
    att_real table[TABLE][3], q[4];
    att_integ s;
    unsigned long n, i, updates = 0;
    att_method m;
    int rc;
    if (argc != 3 || att_integ_method_from_name(argv[1], &m) != ATT_OK)
        return 2;
    n = strtoul(argv[2], NULL, 10);
    for (i = 0; i < TABLE; i++) { /* ~1 rad/s at 100 Hz, varying direction */
        table[i][0] = (att_real)(0.010 + 0.001 * (double)i);
        table[i][1] = (att_real)(-0.007 + 0.0005 * (double)i);
        table[i][2] = (att_real)(0.004 - 0.0003 * (double)i);
    }
    if (att_integ_init(&s, m, NULL) != ATT_OK)
        return 3;
    for (i = 0; i < n; i++) {
        if (m == ATT_METHOD_RK4)
            rc = att_integ_update_rate(&s, table[i % TABLE], (att_real)0.02, q);
        else
            rc = att_integ_update(&s, table[i % TABLE], q);
        if (rc < 0)
            return 4;
        updates += rc == ATT_INTEG_UPDATED;
    }
    printf("%lu updates\n", updates);
    return 0;
}
