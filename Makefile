# libattitude: plain Makefile for users who build with Buildroot, Yocto or
# their own Makefiles (the project's own tasks use `invoke cross-build`).
#
#   make                                         # native build
#   make CROSS_COMPILE=arm-linux-gnueabi- \
#        TARGET_CFLAGS="-march=armv4t -mtune=arm920t -marm -mfloat-abi=soft"   # mini2440
#   make install PREFIX=/usr DESTDIR=$PWD/rootfs   # staged install
#   make PRECISION=f32                           # att_real = float
#
# Honoured variables: CROSS_COMPILE, CC, AR, CFLAGS, CPPFLAGS, LDFLAGS,
# TARGET_CFLAGS (architecture flags), PREFIX, DESTDIR, LIBDIR, INCLUDEDIR,
# BINDIR, PKGCONFIGDIR, BUILDDIR, PRECISION (f64|f32), STATIC_APP (1 = link
# attitude-rx statically, 0 = against libattitude.so), SHARED (0 = no .so),
# PLATFORM (linux = build csrc/platform/linux into the library, e.g. the
# AD7927 spidev HAL; empty = the portable library only).
#
# Products (in $(BUILDDIR)): libattitude.a, libattitude.so(.0, .VERSION),
# attitude-rx, attitude.pc.

VERSION      := 0.1.0
SOVERSION    := 0

CROSS_COMPILE ?=
ifeq ($(origin CC),default)
CC := $(CROSS_COMPILE)gcc
endif
ifeq ($(origin AR),default)
AR := $(CROSS_COMPILE)ar
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
PLATFORM     ?= linux

CFLAGS       ?= -O2
TARGET_CFLAGS ?=
LDFLAGS      ?=

ifeq ($(PRECISION),f32)
PREC_DEFS := -DATT_REAL_F32
else ifeq ($(PRECISION),f64)
PREC_DEFS :=
else
$(error PRECISION must be f64 or f32, not '$(PRECISION)')
endif

# Platform code (HALs on the OS's drivers), if any for PLATFORM.
PLAT_DIR  := csrc/platform/$(PLATFORM)
PLAT_SRCS := $(if $(PLATFORM),$(sort $(wildcard $(PLAT_DIR)/src/*.c)))
PLAT_INC  := $(if $(PLAT_SRCS),-I$(PLAT_DIR)/include)

# Flags the library needs whatever the user's CFLAGS say.
ATT_CFLAGS := -std=c99 -Wall -Wextra -Wpedantic -Icsrc/include $(PLAT_INC) $(PREC_DEFS)

LIB_SRCS := $(sort $(wildcard csrc/src/*.c))
APP_SRCS := $(sort $(wildcard csrc/app/*.c))
HEADERS  := $(sort $(wildcard csrc/include/attitude/*.h) \
                   $(if $(PLAT_SRCS),$(wildcard $(PLAT_DIR)/include/attitude/*.h)))
LIB_OBJS := $(LIB_SRCS:csrc/src/%.c=$(BUILDDIR)/obj/%.o) $(PLAT_SRCS:$(PLAT_DIR)/src/%.c=$(BUILDDIR)/obj/%.o)
PIC_OBJS := $(LIB_SRCS:csrc/src/%.c=$(BUILDDIR)/obj-pic/%.o) \
            $(PLAT_SRCS:$(PLAT_DIR)/src/%.c=$(BUILDDIR)/obj-pic/%.o)
APP_OBJS := $(APP_SRCS:csrc/app/%.c=$(BUILDDIR)/obj-app/%.o)

STATIC_LIB := $(BUILDDIR)/libattitude.a
SHARED_REAL := $(BUILDDIR)/libattitude.so.$(VERSION)
APP := $(BUILDDIR)/attitude-rx
PC := $(BUILDDIR)/attitude.pc

ALL := $(STATIC_LIB) $(PC)
ifeq ($(SHARED),1)
ALL += $(BUILDDIR)/libattitude.so
endif
ifneq ($(APP_SRCS),)
ALL += $(APP)
endif

.PHONY: all install uninstall clean FORCE
all: $(ALL)

$(BUILDDIR)/obj/%.o: csrc/src/%.c $(HEADERS)
	@mkdir -p $(@D)
	$(CC) $(ATT_CFLAGS) $(TARGET_CFLAGS) $(CPPFLAGS) $(CFLAGS) -c $< -o $@

$(BUILDDIR)/obj-pic/%.o: csrc/src/%.c $(HEADERS)
	@mkdir -p $(@D)
	$(CC) $(ATT_CFLAGS) $(TARGET_CFLAGS) $(CPPFLAGS) $(CFLAGS) -fPIC -c $< -o $@

$(BUILDDIR)/obj/%.o: $(PLAT_DIR)/src/%.c $(HEADERS)
	@mkdir -p $(@D)
	$(CC) $(ATT_CFLAGS) $(TARGET_CFLAGS) $(CPPFLAGS) $(CFLAGS) -c $< -o $@

$(BUILDDIR)/obj-pic/%.o: $(PLAT_DIR)/src/%.c $(HEADERS)
	@mkdir -p $(@D)
	$(CC) $(ATT_CFLAGS) $(TARGET_CFLAGS) $(CPPFLAGS) $(CFLAGS) -fPIC -c $< -o $@

$(BUILDDIR)/obj-app/%.o: csrc/app/%.c $(HEADERS) $(wildcard csrc/app/*.h)
	@mkdir -p $(@D)
	$(CC) $(ATT_CFLAGS) -Icsrc/app $(TARGET_CFLAGS) $(CPPFLAGS) $(CFLAGS) -c $< -o $@

$(STATIC_LIB): $(LIB_OBJS)
	@rm -f $@
	$(AR) rcs $@ $^

$(SHARED_REAL): $(PIC_OBJS)
	$(CC) $(TARGET_CFLAGS) $(CFLAGS) $(LDFLAGS) -shared -Wl,-soname,libattitude.so.$(SOVERSION) $^ -o $@ -lm

$(BUILDDIR)/libattitude.so: $(SHARED_REAL)
	ln -sf libattitude.so.$(VERSION) $(BUILDDIR)/libattitude.so.$(SOVERSION)
	ln -sf libattitude.so.$(VERSION) $@

ifeq ($(STATIC_APP),1)
$(APP): $(APP_OBJS) $(STATIC_LIB)
	$(CC) $(TARGET_CFLAGS) $(CFLAGS) $(LDFLAGS) -static $(APP_OBJS) $(STATIC_LIB) -o $@ -pthread -lm
else
$(APP): $(APP_OBJS) $(BUILDDIR)/libattitude.so
	$(CC) $(TARGET_CFLAGS) $(CFLAGS) $(LDFLAGS) $(APP_OBJS) -L$(BUILDDIR) -lattitude -o $@ -pthread -lm
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
	  'Libs.private: -lm' > $@

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
	install -m 755 $(APP) $(DESTDIR)$(BINDIR)/
endif

uninstall:
	rm -f $(DESTDIR)$(LIBDIR)/libattitude.a $(DESTDIR)$(LIBDIR)/libattitude.so* \
	      $(DESTDIR)$(PKGCONFIGDIR)/attitude.pc $(DESTDIR)$(BINDIR)/attitude-rx
	rm -rf $(DESTDIR)$(INCLUDEDIR)/attitude

clean:
	rm -rf $(BUILDDIR)

FORCE:
