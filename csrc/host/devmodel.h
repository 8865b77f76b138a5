/*
 * devmodel.h — pieces shared by the host-only C twins of the device models
 * (tlc2543_model.c, ad7927_model.c): the pin-trace event, its logging into a
 * caller-owned buffer, the latch of the first protocol violation, the
 * checked copy of input voltages, and the description of a twin's status
 * code.
 */
#ifndef ATTITUDE_DEVMODEL_H
#define ATTITUDE_DEVMODEL_H

#include "attitude/common.h"

#ifndef ATT_CDEF
#include <stdarg.h>
#endif

/* One pin-trace event (the models' SIG_* codes and levels). */
typedef struct {
    int64_t t;      /* ns */
    uint8_t signal; /* model-specific signal code */
    uint8_t value;  /* 0, 1, or the model's high-impedance code */
} devm_event;

/* Append an event to trace[0..cap) (NULL: no trace): *len grows, or
 * *dropped when the buffer is full. */
void devm_log(devm_event *trace, size_t cap, size_t *len, size_t *dropped, int64_t t, uint8_t signal,
              uint8_t value);

/* Copy n (<= cap) finite voltages into inputs. ATT_E_NULL, ATT_E_ARG (n >
 * cap) or ATT_E_NONFINITE, with nothing copied. */
int devm_set_inputs(double *inputs, size_t cap, const double *volts, size_t n);

/* Short description of a status code a host twin's function returns (static
 * storage, never NULL): the twins' own codes (TLC2543M_E_VIOLATION,
 * AD7927M_E_VIOLATION) have their own, distinct text; any other code gets
 * att_status_str's ("unknown status" for a value no header defines). The
 * library's table (csrc/src/common.c) does not hold the twins' codes: the
 * twins live outside the library. attitude_c.names.status_text reads this. */
const char *devm_status_str(int status);

#ifndef ATT_CDEF
/* Latch the first violation: if *violation is 0, store code, t and the
 * formatted message (size bytes, truncated). */
void devm_vfail(int *violation, int64_t *violation_t, char *message, size_t size, int64_t t, int code,
                const char *fmt, va_list ap);
#endif

#endif /* ATTITUDE_DEVMODEL_H */
