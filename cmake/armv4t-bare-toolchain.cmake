# GENERATED from toolchain/armv4t-bare.toml by `python -m toolchain.buildfiles`: do not edit.
# The same ARM920T core without an OS: newlib + semihosting, run on qemu's
# ti925t model (an ARMv4T core), so every instruction executed is ARMv4T.
#
#   cmake -S . -B build/cmake-armv4t-bare -DCMAKE_TOOLCHAIN_FILE=cmake/armv4t-bare-toolchain.cmake
#
# The compiler prefix defaults to arm-none-eabi-; for another toolchain for the same core
# (e.g. a vendor's arm-linux-) pass -DCROSS_COMPILE=<prefix> (or set CROSS_COMPILE in
# the environment) and, if it has its own sysroot, -DCMAKE_SYSROOT=/path/to/sysroot.

set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR arm)
set(ATT_CROSS_COMPILE_DEFAULT "arm-none-eabi-")
include("${CMAKE_CURRENT_LIST_DIR}/cross-common.cmake")  # the tools, the find modes

# The target's flags (toolchain/<name>.toml cflags); programs link with its ldflags.
set(CMAKE_C_FLAGS_INIT "-O2 -marm -mcpu=arm920t -mfloat-abi=soft")
set(CMAKE_EXE_LINKER_FLAGS_INIT "--specs=rdimon.specs")
set(CMAKE_SHARED_LINKER_FLAGS_INIT "")

# What this target builds (toolchain/<name>.toml shared/app).
set(ATT_BUILD_SHARED OFF CACHE BOOL "build libattitude.so as well as libattitude.a")
set(ATT_BUILD_APP OFF CACHE BOOL "build the attitude-rx receiver app")

# No OS: the compiler checks build a static library, not a program.
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)

# Run cross-built programs (try_run, ctest) under the target's emulator.
set(CMAKE_CROSSCOMPILING_EMULATOR qemu-arm;-cpu;ti925t)
