# libattitude: plain Makefile for users who build with Buildroot, Yocto or
# their own Makefiles (needs only GNU make and a C compiler).
#
#   make                                          # native build (your CC, CFLAGS)
#   make TARGET=armv4t                            # mini2440 (ARM920T): the project's armv4t preset
#   make TARGET=armv4t CROSS_COMPILE=arm-linux-   # the same flags with a vendor toolchain
#   make TARGET=armv4t install PREFIX=/usr DESTDIR=$PWD/rootfs   # staged install
#   make PRECISION=f32                            # att_real = float
#
# TARGET=NAME takes the compiler and the target flags of toolchain/NAME.toml
# (the presets are generated into toolchain/targets.mk by
# `python -m toolchain.buildfiles`: the same flags as `invoke cross-build`
# and cmake/NAME-toolchain.cmake): host, armv4t, armv4t-bare, armv7hf,
# aarch64, host-asan, host-clang, mcs51 (SDCC: the 8051 parts, libattitude.lib).
# PLATFORM=linux (the default on Linux targets and without TARGET) also builds
# the platform code of csrc/platform/linux into the library (HALs on Linux
# drivers, e.g. the AD7927 spidev HAL); PLATFORM= builds the portable
# library only. Bare-metal targets (os = "none") never take platform code.
#
# Honoured variables: TARGET, CROSS_COMPILE, CC, AR, CFLAGS, CPPFLAGS,
# LDFLAGS, TARGET_CFLAGS (architecture flags; set by TARGET), PREFIX,
# DESTDIR, LIBDIR, INCLUDEDIR, BINDIR, PKGCONFIGDIR, BUILDDIR, PRECISION
# (f64|f32), STATIC_APP (1 = link attitude-rx statically, 0 = against
# libattitude.so), SHARED (0 = no .so), APP (0 = no attitude-rx),
# SHARED_LDFLAGS, SHARED_LIBGCC, SHARED_LIBS (the link of libattitude.so; set
# by TARGET: armv4t links the ARMv4T libgcc.a of arm-none-eabi-gcc and only
# -lm -lc, see docs/cross-build.md).
#
# Products (in $(BUILDDIR), default build/make, or build/make-NAME with
# TARGET=NAME): libattitude.a (libattitude.lib with SDCC),
# libattitude.so(.0, .VERSION), attitude-rx, attitude.pc. APP_OPTIONAL: attitude-rx's optional
# dependencies built in (default: those found, e.g. gpsd with libgps).
# A stamp of the compiler and every flag makes objects rebuild when either
# changes (another TARGET, CFLAGS or compiler in the same BUILDDIR).

# The version's one source: csrc/include/attitude/version.h (`make version` prints it).
att_version_part = $(shell sed -n 's/^ *ATT_VERSION_$(1) = \([0-9][0-9]*\).*/\1/p' csrc/include/attitude/version.h)
VERSION      := $(call att_version_part,MAJOR).$(call att_version_part,MINOR).$(call att_version_part,PATCH)
SOVERSION    := $(call att_version_part,SO)

TARGET ?=
include toolchain/targets.mk
ifneq ($(TARGET),)
ifeq ($(filter $(TARGET),$(ATT_TARGETS)),)
$(error TARGET must be one of: $(ATT_TARGETS) (toolchain/*.toml), not '$(TARGET)')
endif
KIND          := $(ATT_TARGET_KIND_$(TARGET))
CROSS_COMPILE ?= $(ATT_TARGET_CROSS_COMPILE_$(TARGET))
TARGET_CFLAGS ?= $(ATT_TARGET_CFLAGS_$(TARGET))
TARGET_LDFLAGS := $(ATT_TARGET_LDFLAGS_$(TARGET))
TARGET_LIBS   := $(ATT_TARGET_LIBS_$(TARGET))
STATIC_APP    ?= $(ATT_TARGET_STATIC_APP_$(TARGET))
SHARED        ?= $(ATT_TARGET_SHARED_$(TARGET))
APP           ?= $(ATT_TARGET_APP_$(TARGET))
APP_LIBS      := $(ATT_TARGET_APP_LIBS_$(TARGET))
LIB_GLOBS     := $(ATT_TARGET_SOURCES_$(TARGET))
SHARED_LDFLAGS ?= $(ATT_TARGET_SHARED_LDFLAGS_$(TARGET))
SHARED_LIBGCC_CMD := $(ATT_TARGET_SHARED_LIBGCC_$(TARGET))
SHARED_LIBS   ?= $(ATT_TARGET_SHARED_LIBS_$(TARGET))
BUILDDIR      ?= build/make-$(TARGET)
CFLAGS        ?=
ifeq ($(origin CC),default)
CC := $(CROSS_COMPILE)$(ATT_TARGET_CC_$(TARGET))
endif
ifeq ($(origin AR),default)
AR := $(CROSS_COMPILE)$(ATT_TARGET_AR_$(TARGET))
endif
else
KIND          := gcc
CROSS_COMPILE ?=
TARGET_CFLAGS ?=
TARGET_LDFLAGS :=
TARGET_LIBS   := -lm
APP_LIBS      := -pthread
LIB_GLOBS     := csrc/src/*.c
SHARED_LDFLAGS ?=
SHARED_LIBGCC_CMD :=
SHARED_LIBS   ?= $(TARGET_LIBS)
CFLAGS        ?= -O2
ifeq ($(origin CC),default)
CC := $(CROSS_COMPILE)gcc
endif
ifeq ($(origin AR),default)
AR := $(CROSS_COMPILE)ar
endif
endif

PREFIX       ?= /usr/local
DESTDIR      ?=
LIBDIR       ?= $(PREFIX)/lib
INCLUDEDIR   ?= $(PREFIX)/include
BINDIR       ?= $(PREFIX)/bin
PKGCONFIGDIR ?= $(LIBDIR)/pkgconfig
BUILDDIR     ?= build/make
PRECISION    ?= f64
STATIC_APP   ?= 1
SHARED       ?= 1
APP          ?= 1
LDFLAGS      ?=
ifneq ($(TARGET),)
PLATFORM     ?= $(if $(filter linux,$(ATT_TARGET_OS_$(TARGET))),linux,)
else
PLATFORM     ?= linux
endif

# attitude-rx's optional dependencies (toolchain/app/optional.toml, through targets.mk; the
# app's only, never the library's): each is built in when a program that includes its header
# and takes its symbol links with its libraries for this compiler and the app's link flags.
# APP_OPTIONAL=NAMES decides instead (APP_OPTIONAL= builds attitude-rx without any).
att_probe = $(shell printf '\043include <%s>\nint main(void)\n{\n    return (int)(long)&%s;\n}\n' \
  '$(ATT_APP_OPTIONAL_HEADER_$(1))' '$(ATT_APP_OPTIONAL_SYMBOL_$(1))' | $(CC) $(TARGET_CFLAGS) \
  $(CFLAGS) -x c - -o /dev/null $(TARGET_LDFLAGS) $(LDFLAGS) $(if $(filter 1,$(STATIC_APP)),-static) \
  $(APP_LIBS) $(ATT_APP_OPTIONAL_LIBS_$(1)) $(TARGET_LIBS) >/dev/null 2>&1 && echo 1)
ifeq ($(origin APP_OPTIONAL),undefined)
att_building := $(if $(MAKECMDGOALS),$(filter-out version clean uninstall,$(MAKECMDGOALS)),all)
APP_OPTIONAL := $(if $(and $(att_building),$(filter 1,$(APP))),$(foreach f,$(ATT_APP_OPTIONAL),$(if $(call att_probe,$(f)),$(f))))
endif
APP_OPT_DEFS := $(foreach f,$(APP_OPTIONAL),-D$(ATT_APP_OPTIONAL_DEFINE_$(f)))
APP_OPT_LIBS := $(foreach f,$(APP_OPTIONAL),$(ATT_APP_OPTIONAL_LIBS_$(f)))

# libattitude.so of a target that links its own libgcc (armv4t: the ARMv4T one
# of arm-none-eabi-gcc, not the armel compiler's ARMv5TE runtime).
ifeq ($(SHARED),1)
ifneq ($(SHARED_LIBGCC_CMD),)
SHARED_LIBGCC ?= $(shell $(SHARED_LIBGCC_CMD) 2>/dev/null)
endif
endif

ifeq ($(KIND),sdcc)
# SDCC has no double (it would silently be float): always the float build.
override PRECISION := f32
endif
ifeq ($(PRECISION),f32)
PREC_DEFS := -DATT_REAL_F32
else ifeq ($(PRECISION),f64)
PREC_DEFS :=
else
$(error PRECISION must be f64 or f32, not '$(PRECISION)')
endif

# Platform code (HALs on the OS's drivers), if any for PLATFORM.
PLAT_DIR  := csrc/platform/$(PLATFORM)
PLAT_SRCS := $(if $(filter-out sdcc,$(KIND)),$(if $(PLATFORM),$(sort $(wildcard $(PLAT_DIR)/src/*.c))))
PLAT_INC  := $(if $(PLAT_SRCS),-I$(PLAT_DIR)/include)

# Flags the library needs whatever the user's CFLAGS say.
ifeq ($(KIND),sdcc)
ATT_CFLAGS := --std-c99 -Icsrc/include $(PREC_DEFS)
O := rel
STATIC_LIB := $(BUILDDIR)/libattitude.lib
override SHARED := 0
override APP := 0
else
ATT_CFLAGS := -std=c99 -Wall -Wextra -Wpedantic -Icsrc/include $(PLAT_INC) $(PREC_DEFS)
O := o
STATIC_LIB := $(BUILDDIR)/libattitude.a
endif

# The shared library's objects: position independent, and every symbol hidden
# but the public headers' declarations (ATT_API_BEGIN/END, attitude/common.h).
PIC_CFLAGS := -fPIC -fvisibility=hidden

LIB_SRCS := $(sort $(wildcard $(LIB_GLOBS)))
APP_SRCS := $(if $(filter 1,$(APP)),$(sort $(wildcard csrc/app/*.c)))
HEADERS  := $(sort $(wildcard csrc/include/attitude/*.h) \
                   $(if $(PLAT_SRCS),$(wildcard $(PLAT_DIR)/include/attitude/*.h)))
LIB_OBJS := $(LIB_SRCS:csrc/src/%.c=$(BUILDDIR)/obj/%.$(O)) \
            $(PLAT_SRCS:$(PLAT_DIR)/src/%.c=$(BUILDDIR)/obj/%.o)
PIC_OBJS := $(LIB_SRCS:csrc/src/%.c=$(BUILDDIR)/obj-pic/%.o) \
            $(PLAT_SRCS:$(PLAT_DIR)/src/%.c=$(BUILDDIR)/obj-pic/%.o)
APP_OBJS := $(APP_SRCS:csrc/app/%.c=$(BUILDDIR)/obj-app/%.o)

SHARED_REAL := $(BUILDDIR)/libattitude.so.$(VERSION)
APP_EXE := $(BUILDDIR)/attitude-rx
PC := $(BUILDDIR)/attitude.pc
STAMP := $(BUILDDIR)/flags.stamp

ALL := $(STATIC_LIB) $(PC)
ifeq ($(SHARED),1)
ALL += $(BUILDDIR)/libattitude.so
endif
ifneq ($(APP_SRCS),)
ALL += $(APP_EXE)
endif

.PHONY: all install uninstall clean version FORCE
all: $(ALL)

version:
	@echo $(VERSION)

# The stamp holds the compiler (name and version) and every flag that goes
# into an object or a link; it is rewritten only when that text changes, so
# objects rebuild exactly when the compiler or a flag changed.
STAMP_TEXT := $(CC) $(shell $(CC) --version 2>/dev/null | head -n 1) | $(ATT_CFLAGS) $(TARGET_CFLAGS) \
  $(CPPFLAGS) $(CFLAGS) | $(TARGET_LDFLAGS) $(LDFLAGS) $(TARGET_LIBS) | $(AR) | $(STATIC_APP) \
  | $(SHARED_LDFLAGS) $(SHARED_LIBGCC) $(SHARED_LIBS) | $(PIC_CFLAGS) | $(APP_OPT_DEFS) $(APP_OPT_LIBS)
$(STAMP): FORCE
	@mkdir -p $(@D)
	@if [ "$$(cat $@ 2>/dev/null)" != '$(subst ','\'',$(STAMP_TEXT))' ]; then \
	  printf '%s\n' '$(subst ','\'',$(STAMP_TEXT))' > $@; fi

$(BUILDDIR)/obj/%.$(O): csrc/src/%.c $(HEADERS) $(STAMP)
	@mkdir -p $(@D)
	$(CC) $(ATT_CFLAGS) $(TARGET_CFLAGS) $(CPPFLAGS) $(CFLAGS) -c $< -o $@

$(BUILDDIR)/obj-pic/%.o: csrc/src/%.c $(HEADERS) $(STAMP)
	@mkdir -p $(@D)
	$(CC) $(ATT_CFLAGS) $(TARGET_CFLAGS) $(CPPFLAGS) $(CFLAGS) $(PIC_CFLAGS) -c $< -o $@

$(BUILDDIR)/obj/%.o: $(PLAT_DIR)/src/%.c $(HEADERS) $(STAMP)
	@mkdir -p $(@D)
	$(CC) $(ATT_CFLAGS) $(TARGET_CFLAGS) $(CPPFLAGS) $(CFLAGS) -c $< -o $@

$(BUILDDIR)/obj-pic/%.o: $(PLAT_DIR)/src/%.c $(HEADERS) $(STAMP)
	@mkdir -p $(@D)
	$(CC) $(ATT_CFLAGS) $(TARGET_CFLAGS) $(CPPFLAGS) $(CFLAGS) $(PIC_CFLAGS) -c $< -o $@

$(BUILDDIR)/obj-app/%.o: csrc/app/%.c $(HEADERS) $(wildcard csrc/app/*.h) $(STAMP)
	@mkdir -p $(@D)
	$(CC) $(ATT_CFLAGS) -Icsrc/app $(APP_OPT_DEFS) $(TARGET_CFLAGS) $(CPPFLAGS) $(CFLAGS) -c $< -o $@

$(STATIC_LIB): $(LIB_OBJS)
	@rm -f $@
	$(AR) rcs $@ $^

$(SHARED_REAL): $(PIC_OBJS)
ifeq ($(origin SHARED_LIBGCC),file)
	@test -f '$(SHARED_LIBGCC)' || { echo 'libattitude.so (TARGET=$(TARGET)) links the libgcc.a that `$(SHARED_LIBGCC_CMD)` prints: install that compiler, or pass SHARED_LIBGCC=/path/to/libgcc.a, or SHARED=0' >&2; exit 1; }
endif
	$(CC) $(TARGET_CFLAGS) $(CFLAGS) $(TARGET_LDFLAGS) $(LDFLAGS) $(SHARED_LDFLAGS) -shared -Wl,-soname,libattitude.so.$(SOVERSION) $^ -o $@ $(SHARED_LIBGCC) $(SHARED_LIBS)

$(BUILDDIR)/libattitude.so: $(SHARED_REAL)
	ln -sf libattitude.so.$(VERSION) $(BUILDDIR)/libattitude.so.$(SOVERSION)
	ln -sf libattitude.so.$(VERSION) $@

ifeq ($(STATIC_APP),1)
$(APP_EXE): $(APP_OBJS) $(STATIC_LIB)
	$(CC) $(TARGET_CFLAGS) $(CFLAGS) $(TARGET_LDFLAGS) $(LDFLAGS) -static $(APP_OBJS) $(STATIC_LIB) -o $@ $(APP_LIBS) $(APP_OPT_LIBS) $(TARGET_LIBS)
else
$(APP_EXE): $(APP_OBJS) $(BUILDDIR)/libattitude.so
	$(CC) $(TARGET_CFLAGS) $(CFLAGS) $(TARGET_LDFLAGS) $(LDFLAGS) $(APP_OBJS) -L$(BUILDDIR) -lattitude -o $@ $(APP_LIBS) $(APP_OPT_LIBS) $(TARGET_LIBS)
endif

$(PC): FORCE
	@mkdir -p $(@D)
	printf '%s\n' \
	  'prefix=$(PREFIX)' \
	  'libdir=$(LIBDIR)' \
	  'includedir=$(INCLUDEDIR)' \
	  '' \
	  'Name: attitude' \
	  'Description: libattitude strapdown attitude library' \
	  'Version: $(VERSION)' \
	  'Cflags: -I$${includedir} $(PREC_DEFS)' \
	  'Libs: -L$${libdir} -lattitude' \
	  'Libs.private: $(TARGET_LIBS)' > $@

install: all
	install -d $(DESTDIR)$(LIBDIR) $(DESTDIR)$(INCLUDEDIR)/attitude $(DESTDIR)$(PKGCONFIGDIR)
	install -m 644 $(STATIC_LIB) $(DESTDIR)$(LIBDIR)/
	install -m 644 $(HEADERS) $(DESTDIR)$(INCLUDEDIR)/attitude/
	install -m 644 $(PC) $(DESTDIR)$(PKGCONFIGDIR)/
ifeq ($(SHARED),1)
	install -m 755 $(SHARED_REAL) $(DESTDIR)$(LIBDIR)/
	ln -sf libattitude.so.$(VERSION) $(DESTDIR)$(LIBDIR)/libattitude.so.$(SOVERSION)
	ln -sf libattitude.so.$(VERSION) $(DESTDIR)$(LIBDIR)/libattitude.so
endif
ifneq ($(APP_SRCS),)
	install -d $(DESTDIR)$(BINDIR)
	install -m 755 $(APP_EXE) $(DESTDIR)$(BINDIR)/
endif

uninstall:
	rm -f $(DESTDIR)$(LIBDIR)/libattitude.a $(DESTDIR)$(LIBDIR)/libattitude.lib \
	      $(DESTDIR)$(LIBDIR)/libattitude.so* $(DESTDIR)$(PKGCONFIGDIR)/attitude.pc \
	      $(DESTDIR)$(BINDIR)/attitude-rx
	rm -rf $(DESTDIR)$(INCLUDEDIR)/attitude

clean:
	rm -rf $(BUILDDIR)

FORCE:
