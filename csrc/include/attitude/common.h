/*
 * libattitude — common definitions shared by every module.
 *
 * Build-time scalar type: the library is compiled either in double
 * (default) or in float (define ATT_REAL_F32; always float on SDCC).
 * `att_real` is that type.
 *
 * Status codes: every function that can fail returns an `att_status`;
 * ATT_OK (0) is success, negative values are errors. No function ever
 * reports failure through a NaN.
 *
 * Headers in this directory are also fed (after the C preprocessor with
 * ATT_CDEF defined) to CFFI's cdef(), so they must keep to plain
 * declarations outside `#ifndef ATT_CDEF` blocks: no inline functions,
 * no macros that carry meaning to Python (use enums for constants).
 */
#ifndef ATTITUDE_COMMON_H
#define ATTITUDE_COMMON_H

#ifndef ATT_CDEF
#include <stddef.h>
#include <stdint.h>
#endif

/* Exported symbols. The library's shared objects are compiled with
 * -fvisibility=hidden (invoke cross-build, make, CMake, the Python
 * extension): a function is exported only when a public header of this
 * directory declares it between ATT_API_BEGIN and ATT_API_END (at the top
 * and bottom of each header). Internals (att__NAME, declared in the
 * internal headers of csrc/src) stay hidden. ATT_NO_EXPORT exports none of the
 * library (a build that embeds it in another shared object: the Python
 * extension). SDCC and CFFI's cdef see empty macros. */
#if defined(__GNUC__) && !defined(__SDCC) && !defined(ATT_CDEF) && !defined(ATT_NO_EXPORT)
#define ATT_API_BEGIN _Pragma("GCC visibility push(default)")
#define ATT_API_END   _Pragma("GCC visibility pop")
#else
#define ATT_API_BEGIN
#define ATT_API_END
#endif

/* SDCC has no double (it warns and uses float): the 8051 build is float. */
#if defined(ATT_REAL_F32) || defined(__SDCC)
typedef float att_real;
#else
typedef double att_real;
#endif

/* Status codes. Ranges: generic -1..-19, integrator -20..-39,
 * TLC2543 -40..-59, link -60..-79, fixed point -80..-99, block format
 * -100..-119, aiding solvers (alignment, TRIAD, Gauss-Newton, magnetometer
 * calibration) -120..-139, attitude filter -140..-159, wavelet denoiser
 * -160..-179, AD7927 -180..-199, link v2 -200..-219, GNSS parser
 * -220..-239, the GNSS nine-state filter -240..-249. Each module's header
 * defines its own codes inside its range.
 *
 * `att_status` is an int, not the enum type: with short enums (the
 * bare-metal ARM EABI, SDCC) an enum whose values fit in a byte is one byte
 * wide, and the module codes below -128 would not survive the conversion. */
enum {
    ATT_OK = 0,
    ATT_E_NULL = -1,      /* a required pointer argument is NULL */
    ATT_E_ARG = -2,       /* an argument is out of its documented domain */
    ATT_E_NONFINITE = -3, /* NaN or Inf in an input */
    ATT_E_RANGE = -4,     /* value outside the representable range */
    ATT_E_STATE = -5,     /* call not valid in the current state */
    ATT_E_TIMEOUT = -6,   /* a bounded wait expired */
    ATT_E_BUFFER = -7     /* caller buffer too small */
};
typedef int att_status;

ATT_API_BEGIN

/* Short English description of a status code (static storage): every code
 * of every module's header has its own, distinct text (csrc/src/common.c,
 * one table); "unknown status" for any other value. Never NULL. */
const char *att_status_str(int status);

/* Size of att_real in bytes in this build (4 = float, 8 = double). */
int att_real_size(void);

ATT_API_END

#endif /* ATTITUDE_COMMON_H */
