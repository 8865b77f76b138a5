/*
 * Tests of att_status_str (common.h): every status code the headers define
 * (the list below: tests/test_names.py checks that it is exactly the
 * headers' codes) has a description of its own, not "unknown status", and
 * no value outside the list has one.
 */
#include <string.h>

#include "attitude/attitude.h"
#include "att_test.h"

#define CODE(name)  \
    {               \
        name, #name \
    }

static const struct {
    int code;
    const char *name;
} codes[] = {
    CODE(ATT_E_NULL),
    CODE(ATT_E_ARG),
    CODE(ATT_E_NONFINITE),
    CODE(ATT_E_RANGE),
    CODE(ATT_E_STATE),
    CODE(ATT_E_TIMEOUT),
    CODE(ATT_E_BUFFER),
    CODE(ATT_E_INTEG_METHOD),
    CODE(ATT_E_INTEG_DIVERGED),
    CODE(ATT_E_INTEG_RANGE),
    CODE(TLC2543_E_EOC_TIMEOUT),
    CODE(TLC2543_E_SELFTEST_MID),
    CODE(TLC2543_E_SELFTEST_REFM),
    CODE(TLC2543_E_SELFTEST_REFP),
    CODE(ATT_LINK_E_NULL),
    CODE(ATT_LINK_E_CONFIG),
    CODE(ATT_LINK_E_BUSY),
    CODE(ATT_LINK_E_STATE),
    CODE(ATT_FX_E_RANGE),
    CODE(ATT_FX_E_METHOD),
    CODE(ATT_FX_E_ZERO),
    CODE(ATT_BLOCK_E_CODE),
    CODE(ATT_BLOCK_E_KIND),
    CODE(ATT_BLOCK_E_FIELD),
    CODE(ATT_BLOCK_E_SEQ),
    CODE(ATT_AID_E_ZERO_F),
    CODE(ATT_AID_E_ZERO_M),
    CODE(ATT_AID_E_PARALLEL),
    CODE(ATT_AID_E_MOVING),
    CODE(ATT_AID_E_FEW),
    CODE(ATT_AID_E_SINGULAR),
    CODE(ATT_AID_E_NOCONV),
    CODE(ATT_AID_E_SPAN),
    CODE(ATT_AID_E_FIT),
    CODE(ATT_E_AHRS_DT),
    CODE(ATT_E_AHRS_UNITS),
    CODE(ATT_E_AHRS_SETTINGS),
    CODE(ATT_E_AHRS_DIVERGED),
    CODE(ATT_E_AHRS_ALIGN),
    CODE(ATT_E_TEKF_DT),
    CODE(ATT_E_TEKF_SETTINGS),
    CODE(ATT_E_TEKF_DIVERGED),
    CODE(ATT_E_TEKF_ALIGN),
    CODE(ATT_E_G9_DT),
    CODE(ATT_E_G9_SETTINGS),
    CODE(ATT_E_G9_DIVERGED),
    CODE(ATT_E_G9_ALIGN),
    CODE(ATT_E_G9_AGE),
    CODE(ATT_E_WDEN_WAVELET),
    CODE(ATT_E_WDEN_MODE),
    CODE(ATT_E_WDEN_LEVELS),
    CODE(ATT_E_WDEN_BLOCK),
    CODE(ATT_E_WDEN_EDGE),
    CODE(ATT_E_WDEN_SHORT),
    CODE(ATT_E_WDEN_OVERFLOW),
    CODE(AD7927_E_CHANNEL),
    CODE(AD7927_E_FRAME),
    CODE(AD7927_E_TRANSFER),
    CODE(ATT_LINK2_E_NULL),
    CODE(ATT_LINK2_E_CONFIG),
    CODE(ATT_LINK2_E_FULL),
    CODE(ATT_LINK2_E_STATE),
    CODE(ATT_GNSS_E_NULL),
    CODE(ATT_GNSS_E_STATE),
};

#define N_CODES (sizeof codes / sizeof codes[0])

static const char UNKNOWN[] = "unknown status";

static int listed(int code)
{
    size_t i;
    for (i = 0; i < N_CODES; i++) {
        if (codes[i].code == code) {
            return 1;
        }
    }
    return 0;
}

static void test_every_code_has_its_own_text(void)
{
    size_t i, j;
    for (i = 0; i < N_CODES; i++) {
        const char *t = att_status_str(codes[i].code);
        int ok =
            t != NULL && t[0] != '\0' && strcmp(t, UNKNOWN) != 0 && strcmp(t, att_status_str(ATT_OK)) != 0;
        CHECK(ok);
        if (!ok) {
            printf("  %s (%d): no description\n", codes[i].name, codes[i].code);
        }
        for (j = 0; j < i; j++) {
            int same_code = codes[i].code == codes[j].code;
            int same_text = strcmp(t, att_status_str(codes[j].code)) == 0;
            CHECK(!same_code && !same_text);
            if (same_code || same_text) {
                printf("  %s and %s share a code or a description\n", codes[i].name, codes[j].name);
            }
        }
    }
}

static void test_nothing_else_is_named(void)
{
    int c;
    /* every module range (common.h): -1..-219, and beyond */
    for (c = -400; c <= 400; c++) {
        if (c != ATT_OK && !listed(c)) {
            CHECK(strcmp(att_status_str(c), UNKNOWN) == 0);
        }
    }
    CHECK(strcmp(att_status_str(ATT_OK), "ok") == 0);
    CHECK(strcmp(att_status_str(-2147483647 - 1), UNKNOWN) == 0);
}

int main(void)
{
    test_every_code_has_its_own_text();
    test_nothing_else_is_named();
    return ATT_TEST_REPORT();
}
