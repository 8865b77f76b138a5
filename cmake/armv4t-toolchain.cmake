# CMake toolchain file for the mini2440 (Samsung S3C2440, ARM920T core:
# ARMv4T, no FPU) running Linux.
#
#   cmake -S . -B build/cmake-armv4t -DCMAKE_TOOLCHAIN_FILE=cmake/armv4t-toolchain.cmake
#
# The compiler prefix defaults to Debian's arm-linux-gnueabi-; for a vendor
# toolchain (e.g. FriendlyARM's arm-linux-) pass -DCROSS_COMPILE=arm-linux-
# (or set the CROSS_COMPILE environment variable) and, if it has its own
# sysroot, -DCMAKE_SYSROOT=/path/to/sysroot.
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

# ARMv4T, ARM state, software floating point (same flags as toolchain/armv4t.toml).
set(CMAKE_C_FLAGS_INIT "-march=armv4t -mtune=arm920t -marm -mfloat-abi=soft")

set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)

# Run cross-built test programs (try_run, ctest) under qemu-user.
set(CMAKE_CROSSCOMPILING_EMULATOR qemu-arm)
