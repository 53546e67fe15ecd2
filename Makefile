# sidx — build, test, demo, bench.
#
#   make            build the library (build/lib), programs (build/bin), lessons
#                   (build/lessons) and tests; installs nothing
#   make deps       install the missing Debian packages (as root; else prints the command)
#   make demo       deps, build, run the guided tour
#   make test       deps, build, run every cmocka suite and the lessons' checks
#   make test SAN=1 the same under AddressSanitizer + UndefinedBehaviorSanitizer (build/san, -O1),
#                   the suites at their small sizes (SIDX_FAST_TESTS=1; FAST_TESTS=0 for full,
#                   FAST_TESTS=2 for the smallest)
#   make test-tsan  the threaded suites under ThreadSanitizer (build/tsan, -O1)
#   make valgrind   the suites under valgrind memcheck (smallest sizes; VALGRIND_SKIP)
#   TEST_JOBS=N     how many suites run at once (default: the number of cores)
#   make cppcheck   static analysis of every C file (cppcheck, warning + portability)
#   make bench      the benchmark table (build/bench/); refreshes the figures in
#                   docs/benchmark.md and README.md (docs/bench_refresh.sh)
#   make apidocs    the API reference from the headers (Doxygen, build/apidocs/html)
#   make install PREFIX=/usr/local
#
# Everything is found by wildcard: a new lib/*.c joins the library, a new
# tests/test_*.c becomes a suite, a new lessons/*.c a lesson, a new
# viz/sidx_*.c a program.
#
# What the build needs: the library, the lessons and the core tests need a
# C11 compiler and cmocka, nothing else.  The optional parts are found with
# pkg-config (Embree, which ships no .pc file on Debian, by its header) and
# skipped, with one line saying so, when missing:
#   Graphviz (libgraphviz-dev)          sidx-dot and the tree drawings
#   SDL2 + SDL2_image (libsdl2-dev ...) sidx-view and its screenshot tests
#   Embree 3 (libembree-dev)            sidx-bench, the peer of the benchmark
#   tmux                                the test of sidx-step's stepper in a terminal
#                                       (tests/run_step_tmux.sh; skipped without)
#   chromium                            the headless-browser test of those pages (tests/test_html.c;
#                                       skipped without)
#   chromium + nodejs                   the web pages driven through the DevTools protocol
#                                       (tests/run_web_page.sh; skipped without)
#   emscripten                          make web: the lab page with the library in WebAssembly
#                                       (tests/run_web_module.sh; skipped without)
# HAVE_GRAPHVIZ=0, HAVE_SDL=0, HAVE_EMBREE=0 (or MINIMAL=1 for all three)
# build without one even where it is installed.

DEBS := pkg-config libcmocka-dev libgraphviz-dev libsdl2-dev libsdl2-image-dev libembree-dev gnuplot-nox valgrind tmux chromium nodejs emscripten
# More packages for one call, e.g. `make deps EXTRA_DEBS="clang cppcheck"` (.ci/run).
EXTRA_DEBS ?=

PREFIX ?= /usr/local
OPT ?= -O2
# Debug information: full (-g) unless given.  The sanitizer builds take
# -g1 unless DEBUG is given: line tables and function names, all that a
# sanitizer's report prints of a frame; gcc's variable tracking through the
# inlined walk templates is half of their compile time (lib/bvh_wide.c
# under ASan: 46 s with -g, 25 s with -g1).  The level of debug information
# changes no generated code.
DEBUG ?= -g
SAN ?= 0
TSAN ?= 0

# BUILDDIR=build/NAME gives a separate tree (parallel work in one checkout).
BUILDDIR ?= build
ifeq ($(SAN),1)
BUILD := $(BUILDDIR)/san
SANFLAGS := -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer
else ifeq ($(TSAN),1)
BUILD := $(BUILDDIR)/tsan
SANFLAGS := -fsanitize=thread -fno-omit-frame-pointer
else
BUILD := $(BUILDDIR)
SANFLAGS :=
endif
# Both sanitizer builds: -O1 unless OPT is given (gcc compiles the
# instrumented code in about half the CPU time of -O2 under ASan, a third
# less under TSan, lib/bvh_wide.c 19 s -> 12 s; the suites run under 10 %
# slower), and -g1 unless DEBUG is given (above).
ifneq ($(SANFLAGS),)
ifeq ($(origin OPT),file)
OPT := -O1
endif
ifeq ($(origin DEBUG),file)
DEBUG := -g1
endif
endif

# ---- optional parts ---------------------------------------------------------
ifeq ($(MINIMAL),1)
HAVE_GRAPHVIZ ?= 0
HAVE_SDL ?= 0
HAVE_EMBREE ?= 0
endif
pc_exists = $(if $(shell pkg-config --exists $(1) 2>/dev/null && echo y),1,0)
ifndef HAVE_GRAPHVIZ
HAVE_GRAPHVIZ := $(call pc_exists,libcgraph libgvc)
endif
ifndef HAVE_SDL
HAVE_SDL := $(call pc_exists,sdl2 SDL2_image)
endif
ifndef HAVE_EMBREE
HAVE_EMBREE := $(if $(shell printf '\043include <embree3/rtcore.h>\n' | $(CC) -E -x c - >/dev/null 2>&1 && echo y),1,0)
endif
HAVE_CMOCKA := $(call pc_exists,cmocka)

PKGS := $(if $(filter 1,$(HAVE_GRAPHVIZ)),libcgraph libgvc) $(if $(filter 1,$(HAVE_SDL)),sdl2 SDL2_image)
PKG_CFLAGS := $(if $(strip $(PKGS)),$(shell pkg-config --cflags $(PKGS) 2>/dev/null))
PKG_LIBS := $(if $(strip $(PKGS)),$(shell pkg-config --libs $(PKGS) 2>/dev/null))
CMOCKA_CFLAGS := $(if $(filter 1,$(HAVE_CMOCKA)),$(shell pkg-config --cflags cmocka 2>/dev/null))
CMOCKA_LIBS := $(if $(filter 1,$(HAVE_CMOCKA)),$(shell pkg-config --libs cmocka 2>/dev/null),-lcmocka)
# The programs and tests that use an optional part ask these (#if SIDX_HAVE_SDL).
FEATURES := -DSIDX_HAVE_GRAPHVIZ=$(HAVE_GRAPHVIZ) -DSIDX_HAVE_SDL=$(HAVE_SDL) -DSIDX_HAVE_EMBREE=$(HAVE_EMBREE)

WARN := -Wall -Wextra -Wpedantic -Werror
# -ffp-contract=off: the watertight test is watertight because neighbouring
# triangles compute the same edge function bit for bit; a compiler fusing
# a*b - c*d into an FMA in one code path (clang does in the AVX2 kernels)
# breaks that.  gcc's ISO mode already defaults to off; clang's does not.
FPFLAGS := -ffp-contract=off
CFLAGS := -std=c11 $(OPT) $(DEBUG) $(WARN) $(FPFLAGS) -fPIC -D_DEFAULT_SOURCE -Ilib/include -Ilib $(FEATURES) $(SANFLAGS) $(EXTRA_CFLAGS)
LDFLAGS := $(SANFLAGS) -pthread
LDLIBS := -lm

LIB_SRC := $(wildcard lib/*.c)
LIB_OBJ := $(LIB_SRC:%.c=$(BUILD)/obj/%.o)
# The viewer's pieces need SDL2; sidx-dot needs Graphviz (viz/dot.c itself
# builds either way: without Graphviz sidx_dot_write answers
# SIDX_ERR_UNSUPPORTED); sidx-bench needs Embree; the suites need cmocka.
VIZ_SDL_SRC := viz/font.c viz/html.c viz/sidx_view.c $(wildcard viz/view_*.c)
VIZ_PROG_SRC := $(filter-out $(if $(filter 1,$(HAVE_SDL)),,viz/sidx_view.c) \
                  $(if $(filter 1,$(HAVE_GRAPHVIZ)),,viz/sidx_dot.c),$(wildcard viz/sidx_*.c))
VIZ_LIB_SRC := $(filter-out $(wildcard viz/sidx_*.c) $(if $(filter 1,$(HAVE_SDL)),,$(VIZ_SDL_SRC)),$(wildcard viz/*.c))
# sidx-view --html's page template, viz/page.html, becomes a C array
# (sidx_page_html) so the installed program needs no file beside it; od
# and sed (coreutils) write the bytes.  The script both web pages share,
# viz/page_common.js, takes the place of each page's line
# /*@SIDX_PAGE_COMMON@*/ (PAGE_COMMON_SPLICE; PAGE_COMMON_CHECK wants one
# such line and no '</script' in the shared text).
PAGE_OBJ := $(if $(filter 1,$(HAVE_SDL)),$(BUILD)/obj/gen/page_html.o)
PAGE_COMMON_SPLICE = awk -v js=viz/page_common.js '$$0 == "/*@SIDX_PAGE_COMMON@*/" { \
  while ((getline l < js) > 0) print l; close(js); next } { print }'
PAGE_COMMON_CHECK = if [ "$$(grep -c '^/\*@SIDX_PAGE_COMMON@\*/$$' $(1))" != 1 ]; then \
  echo "$(1) wants exactly one line /*@SIDX_PAGE_COMMON@*/"; exit 1; fi; \
  if grep -qi '</script' viz/page_common.js; then echo "viz/page_common.js holds '</script': it cannot be inlined"; exit 1; fi
VIZ_OBJ := $(VIZ_LIB_SRC:%.c=$(BUILD)/obj/%.o) $(PAGE_OBJ)
TEST_SRC := $(if $(filter 1,$(HAVE_CMOCKA)),$(wildcard tests/test_*.c))
TEST_COMMON_SRC := $(wildcard tests/common/*.c)
TEST_COMMON_OBJ := $(TEST_COMMON_SRC:%.c=$(BUILD)/obj/%.o)
TESTS := $(TEST_SRC:tests/%.c=$(BUILD)/tests/%)
LESSON_SRC := $(filter-out lessons/tour.c,$(wildcard lessons/*.c))
LESSONS := $(LESSON_SRC:lessons/%.c=$(BUILD)/lessons/%)
BENCH_SRC := $(if $(filter 1,$(HAVE_EMBREE)),$(wildcard tests/bench/*.c))
BENCH_OBJ := $(BENCH_SRC:%.c=$(BUILD)/obj/%.o)
VIZ_PROGS := $(VIZ_PROG_SRC:viz/sidx_%.c=$(BUILD)/bin/sidx-%)

LIBA := $(BUILD)/lib/libsidx.a
LIBSO := $(BUILD)/lib/libsidx.so
VIZA := $(BUILD)/lib/libsidxviz.a
# The library again with every hook compiled out (-DSIDX_NO_HOOKS), linked
# into sidx-bench-nohooks: `sidx-bench run` compares it with sidx-bench.
# NOHOOKS=0 leaves that second library out of the build (a second tree
# for another compiler: the gcc build of make test compiles it, and
# nothing but make bench runs it).
NOHOOKS ?= 1
PROGS := $(VIZ_PROGS) $(BUILD)/bin/sidx-check $(if $(wildcard lessons/tour.c),$(BUILD)/bin/sidx-tour) \
         $(if $(BENCH_SRC),$(BUILD)/bin/sidx-bench $(if $(filter 1,$(NOHOOKS)),$(BUILD)/bin/sidx-bench-nohooks))
NOHOOKS_OBJ := $(LIB_SRC:%.c=$(BUILD)/nohooks/obj/%.o)
ALL_LIBS = $(VIZA) $(LIBA) $(PKG_LIBS) $(LDLIBS)

.PHONY: web web-if-emcc all deps build optional-parts demo test test-run test-tsan valgrind bench install clean docs apidocs fuzz cppcheck

# No object is intermediate: the programs', lessons' and suites' objects are
# reached only through pattern rules, and make would delete them after the
# first build, then compile them again once their .d files name them.
.SECONDARY:

all: build

build: optional-parts $(LIBA) $(LIBSO) $(VIZA) $(PROGS) $(LESSONS) $(TESTS)

# One line per optional part that is missing, before anything is compiled.
optional-parts:
	@$(if $(filter 1,$(HAVE_GRAPHVIZ)),,echo "build: without Graphviz (libgraphviz-dev): no sidx-dot, no tree drawings";) \
	 $(if $(filter 1,$(HAVE_SDL)),,echo "build: without SDL2 (libsdl2-dev libsdl2-image-dev): no sidx-view, viewer tests skipped";) \
	 $(if $(filter 1,$(HAVE_EMBREE)),,echo "build: without Embree (libembree-dev): no sidx-bench";) \
	 $(if $(filter 1,$(HAVE_CMOCKA)),,echo "build: without cmocka (libcmocka-dev): the test suites are not built";) true

# Installs what is missing (as root), else prints the exact command and stops.
deps:
	@missing=""; for p in $(DEBS) $(EXTRA_DEBS); do dpkg -s $$p >/dev/null 2>&1 || missing="$$missing $$p"; done; \
	if [ -n "$$missing" ]; then \
	  if [ "$$(id -u)" = 0 ]; then \
	    echo "deps: installing$$missing"; \
	    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq$$missing >/dev/null || exit 1; \
	  else \
	    echo "deps: missing Debian packages:$$missing"; \
	    echo "deps: run: sudo apt-get install -y$$missing"; exit 1; \
	  fi; \
	fi

$(BUILD)/obj/%.o: %.c
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) $(PKG_CFLAGS) $(CMOCKA_CFLAGS) -MMD -MP -c $< -o $@

$(BUILD)/gen/page_html.c: viz/page.html viz/page_common.js
	@mkdir -p $(dir $@)
	@$(call PAGE_COMMON_CHECK,$<)
	{ echo '/* generated from viz/page.html and viz/page_common.js by the Makefile: do not edit */'; echo '#include <stddef.h>'; \
	  echo 'const unsigned char sidx_page_html[] = {'; \
	  $(PAGE_COMMON_SPLICE) $< | od -An -v -tx1 | sed -e 's/\([0-9a-f][0-9a-f]\)/0x\1,/g'; echo '0x00};'; \
	  echo 'const size_t sidx_page_html_len = sizeof sidx_page_html - 1;'; } > $@.tmp && mv $@.tmp $@

$(BUILD)/obj/gen/page_html.o: $(BUILD)/gen/page_html.c
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) -c $< -o $@

$(LIBA): $(LIB_OBJ)
	@mkdir -p $(dir $@)
	rm -f $@ && ar rcs $@ $^

$(LIBSO): $(LIB_OBJ)
	@mkdir -p $(dir $@)
	$(CC) -shared $(LDFLAGS) -o $@ $^ $(LDLIBS)

$(VIZA): $(VIZ_OBJ)
	@mkdir -p $(dir $@)
	rm -f $@ && ar rcs $@ $^

$(BUILD)/bin/sidx-%: $(BUILD)/obj/viz/sidx_%.o $(VIZA) $(LIBA)
	@mkdir -p $(dir $@)
	$(CC) $(LDFLAGS) -o $@ $< $(ALL_LIBS)

$(BUILD)/bin/sidx-tour: $(BUILD)/obj/lessons/tour.o $(VIZA) $(LIBA)
	@mkdir -p $(dir $@)
	$(CC) $(LDFLAGS) -o $@ $< $(ALL_LIBS)

$(BUILD)/bin/sidx-bench: $(BENCH_OBJ) $(VIZA) $(LIBA)
	@mkdir -p $(dir $@)
	$(CC) $(LDFLAGS) -o $@ $(BENCH_OBJ) $(ALL_LIBS) -lembree3

# Line tables only (-g1): what perf shows of a profile; a third less
# compile time than -g for the walk templates, and the same code.
$(BUILD)/nohooks/obj/%.o: %.c
	@mkdir -p $(dir $@)
	$(CC) $(filter-out $(DEBUG),$(CFLAGS)) -g1 -DSIDX_NO_HOOKS -MMD -MP -c $< -o $@

$(BUILD)/bin/sidx-bench-nohooks: $(BENCH_OBJ) $(NOHOOKS_OBJ)
	@mkdir -p $(dir $@)
	$(CC) $(LDFLAGS) -o $@ $(BENCH_OBJ) $(NOHOOKS_OBJ) $(LDLIBS) -lembree3

$(BUILD)/lessons/%: $(BUILD)/obj/lessons/%.o $(VIZA) $(LIBA)
	@mkdir -p $(dir $@)
	$(CC) $(LDFLAGS) -o $@ $< $(ALL_LIBS)

$(BUILD)/tests/%: $(BUILD)/obj/tests/%.o $(TEST_COMMON_OBJ) $(VIZA) $(LIBA)
	@mkdir -p $(dir $@)
	$(CC) $(LDFLAGS) -o $@ $< $(TEST_COMMON_OBJ) $(ALL_LIBS) $(CMOCKA_LIBS)

# The build inside demo, test, valgrind, bench and docs uses every core,
# unless make was given its own -j (MAKEFLAGS holds it in a recipe only).
NPROC := $(shell nproc 2>/dev/null || echo 2)
BUILD_JOBS = $(if $(filter -j%,$(MAKEFLAGS)),,-j$(NPROC))

demo: deps
	@$(MAKE) --no-print-directory $(BUILD_JOBS) build
	$(BUILD)/bin/sidx-tour

# build and test-run as two commands: in one -j call make would start the
# suites before the build is done.
test: deps
	@$(MAKE) --no-print-directory $(BUILD_JOBS) build
	@$(MAKE) --no-print-directory $(BUILD_JOBS) web-if-emcc
	@$(MAKE) --no-print-directory test-run

# Every suite and every shell check (tests/run_*.sh, given BUILD), from the
# repository root, TEST_JOBS at a time; all run even if one fails.
# tests/runner.sh prints each one's output whole, in this order (the shell
# checks first: the lessons take longest), and ends on "test-run: N passed,
# N failed".  Under the sanitizers the suites run at their small sizes
# (SIDX_FAST_TESTS=1, as under valgrind): they look for memory errors and
# undefined behaviour on every path, which more rays do not add to.
# TEST_SKIP="tests/run_x.sh test_y ..." leaves those shell checks and
# suites out (.ci/run runs the checks that read only the sources and docs,
# and the browser's, in one build).
TEST_JOBS ?= $(NPROC)
TEST_SKIP ?=
TEST_SCRIPTS := $(filter-out $(TEST_SKIP),$(wildcard tests/run_*.sh))
TEST_SUITES = $(filter-out $(TEST_SKIP:%=$(BUILD)/tests/%),$(TESTS))
FAST_TESTS ?= $(if $(SANFLAGS),1,0)
FAST_ENV := $(if $(filter 1 2,$(FAST_TESTS)),SIDX_FAST_TESTS=$(FAST_TESTS))
# Under ASan, LeakSanitizer ignores the system libraries' own leaks
# (tests/lsan.supp: fontconfig's, reached through Graphviz).
SAN_ENV := $(if $(filter 1,$(SAN)),LSAN_OPTIONS=suppressions=$(CURDIR)/tests/lsan.supp:print_suppressions=0)
test-run:
	@$(FAST_ENV) $(SAN_ENV) JOBS=$(TEST_JOBS) BUILD=$(BUILD) LABEL=test-run sh tests/runner.sh $(TEST_SCRIPTS) $(TEST_SUITES)

# ThreadSanitizer over the suites that run threads: the parallel build, the
# parallel trace and the worker pool (test_parallel), concurrent queries on
# every structure (test_threads), threads racing into unbuilt nodes of
# lazy trees (test_lazy), threads racing into an unbuilt lazy instance
# (test_lazy_instance), threads streaming buffers through one structure
# (test_stream).  Only these are built, in build/tsan (TSAN=1),
# and run at their smallest sizes, SIDX_FAST_TESTS=2: what ThreadSanitizer
# checks is how the threads meet, which more rays do not add to
# (FAST_TESTS=0: the full sizes).
# die_after_fork=0: test_pool_after_fork forks while the pool's threads
# run, on purpose (the child must not inherit them); its child only
# queries serially.  Any report fails the run (exitcode).
TSAN_TESTS := test_parallel test_threads test_lazy test_lazy_instance test_stream
TSAN_FAST := $(if $(filter command line environment,$(origin FAST_TESTS)),$(FAST_TESTS),1)
test-tsan:
	@$(MAKE) --no-print-directory $(BUILD_JOBS) TSAN=1 $(TSAN_TESTS:%=$(BUILDDIR)/tsan/tests/%)
	@TSAN_OPTIONS="halt_on_error=1 exitcode=66 die_after_fork=0 second_deadlock_stack=1" \
	  $(if $(filter 0,$(TSAN_FAST)),,SIDX_FAST_TESTS=2) JOBS=$(TEST_JOBS) LABEL=test-tsan \
	  sh tests/runner.sh $(TSAN_TESTS:%=$(BUILDDIR)/tsan/tests/%) \
	  && echo "test-tsan: the threaded suites ran with no ThreadSanitizer report"

# Each suite at its smallest size (SIDX_FAST_TESTS=2: a sixteenth of the
# full ray counts, the largest builds left to the sanitizer run) under
# memcheck; a suite's output is printed only when it fails (errors, leaks:
# exit 99).  What memcheck finds that
# ASan + UBSan (make test SAN=1, the same suites) do not is a read of
# uninitialised memory, in the optimised build itself; VALGRIND_SKIP are
# the suites whose work happens where memcheck does not look: in other
# programs (sidx-view in Chromium, sidx-check and the compiler), or in
# threads, which ThreadSanitizer checks (make test-tsan) and memcheck
# serialises.
VALGRIND_SKIP ?= test_html test_view_display test_exercises test_parallel test_threads
VALGRIND_TESTS = $(filter-out $(VALGRIND_SKIP:%=$(BUILD)/tests/%),$(TESTS))
VALGRIND := valgrind -q --error-exitcode=99 --suppressions=tests/valgrind.supp --leak-check=full \
            --show-leak-kinds=definite,indirect,possible --errors-for-leak-kinds=definite,indirect,possible
valgrind: deps
	@$(MAKE) --no-print-directory $(BUILD_JOBS) build
	@SIDX_FAST_TESTS=2 PREFIX="$(VALGRIND)" QUIET=1 JOBS=$(TEST_JOBS) BUILD=$(BUILD) LABEL=valgrind \
	  sh tests/runner.sh $(VALGRIND_TESTS) && echo "valgrind: every suite but $(VALGRIND_SKIP) ran with zero errors and zero leaks"

bench: deps
	@$(MAKE) --no-print-directory $(BUILD_JOBS) build
	@mkdir -p $(BUILD)/bench
	$(BUILD)/bin/sidx-bench run --csv $(BUILD)/bench/table.csv --plot $(BUILD)/bench/error_vs_speed.svg \
	  --markdown $(BUILD)/bench/table.md --md-command "make bench" --revision "$$(git describe --always --dirty 2>/dev/null)" \
	  $(if $(wildcard ../shared/scenes),--scenes ../shared/scenes) | tee $(BUILD)/bench/table.txt
	$(BUILD)/bin/sidx-bench extras $(if $(wildcard ../shared/scenes),--scenes ../shared/scenes) | tee $(BUILD)/bench/extras.txt
	@if [ -d ../shared/scenes ]; then sh docs/bench_refresh.sh $(BUILD)/bench/table.md docs/benchmark.md README.md; \
	else echo "bench: no ../shared/scenes (bunny, Sponza): docs/benchmark.md and README.md keep their figures"; fi

# Static analysis: every C file of the tree, in the configuration the build
# uses on Debian (all optional parts present).  Exit 1 on any finding.
CPPCHECK_FLAGS := --enable=warning,portability --std=c11 --error-exitcode=1 --inline-suppr --quiet \
                  -DSIDX_HAVE_GRAPHVIZ=1 -DSIDX_HAVE_SDL=1 -DSIDX_HAVE_EMBREE=1 -Ilib/include -Ilib -Itests
cppcheck:
	@command -v cppcheck >/dev/null 2>&1 || { echo "cppcheck: not installed (apt-get install cppcheck)"; exit 1; }
	cppcheck $(CPPCHECK_FLAGS) lib viz lessons tests
	@echo "cppcheck: no findings"

# Fuzzing with libFuzzer (clang): every tests/fuzz/fuzz_*.c target runs for
# FUZZ_SECONDS, starting from the checked-in seeds in tests/fuzz/corpus/<name>
# (copied, so the checked-in corpus stays small); crashes go to
# $(BUILDDIR)/fuzz/crashes/<name>/.  FUZZ_TARGETS=rays picks targets;
# FUZZ_ARGS passes more libFuzzer options.
FUZZ_SECONDS ?= 60
FUZZ_CC ?= clang
FUZZ_ARGS ?=
FUZZ_FLAGS := -std=c11 -O1 -g $(FPFLAGS) -D_DEFAULT_SOURCE -Ilib/include -Ilib -Itests -fsanitize=address,undefined -fno-sanitize-recover=all
FUZZ_SRC := $(wildcard tests/fuzz/fuzz_*.c)
FUZZ_TARGETS ?= $(FUZZ_SRC:tests/fuzz/fuzz_%.c=%)
FUZZ_DIR := $(BUILDDIR)/fuzz
FUZZ_BINS := $(FUZZ_TARGETS:%=$(FUZZ_DIR)/fuzz_%)

# The library and test kit are compiled once (instrumented) and shared by
# every target.
FUZZ_OBJ := $(LIB_SRC:%.c=$(FUZZ_DIR)/obj/%.o) $(TEST_COMMON_SRC:%.c=$(FUZZ_DIR)/obj/%.o)

$(FUZZ_DIR)/obj/%.o: %.c
	@mkdir -p $(dir $@)
	$(FUZZ_CC) $(FUZZ_FLAGS) -fsanitize=fuzzer-no-link -MMD -MP -c $< -o $@

$(FUZZ_DIR)/fuzz_%: $(FUZZ_DIR)/obj/tests/fuzz/fuzz_%.o $(FUZZ_OBJ)
	@mkdir -p $(dir $@)
	$(FUZZ_CC) $(FUZZ_FLAGS) -fsanitize=fuzzer -o $@ $^ -lm -pthread

fuzz: $(FUZZ_BINS)
	@for f in $(FUZZ_BINS); do \
	  name=$$(basename $$f | sed 's/^fuzz_//'); \
	  mkdir -p $(FUZZ_DIR)/corpus/$$name $(FUZZ_DIR)/crashes/$$name; \
	  cp -n tests/fuzz/corpus/$$name/* $(FUZZ_DIR)/corpus/$$name/ 2>/dev/null || true; \
	  echo "== fuzz $$name for $(FUZZ_SECONDS) s"; \
	  $$f -max_total_time=$(FUZZ_SECONDS) -print_final_stats=1 -artifact_prefix=$(FUZZ_DIR)/crashes/$$name/ $(FUZZ_ARGS) \
	    $(FUZZ_DIR)/corpus/$$name 2>&1 | grep -E "^(#[0-9]+.*DONE|stat::number_of_executed_units|stat::peak_rss|==[0-9]+==ERROR|SUMMARY)|cov:" | tail -4 \
	    || exit 1; \
	done

# Pictures for docs/: Graphviz trees and viewer screenshots (headless),
# the web pages of docs/web/ (sidx-view --html), then the API reference.
docs: deps
	@$(MAKE) --no-print-directory $(BUILD_JOBS) build
	sh viz/make_docs_pictures.sh $(BUILD) docs/img
	sh docs/make_tutorial.sh $(BUILD) docs/tutorial.md
	@$(MAKE) --no-print-directory apidocs

# API reference from lib/include/sidx/*.h and docs/*.md (Doxygen), into
# build/apidocs/html.  Installs doxygen the way deps does (not part of DEBS:
# make test does not need it).
apidocs:
	@if ! command -v doxygen >/dev/null 2>&1; then \
	  if [ "$$(id -u)" = 0 ]; then \
	    echo "apidocs: installing doxygen"; \
	    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq doxygen >/dev/null || exit 1; \
	  else \
	    echo "apidocs: missing Debian package: doxygen"; \
	    echo "apidocs: run: sudo apt-get install -y doxygen"; exit 1; \
	  fi; \
	fi
	doxygen docs/Doxyfile
	@echo "apidocs: build/apidocs/html/index.html"

install: build
	install -d $(DESTDIR)$(PREFIX)/include/sidx $(DESTDIR)$(PREFIX)/lib/pkgconfig $(DESTDIR)$(PREFIX)/bin
	install -m 644 lib/include/sidx/*.h $(DESTDIR)$(PREFIX)/include/sidx/
	install -m 644 $(LIBA) $(VIZA) $(DESTDIR)$(PREFIX)/lib/
	install -m 755 $(LIBSO) $(DESTDIR)$(PREFIX)/lib/
	install -m 755 $(PROGS) $(DESTDIR)$(PREFIX)/bin/
	sed -e 's|@PREFIX@|$(PREFIX)|g' sidx.pc.in > $(DESTDIR)$(PREFIX)/lib/pkgconfig/sidx.pc

clean:
	rm -rf $(BUILDDIR)

# ---- the web lab ---------------------------------------------------------------
# make web: $(BUILDDIR)/web/sidx-lab.html, one self-contained page (no
# network, works from file://) with the library's own sources and the lab's
# entry layer (viz/lab.c) compiled to WebAssembly by emscripten and inlined
# (-sSINGLE_FILE: the module as base64 in the JavaScript, the JavaScript
# in viz/lab_page.html at its @SIDX_LAB_MODULE@ line; viz/page_common.js at
# its @SIDX_PAGE_COMMON@ line).  WebAssembly SIMD:
# -msimd128 -msse4.1 maps the SSE kernels onto it (lib/simd_isa.h);
# WEB_SIMD=0 builds the scalar fallback in $(BUILDDIR)/web-scalar.
# Debian's emscripten runs node with acorn from node-acorn
# (/usr/share/nodejs), which a node not built by Debian does not search:
# NODE_PATH names it.  The page is refused above WEB_MAX_BYTES.
# $(WEB_DIR)/site/ is a folder ready to publish on a course page: the same
# page as index.html (it loads nothing else; its links keep the state in
# the address's hash, so they work wherever the folder is served).
EMCC ?= emcc
WEB_SIMD ?= 1
WEB_DIR := $(BUILDDIR)/web$(if $(filter 0,$(WEB_SIMD)),-scalar)
WEB_SRC := $(LIB_SRC) viz/lab.c viz/json_write.c viz/camera.c viz/knobs.c
WEB_OBJ := $(WEB_SRC:%.c=$(WEB_DIR)/obj/%.o)
WEB_CFLAGS := -std=c11 -O3 $(WARN) $(FPFLAGS) -D_DEFAULT_SOURCE -Ilib/include -Ilib \
              $(if $(filter 0,$(WEB_SIMD)),,-msimd128 -msse4.1)
# every sidx_lab_* function lab.h declares, and malloc/free (the page passes a dropped file's bytes)
WEB_EXPORTS := ${shell sed -n 's/^[a-z].* \**\(sidx_lab_[a-z_]*\)(.*/_\1/p' viz/lab.h | tr '\n' ','}_malloc,_free
WEB_LDFLAGS := -O3 -sMODULARIZE=1 -sEXPORT_NAME=SidxLab -sENVIRONMENT=web,node -sSINGLE_FILE=1 \
               -sALLOW_MEMORY_GROWTH=1 -sEXPORTED_FUNCTIONS=$(WEB_EXPORTS) \
               -sEXPORTED_RUNTIME_METHODS=ccall,cwrap,UTF8ToString,stringToUTF8,lengthBytesUTF8,HEAPU8,HEAPU32
WEB_NODE_PATH := NODE_PATH=/usr/share/nodejs$${NODE_PATH:+:$$NODE_PATH}
WEB_MAX_BYTES := 3145728

web:
	@command -v $(EMCC) >/dev/null 2>&1 || { echo "web: emcc not found: install Debian's emscripten (apt-get install emscripten)"; exit 1; }
	@$(MAKE) --no-print-directory $(WEB_DIR)/sidx-lab.html $(WEB_DIR)/site/index.html

# make test: the module where emscripten is installed, one line where not.
web-if-emcc:
	@if command -v $(EMCC) >/dev/null 2>&1; then $(MAKE) --no-print-directory $(WEB_DIR)/sidx-lab.html $(WEB_DIR)/site/index.html; \
	else echo "web: without emscripten (apt-get install emscripten): no build/web/sidx-lab.html, its tests skipped"; fi

$(WEB_DIR)/obj/%.o: %.c
	@mkdir -p $(dir $@)
	$(EMCC) $(WEB_CFLAGS) -MMD -MP -c $< -o $@

$(WEB_DIR)/sidx-lab.js: $(WEB_OBJ) viz/lab.h
	$(WEB_NODE_PATH) $(EMCC) $(WEB_LDFLAGS) -o $@ $(WEB_OBJ)

$(WEB_DIR)/sidx-lab.html: $(WEB_DIR)/sidx-lab.js viz/lab_page.html viz/page_common.js
	@if grep -qi '</script' $(WEB_DIR)/sidx-lab.js; then echo "web: the module's JavaScript holds '</script': it cannot be inlined"; exit 1; fi
	@if [ "$$(grep -c '^<script>/\*@SIDX_LAB_MODULE@\*/</script>$$' viz/lab_page.html)" != 1 ]; then \
	  echo "web: viz/lab_page.html wants exactly one line <script>/*@SIDX_LAB_MODULE@*/</script>"; exit 1; fi
	@$(call PAGE_COMMON_CHECK,viz/lab_page.html)
	awk -v js=$(WEB_DIR)/sidx-lab.js '$$0 == "<script>/*@SIDX_LAB_MODULE@*/</script>" { print "<script>"; \
	  while ((getline l < js) > 0) print l; print "</script>"; next } { print }' viz/lab_page.html | $(PAGE_COMMON_SPLICE) > $@.tmp
	@size=$$(wc -c < $@.tmp); if [ $$size -gt $(WEB_MAX_BYTES) ]; then \
	  echo "web: $@ would be $$size bytes, over the limit of $(WEB_MAX_BYTES)"; rm -f $@.tmp; exit 1; fi
	mv $@.tmp $@
	@echo "web: $@ ($$(wc -c < $@) bytes)"

$(WEB_DIR)/site/index.html: $(WEB_DIR)/sidx-lab.html
	@mkdir -p $(dir $@)
	cp $< $@

-include $(shell find $(WEB_DIR)/obj -name '*.d' 2>/dev/null)

# Exercises (docs/exercises.md).  sidx-check links a student's file with
# the exercise's checker driver and the runner, compiled here, against
# this build's library (and its sanitizer flags, under SAN=1).
# The kit's own command-line front end (sidx_check.c, with class mode in
# class_mode.c) lives beside the drivers and becomes bin/sidx-check; it
# links neither driver nor runner, which it compiles only for the students.
EX_FRONT_SRC := lessons/exercises/check/sidx_check.c lessons/exercises/check/class_mode.c lessons/exercises/check/borrowed.c \
                lessons/exercises/check/sandbox.c
EX_FRONT_OBJ := $(EX_FRONT_SRC:%.c=$(BUILD)/obj/%.o)
# sandbox.c serves both: the front end tries it before a class, the runner enters it.
EX_CHECK_SRC := $(filter-out $(EX_FRONT_SRC),$(wildcard lessons/exercises/check/*.c)) lessons/exercises/check/sandbox.c
EX_CHECK_OBJ := $(EX_CHECK_SRC:%.c=$(BUILD)/obj/%.o)
$(BUILD)/obj/lessons/exercises/check/sidx_check.o: CFLAGS += -DSIDX_CHECK_SRCDIR='"$(CURDIR)"' -DSIDX_CHECK_SANFLAGS='"$(SANFLAGS)"'
$(BUILD)/bin/sidx-check: $(EX_FRONT_OBJ) $(EX_CHECK_OBJ) $(LIBA)
	@mkdir -p $(dir $@)
	$(CC) $(LDFLAGS) -o $@ $(EX_FRONT_OBJ) $(LDLIBS)
# The runner writes a failing case as a web page (--html): viz/check_page.html
# with viz/page_common.js spliced in, as the bytes of a C array the runner
# includes (sidx_check_page_html), so the checker needs no file beside it.
$(BUILD)/gen/check_page_html.inc: viz/check_page.html viz/page_common.js
	@mkdir -p $(dir $@)
	@$(call PAGE_COMMON_CHECK,$<)
	@if [ "$$(grep -c '"@SIDX_CHECK_DATA@"' $<)" != 1 ]; then echo "$< wants exactly one \"@SIDX_CHECK_DATA@\""; exit 1; fi
	{ echo '/* generated from viz/check_page.html and viz/page_common.js by the Makefile: do not edit */'; \
	  echo 'static const unsigned char sidx_check_page_html[] = {'; \
	  $(PAGE_COMMON_SPLICE) $< | od -An -v -tx1 | sed -e 's/\([0-9a-f][0-9a-f]\)/0x\1,/g'; echo '0x00};'; } > $@.tmp && mv $@.tmp $@
$(BUILD)/obj/lessons/exercises/check/runner.o: $(BUILD)/gen/check_page_html.inc
$(BUILD)/obj/lessons/exercises/check/runner.o: CFLAGS += -I$(BUILD)/gen

# make exercise EX=NAME: check lessons/exercises/NAME.c, the stub a student
# edits in place.  make exercises-handout: the repository without the
# reference solutions and the planted mistakes (which are solutions too).
# make exercise-mutants: every generated mutant of every reference solution
# and every planted mistake through sidx-check (tests/exercises/mutants.sh;
# the mutation score per exercise, exit 1 if a non-equivalent mutant survives).
.PHONY: exercise exercises-handout exercise-mutants
exercise-mutants: build
	BUILD=$(BUILD) sh tests/exercises/mutants.sh

exercise: build
	@if [ -z "$(EX)" ]; then echo "usage: make exercise EX=NAME   (NAME from: $(BUILD)/bin/sidx-check --list)"; exit 2; fi
	$(BUILD)/bin/sidx-check $(EX) lessons/exercises/$(EX).c

exercises-handout:
	@mkdir -p $(BUILDDIR)
	git ls-files | grep -v -e '^lessons/exercises/solutions/' -e '^tests/exercises/' \
	  | tar -czf $(BUILDDIR)/sidx-exercises.tar.gz --transform 's,^,sidx-exercises/,' -T -
	@echo "exercises-handout: $(BUILDDIR)/sidx-exercises.tar.gz (no lessons/exercises/solutions/, no tests/exercises/)"

# This configuration's dependency files only: another tree under build/ may
# be compiling at the same time (.ci/run builds several side by side).
-include $(shell find $(BUILD)/obj $(BUILD)/nohooks $(FUZZ_DIR)/obj -name '*.d' 2>/dev/null)
