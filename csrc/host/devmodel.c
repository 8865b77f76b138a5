/* Shared pieces of the C twins of the device models (host only). */
#include "devmodel.h"

#include <math.h>
#include <stdio.h>

#include "ad7927_model.h"
#include "tlc2543_model.h"

void devm_log(devm_event *trace, size_t cap, size_t *len, size_t *dropped, int64_t t, uint8_t signal,
              uint8_t value)
{
    if (trace == 0) {
        return;
    }
    if (*len < cap) {
        trace[*len].t = t;
        trace[*len].signal = signal;
        trace[*len].value = value;
        (*len)++;
    } else {
        (*dropped)++;
    }
}

int devm_set_inputs(double *inputs, size_t cap, const double *volts, size_t n)
{
    size_t i;
    if (inputs == 0 || (volts == 0 && n != 0u)) {
        return ATT_E_NULL;
    }
    if (n > cap) {
        return ATT_E_ARG;
    }
    for (i = 0; i < n; i++) {
        if (!isfinite(volts[i])) {
            return ATT_E_NONFINITE;
        }
    }
    for (i = 0; i < n; i++) {
        inputs[i] = volts[i];
    }
    return ATT_OK;
}

void devm_vfail(int *violation, int64_t *violation_t, char *message, size_t size, int64_t t, int code,
                const char *fmt, va_list ap)
{
    if (*violation == 0) {
        *violation = code;
        *violation_t = t;
        vsnprintf(message, size, fmt, ap);
    }
}

const char *devm_status_str(int status)
{
    switch (status) {
    case TLC2543M_E_VIOLATION:
        return "TLC2543 model: the driver broke a protocol rule (the model's violation says which)";
    case AD7927M_E_VIOLATION:
        return "AD7927 model: the driver broke a protocol rule (the model's violation says which)";
    default:
        return att_status_str(status);
    }
}
