# sidx — build, test, demo, bench.
#
#   make            library (build/lib), programs (build/bin), lessons (build/lessons)
#   make demo       install missing Debian packages, build, run the guided tour
#   make test       install missing Debian packages, build, run every cmocka suite
#   make test SAN=1 the same under AddressSanitizer + UndefinedBehaviorSanitizer (build/san)
#   make valgrind   the suites under valgrind memcheck
#   make bench      the benchmark table (build/bench/); refreshes the figures in
#                   docs/benchmark.md and README.md (docs/bench_refresh.sh)
#   make apidocs    the API reference from the headers (Doxygen, build/apidocs/html)
#   make install PREFIX=/usr/local
#
# Everything is found by wildcard: a new lib/*.c joins the library, a new
# tests/test_*.c becomes a suite, a new lessons/*.c a lesson, a new
# viz/sidx_*.c a program.

DEBS := pkg-config libcmocka-dev libgraphviz-dev libsdl2-dev libsdl2-image-dev libembree-dev gnuplot-nox valgrind

PREFIX ?= /usr/local
OPT ?= -O2
SAN ?= 0

# BUILDDIR=build/NAME gives a separate tree (parallel work in one checkout).
BUILDDIR ?= build
ifeq ($(SAN),1)
BUILD := $(BUILDDIR)/san
SANFLAGS := -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer
else
BUILD := $(BUILDDIR)
SANFLAGS :=
endif

PKGS := libcgraph libgvc sdl2 SDL2_image
PKG_CFLAGS = $(shell pkg-config --cflags $(PKGS) 2>/dev/null)
PKG_LIBS = $(shell pkg-config --libs $(PKGS) 2>/dev/null)

WARN := -Wall -Wextra -Wpedantic -Werror
# -ffp-contract=off: the watertight test is watertight because neighbouring
# triangles compute the same edge function bit for bit; a compiler fusing
# a*b - c*d into an FMA in one code path (clang does in the AVX2 kernels)
# breaks that.  gcc's ISO mode already defaults to off; clang's does not.
FPFLAGS := -ffp-contract=off
CFLAGS := -std=c11 $(OPT) -g $(WARN) $(FPFLAGS) -fPIC -D_DEFAULT_SOURCE -Ilib/include -Ilib $(SANFLAGS) $(EXTRA_CFLAGS)
LDFLAGS := $(SANFLAGS) -pthread
LDLIBS := -lm

LIB_SRC := $(wildcard lib/*.c)
LIB_OBJ := $(LIB_SRC:%.c=$(BUILD)/obj/%.o)
VIZ_PROG_SRC := $(wildcard viz/sidx_*.c)
VIZ_LIB_SRC := $(filter-out $(VIZ_PROG_SRC),$(wildcard viz/*.c))
VIZ_OBJ := $(VIZ_LIB_SRC:%.c=$(BUILD)/obj/%.o)
TEST_SRC := $(wildcard tests/test_*.c)
TEST_COMMON_SRC := $(wildcard tests/common/*.c)
TEST_COMMON_OBJ := $(TEST_COMMON_SRC:%.c=$(BUILD)/obj/%.o)
TESTS := $(TEST_SRC:tests/%.c=$(BUILD)/tests/%)
LESSON_SRC := $(filter-out lessons/tour.c,$(wildcard lessons/*.c))
LESSONS := $(LESSON_SRC:lessons/%.c=$(BUILD)/lessons/%)
BENCH_SRC := $(wildcard tests/bench/*.c)
BENCH_OBJ := $(BENCH_SRC:%.c=$(BUILD)/obj/%.o)
VIZ_PROGS := $(VIZ_PROG_SRC:viz/sidx_%.c=$(BUILD)/bin/sidx-%)

LIBA := $(BUILD)/lib/libsidx.a
LIBSO := $(BUILD)/lib/libsidx.so
VIZA := $(BUILD)/lib/libsidxviz.a
PROGS := $(VIZ_PROGS) $(if $(wildcard lessons/tour.c),$(BUILD)/bin/sidx-tour) \
         $(if $(BENCH_SRC),$(BUILD)/bin/sidx-bench $(BUILD)/bin/sidx-bench-nohooks)
# The library again with every hook compiled out (-DSIDX_NO_HOOKS), linked
# into sidx-bench-nohooks: `sidx-bench run` compares it with sidx-bench.
NOHOOKS_OBJ := $(LIB_SRC:%.c=$(BUILD)/nohooks/obj/%.o)
ALL_LIBS = $(VIZA) $(LIBA) $(PKG_LIBS) $(LDLIBS)

.PHONY: all deps build demo test test-run valgrind bench install clean docs apidocs fuzz

all: deps
	@$(MAKE) --no-print-directory build

build: $(LIBA) $(LIBSO) $(VIZA) $(PROGS) $(LESSONS) $(TESTS)

# Installs what is missing (as root), else prints the exact command and stops.
deps:
	@missing=""; for p in $(DEBS); do dpkg -s $$p >/dev/null 2>&1 || missing="$$missing $$p"; done; \
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
	$(CC) $(CFLAGS) $(PKG_CFLAGS) -MMD -MP -c $< -o $@

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

$(BUILD)/nohooks/obj/%.o: %.c
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) -DSIDX_NO_HOOKS -MMD -MP -c $< -o $@

$(BUILD)/bin/sidx-bench-nohooks: $(BENCH_OBJ) $(NOHOOKS_OBJ)
	@mkdir -p $(dir $@)
	$(CC) $(LDFLAGS) -o $@ $(BENCH_OBJ) $(NOHOOKS_OBJ) $(LDLIBS) -lembree3

$(BUILD)/lessons/%: $(BUILD)/obj/lessons/%.o $(VIZA) $(LIBA)
	@mkdir -p $(dir $@)
	$(CC) $(LDFLAGS) -o $@ $< $(ALL_LIBS)

$(BUILD)/tests/%: $(BUILD)/obj/tests/%.o $(TEST_COMMON_OBJ) $(VIZA) $(LIBA)
	@mkdir -p $(dir $@)
	$(CC) $(LDFLAGS) -o $@ $< $(TEST_COMMON_OBJ) $(ALL_LIBS) -lcmocka

demo: deps
	@$(MAKE) --no-print-directory build
	$(BUILD)/bin/sidx-tour

# Each suite runs from the repository root; all run even if one fails.
test: deps
	@$(MAKE) --no-print-directory build
	@$(MAKE) --no-print-directory test-run

test-run:
	@failed=0; for t in $(TESTS); do \
	  echo "== $$t"; \
	  $$t || { echo "!! FAILED: $$t"; failed=$$((failed+1)); }; \
	done; \
	if [ -x tests/run_lessons.sh ]; then \
	  echo "== lessons"; BUILD=$(BUILD) sh tests/run_lessons.sh || { echo "!! FAILED: lessons"; failed=$$((failed+1)); }; \
	fi; \
	if [ $$failed -ne 0 ]; then echo "$$failed suite(s) failed"; exit 1; fi; \
	echo "all suites passed"

valgrind: deps
	@$(MAKE) --no-print-directory build
	@failed=0; for t in $(TESTS); do \
	  echo "== valgrind $$t"; \
	  SIDX_FAST_TESTS=1 valgrind -q --error-exitcode=99 --suppressions=tests/valgrind.supp --leak-check=full --show-leak-kinds=definite,indirect,possible \
	    --errors-for-leak-kinds=definite,indirect,possible $$t >/dev/null || { echo "!! FAILED: $$t"; failed=1; }; \
	done; \
	if [ $$failed -eq 0 ]; then echo "valgrind: every suite ran with zero errors and zero leaks"; fi; exit $$failed

bench: deps
	@$(MAKE) --no-print-directory build
	@mkdir -p $(BUILD)/bench
	$(BUILD)/bin/sidx-bench run --csv $(BUILD)/bench/table.csv --plot $(BUILD)/bench/error_vs_speed.svg \
	  --markdown $(BUILD)/bench/table.md --md-command "make bench" --revision "$$(git describe --always --dirty 2>/dev/null)" \
	  $(if $(wildcard ../shared/scenes),--scenes ../shared/scenes) | tee $(BUILD)/bench/table.txt
	$(BUILD)/bin/sidx-bench extras $(if $(wildcard ../shared/scenes),--scenes ../shared/scenes) | tee $(BUILD)/bench/extras.txt
	@if [ -d ../shared/scenes ]; then sh docs/bench_refresh.sh $(BUILD)/bench/table.md docs/benchmark.md README.md; \
	else echo "bench: no ../shared/scenes (bunny, Sponza): docs/benchmark.md and README.md keep their figures"; fi

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
# then the API reference.
docs: deps
	@$(MAKE) --no-print-directory build
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

install: all
	install -d $(DESTDIR)$(PREFIX)/include/sidx $(DESTDIR)$(PREFIX)/lib/pkgconfig $(DESTDIR)$(PREFIX)/bin
	install -m 644 lib/include/sidx/*.h $(DESTDIR)$(PREFIX)/include/sidx/
	install -m 644 $(LIBA) $(VIZA) $(DESTDIR)$(PREFIX)/lib/
	install -m 755 $(LIBSO) $(DESTDIR)$(PREFIX)/lib/
	install -m 755 $(PROGS) $(DESTDIR)$(PREFIX)/bin/
	sed -e 's|@PREFIX@|$(PREFIX)|g' sidx.pc.in > $(DESTDIR)$(PREFIX)/lib/pkgconfig/sidx.pc

clean:
	rm -rf build

-include $(shell find build -name '*.d' 2>/dev/null)

# Exercises (docs/exercises.md).  sidx-check links a student's file with
# the exercise's checker driver and the runner, compiled here, against
# this build's library (and its sanitizer flags, under SAN=1).
EX_CHECK_SRC := $(wildcard lessons/exercises/check/*.c)
EX_CHECK_OBJ := $(EX_CHECK_SRC:%.c=$(BUILD)/obj/%.o)
$(BUILD)/obj/viz/sidx_check.o: CFLAGS += -DSIDX_CHECK_SRCDIR='"$(CURDIR)"' -DSIDX_CHECK_SANFLAGS='"$(SANFLAGS)"'
$(BUILD)/bin/sidx-check: $(EX_CHECK_OBJ)

# make exercise EX=NAME: check lessons/exercises/NAME.c, the stub a student
# edits in place.  make exercises-handout: the repository without the
# reference solutions and the planted mistakes (which are solutions too).
.PHONY: exercise exercises-handout
exercise: build
	@if [ -z "$(EX)" ]; then echo "usage: make exercise EX=NAME   (NAME from: $(BUILD)/bin/sidx-check --list)"; exit 2; fi
	$(BUILD)/bin/sidx-check $(EX) lessons/exercises/$(EX).c

exercises-handout:
	@mkdir -p $(BUILDDIR)
	git ls-files | grep -v -e '^lessons/exercises/solutions/' -e '^tests/exercises/' \
	  | tar -czf $(BUILDDIR)/sidx-exercises.tar.gz --transform 's,^,sidx-exercises/,' -T -
	@echo "exercises-handout: $(BUILDDIR)/sidx-exercises.tar.gz (no lessons/exercises/solutions/, no tests/exercises/)"
