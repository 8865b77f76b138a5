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
set(ATT_CROSS_COMPILE_DEFAULT "arm-linux-gnueabi-")
include("${CMAKE_CURRENT_LIST_DIR}/cross-common.cmake")  # the tools, the find modes

# The target's flags (toolchain/<name>.toml cflags); programs link with its ldflags but -static,
# which only attitude-rx takes (below): a program that uses this file may link
# attitude::attitude_shared.
set(CMAKE_C_FLAGS_INIT "-O2 -march=armv4t -mtune=arm920t -marm -mfloat-abi=soft")
set(CMAKE_EXE_LINKER_FLAGS_INIT "")
set(CMAKE_SHARED_LINKER_FLAGS_INIT "")

# attitude-rx links statically (the Makefile's STATIC_APP): read by the library's
# CMakeLists.txt for that one program.
set(ATT_APP_LINK_OPTIONS "-static")

# How libattitude.so is linked (toolchain/<name>.toml shared_*): read by the
# library's CMakeLists.txt for that one target, not applied to other targets.
set(ATT_SHARED_LINK_OPTIONS "-nostdlib;-Wl,--no-undefined;-Wl,-z,noexecstack")
set(ATT_SHARED_LIBGCC_CMD "arm-none-eabi-gcc;-marm;-mcpu=arm920t;-mfloat-abi=soft;-print-libgcc-file-name")
set(ATT_SHARED_LIBS "-lm;-lc")

# Run cross-built programs (try_run, ctest) under the target's emulator.
set(CMAKE_CROSSCOMPILING_EMULATOR qemu-arm)
