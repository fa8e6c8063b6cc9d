# layerlab — build, test, install.
#   make deps          install the missing Debian packages (scripts/deps.sh); the
#                      only target that installs anything: on a fresh machine
#                      `make deps demo` and `make deps test`
#   make               libraries (liblayerlab, liblayerlab_reader; shared + static) and tools
#   make lib           the libraries alone
#   make test          the fast tier: deterministic unit and integration tests (C
#                      suite, tool and ABI checks, the Python package in build/venv)
#   make check         `make test` and the slow tier: signals, MPI, the cross-checks
#                      against iadpython/DISORT, the convergence subset, the pbrt-v3
#                      shim's adapter, the Mitsuba renders (SLOW_TESTS, SLOW_SCRIPTS)
#   make test SANITIZE=1   the C suite under ASan + UBSan (build-san/)
#   make test TSAN=1   the concurrent reader tests under ThreadSanitizer (build-tsan/)
#   make coverage      the fast C tier in build-cov/, line coverage of src/ (gcovr)
#   make clang         the libraries and the C tests built by clang, warnings as errors
#   make cmake-check   the CMake build installed, and a CMake project that uses it
#   make abi-baseline  rewrite abi/*.abi from the libraries just built (see abi/README.md)
#   make api-doc       rewrite docs/api.md from the headers' comments (after changing one)
#   DEV=1 (or CI=true) turns warnings into errors
#   make bench         the headline benchmarks, under 10 minutes (make bench-full: all); never in the tests
#   make install PREFIX=/usr/local
# Nothing but `make deps` installs a package: a missing one stops the build
# with its Debian name (scripts/need.sh).

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
# Measured spectra of metals for `conductor eta=Au` (data/ior/README.md). The
# library looks for them in ../share/layerlab/ior from its own folder
# (src/material/ior.c), so they are installed to PREFIX/share/layerlab/ior and
# copied to $(BUILD)/share/layerlab/ior in a build tree: one rule for both.
IOR_SRC ?= data/ior

BUILD   ?= build
CC      ?= cc
CXX     ?= c++
PYTHON  ?= python3
export PYTHON

# OpenBLAS: prefer the OpenMP build, which runs single-threaded inside our own
# parallel regions (see src/support/threads.c). pkg-config names the folder
# of the variant the system selected; a distribution that installs its
# variants side by side (Debian: openblas-pthread/, openblas-openmp/) has the
# OpenMP one beside it. Without pkg-config's answer, -lopenblas is whatever
# the compiler's search path holds.
OPENBLAS_PC_DIR := $(patsubst %/,%,$(shell pkg-config --variable=libdir openblas 2>/dev/null))
ifneq ($(OPENBLAS_PC_DIR),)
OPENBLAS_DIR ?= $(firstword $(wildcard $(dir $(OPENBLAS_PC_DIR))openblas-openmp) $(OPENBLAS_PC_DIR))
endif
ifneq ($(OPENBLAS_DIR),)
BLAS_LIBS := -L$(OPENBLAS_DIR) -Wl,-rpath,$(OPENBLAS_DIR) -llapacke -lopenblas
else
BLAS_LIBS := -llapacke -lopenblas
endif

OPT      ?= -O2
# zstd's warning set, as far as it suits this C99 code. Left out:
# -Wc++-compat (C99 converts void * implicitly), -Wfloat-equal (the numerics
# test exact zeros on purpose), -Wswitch-enum (a default: is meant to cover
# the rest), -Wstrict-aliasing=1 (its guesses flag the tests' deliberate
# struct-size probes; -Wall's level 3 stays). Errors only in development and
# CI builds (DEV=1, CI=true), so that a newer compiler's new warning does not
# break a user's `make`.
WARN     := -Wall -Wextra -pedantic -Wshadow -Wmissing-prototypes -Wstrict-prototypes -Wvla \
            -Wcast-qual -Wcast-align -Wundef -Wpointer-arith -Wformat=2 \
            -Wdeclaration-after-statement -Winit-self -Wwrite-strings -Wredundant-decls
ifneq ($(filter 1,$(DEV))$(filter true,$(CI)),)
WARN     += -Werror
endif
# The library implements the experimental tier too (LL_EXPERIMENTAL: the
# declarations that may change in a minor release).
CFLAGS_LIB := -std=c99 $(OPT) -g $(WARN) -fPIC -fvisibility=hidden \
              -D_POSIX_C_SOURCE=200809L -DLL_BUILDING_LIBRARY -DLL_EXPERIMENTAL -Iinclude -Isrc
ifeq ($(SANITIZE),1)
SAN      := -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined
BUILD    := build-san
endif
ifeq ($(TSAN),1)
SAN      := -fsanitize=thread -fno-omit-frame-pointer
BUILD    := build-tsan
endif
# Line coverage (make coverage): gcc's --coverage at the usual -O2 (the
# numerics stay fast; a line counts as run or not either way), with atomic
# counters, since OpenMP threads run the same lines at once.
ifeq ($(COVERAGE),1)
SAN      := --coverage -fprofile-update=atomic
BUILD    := build-cov
endif
CFLAGS_LIB += $(SAN)
LDLIBS_LIB := $(BLAS_LIBS) -fopenmp -lm -lpthread

LIB_SRC  := $(sort $(wildcard src/*/*.c))
LIB_OBJ  := $(LIB_SRC:src/%.c=$(BUILD)/obj/%.o)
SONAME   := liblayerlab.so.$(ABI_VERSION)
SHARED   := $(BUILD)/lib/liblayerlab.so.$(VERSION)
STATIC   := $(BUILD)/lib/liblayerlab.a

# The reader library: open, inspect, evaluate and sample .bsdf files, for
# renderers. Its files are support/ without the threads (OpenMP), the
# splines of numerics/, and reader/ (the writer is writer/): the folder says
# which library a file is in, so a new file in reader/ is a reader file
# whatever its name. They must not include layer/, words/, search/,
# grammar/, writer/, distribution/ or material/ (tests/layering.sh).
# The folders live in src/reader-sources.txt, which CMakeLists.txt reads
# too: one list for both builds. Reader objects are compiled without
# -fopenmp (they have no OpenMP) and shared with liblayerlab.
READER_PATTERNS := $(shell sed -n 's/^\([^\#!].*\)/\1/p' src/reader-sources.txt)
READER_EXCLUDED := $(shell sed -n 's/^!//p' src/reader-sources.txt)
READER_SRC := $(sort $(filter-out $(wildcard $(READER_EXCLUDED)),$(wildcard $(READER_PATTERNS))))
READER_OBJ := $(READER_SRC:src/%.c=$(BUILD)/obj/%.o)
READER_SONAME := liblayerlab_reader.so.$(ABI_VERSION)
READER_SHARED := $(BUILD)/lib/liblayerlab_reader.so.$(VERSION)
READER_STATIC := $(BUILD)/lib/liblayerlab_reader.a
READER_LIBS := -lm
# Everything else may use OpenMP.
$(filter-out $(READER_OBJ),$(LIB_OBJ)): CFLAGS_OMP := -fopenmp

# Tools: each directory tools/NAME/ holds the sources of one program NAME.
TOOL_NAMES := $(notdir $(patsubst %/,%,$(sort $(dir $(wildcard tools/*/*.c)))))
# llbuild-mpi (tools/llbuild-mpi, docs/mpi.md) needs MPI's compiler wrapper:
# built only where mpicc is found (make deps installs OpenMPI).
MPICC ?= $(shell command -v mpicc 2>/dev/null)
ifeq ($(MPICC),)
TOOL_NAMES := $(filter-out llbuild-mpi,$(TOOL_NAMES))
endif
TOOLS    := $(TOOL_NAMES:%=$(BUILD)/bin/%)
TOOL_CFLAGS = -std=c99 $(OPT) -g $(WARN) -D_POSIX_C_SOURCE=200809L -Iinclude $(SAN) \
               $(shell pkg-config --cflags cairo OpenEXR 2>/dev/null)
TOOL_LIBS = $(shell pkg-config --libs cairo OpenEXR 2>/dev/null) -lm

# Tests: each tests/test_*.c is one cmocka program, linked statically so it
# can reach internal functions too; each tests/*.sh is a shell check.
# Two tiers. A new test is in the fast one (`make test`) unless named here:
# the slow tier (`make check`) holds what takes minutes, needs MPI or
# Mitsuba, signals running processes, or installs the cross-checks' codes.
SLOW_TESTS   := test_convergence test_material_fuzz_replay test_ms_walk test_tables_tolerance \
                test_tables_transmit_tolerance test_microfacet_walk test_coat_ggx_monte_carlo
# Measurements that take longer than a CI run allows (`make figures`, not in
# either tier): they print the figures docs/formats.md quotes and hold what
# is met.
FIGURE_TESTS := test_tables_textured_seed
SLOW_SCRIPTS := tests/llbuild_signals.sh tests/llbuild_mpi.sh tests/reference.sh \
                tests/llbuild_time.sh \
                tests/pbrt_shim.sh
TEST_SRC := $(sort $(wildcard tests/test_*.c))
TESTS    := $(TEST_SRC:tests/%.c=$(BUILD)/tests/%)
# The tests reach into the library (its internal headers use the
# experimental tier) and test the experimental calls too.
FAST_TESTS := $(filter-out $(SLOW_TESTS:%=$(BUILD)/tests/%) $(FIGURE_TESTS:%=$(BUILD)/tests/%),\
                $(TESTS))
CHECK_TESTS := $(filter $(SLOW_TESTS:%=$(BUILD)/tests/%),$(TESTS))
FAST_SCRIPTS := $(filter-out $(SLOW_SCRIPTS),$(sort $(wildcard tests/*.sh)))
CHECK_SCRIPTS := $(filter $(SLOW_SCRIPTS),$(sort $(wildcard tests/*.sh)))
# The tests' Python (scripts/venv.sh): one environment per checkout, shared
# by every BUILD.
VENV ?= $(CURDIR)/build/venv
export VENV
TEST_CFLAGS := -std=c99 $(OPT) -g $(WARN) -Wno-unused-parameter -D_POSIX_C_SOURCE=200809L \
               -DLL_EXPERIMENTAL -Iinclude -Isrc -Itests -fopenmp $(SAN) \
               -DLL_SOURCE_DIR='"$(CURDIR)"' -DLL_BUILD_DIR='"$(CURDIR)/$(BUILD)"'
TEST_LIBS := $(STATIC) -lcmocka $(LDLIBS_LIB)

.PHONY: all deps deps-lib deps-tools deps-test deps-fuzz deps-ci lib tools test check \
        test-c test-python check-c check-python test-tsan coverage clang cmake-check \
        bench bench-full figures install uninstall clean fuzz demo abi-baseline api-doc print-reader-src print-blas-libs tests \
        need-lib need-tools need-test need-check need-coverage need-cmake \
        venv-test venv-check
all: lib tools

# The Debian packages, by who needs them (scripts/deps.sh). Only these
# targets install anything; put `deps` before the others on a fresh machine
# (`make deps test`: make runs the goals in order).
deps:
	@sh scripts/deps.sh lib tools test fuzz ci
deps-lib:
	@sh scripts/deps.sh lib
deps-tools:
	@sh scripts/deps.sh tools
deps-test:
	@sh scripts/deps.sh test
deps-fuzz:
	@sh scripts/deps.sh fuzz
deps-ci:
	@sh scripts/deps.sh ci

# What each step needs, checked (never installed) before it runs: a missing
# piece stops with its Debian package and `make deps` (scripts/need.sh).
need-lib:
	@CC='$(CC)' sh scripts/need.sh lib
need-tools:
	@CC='$(CC)' sh scripts/need.sh tools
need-test:
	@CC='$(CC)' sh scripts/need.sh test
need-check:
	@CC='$(CC)' CXX='$(CXX)' MPICC='$(or $(MPICC),mpicc)' sh scripts/need.sh check
need-coverage:
	@sh scripts/need.sh coverage
need-cmake:
	@sh scripts/need.sh cmake

# The tests' Python packages, into $(VENV) only (scripts/venv.sh).
venv-test: | need-test
	@sh scripts/venv.sh base
venv-check: | need-test
	@sh scripts/venv.sh base reference mitsuba

# Every test program of this BUILD, built (not run).
tests: $(TESTS)

# The reader's file list, for tests/layering.sh run by hand.
print-reader-src:
	@echo $(READER_SRC)

# The OpenBLAS and LAPACKE link flags the library uses, for scripts that
# link programs against the same OpenBLAS (bench/run.sh).
print-blas-libs:
	@echo $(BLAS_LIBS)

lib: $(SHARED) $(STATIC) $(BUILD)/lib/layerlab.pc \
     $(READER_SHARED) $(READER_STATIC) $(BUILD)/lib/layerlab-reader.pc

$(BUILD)/obj/%.o: src/%.c $(wildcard src/*/*.h) $(wildcard include/*.h include/layerlab/*.h) | need-lib
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS_LIB) $(CFLAGS_OMP) -c $< -o $@

# -z nodelete: the parallel loops' worker threads (src/support/threads.c)
# outlive a call, so the library must stay mapped if a host dlclose()s it.
$(SHARED): $(LIB_OBJ) src/liblayerlab.map
	@mkdir -p $(dir $@)
	$(CC) -shared -o $@ $(LIB_OBJ) -Wl,-soname,$(SONAME) \
	    -Wl,--version-script=src/liblayerlab.map -Wl,--no-undefined -Wl,-z,nodelete \
	    $(SAN) $(LDLIBS_LIB)
	ln -sf liblayerlab.so.$(VERSION) $(BUILD)/lib/$(SONAME)
	ln -sf $(SONAME) $(BUILD)/lib/liblayerlab.so

$(STATIC): $(LIB_OBJ)
	@mkdir -p $(dir $@)
	rm -f $@
	ar rcs $@ $(LIB_OBJ)

# --as-needed: the reader's NEEDED list is what its objects use (libm, libc),
# never OpenBLAS, LAPACKE or libgomp (tests/abi.sh checks).
$(READER_SHARED): $(READER_OBJ) src/liblayerlab_reader.map
	@mkdir -p $(dir $@)
	$(CC) -shared -o $@ $(READER_OBJ) -Wl,-soname,$(READER_SONAME) \
	    -Wl,--version-script=src/liblayerlab_reader.map -Wl,--no-undefined -Wl,--as-needed \
	    $(SAN) $(READER_LIBS)
	ln -sf liblayerlab_reader.so.$(VERSION) $(BUILD)/lib/$(READER_SONAME)
	ln -sf $(READER_SONAME) $(BUILD)/lib/liblayerlab_reader.so

$(READER_STATIC): $(READER_OBJ)
	@mkdir -p $(dir $@)
	rm -f $@
	ar rcs $@ $(READER_OBJ)

# layerlab-reader.pc, written as layerlab.pc is (below): for the PREFIX in
# effect, at build time and again by `make install`.
write_reader_pc = printf '%s\n' 'prefix=$(PREFIX)' 'libdir=$(LIBDIR)' 'includedir=$(INCDIR)' '' \
	  'Name: layerlab-reader' 'Description: Reading, evaluating and sampling .bsdf files (layerlab without the layer builder)' \
	  'Version: $(VERSION)' 'Cflags: -I$${includedir}' 'Libs: -L$${libdir} -Wl,-rpath,$${libdir} -llayerlab_reader' \
	  'Libs.private: $(READER_LIBS)' > $(1)

$(BUILD)/lib/layerlab-reader.pc: Makefile
	@mkdir -p $(dir $@)
	@$(call write_reader_pc,$@)

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

# The build tree's copy of the spectra, beside $(BUILD)/lib as an installed
# copy is beside PREFIX/lib (recursive variables: SANITIZE changes BUILD).
IOR_BUILT = $(patsubst $(IOR_SRC)/%,$(BUILD)/share/layerlab/ior/%,$(wildcard $(IOR_SRC)/*.spd))
lib: $(IOR_BUILT)
$(TESTS): | $(IOR_BUILT)
$(BUILD)/share/layerlab/ior/%.spd: $(IOR_SRC)/%.spd
	@mkdir -p $(dir $@)
	cp $< $@

tools: $(TOOLS)

.SECONDEXPANSION:
$(BUILD)/bin/%: $$(wildcard tools/%/*.c) $$(wildcard tools/%/*.h) $(SHARED) | need-tools
	@mkdir -p $(dir $@)
	$(CC) $(TOOL_CFLAGS) -o $@ $(filter %.c,$^) -L$(BUILD)/lib -Wl,-rpath,'$$ORIGIN/../lib' \
	    -llayerlab $(TOOL_LIBS)

# llbuild-mpi: its own sources, llbuild's (which it includes) and llbuild's
# progress display, through mpicc with this build's compiler.
LLBUILD_MPI_SRC := $(wildcard tools/llbuild-mpi/*.c)
$(BUILD)/bin/llbuild-mpi: $(LLBUILD_MPI_SRC) $(wildcard tools/llbuild-mpi/*.h tools/llbuild/*.c \
                          tools/llbuild/*.h) $(SHARED) | need-tools
	@mkdir -p $(dir $@)
	OMPI_CC=$(CC) $(MPICC) $(TOOL_CFLAGS) -o $@ $(LLBUILD_MPI_SRC) tools/llbuild/progress.c tools/llbuild/time_model.c \
	    tools/llbuild/energy.c \
	    -L$(BUILD)/lib -Wl,-rpath,'$$ORIGIN/../lib' -llayerlab -lm

$(BUILD)/tests/%: tests/%.c $(wildcard tests/*.h) $(STATIC) | need-test
	@mkdir -p $(dir $@)
	$(CC) $(TEST_CFLAGS) -o $@ $< $(TEST_LIBS)

# The concurrent reader tests, linked against the reader library (no OpenMP,
# so ThreadSanitizer sees every synchronisation): `make test TSAN=1`.
TSAN_TEST_SRC := tests/test_bsdf_threads.c
TSAN_TESTS := $(TSAN_TEST_SRC:tests/%.c=$(BUILD)/tests/reader/%)
$(BUILD)/tests/reader/%: tests/%.c $(wildcard tests/*.h) $(READER_SHARED) | need-test
	@mkdir -p $(dir $@)
	$(CC) $(filter-out -fopenmp,$(TEST_CFLAGS)) -o $@ $< -L$(BUILD)/lib \
	    -Wl,-rpath,'$$ORIGIN/../../lib' -llayerlab_reader -lcmocka -lm -lpthread

test-tsan: $(TSAN_TESTS)
	@set -e; failed=0; \
	for t in $(TSAN_TESTS); do \
	  echo "== $$t (ThreadSanitizer)"; \
	  if ! TSAN_OPTIONS="halt_on_error=1 $$TSAN_OPTIONS" $$t; then failed=$$((failed+1)); fi; \
	done; \
	if [ $$failed -ne 0 ]; then echo "$$failed test program(s) failed under TSan"; exit 1; fi

# Runs cmocka programs ($(1)), then shell checks ($(2)); each prints its own
# summary lines, and the run fails when one of them does.
run_tests = set -e; failed=0; \
	for t in $(1); do \
	  echo "== $$t"; \
	  if ! $$t; then failed=$$((failed+1)); fi; \
	done; \
	for s in $(2); do \
	  echo "== $$s"; \
	  if ! BUILD=$(BUILD) CC=$(CC) CXX=$(CXX) READER_SRC='$(READER_SRC)' sh $$s; then \
	    failed=$$((failed+1)); fi; \
	done; \
	if [ $$failed -ne 0 ]; then echo "$$failed test program(s) failed"; exit 1; fi

# The fast C tier: the cmocka programs and shell checks (ABI, headers,
# tools) not named in SLOW_TESTS / SLOW_SCRIPTS.
test-c: all $(FAST_TESTS)
	@$(call run_tests,$(FAST_TESTS),$(FAST_SCRIPTS))

# The slow C tier (make check).
check-c: all $(CHECK_TESTS) | need-check venv-check
	@$(call run_tests,$(CHECK_TESTS),$(CHECK_SCRIPTS))

# The long measurements (FIGURE_TESTS).
figures: all $(FIGURE_TESTS:%=$(BUILD)/tests/%)
	@$(call run_tests,$(FIGURE_TESTS:%=$(BUILD)/tests/%),)

# The Python package against this build's library; the Mitsuba renders
# only in `make check`.
test-python: all | venv-test
	@BUILD=$(BUILD) sh python/tests/run.sh
check-python: all | venv-check
	@BUILD=$(BUILD) sh python/tests/run.sh --mitsuba

ifeq ($(TSAN),1)
test: test-tsan
check: test-tsan
else ifneq ($(SANITIZE)$(COVERAGE),)
test: test-c
check: test-c check-c
else
test: test-c test-python
check: test-c test-python check-c check-python
endif

# Line coverage of src/ by the fast C tier, in build-cov/; fails below
# COVERAGE_FLOOR percent of the lines: a few points under the measured
# 95.2 %, so that a change that leaves much code untested is noticed.
COVERAGE_FLOOR ?= 92
coverage: | need-coverage
	@find build-cov -name '*.gcda' -delete 2>/dev/null || true
	@$(MAKE) --no-print-directory test-c COVERAGE=1
	@gcovr --root . --filter 'src/' --object-directory build-cov/obj --print-summary \
	    --gcov-ignore-parse-errors --fail-under-line $(COVERAGE_FLOOR) \
	    -o build-cov/coverage.txt build-cov/obj
	@echo "coverage: per file in build-cov/coverage.txt (floor $(COVERAGE_FLOOR) %)"

# The libraries and every C test built by clang, warnings as errors, in a
# build folder of their own (run by CI beside the gcc build).
clang:
	@$(MAKE) --no-print-directory lib tests CC=clang BUILD=build-clang DEV=1

# The CMake build (CMakeLists.txt): configured, built and installed into
# build-cmake/prefix, then tests/cmake-consumer built against that install
# with find_package(layerlab) and run.
cmake-check: | need-cmake
	@sh tests/cmake-consumer/run.sh

# docs/api.md, the API reference, from the public headers' comments
# (scripts/api_doc.py, Python 3's standard library only); tests/api_doc.sh
# fails in `make test` when the page is not current.
api-doc:
	@python3 scripts/api_doc.py -o docs/api.md
	@echo "docs/api.md written from include/layerlab/*.h"

# The ABI baselines that tests/abidiff.sh compares the libraries with. Run
# after a deliberate, compatible change that abidiff reports (a field
# appended to a size-tagged struct), and at each release; never to silence
# a removal (see abi/README.md).
abi-baseline: lib
	@BUILD=$(BUILD) sh tests/abidiff.sh --write-baseline

# The headline figures (under 10 minutes on 2 cores) and everything
# (hours: the full-size dust on gold, the tolerance's cost, MPI scaling, the
# convergence grid), on the library and tools built with -O3 in build-bench/;
# results in build-bench/bench/results.json.
BENCH_BUILD = $(MAKE) --no-print-directory all BUILD=build-bench OPT='-O3 -march=x86-64-v2'
bench:
	@$(BENCH_BUILD)
	@BUILD=build-bench sh bench/run.sh
bench-full:
	@$(BENCH_BUILD)
	@BUILD=build-bench sh bench/run.sh --full

fuzz: | need-lib
	@if [ -f tests/fuzz/run.sh ]; then BUILD=$(BUILD) sh tests/fuzz/run.sh "$(FUZZ_SECONDS)" $(FUZZ_TARGET); fi

demo: all
	@sh scripts/demo.sh

# Two pbrt-v3 programs the user already has, one built with the shim
# (PBRT) and one without (PBRT_STOCK), rendered on intact and damaged
# files (shims/pbrt-v3/check/check.sh; not part of the tests). It builds
# no renderer: shims/pbrt-v3/README.md says what the shim replaces.
PBRT_WORK   ?= $(BUILD)/pbrt-check
PBRT_GOLDEN ?= tests/data/roughgold_alpha_0.2.bsdf
.PHONY: pbrt-check
pbrt-check: all
	@test -n "$(PBRT)" && test -n "$(PBRT_STOCK)" || { echo "make pbrt-check needs" \
	    "PBRT=/path/to/pbrt (pbrt-v3 built with the shim) and PBRT_STOCK=/path/to/pbrt (unmodified)"; \
	    exit 1; }
	@$(MAKE) --no-print-directory install PREFIX=$(abspath $(PBRT_WORK))/layerlab > /dev/null
	@sh shims/pbrt-v3/check/check.sh "$(PBRT)" "$(PBRT_STOCK)" "$(PBRT_WORK)" "$(PBRT_GOLDEN)" \
	    "$(abspath $(PBRT_WORK))/layerlab"

# A pbrt-v4 binary the user already has (PBRT4): our spectral table files in
# its `measured` material, checked by a furnace and against pbrt-v4's own
# layered materials (shims/pbrt-v4/check/check.py; not part of the tests;
# PBRT4_ARGS passes options, e.g. --pictures DIR). It builds no renderer.
PBRT4_WORK ?= $(BUILD)/pbrt4-check
.PHONY: pbrt4-check
pbrt4-check: all venv-test
	@test -n "$(PBRT4)" || { echo "make pbrt4-check needs PBRT4=/path/to/pbrt (a pbrt-v4 binary)"; \
	    exit 1; }
	@"$(VENV)/bin/python" shims/pbrt-v4/check/check.py --pbrt "$(PBRT4)" --build "$(BUILD)" \
	    --work "$(PBRT4_WORK)" $(PBRT4_ARGS)

install: all
	install -d $(DESTDIR)$(LIBDIR) $(DESTDIR)$(INCDIR)/layerlab $(DESTDIR)$(BINDIR) $(DESTDIR)$(PKGDIR)
	install -m 644 include/layerlab.h $(DESTDIR)$(INCDIR)/
	install -m 644 include/layerlab/*.h $(DESTDIR)$(INCDIR)/layerlab/
	install -m 755 $(SHARED) $(DESTDIR)$(LIBDIR)/
	ln -sf liblayerlab.so.$(VERSION) $(DESTDIR)$(LIBDIR)/$(SONAME)
	ln -sf $(SONAME) $(DESTDIR)$(LIBDIR)/liblayerlab.so
	install -m 644 $(STATIC) $(DESTDIR)$(LIBDIR)/
	$(call write_pc,$(DESTDIR)$(PKGDIR)/layerlab.pc)
	install -m 755 $(READER_SHARED) $(DESTDIR)$(LIBDIR)/
	ln -sf liblayerlab_reader.so.$(VERSION) $(DESTDIR)$(LIBDIR)/$(READER_SONAME)
	ln -sf $(READER_SONAME) $(DESTDIR)$(LIBDIR)/liblayerlab_reader.so
	install -m 644 $(READER_STATIC) $(DESTDIR)$(LIBDIR)/
	$(call write_reader_pc,$(DESTDIR)$(PKGDIR)/layerlab-reader.pc)
	@# the tools find the library through their RUNPATH $$ORIGIN/../lib
	install -d $(DESTDIR)$(DATADIR)/ior
	install -m 644 $(IOR_SRC)/*.spd $(IOR_SRC)/README.md $(DESTDIR)$(DATADIR)/ior/
	for t in $(TOOLS); do install -m 755 $$t $(DESTDIR)$(BINDIR)/; done

uninstall:
	rm -f $(DESTDIR)$(LIBDIR)/liblayerlab.* $(DESTDIR)$(PKGDIR)/layerlab.pc $(DESTDIR)$(INCDIR)/layerlab.h
	rm -f $(DESTDIR)$(LIBDIR)/liblayerlab_reader.* $(DESTDIR)$(PKGDIR)/layerlab-reader.pc
	rm -rf $(DESTDIR)$(INCDIR)/layerlab $(DESTDIR)$(DATADIR)
	for t in $(TOOL_NAMES); do rm -f $(DESTDIR)$(BINDIR)/$$t; done

clean:
	rm -rf build build-san build-tsan build-bench build-cov build-clang build-cmake
