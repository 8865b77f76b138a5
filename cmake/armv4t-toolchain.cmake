# GENERATED from toolchain/armv4t.toml by `python -m toolchain.buildfiles`: do not edit.
# Embedded Linux on the ARM920T (S3C2440, mini2440): ARMv4T, no FPU.
# The Debian armel libc is built for ARMv5, so programs run under plain qemu-arm.
#
#   cmake -S . -B build/cmake-armv4t -DCMAKE_TOOLCHAIN_FILE=cmake/armv4t-toolchain.cmake
#
# The compiler prefix defaults to arm-linux-gnueabi-; for another toolchain for the same core
# (e.g. a vendor's arm-linux-) pass -DCROSS_COMPILE=<prefix> (or set CROSS_COMPILE in
# the environment) and, if it has its own sysroot, -DCMAKE_SYSROOT=/path/to/sysroot.

set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR arm)

if(NOT DEFINED CROSS_COMPILE)
  if(DEFINED ENV{CROSS_COMPILE})
    set(CROSS_COMPILE "$ENV{CROSS_COMPILE}")
  else()
    set(CROSS_COMPILE "arm-linux-gnueabi-")
  endif()
endif()
set(CROSS_COMPILE "${CROSS_COMPILE}" CACHE STRING "cross compiler prefix")
set(CMAKE_C_COMPILER ${CROSS_COMPILE}gcc)
set(CMAKE_AR ${CROSS_COMPILE}ar CACHE FILEPATH "archiver")
set(CMAKE_RANLIB ${CROSS_COMPILE}ranlib CACHE FILEPATH "ranlib")

# The target's flags (toolchain/<name>.toml cflags); programs link with its ldflags.
set(CMAKE_C_FLAGS_INIT "-O2 -march=armv4t -mtune=arm920t -marm -mfloat-abi=soft")
set(CMAKE_EXE_LINKER_FLAGS_INIT "-static")
set(CMAKE_SHARED_LINKER_FLAGS_INIT "")

# How libattitude.so is linked (toolchain/<name>.toml shared_*): read by the
# library's CMakeLists.txt for that one target, not applied to other targets.
set(ATT_SHARED_LINK_OPTIONS "-nostdlib;-Wl,--no-undefined;-Wl,-z,noexecstack")
set(ATT_SHARED_LIBGCC_CMD "arm-none-eabi-gcc;-marm;-mcpu=arm920t;-mfloat-abi=soft;-print-libgcc-file-name")
set(ATT_SHARED_LIBS "-lm;-lc")

set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)

# Run cross-built programs (try_run, ctest) under the target's emulator.
set(CMAKE_CROSSCOMPILING_EMULATOR qemu-arm)
