# GENERATED from toolchain/host.toml by `python -m toolchain.buildfiles`: do not edit.
# Native build for tests on the development machine.
#
#   cmake -S . -B build/cmake-host -DCMAKE_TOOLCHAIN_FILE=cmake/host-toolchain.cmake
#

set(CMAKE_C_COMPILER gcc)

# The target's flags (toolchain/<name>.toml cflags); programs link with its ldflags.
set(CMAKE_C_FLAGS_INIT "-O2")
set(CMAKE_EXE_LINKER_FLAGS_INIT "")
set(CMAKE_SHARED_LINKER_FLAGS_INIT "")
