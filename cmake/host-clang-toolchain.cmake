# GENERATED from toolchain/host-clang.toml by `python -m toolchain.buildfiles`: do not edit.
# Host build with clang, sanitizers on (proves the sources are clean under a second compiler).
#
#   cmake -S . -B build/cmake-host-clang -DCMAKE_TOOLCHAIN_FILE=cmake/host-clang-toolchain.cmake
#

set(CMAKE_C_COMPILER clang)

# The target's flags (toolchain/<name>.toml cflags); programs link with its ldflags.
set(CMAKE_C_FLAGS_INIT "-O1 -g -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer")
set(CMAKE_EXE_LINKER_FLAGS_INIT "-fsanitize=address,undefined")
set(CMAKE_SHARED_LINKER_FLAGS_INIT "-fsanitize=address,undefined")

# What this target builds (toolchain/<name>.toml shared/app).
set(ATT_BUILD_SHARED OFF CACHE BOOL "build libattitude.so as well as libattitude.a")
set(ATT_BUILD_APP OFF CACHE BOOL "build the attitude-rx receiver app")
