# GENERATED from toolchain/armv7hf.toml by `python -m toolchain.buildfiles`: do not edit.
# Embedded Linux on ARMv7-A with VFP (e.g. Cortex-A8/A9 boards).
#
#   cmake -S . -B build/cmake-armv7hf -DCMAKE_TOOLCHAIN_FILE=cmake/armv7hf-toolchain.cmake
#
# The compiler prefix defaults to arm-linux-gnueabihf-; for another toolchain for the same core
# (e.g. a vendor's arm-linux-) pass -DCROSS_COMPILE=<prefix> (or set CROSS_COMPILE in
# the environment) and, if it has its own sysroot, -DCMAKE_SYSROOT=/path/to/sysroot.

set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR arm)

if(NOT DEFINED CROSS_COMPILE)
  if(DEFINED ENV{CROSS_COMPILE})
    set(CROSS_COMPILE "$ENV{CROSS_COMPILE}")
  else()
    set(CROSS_COMPILE "arm-linux-gnueabihf-")
  endif()
endif()
set(CROSS_COMPILE "${CROSS_COMPILE}" CACHE STRING "cross compiler prefix")
set(CMAKE_C_COMPILER ${CROSS_COMPILE}gcc)
set(CMAKE_AR ${CROSS_COMPILE}ar CACHE FILEPATH "archiver")
set(CMAKE_RANLIB ${CROSS_COMPILE}ranlib CACHE FILEPATH "ranlib")

# The target's flags (toolchain/<name>.toml cflags); programs link with its ldflags.
set(CMAKE_C_FLAGS_INIT "-O2 -march=armv7-a -mfpu=vfpv3-d16 -mfloat-abi=hard")
set(CMAKE_EXE_LINKER_FLAGS_INIT "-static")
set(CMAKE_SHARED_LINKER_FLAGS_INIT "")

set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)

# Run cross-built programs (try_run, ctest) under the target's emulator.
set(CMAKE_CROSSCOMPILING_EMULATOR qemu-arm)
