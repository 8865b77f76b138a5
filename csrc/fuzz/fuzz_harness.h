/*
 * What the libFuzzer targets of csrc/fuzz share (`invoke fuzz`, toolchain/tasks/link.py):
 * the oracle's failure, the entry point, big-endian input fields, and the timer oracle
 * of a byte-driven machine (attitude/link.h, attitude/link2.h).
 */
#ifndef ATT_FUZZ_HARNESS_H
#define ATT_FUZZ_HARNESS_H

#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

/* An oracle violated: abort(), which libFuzzer reports as a crash with its input. */
#define FUZZ_CHECK(c) \
    do {              \
        if (!(c)) {   \
            abort();  \
        }             \
    } while (0)

/* The entry point libFuzzer calls with each input. */
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* A 16-bit big-endian field of the input. */
static inline uint16_t fuzz_be16(const uint8_t *p)
{
    return (uint16_t)((uint16_t)p[0] << 8 | p[1]);
}

/* The timer oracle of a machine whose ticks_left(now) returned k (0 < k < NO_TIMER): a copy
 * of *M (type T) polled with POLL(&copy, tick, &byte) at now + k - 1 fires nothing
 * (BEFORE(status) holds), one polled at now + k fires (AT(status) holds). */
#define FUZZ_TIMER_ORACLE(T, M, NOW, K, POLL, BEFORE, AT)                          \
    do {                                                                           \
        T fuzz_copy_ = *(M);                                                       \
        uint8_t fuzz_byte_;                                                        \
        int fuzz_st_ = POLL(&fuzz_copy_, (uint16_t)((NOW) + (K)-1u), &fuzz_byte_); \
        FUZZ_CHECK(BEFORE(fuzz_st_));                                              \
        fuzz_copy_ = *(M);                                                         \
        fuzz_st_ = POLL(&fuzz_copy_, (uint16_t)((NOW) + (K)), &fuzz_byte_);        \
        FUZZ_CHECK(AT(fuzz_st_));                                                  \
    } while (0)

#endif /* ATT_FUZZ_HARNESS_H */
