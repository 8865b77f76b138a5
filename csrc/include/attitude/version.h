/*
 * libattitude version: the one place it is written.
 *
 * Everything else reads it from here: CMake (project version, package
 * version file, .so version, attitude.pc), the Makefile (.so version,
 * attitude.pc), `invoke cross-build`, setup.py (the Python distribution's
 * version) and attitude_c.__version__ (through the compiled library).
 * tests/test_version.py checks that they all agree.
 *
 * Constants as enums (these headers are also CFFI's cdef); build tools find
 * them by the pattern "ATT_VERSION_<PART> = <number>", one per line.
 */
#ifndef ATTITUDE_VERSION_H
#define ATTITUDE_VERSION_H

enum {
    /* MAJOR.MINOR.PATCH, semantic versioning; in 0.x a new minor version may
     * change the API (the CMake package accepts the same minor version only). */
    ATT_VERSION_MAJOR = 0,
    ATT_VERSION_MINOR = 1,
    ATT_VERSION_PATCH = 0,
    /* N of the shared library's soname libattitude.so.N: raised when the ABI
     * changes incompatibly. */
    ATT_VERSION_SO = 0
};

#endif /* ATTITUDE_VERSION_H */
