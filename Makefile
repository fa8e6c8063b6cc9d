# layerlab — build, test, install.
#   make               library (shared + static) and tools
#   make test          cmocka suite (+ Python tests when numpy is importable)
#   make test SANITIZE=1   the same under ASan + UBSan
#   make bench         benchmarks (never part of `make test`)
#   make install PREFIX=/usr/local
#   make deps          install missing Debian packages (run by the others)

# ------------------------------------------------------------- versions
# Read from the header, the single source of truth.
HEADER_COMMON := include/layerlab/ll_common.h
VERSION_MAJOR := $(shell sed -n 's/^\#define LL_VERSION_MAJOR \([0-9]*\).*/\1/p' $(HEADER_COMMON))
VERSION_MINOR := $(shell sed -n 's/^\#define LL_VERSION_MINOR \([0-9]*\).*/\1/p' $(HEADER_COMMON))
VERSION_PATCH := $(shell sed -n 's/^\#define LL_VERSION_PATCH \([0-9]*\).*/\1/p' $(HEADER_COMMON))
ABI_VERSION   := $(shell sed -n 's/^\#define LL_ABI_VERSION \([0-9]*\).*/\1/p' $(HEADER_COMMON))
VERSION       := $(VERSION_MAJOR).$(VERSION_MINOR).$(VERSION_PATCH)

PREFIX  ?= /usr/local
LIBDIR  ?= $(PREFIX)/lib
INCDIR  ?= $(PREFIX)/include
BINDIR  ?= $(PREFIX)/bin
PKGDIR  ?= $(LIBDIR)/pkgconfig
DATADIR ?= $(PREFIX)/share/layerlab
# Measured spectra of metals for `conductor eta=Au` (installed so that an
# installed llbuild finds them; see docs/material-language.md).
IOR_SRC ?= $(firstword $(wildcard ../shared/ior))

BUILD   ?= build
CC      ?= cc
CXX     ?= c++
MULTIARCH := $(shell $(CC) -print-multiarch 2>/dev/null)

# OpenBLAS: prefer the OpenMP build, which runs single-threaded inside our own
# parallel regions (see src/support/threads.c); fall back to whatever -lopenblas is.
OPENBLAS_DIR ?= $(firstword $(wildcard /usr/lib/$(MULTIARCH)/openblas-openmp))
ifneq ($(OPENBLAS_DIR),)
BLAS_LIBS := -L$(OPENBLAS_DIR) -Wl,-rpath,$(OPENBLAS_DIR) -llapacke -lopenblas
else
BLAS_LIBS := -llapacke -lopenblas
endif

OPT      ?= -O2
WARN     := -Wall -Wextra -pedantic -Werror
CFLAGS_LIB := -std=c99 $(OPT) -g $(WARN) -fPIC -fvisibility=hidden -fopenmp \
              -D_POSIX_C_SOURCE=200809L -DLL_BUILDING_LIBRARY -Iinclude -Isrc
ifeq ($(SANITIZE),1)
SAN      := -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined
BUILD    := build-san
endif
CFLAGS_LIB += $(SAN)
LDLIBS_LIB := $(BLAS_LIBS) -fopenmp -lm -lpthread

LIB_SRC  := $(sort $(wildcard src/*/*.c))
LIB_OBJ  := $(LIB_SRC:src/%.c=$(BUILD)/obj/%.o)
SONAME   := liblayerlab.so.$(ABI_VERSION)
SHARED   := $(BUILD)/lib/liblayerlab.so.$(VERSION)
STATIC   := $(BUILD)/lib/liblayerlab.a

# Tools: each directory tools/NAME/ holds the sources of one program NAME.
TOOL_NAMES := $(notdir $(patsubst %/,%,$(sort $(dir $(wildcard tools/*/*.c)))))
TOOLS    := $(TOOL_NAMES:%=$(BUILD)/bin/%)
TOOL_CFLAGS = -std=c99 $(OPT) -g $(WARN) -D_POSIX_C_SOURCE=200809L -Iinclude $(SAN) \
               $(shell pkg-config --cflags cairo OpenEXR 2>/dev/null)
TOOL_LIBS = $(shell pkg-config --libs cairo OpenEXR 2>/dev/null) -lm

# Tests: each tests/test_*.c is one cmocka program, linked statically so it
# can reach internal functions too.
TEST_SRC := $(sort $(wildcard tests/test_*.c))
TESTS    := $(TEST_SRC:tests/%.c=$(BUILD)/tests/%)
TEST_CFLAGS := -std=c99 $(OPT) -g $(WARN) -Wno-unused-parameter -D_POSIX_C_SOURCE=200809L \
               -Iinclude -Isrc -Itests -fopenmp $(SAN) \
               -DLL_SOURCE_DIR='"$(CURDIR)"' -DLL_BUILD_DIR='"$(CURDIR)/$(BUILD)"'
TEST_LIBS := $(STATIC) -lcmocka $(LDLIBS_LIB)

.PHONY: all deps lib tools test test-c test-python bench install uninstall clean fuzz demo
all: deps lib tools

deps:
	@sh scripts/deps.sh

lib: $(SHARED) $(STATIC) $(BUILD)/lib/layerlab.pc

$(BUILD)/obj/%.o: src/%.c $(wildcard src/*/*.h) $(wildcard include/*.h include/layerlab/*.h) | deps
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS_LIB) -c $< -o $@

$(SHARED): $(LIB_OBJ) src/liblayerlab.map
	@mkdir -p $(dir $@)
	$(CC) -shared -o $@ $(LIB_OBJ) -Wl,-soname,$(SONAME) \
	    -Wl,--version-script=src/liblayerlab.map -Wl,--no-undefined $(SAN) $(LDLIBS_LIB)
	ln -sf liblayerlab.so.$(VERSION) $(BUILD)/lib/$(SONAME)
	ln -sf $(SONAME) $(BUILD)/lib/liblayerlab.so

$(STATIC): $(LIB_OBJ)
	@mkdir -p $(dir $@)
	rm -f $@
	ar rcs $@ $(LIB_OBJ)

# layerlab.pc names the install directories, so it is written for the
# PREFIX/LIBDIR/INCDIR in effect: at build time for the default, and again
# by `make install` for the ones given there.
write_pc = printf '%s\n' 'prefix=$(PREFIX)' 'libdir=$(LIBDIR)' 'includedir=$(INCDIR)' '' \
	  'Name: layerlab' 'Description: Layered material reflectance (adding-doubling, .bsdf files)' \
	  'Version: $(VERSION)' 'Cflags: -I$${includedir}' 'Libs: -L$${libdir} -Wl,-rpath,$${libdir} -llayerlab' \
	  'Libs.private: $(BLAS_LIBS) -fopenmp -lm -lpthread' > $(1)

$(BUILD)/lib/layerlab.pc: Makefile
	@mkdir -p $(dir $@)
	@$(call write_pc,$@)

tools: $(TOOLS)

.SECONDEXPANSION:
$(BUILD)/bin/%: $$(wildcard tools/%/*.c) $$(wildcard tools/%/*.h) $(SHARED) | deps
	@mkdir -p $(dir $@)
	$(CC) $(TOOL_CFLAGS) -o $@ $(filter %.c,$^) -L$(BUILD)/lib -Wl,-rpath,'$$ORIGIN/../lib' \
	    -llayerlab $(TOOL_LIBS)

$(BUILD)/tests/%: tests/%.c $(wildcard tests/*.h) $(STATIC) | deps
	@mkdir -p $(dir $@)
	$(CC) $(TEST_CFLAGS) -o $@ $< $(TEST_LIBS)

# The C suite: every cmocka program, then the shell checks of the tests/*.sh
# scripts (ABI, headers, tools). Each prints its own summary lines.
test-c: all $(TESTS)
	@set -e; failed=0; \
	for t in $(TESTS); do \
	  echo "== $$t"; \
	  if ! $$t; then failed=$$((failed+1)); fi; \
	done; \
	for s in $(sort $(wildcard tests/*.sh)); do \
	  echo "== $$s"; \
	  if ! BUILD=$(BUILD) CC=$(CC) CXX=$(CXX) sh $$s; then failed=$$((failed+1)); fi; \
	done; \
	if [ $$failed -ne 0 ]; then echo "$$failed test program(s) failed"; exit 1; fi

test-python: all
	@if [ -f python/tests/run.sh ]; then BUILD=$(BUILD) sh python/tests/run.sh; fi

ifeq ($(SANITIZE),1)
test: test-c
else
test: test-c test-python
endif

bench:
	@$(MAKE) --no-print-directory all BUILD=build-bench OPT='-O3 -march=x86-64-v2'
	@if [ -f bench/run.sh ]; then BUILD=build-bench sh bench/run.sh; fi

fuzz:
	@if [ -f tests/fuzz/run.sh ]; then sh tests/fuzz/run.sh $(FUZZ_SECONDS); fi

demo: all
	@sh scripts/demo.sh

# pbrt-v3 built stock and with the shim against the system's libraries,
# rendered on intact and damaged files (shims/pbrt-v3/check/check.sh; not
# part of `make test`). Needs PBRT_SRC=<a plain pbrt-v3 source tree>.
PBRT_WORK   ?= $(BUILD)/pbrt-check
PBRT_GOLDEN ?= tests/data/roughgold_alpha_0.2.bsdf
.PHONY: pbrt-check
pbrt-check: all
	@test -n "$(PBRT_SRC)" || { echo "make pbrt-check needs PBRT_SRC=/path/to/pbrt-v3"; exit 1; }
	@$(MAKE) --no-print-directory install PREFIX=$(abspath $(PBRT_WORK))/layerlab > /dev/null
	@sh shims/pbrt-v3/check/check.sh "$(PBRT_SRC)" "$(PBRT_WORK)" "$(PBRT_GOLDEN)" \
	    "$(abspath $(PBRT_WORK))/layerlab"

install: all
	install -d $(DESTDIR)$(LIBDIR) $(DESTDIR)$(INCDIR)/layerlab $(DESTDIR)$(BINDIR) $(DESTDIR)$(PKGDIR)
	install -m 644 include/layerlab.h $(DESTDIR)$(INCDIR)/
	install -m 644 include/layerlab/*.h $(DESTDIR)$(INCDIR)/layerlab/
	install -m 755 $(SHARED) $(DESTDIR)$(LIBDIR)/
	ln -sf liblayerlab.so.$(VERSION) $(DESTDIR)$(LIBDIR)/$(SONAME)
	ln -sf $(SONAME) $(DESTDIR)$(LIBDIR)/liblayerlab.so
	install -m 644 $(STATIC) $(DESTDIR)$(LIBDIR)/
	$(call write_pc,$(DESTDIR)$(PKGDIR)/layerlab.pc)
	@# the tools find the library through their RUNPATH $$ORIGIN/../lib
	if [ -n "$(IOR_SRC)" ]; then install -d $(DESTDIR)$(DATADIR)/ior && \
	  install -m 644 $(IOR_SRC)/*.spd $(DESTDIR)$(DATADIR)/ior/; fi
	for t in $(TOOLS); do install -m 755 $$t $(DESTDIR)$(BINDIR)/; done

uninstall:
	rm -f $(DESTDIR)$(LIBDIR)/liblayerlab.* $(DESTDIR)$(PKGDIR)/layerlab.pc $(DESTDIR)$(INCDIR)/layerlab.h
	rm -rf $(DESTDIR)$(INCDIR)/layerlab $(DESTDIR)$(DATADIR)
	for t in $(TOOL_NAMES); do rm -f $(DESTDIR)$(BINDIR)/$$t; done

clean:
	rm -rf build build-san build-bench
