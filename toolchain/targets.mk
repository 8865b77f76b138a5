# GENERATED from toolchain/*.toml by `python -m toolchain.buildfiles`: do not edit.
# Target presets of the Makefile: make TARGET=<name> (see the Makefile's header).

ATT_TARGETS := aarch64 armv4t armv4t-bare armv7hf host host-asan host-clang mcs51 mcs52

# 64-bit ARM Linux.
ATT_TARGET_KIND_aarch64 := gcc
ATT_TARGET_OS_aarch64 := linux
ATT_TARGET_CROSS_COMPILE_aarch64 := aarch64-linux-gnu-
ATT_TARGET_CC_aarch64 := gcc
ATT_TARGET_AR_aarch64 := ar
ATT_TARGET_CFLAGS_aarch64 := -O2
ATT_TARGET_LDFLAGS_aarch64 :=
ATT_TARGET_LIBS_aarch64 := -lm
ATT_TARGET_STATIC_APP_aarch64 := 1
ATT_TARGET_SHARED_aarch64 := 1
ATT_TARGET_APP_aarch64 := 1
ATT_TARGET_APP_LIBS_aarch64 := -pthread
ATT_TARGET_SOURCES_aarch64 := csrc/src/*.c
ATT_TARGET_SHARED_LDFLAGS_aarch64 :=
ATT_TARGET_SHARED_LIBGCC_aarch64 :=
ATT_TARGET_SHARED_LIBS_aarch64 := -lm

# Embedded Linux on the ARM920T (S3C2440, mini2440): ARMv4T, no FPU.
# The Debian armel libc is built for ARMv5, so programs run under plain qemu-arm.
ATT_TARGET_KIND_armv4t := gcc
ATT_TARGET_OS_armv4t := linux
ATT_TARGET_CROSS_COMPILE_armv4t := arm-linux-gnueabi-
ATT_TARGET_CC_armv4t := gcc
ATT_TARGET_AR_armv4t := ar
ATT_TARGET_CFLAGS_armv4t := -O2 -march=armv4t -mtune=arm920t -marm -mfloat-abi=soft
ATT_TARGET_LDFLAGS_armv4t :=
ATT_TARGET_LIBS_armv4t := -lm
ATT_TARGET_STATIC_APP_armv4t := 1
ATT_TARGET_SHARED_armv4t := 1
ATT_TARGET_APP_armv4t := 1
ATT_TARGET_APP_LIBS_armv4t := -pthread
ATT_TARGET_SOURCES_armv4t := csrc/src/*.c
ATT_TARGET_SHARED_LDFLAGS_armv4t := -nostdlib -Wl,--no-undefined -Wl,-z,noexecstack
ATT_TARGET_SHARED_LIBGCC_armv4t := arm-none-eabi-gcc -marm -mcpu=arm920t -mfloat-abi=soft -print-libgcc-file-name
ATT_TARGET_SHARED_LIBS_armv4t := -lm -lc

# The same ARM920T core without an OS: newlib + semihosting, run on qemu's
# ti925t model (an ARMv4T core), so every instruction executed is ARMv4T.
ATT_TARGET_KIND_armv4t-bare := gcc
ATT_TARGET_OS_armv4t-bare := none
ATT_TARGET_CROSS_COMPILE_armv4t-bare := arm-none-eabi-
ATT_TARGET_CC_armv4t-bare := gcc
ATT_TARGET_AR_armv4t-bare := ar
ATT_TARGET_CFLAGS_armv4t-bare := -O2 -marm -mcpu=arm920t -mfloat-abi=soft
ATT_TARGET_LDFLAGS_armv4t-bare :=
ATT_TARGET_LIBS_armv4t-bare := -lm
ATT_TARGET_STATIC_APP_armv4t-bare := 0
ATT_TARGET_SHARED_armv4t-bare := 0
ATT_TARGET_APP_armv4t-bare := 0
ATT_TARGET_APP_LIBS_armv4t-bare :=
ATT_TARGET_SOURCES_armv4t-bare := csrc/src/*.c
ATT_TARGET_SHARED_LDFLAGS_armv4t-bare :=
ATT_TARGET_SHARED_LIBGCC_armv4t-bare :=
ATT_TARGET_SHARED_LIBS_armv4t-bare := -lm

# Embedded Linux on ARMv7-A with VFP (e.g. Cortex-A8/A9 boards).
ATT_TARGET_KIND_armv7hf := gcc
ATT_TARGET_OS_armv7hf := linux
ATT_TARGET_CROSS_COMPILE_armv7hf := arm-linux-gnueabihf-
ATT_TARGET_CC_armv7hf := gcc
ATT_TARGET_AR_armv7hf := ar
ATT_TARGET_CFLAGS_armv7hf := -O2 -march=armv7-a -mfpu=vfpv3-d16 -mfloat-abi=hard
ATT_TARGET_LDFLAGS_armv7hf :=
ATT_TARGET_LIBS_armv7hf := -lm
ATT_TARGET_STATIC_APP_armv7hf := 1
ATT_TARGET_SHARED_armv7hf := 1
ATT_TARGET_APP_armv7hf := 1
ATT_TARGET_APP_LIBS_armv7hf := -pthread
ATT_TARGET_SOURCES_armv7hf := csrc/src/*.c
ATT_TARGET_SHARED_LDFLAGS_armv7hf :=
ATT_TARGET_SHARED_LIBGCC_armv7hf :=
ATT_TARGET_SHARED_LIBS_armv7hf := -lm

# Native build for tests on the development machine.
ATT_TARGET_KIND_host := gcc
ATT_TARGET_OS_host := linux
ATT_TARGET_CROSS_COMPILE_host :=
ATT_TARGET_CC_host := gcc
ATT_TARGET_AR_host := ar
ATT_TARGET_CFLAGS_host := -O2
ATT_TARGET_LDFLAGS_host :=
ATT_TARGET_LIBS_host := -lm
ATT_TARGET_STATIC_APP_host := 0
ATT_TARGET_SHARED_host := 1
ATT_TARGET_APP_host := 1
ATT_TARGET_APP_LIBS_host := -pthread
ATT_TARGET_SOURCES_host := csrc/src/*.c
ATT_TARGET_SHARED_LDFLAGS_host :=
ATT_TARGET_SHARED_LIBGCC_host :=
ATT_TARGET_SHARED_LIBS_host := -lm

# Host build with AddressSanitizer + UndefinedBehaviorSanitizer (C test programs).
ATT_TARGET_KIND_host-asan := gcc
ATT_TARGET_OS_host-asan := linux
ATT_TARGET_CROSS_COMPILE_host-asan :=
ATT_TARGET_CC_host-asan := gcc
ATT_TARGET_AR_host-asan := ar
ATT_TARGET_CFLAGS_host-asan := -O1 -g -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer
ATT_TARGET_LDFLAGS_host-asan := -fsanitize=address,undefined
ATT_TARGET_LIBS_host-asan := -lm
ATT_TARGET_STATIC_APP_host-asan := 0
ATT_TARGET_SHARED_host-asan := 0
ATT_TARGET_APP_host-asan := 0
ATT_TARGET_APP_LIBS_host-asan :=
ATT_TARGET_SOURCES_host-asan := csrc/src/*.c
ATT_TARGET_SHARED_LDFLAGS_host-asan :=
ATT_TARGET_SHARED_LIBGCC_host-asan :=
ATT_TARGET_SHARED_LIBS_host-asan := -lm

# Host build with clang, sanitizers on (proves the sources are clean under a second compiler).
ATT_TARGET_KIND_host-clang := gcc
ATT_TARGET_OS_host-clang := linux
ATT_TARGET_CROSS_COMPILE_host-clang :=
ATT_TARGET_CC_host-clang := clang
ATT_TARGET_AR_host-clang := ar
ATT_TARGET_CFLAGS_host-clang := -O1 -g -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer
ATT_TARGET_LDFLAGS_host-clang := -fsanitize=address,undefined
ATT_TARGET_LIBS_host-clang := -lm
ATT_TARGET_STATIC_APP_host-clang := 0
ATT_TARGET_SHARED_host-clang := 0
ATT_TARGET_APP_host-clang := 0
ATT_TARGET_APP_LIBS_host-clang :=
ATT_TARGET_SOURCES_host-clang := csrc/src/*.c
ATT_TARGET_SHARED_LDFLAGS_host-clang :=
ATT_TARGET_SHARED_LIBGCC_host-clang :=
ATT_TARGET_SHARED_LIBS_host-clang := -lm

# AT89S51: 8051 core, 4 KB flash, 128 bytes of RAM, no external RAM.
# Only the parts of the library meant for the 8051 are built here
# (TLC2543 driver, link sender, block format, fixed-point core).
ATT_TARGET_KIND_mcs51 := sdcc
ATT_TARGET_OS_mcs51 := none
ATT_TARGET_CROSS_COMPILE_mcs51 :=
ATT_TARGET_CC_mcs51 := sdcc
ATT_TARGET_AR_mcs51 := sdar
ATT_TARGET_CFLAGS_mcs51 := -mmcs51 --model-small --iram-size 128 --xram-size 0 --code-size 4096
ATT_TARGET_LDFLAGS_mcs51 :=
ATT_TARGET_LIBS_mcs51 :=
ATT_TARGET_STATIC_APP_mcs51 := 0
ATT_TARGET_SHARED_mcs51 := 0
ATT_TARGET_APP_mcs51 := 0
ATT_TARGET_APP_LIBS_mcs51 :=
ATT_TARGET_SOURCES_mcs51 := csrc/src/common.c csrc/src/tlc2543.c csrc/src/link_sender*.c csrc/src/block*.c csrc/src/fixed*.c
ATT_TARGET_SHARED_LDFLAGS_mcs51 :=
ATT_TARGET_SHARED_LIBGCC_mcs51 :=
ATT_TARGET_SHARED_LIBS_mcs51 :=

# AT89S52: the aided board's MCU. Pin-compatible with the AT89S51 (8051 core),
# 8 KB flash, 256 bytes of RAM (the upper 128 reached indirectly: SDCC puts the
# stack there), Timer 2 (the UART's baud generator: 57600 and 115200 baud exact
# from 11.0592 MHz). s51 simulates it as the C52 core (T2 included).
ATT_TARGET_KIND_mcs52 := sdcc
ATT_TARGET_OS_mcs52 := none
ATT_TARGET_CROSS_COMPILE_mcs52 :=
ATT_TARGET_CC_mcs52 := sdcc
ATT_TARGET_AR_mcs52 := sdar
ATT_TARGET_CFLAGS_mcs52 := -mmcs51 --model-small --iram-size 256 --xram-size 0 --code-size 8192
ATT_TARGET_LDFLAGS_mcs52 :=
ATT_TARGET_LIBS_mcs52 :=
ATT_TARGET_STATIC_APP_mcs52 := 0
ATT_TARGET_SHARED_mcs52 := 0
ATT_TARGET_APP_mcs52 := 0
ATT_TARGET_APP_LIBS_mcs52 :=
ATT_TARGET_SOURCES_mcs52 := csrc/src/common.c csrc/src/tlc2543.c csrc/src/link_sender*.c csrc/src/block*.c csrc/src/fixed*.c
ATT_TARGET_SHARED_LDFLAGS_mcs52 :=
ATT_TARGET_SHARED_LIBGCC_mcs52 :=
ATT_TARGET_SHARED_LIBS_mcs52 :=

# attitude-rx's optional dependencies (toolchain/app/optional.toml), probed by the Makefile.
ATT_APP_OPTIONAL := gpsd
ATT_APP_OPTIONAL_DEFINE_gpsd := ATT_RX_GPSD
ATT_APP_OPTIONAL_HEADER_gpsd := gps.h
ATT_APP_OPTIONAL_SYMBOL_gpsd := gps_open
ATT_APP_OPTIONAL_LIBS_gpsd := -lgps
