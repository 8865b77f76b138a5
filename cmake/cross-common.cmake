# GENERATED from toolchain/buildfiles.py by `python -m toolchain.buildfiles`: do not edit.
# Included by every cross toolchain file (cmake/<name>-toolchain.cmake), which sets
# ATT_CROSS_COMPILE_DEFAULT first: the compiler prefix CROSS_COMPILE (-DCROSS_COMPILE=<prefix>,
# else the environment's CROSS_COMPILE, else that default), the tools under it, and
# find_* looking in the sysroot only (programs: on the build machine).

if(NOT DEFINED CROSS_COMPILE)
  if(DEFINED ENV{CROSS_COMPILE})
    set(CROSS_COMPILE "$ENV{CROSS_COMPILE}")
  else()
    set(CROSS_COMPILE "${ATT_CROSS_COMPILE_DEFAULT}")
  endif()
endif()
set(CROSS_COMPILE "${CROSS_COMPILE}" CACHE STRING "cross compiler prefix")
set(CMAKE_C_COMPILER ${CROSS_COMPILE}gcc)
set(CMAKE_AR ${CROSS_COMPILE}ar CACHE FILEPATH "archiver")
set(CMAKE_RANLIB ${CROSS_COMPILE}ranlib CACHE FILEPATH "ranlib")

set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
