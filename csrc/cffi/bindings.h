/*
 * What the Python extension modules see: the public library plus the
 * host-only pieces (device models and test doubles from csrc/host/).
 * Preprocessed with -DATT_CDEF and fed to cffi's cdef().
 */
#ifndef ATTITUDE_CFFI_BINDINGS_H
#define ATTITUDE_CFFI_BINDINGS_H

#include "attitude/attitude.h"
#include "link_sim.h"
#include "link2_sim.h"
#include "tlc2543_model.h"
#include "ad7927_model.h"

#endif
