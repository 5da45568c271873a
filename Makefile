# cmam — top-level convenience targets. The real build is CMake (see CMakePresets.json).
#   make          build the cmam binary (build/release/app/cmam)
#   make demo     install dependencies, build, render scenes/demo.pbrt
#   make test     install dependencies, build, run every test through CTest
#   make bench    build and run the benchmarks (Google Benchmark), then whole-process figures
#                 (start-up, peak memory, renders at 1 and 64 spp; PBRT=/path/to/pbrt adds pbrt-v3)
#   make paper-figures  render the paper's scenes with the CMAM on and off, with an error table
#   make results  evaluate every method on the bundled scenes; rewrites docs/results.md
#   make fuzz     build the fuzz targets (Clang, build/fuzz) and run each for FUZZ_SECONDS
# The release build is profile-guided (GCC): the renderer is first built instrumented in
# build/pgo and trained on the bundled scenes (scripts/pgo-train.sh), again whenever its sources
# are newer than the profile. PGO=0 builds without (e.g. `make PGO=0 test`).
JOBS ?= $(shell nproc)
BUILD := build/release
CMAM := $(BUILD)/app/cmam
DEMO_OUT ?= $(BUILD)/demo.png

FUZZ_SECONDS ?= 60
FUZZ_TARGETS ?= parse scene ply image bsdf filter

PGO ?= 1
PGO_PROFILE := $(abspath build/pgo-profile)
PGO_STAMP := $(PGO_PROFILE)/trained
PGO_MODE := $(if $(filter 1,$(PGO)),use,)
PGO_FLAGS := -DCMAM_PGO=$(PGO_MODE) -DCMAM_PGO_DIR=$(PGO_PROFILE)
PGO_SOURCES := $(shell find texture render pbrt app eval -name '*.cpp' -o -name '*.h') \
               CMakeLists.txt scripts/pgo-train.sh $(wildcard scripts/pgo/*.pbrt)

.PHONY: all build deps configure demo test bench paper-figures results fuzz clean

all: build

deps:
	@bash scripts/setup-deps.sh

# Configured when new, and again when PGO changes; after the training (whose time stamp the
# profile's objects depend on, when it exists at configure time).
configure: $(if $(PGO_MODE),$(PGO_STAMP))
	@if [ ! -f $(BUILD)/build.ninja ]; then cmake --preset release $(PGO_FLAGS) >/dev/null; \
	elif ! grep -qx 'CMAM_PGO:STRING=$(PGO_MODE)' $(BUILD)/CMakeCache.txt; then \
	  cmake -B $(BUILD) $(PGO_FLAGS) >/dev/null; fi

$(PGO_STAMP): $(PGO_SOURCES)
	@echo "profile-guided optimisation: the renderer built instrumented (build/pgo) and trained"
	@cmake --preset pgo-generate -DCMAM_PGO_DIR=$(PGO_PROFILE) >/dev/null
	@cmake --build build/pgo -j $(JOBS) --target cmam
	@bash scripts/pgo-train.sh build/pgo/app/cmam $(PGO_PROFILE)
	@touch $@

build: configure
	@cmake --build $(BUILD) -j $(JOBS)

demo: deps
	@$(MAKE) --no-print-directory build
	@$(CMAM) render scenes/demo.pbrt -o $(DEMO_OUT)
	@echo "demo image: $(abspath $(DEMO_OUT))"

# Configured again after the test dependencies are installed: a build configured before (by
# make demo) would not have found Clang, and would skip texture.clang_build.
test:
	@bash scripts/setup-deps.sh --test
	@if [ -n "$(PGO_MODE)" ]; then $(MAKE) --no-print-directory $(PGO_STAMP); fi
	@cmake --preset release $(PGO_FLAGS) >/dev/null
	@$(MAKE) --no-print-directory build
	@cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

bench: deps
	@$(MAKE) --no-print-directory build
	@$(BUILD)/bench/render_bench
	@$(BUILD)/bench/filter_bench
	@bash scripts/process-bench.sh $(CMAM)

paper-figures: deps
	@$(MAKE) --no-print-directory build
	@bash scripts/paper-figures.sh $(CMAM) out/paper-figures

results: deps
	@$(MAKE) --no-print-directory build
	@bash scripts/results.sh $(CMAM)

# Each target replays its seeds and regressions, then fuzzes; crashing inputs are written to
# fuzz/regressions/TARGET/ (commit them). Every target runs even when one fails.
fuzz:
	@bash scripts/setup-deps.sh --fuzz
	@JOBS=$(JOBS) bash fuzz/run.sh build
	@failed=""; for t in $(FUZZ_TARGETS); do \
	  echo "== fuzz_$$t: $(FUZZ_SECONDS) s"; \
	  bash fuzz/run.sh fuzz $$t $(FUZZ_SECONDS) || failed="$$failed $$t"; \
	done; \
	if [ -n "$$failed" ]; then echo "fuzz: inputs that fail are in fuzz/regressions/ for:$$failed"; exit 1; fi

clean:
	rm -rf build
