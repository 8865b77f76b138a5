# GENERATED from toolchain/aarch64.toml by `python -m toolchain.buildfiles`: do not edit.
# 64-bit ARM Linux.
#
#   cmake -S . -B build/cmake-aarch64 -DCMAKE_TOOLCHAIN_FILE=cmake/aarch64-toolchain.cmake
#
# The compiler prefix defaults to aarch64-linux-gnu-; for another toolchain for the same core
# (e.g. a vendor's arm-linux-) pass -DCROSS_COMPILE=<prefix> (or set CROSS_COMPILE in
# the environment) and, if it has its own sysroot, -DCMAKE_SYSROOT=/path/to/sysroot.

set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(ATT_CROSS_COMPILE_DEFAULT "aarch64-linux-gnu-")
include("${CMAKE_CURRENT_LIST_DIR}/cross-common.cmake")  # the tools, the find modes

# The target's flags (toolchain/<name>.toml cflags); programs link with its ldflags but -static,
# which only attitude-rx takes (below): a program that uses this file may link
# attitude::attitude_shared.
set(CMAKE_C_FLAGS_INIT "-O2")
set(CMAKE_EXE_LINKER_FLAGS_INIT "")
set(CMAKE_SHARED_LINKER_FLAGS_INIT "")

# attitude-rx links statically (the Makefile's STATIC_APP): read by the library's
# CMakeLists.txt for that one program.
set(ATT_APP_LINK_OPTIONS "-static")

# Run cross-built programs (try_run, ctest) under the target's emulator.
set(CMAKE_CROSSCOMPILING_EMULATOR qemu-aarch64)
