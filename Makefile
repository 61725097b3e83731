# fovea: GNU make build. No generated build system.
#   make [all] | deps | test | run | bench | check-asan | check-tsan | install | clean
#   CROSS=aarch64-linux-gnu-   cross-builds into build-aarch64/ (tests run under qemu-aarch64)
#   CC, CXX, CFLAGS, LDFLAGS, PREFIX, DESTDIR are respected.

CROSS ?=
ifeq ($(origin CC),default)
CC := $(CROSS)gcc
endif
ifeq ($(origin CXX),default)
CXX := $(CROSS)g++
endif
AR := $(CROSS)ar

MACHINE := $(shell $(CC) -dumpmachine 2>/dev/null)
ifneq ($(findstring aarch64,$(MACHINE)),)
ARCH := aarch64
else ifneq ($(findstring x86_64,$(MACHINE)),)
ARCH := x86_64
else
ARCH := generic
endif

SAN ?=
ifeq ($(SAN),asan)
BUILD ?= build-asan
SANFLAGS := -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all
else ifeq ($(SAN),tsan)
BUILD ?= build-tsan
SANFLAGS := -fsanitize=thread
else ifeq ($(SAN),fuzz)
# make fuzz: clang, the libraries instrumented for libFuzzer's coverage, ASan + UBSan (C++ without
# UBSan's function check: its handler is in the C++ runtime, which the C driver's link leaves out)
BUILD ?= build-fuzz
SANFLAGS := -fsanitize=address,undefined,fuzzer-no-link -fno-omit-frame-pointer -fno-sanitize-recover=all
else ifneq ($(CROSS),)
BUILD ?= build-$(ARCH)
else
BUILD ?= build
endif

OPT ?= -O2 -g
CFLAGS ?=
LDFLAGS ?=
WARN := -Wall -Wextra -Werror
# ISO C: no silent FMA contraction, so the plain-C references give the same bits everywhere.
BASE_CFLAGS := -std=c11 -D_POSIX_C_SOURCE=200809L $(OPT) $(WARN) -ffp-contract=off -fno-math-errno -pthread -Icore -Iplatform $(SANFLAGS)
BASE_CXXFLAGS := -std=c++17 $(OPT) $(WARN) -Wno-unused-parameter -pthread -Icore $(SANFLAGS) $(if $(filter asan fuzz,$(SAN)),-fno-sanitize=vptr) \
                 $(if $(filter fuzz,$(SAN)),-fno-sanitize=function)
LIBS := -lembree3 -ltinygltf -lstb -ljpeg -lstdc++ -lm -lpthread
TEST_LIBS := -lcmocka

# Hardware back ends of platform/ (GPIO vsync: libgpiod 1.6, KMS: libdrm, window: SDL2), native
# builds only: the cross leg runs the core's tests and has none of them. A back end whose
# library is missing compiles to a stub whose open() says so. Linked --as-needed, so only the
# programs that use a back end depend on its library.
PKG_CONFIG ?= pkg-config
ifeq ($(CROSS),)
HW_PKGS := $(foreach p,libgpiod libdrm sdl2,$(if $(shell $(PKG_CONFIG) --exists $(p) 2>/dev/null && echo y),$(p)))
endif
HW_DEFS := $(if $(filter libgpiod,$(HW_PKGS)),-DFV_HAVE_GPIOD) $(if $(filter libdrm,$(HW_PKGS)),-DFV_HAVE_DRM) \
           $(if $(filter sdl2,$(HW_PKGS)),-DFV_HAVE_SDL2)
HW_CFLAGS := $(HW_DEFS) $(if $(HW_PKGS),$(shell $(PKG_CONFIG) --cflags $(HW_PKGS)))
AS_NEEDED := -Wl,--push-state,--as-needed
AS_NEEDED_END := -Wl,--pop-state
HW_LIBS := $(if $(HW_PKGS),$(AS_NEEDED) $(shell $(PKG_CONFIG) --libs $(HW_PKGS)) $(AS_NEEDED_END))

ALL_CFLAGS = $(BASE_CFLAGS) $(CFLAGS)
ALL_CXXFLAGS = $(BASE_CXXFLAGS) $(CXXFLAGS)
ALL_LDFLAGS = $(SANFLAGS) -pthread $(LDFLAGS)

CORE_C := $(wildcard core/*.c core/base/*.c core/dof/*.c core/eyetrack/*.c)
CORE_CXX := $(wildcard core/*.cpp)
ifeq ($(ARCH),x86_64)
CORE_ISA := $(wildcard core/x86/*.c)
else ifeq ($(ARCH),aarch64)
CORE_ISA := $(wildcard core/arm/*.c)
endif
PLATFORM_C := $(wildcard platform/*.c)
APPS := $(patsubst apps/%.c,$(BUILD)/bin/%,$(wildcard apps/fovea-*.c))
TOOLS := $(patsubst tools/%.c,$(BUILD)/tools/%,$(wildcard tools/*.c))
TESTS := $(patsubst tests/%.c,$(BUILD)/tests/%,$(wildcard tests/test_*.c))
# checkasm (tests/checkasm/): every kernel's ISA versions against C, and --bench. fovea-bench
# --kernels links its bench.o (no cmocka in it).
CHECKASM := $(BUILD)/tests/checkasm/checkasm
CHECKASM_OBJ := $(patsubst %.c,$(BUILD)/%.o,$(wildcard tests/checkasm/*.c))
CHECKASM_BENCH_OBJ := $(BUILD)/tests/checkasm/bench.o

CORE_OBJ := $(patsubst %.c,$(BUILD)/%.o,$(CORE_C) $(CORE_ISA)) $(patsubst %.cpp,$(BUILD)/%.o,$(CORE_CXX))
PLATFORM_OBJ := $(patsubst %.c,$(BUILD)/%.o,$(PLATFORM_C))
LIB := $(BUILD)/libfovea.a
PLIB := $(BUILD)/libfovea-platform.a

# The bundled "space shooting range" scene is generated (deterministically) at build time.
RANGE := assets/range.glb
# The bundled synthetic eye video (tools/gen_eye.c, driven by the bundled gaze trace) and its
# ground truth; deterministic, about 1.5 s to make.
EYE_SYNTH := assets/eye_synth.y4m
EYE_SYNTH_TRUTH := assets/eye_synth.csv
# Where the shared assets live (scenes, eye images); tests read them from here.
SHARED ?= ../shared

# Build folders of the checks; BUILD=... on the command line names the one they all use.
ifeq ($(origin BUILD),command line)
ASAN_BUILD := $(BUILD)
TSAN_BUILD := $(BUILD)
CROSS_BUILD := $(BUILD)
else
ASAN_BUILD := build-asan
TSAN_BUILD := build-tsan
CROSS_BUILD := build-aarch64
endif

.PHONY: all deps test run bench check-asan check-tsan check-aarch64 install clean test-bin test-hil fuzz fuzz-bin soak
all: $(LIB) $(PLIB) $(APPS) $(TOOLS)

$(BUILD)/%.o: %.c
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -MMD -MP -c $< -o $@
$(BUILD)/core/x86/%_sse41.o: core/x86/%_sse41.c
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -msse4.1 -MMD -MP -c $< -o $@
$(BUILD)/core/x86/%_avx2.o: core/x86/%_avx2.c
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -mavx2 -mfma -MMD -MP -c $< -o $@
$(BUILD)/%.o: %.cpp
	@mkdir -p $(dir $@)
	$(CXX) $(ALL_CXXFLAGS) -MMD -MP -c $< -o $@

$(LIB): $(CORE_OBJ)
	@rm -f $@
	$(AR) rcs $@ $^
$(PLATFORM_OBJ): ALL_CFLAGS += $(HW_CFLAGS)
$(PLIB): $(PLATFORM_OBJ)
	@rm -f $@
	$(AR) rcs $@ $^

$(BUILD)/bin/%: apps/%.c $(PLIB) $(LIB)
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) $< $(PLIB) $(LIB) $(ALL_LDFLAGS) $(LIBS) $(HW_LIBS) -o $@
$(BUILD)/bin/fovea-bench: apps/fovea-bench.c $(CHECKASM_BENCH_OBJ) $(PLIB) $(LIB)
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -Itests $< $(CHECKASM_BENCH_OBJ) $(PLIB) $(LIB) $(ALL_LDFLAGS) $(LIBS) $(HW_LIBS) -o $@
$(BUILD)/tools/%: tools/%.c $(PLIB) $(LIB)
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) $< $(PLIB) $(LIB) $(ALL_LDFLAGS) $(LIBS) $(HW_LIBS) -o $@
$(BUILD)/tests/%: tests/%.c tests/testutil.h tests/testscene.h $(PLIB) $(LIB)
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -Itests $< $(PLIB) $(LIB) $(ALL_LDFLAGS) $(LIBS) $(HW_LIBS) $(TEST_LIBS) -o $@

# Fuzz harnesses (tests/fuzz/, docs/robustness.md): linked into tests/test_fuzz (seeds plus
# deterministic mutations, every make test) and, by make fuzz, into clang libFuzzer binaries.
FUZZ_OBJ := $(BUILD)/tests/fuzz/targets.o
$(FUZZ_OBJ): ALL_CFLAGS += -Itests $(HW_CFLAGS)
$(BUILD)/tests/test_fuzz: tests/test_fuzz.c tests/testutil.h tests/fuzz/targets.h $(FUZZ_OBJ) $(PLIB) $(LIB)
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -Itests $< $(FUZZ_OBJ) $(PLIB) $(LIB) $(ALL_LDFLAGS) $(LIBS) $(HW_LIBS) $(TEST_LIBS) -o $@

$(CHECKASM_OBJ): ALL_CFLAGS += -Itests
$(CHECKASM): $(CHECKASM_OBJ) $(PLIB) $(LIB)
	@mkdir -p $(dir $@)
	$(CC) $(CHECKASM_OBJ) $(PLIB) $(LIB) $(ALL_LDFLAGS) $(LIBS) $(HW_LIBS) $(TEST_LIBS) -o $@

$(RANGE): tools/gen_range.c
	$(MAKE) --no-print-directory $(BUILD)/tools/gen_range
	$(BUILD)/tools/gen_range --out $@

# (order-only on the tool: built by this make, not a recursive one racing it under -j; the asset
# is remade when its sources change, not whenever some build folder's tool is newer)
$(EYE_SYNTH): tools/gen_eye.c core/eyetrack/synth.c core/eyetrack/synth.h assets/gaze_sweep.csv | $(BUILD)/tools/gen_eye
	$(BUILD)/tools/gen_eye --trace assets/gaze_sweep.csv --out $@ --truth $(EYE_SYNTH_TRUTH)
$(EYE_SYNTH_TRUTH): $(EYE_SYNTH)

deps:
	@tools/deps.sh $(if $(CROSS),--cross)

test-bin: $(LIB) $(PLIB) $(APPS) $(TOOLS) $(TESTS) $(CHECKASM) $(RANGE) $(EYE_SYNTH)

# The suite: unit tests and checkasm (cmocka) and the command-line tests; one summary line at the end.
test: deps
	@$(MAKE) --no-print-directory test-bin
	@BUILD=$(BUILD) SHARED=$(SHARED) tests/run.sh

# Hardware in the loop (docs/hil.md): Debian's kernel under QEMU (TCG) with vivid, gpio-sim and
# bochs-drm; the guest program is linked statically (busybox initramfs); fovea-headset runs there
# with its shared libraries on range.glb (fovea-replay renders the host's reference).
# tools/hil/prepare.sh installs what it needs and caches the kernel and the gpio-sim module
# under $(BUILD)/hil.
HIL_GUEST := $(BUILD)/hil/fovea-hil
$(HIL_GUEST): tests/hil/guest.c tests/hil/pattern.h $(PLIB) $(LIB)
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -Itests/hil $< $(PLIB) $(LIB) -static $(ALL_LDFLAGS) \
		-lgpiod -ldrm -lstb -ljpeg -lm -o $@

test-hil:
	@tools/deps.sh
	@$(MAKE) --no-print-directory $(HIL_GUEST) $(EYE_SYNTH) $(RANGE) $(BUILD)/bin/fovea-headset $(BUILD)/bin/fovea-replay
	@BUILD=$(BUILD) tests/hil/run.sh

# Cross leg: build everything for aarch64 and run the core's tests under qemu-aarch64.
check-aarch64:
	@tools/deps.sh --cross
	@# the generated assets are data (same bytes on any ISA): made by host tools, not qemu
	@$(MAKE) --no-print-directory $(RANGE) $(EYE_SYNTH)
	@$(MAKE) --no-print-directory CROSS=aarch64-linux-gnu- test-bin
	@BUILD=$(CROSS_BUILD) SHARED=$(SHARED) RUNNER=qemu-aarch64 tests/run.sh --core

# Fuzzing (docs/robustness.md): each harness of tests/fuzz/ as a clang libFuzzer binary with ASan +
# UBSan, run FUZZ_SECONDS (default 60) on a working corpus seeded from tests/fuzz/corpus/NAME;
# FUZZ_TARGETS narrows the list. Not in CI (make test replays the seeds with mutations instead).
FUZZ_SECONDS ?= 60
FUZZ_TARGETS ?= gltf trace lens calib y4m imagelist pixfmt png
FUZZ_BUILD := build-fuzz
fuzz:
	@tools/deps.sh --fuzz
	@$(MAKE) --no-print-directory SAN=fuzz CC=clang CXX=clang++ BUILD=$(FUZZ_BUILD) fuzz-bin
	@set -e; for t in $(FUZZ_TARGETS); do \
	    mkdir -p $(FUZZ_BUILD)/corpus/$$t; \
	    echo "== fuzz $$t: $(FUZZ_SECONDS) s"; \
	    $(FUZZ_BUILD)/fuzz/fuzz_$$t -max_total_time=$(FUZZ_SECONDS) -print_final_stats=1 -timeout=10 \
	        -rss_limit_mb=3072 -artifact_prefix=$(FUZZ_BUILD)/crash-$$t- \
	        $(FUZZ_BUILD)/corpus/$$t tests/fuzz/corpus/$$t 2>&1 | \
	        grep -E '^(stat::number_of_executed_units|stat::peak_rss_mb|==[0-9]+==ERROR|SUMMARY)|Done|INFO: Seed' || true; \
	    ls $(FUZZ_BUILD)/crash-$$t-* >/dev/null 2>&1 && { echo "fuzz $$t: crash, see $(FUZZ_BUILD)/crash-$$t-*"; exit 1; }; \
	done; echo "fuzz: no crash in $(FUZZ_TARGETS)"
fuzz-bin: $(LIB) $(PLIB) $(patsubst %,$(BUILD)/fuzz/fuzz_%,$(FUZZ_TARGETS))
$(BUILD)/fuzz/fuzz_%: tests/fuzz/libfuzzer.c $(FUZZ_OBJ) $(PLIB) $(LIB)
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -Itests -DFV_FUZZ_FN=fv_fuzz_$* -fsanitize=fuzzer $< $(FUZZ_OBJ) $(PLIB) $(LIB) \
	    $(ALL_LDFLAGS) -fsanitize=fuzzer $(LIBS) $(HW_LIBS) -o $@

# Soak (docs/robustness.md; not in CI): 100,000 replayed frames and a 10-minute headset run, RSS
# and open descriptors sampled, both must stay flat. SOAK_FRAMES / SOAK_SECONDS shorten it.
soak: deps
	@$(MAKE) --no-print-directory all $(RANGE) $(EYE_SYNTH)
	@BUILD=$(BUILD) tools/soak.sh

check-asan:
	@tools/deps.sh
	@$(MAKE) --no-print-directory SAN=asan test-bin
	@BUILD=$(ASAN_BUILD) SHARED=$(SHARED) ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 tests/run.sh

check-tsan:
	@tools/deps.sh
	@$(MAKE) --no-print-directory SAN=tsan test-bin
	@BUILD=$(TSAN_BUILD) SHARED=$(SHARED) TSAN_OPTIONS="suppressions=$(CURDIR)/tests/tsan.supp halt_on_error=1" tests/run.sh

run: deps
	@$(MAKE) --no-print-directory all $(RANGE)
	@rm -rf out/run
	$(BUILD)/bin/fovea-replay --scene $(RANGE) --trace assets/gaze_sweep.csv --frames 120 --out out/run
	@echo "frames: out/run/frame_*.png   stats: out/run/stats.csv"

bench:
	@tools/deps.sh --bench
	@$(MAKE) --no-print-directory all $(RANGE)
	@mkdir -p out/bench
	$(BUILD)/bin/fovea-bench --scene $(RANGE) --mode both --frames 30 --json out/bench/range.json
	$(BUILD)/bin/fovea-bench --scene $(RANGE) --mode foveated --frames 30 --yaw-rate 30 --json out/bench/range-turning.json
	$(BUILD)/bin/fovea-bench --scene $(RANGE) --mode both --frames 30 --dof weak --json out/bench/range-dof.json
	for m in hussain mantiuk konrad liu; do \
	    $(BUILD)/bin/fovea-bench --scene $(RANGE) --mode foveated --frames 5 --warmup 1 --dof weak --dof-model $$m \
	        --json out/bench/range-dof-$$m.json || exit 1; done
	$(BUILD)/bin/fovea-bench --kernels --json out/bench/kernels.json
	$(BUILD)/bin/fovea-bench --scene $(RANGE) --mode both --frames 10 --warmup 2 --dof weak --sweep threads=1..$(shell nproc) \
	    --json out/bench/range-scaling.json
	$(BUILD)/bin/fovea-bench --scene $(RANGE) --mode foveated --frames 5 --warmup 2 --dof weak \
	    --sweep pmin=0.05,0.1,0.2,0.4 --sweep size=640x720,960x1080,1280x1440 --sweep r0=5,10,15 \
	    --json out/bench/range-sweeps.json
	$(BUILD)/bin/fovea-bench --scene $(RANGE) --mode foveated --frames 3 --warmup 1 --dof weak \
	    --trace-out out/bench/range-trace.json >/dev/null
	python3 tools/plot_bench.py out/bench out/bench/range-dof.json out/bench/range-scaling.json out/bench/range-sweeps.json \
	    out/bench/kernels.json
	@echo "charts: out/bench/*.png   trace (Perfetto / chrome://tracing): out/bench/range-trace.json"

PREFIX ?= /usr/local
install: all
	install -d $(DESTDIR)$(PREFIX)/lib $(DESTDIR)$(PREFIX)/include/fovea $(DESTDIR)$(PREFIX)/bin $(DESTDIR)$(PREFIX)/lib/pkgconfig
	install -m 644 $(LIB) $(PLIB) $(DESTDIR)$(PREFIX)/lib/
	install -m 644 core/*.h core/base/*.h core/dof/*.h core/eyetrack/*.h platform/*.h $(DESTDIR)$(PREFIX)/include/fovea/
	install -m 755 $(APPS) $(DESTDIR)$(PREFIX)/bin/
	sed -e 's|@PREFIX@|$(PREFIX)|g' tools/fovea.pc.in > $(DESTDIR)$(PREFIX)/lib/pkgconfig/fovea.pc

clean:
	rm -rf build build-asan build-tsan build-aarch64 build-fuzz out $(RANGE) $(EYE_SYNTH) $(EYE_SYNTH_TRUTH)

-include $(shell find $(BUILD) -name '*.d' 2>/dev/null)
