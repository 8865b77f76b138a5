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
set(ATT_CROSS_COMPILE_DEFAULT "arm-linux-gnueabihf-")
include("${CMAKE_CURRENT_LIST_DIR}/cross-common.cmake")  # the tools, the find modes

# The target's flags (toolchain/<name>.toml cflags); programs link with its ldflags but -static,
# which only attitude-rx takes (below): a program that uses this file may link
# attitude::attitude_shared.
set(CMAKE_C_FLAGS_INIT "-O2 -march=armv7-a -mfpu=vfpv3-d16 -mfloat-abi=hard")
set(CMAKE_EXE_LINKER_FLAGS_INIT "")
set(CMAKE_SHARED_LINKER_FLAGS_INIT "")

# attitude-rx links statically (the Makefile's STATIC_APP): read by the library's
# CMakeLists.txt for that one program.
set(ATT_APP_LINK_OPTIONS "-static")

# Run cross-built programs (try_run, ctest) under the target's emulator.
set(CMAKE_CROSSCOMPILING_EMULATOR qemu-arm)
