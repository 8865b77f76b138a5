/*
 * Tests of devm_status_str (csrc/host/devmodel.h): every status code the
 * host twins' headers define (the list below: tests/test_names.py checks
 * that it is exactly those headers' codes) has a description of its own,
 * distinct from every library code's; any other code gets att_status_str's.
 */
#include <string.h>

#include "ad7927_model.h"
#include "att_test.h"
#include "tlc2543_model.h"

#define HOST_CODE(name) \
    {                   \
        name, #name     \
    }

static const struct {
    int code;
    const char *name;
} host_codes[] = {
    HOST_CODE(TLC2543M_E_VIOLATION),
    HOST_CODE(AD7927M_E_VIOLATION),
};

#define N_HOST (sizeof host_codes / sizeof host_codes[0])

static int is_host_code(int code)
{
    size_t i;
    for (i = 0; i < N_HOST; i++) {
        if (host_codes[i].code == code) {
            return 1;
        }
    }
    return 0;
}

static void test_every_twin_code_has_its_own_text(void)
{
    size_t i, j;
    int c;
    for (i = 0; i < N_HOST; i++) {
        const char *t = devm_status_str(host_codes[i].code);
        int ok = t != NULL && t[0] != '\0' && strcmp(t, "unknown status") != 0;
        CHECK(ok);
        /* the library has no text for it, and no library code has this text */
        CHECK(strcmp(att_status_str(host_codes[i].code), "unknown status") == 0);
        for (c = -400; c <= 0; c++) {
            CHECK(c == host_codes[i].code || strcmp(t, devm_status_str(c)) != 0);
        }
        for (j = 0; j < i; j++) {
            CHECK(host_codes[i].code != host_codes[j].code);
        }
        if (!ok) {
            printf("  %s (%d): no description\n", host_codes[i].name, host_codes[i].code);
        }
    }
}

static void test_every_other_code_is_the_librarys(void)
{
    int c;
    for (c = -400; c <= 400; c++) {
        if (!is_host_code(c)) {
            CHECK(devm_status_str(c) == att_status_str(c));
        }
    }
    CHECK(devm_status_str(-2147483647 - 1) == att_status_str(-2147483647 - 1));
    CHECK(strcmp(devm_status_str(ATT_E_ARG), att_status_str(ATT_E_ARG)) == 0);
}

int main(void)
{
    test_every_twin_code_has_its_own_text();
    test_every_other_code_is_the_librarys();
    return ATT_TEST_REPORT();
}
