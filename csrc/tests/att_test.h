/*
 * Minimal C test harness for libattitude's own checks (no malloc, no
 * framework). Every test program prints "N passed, M failed" on its last
 * line and exits non-zero on any failure. Works on the host, under qemu
 * with semihosting, and anywhere printf exists.
 */
#ifndef ATT_TEST_H
#define ATT_TEST_H

#include <math.h>
#include <stdio.h>

static int att_test_pass_count = 0;
static int att_test_fail_count = 0;

#define CHECK(cond)                                                \
    do {                                                           \
        if (cond) {                                                \
            att_test_pass_count++;                                 \
        } else {                                                   \
            att_test_fail_count++;                                 \
            printf("FAIL %s:%d: %s\n", __FILE__, __LINE__, #cond); \
        }                                                          \
    } while (0)

#define CHECK_EQ_INT(a, b)                                                                             \
    do {                                                                                               \
        long att_a_ = (long)(a), att_b_ = (long)(b);                                                   \
        if (att_a_ == att_b_) {                                                                        \
            att_test_pass_count++;                                                                     \
        } else {                                                                                       \
            att_test_fail_count++;                                                                     \
            printf("FAIL %s:%d: %s == %s (%ld vs %ld)\n", __FILE__, __LINE__, #a, #b, att_a_, att_b_); \
        }                                                                                              \
    } while (0)

#define CHECK_CLOSE(a, b, tol)                                                                           \
    do {                                                                                                 \
        double att_a_ = (double)(a), att_b_ = (double)(b);                                               \
        if (fabs(att_a_ - att_b_) <= (tol)) {                                                            \
            att_test_pass_count++;                                                                       \
        } else {                                                                                         \
            att_test_fail_count++;                                                                       \
            printf("FAIL %s:%d: %s ~ %s (%.17g vs %.17g, tol %g)\n", __FILE__, __LINE__, #a, #b, att_a_, \
                   att_b_, (double)(tol));                                                               \
        }                                                                                                \
    } while (0)

#define ATT_TEST_REPORT()                                                        \
    (printf("%d passed, %d failed\n", att_test_pass_count, att_test_fail_count), \
     att_test_fail_count == 0 ? 0 : 1)

#endif /* ATT_TEST_H */
