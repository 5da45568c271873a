# cmam — top-level convenience targets. The real build is CMake (see CMakePresets.json).
#   make          build the cmam binary (build/release/app/cmam)
#   make demo     install dependencies, build, render scenes/demo.pbrt
#   make test     install dependencies, build, run every test through CTest
#   make bench    build and run the benchmarks (Google Benchmark), then whole-process figures
#                 (start-up, peak memory, renders at 1 and 64 spp; PBRT=/path/to/pbrt adds pbrt-v3)
#   make paper-figures  render the paper's scenes with the CMAM on and off, with an error table
#   make results  evaluate every method on the bundled scenes; rewrites docs/results.md
#   make fuzz     build the fuzz targets (Clang, build/fuzz) and run each for FUZZ_SECONDS
JOBS ?= $(shell nproc)
BUILD := build/release
CMAM := $(BUILD)/app/cmam
DEMO_OUT ?= $(BUILD)/demo.png

FUZZ_SECONDS ?= 60
FUZZ_TARGETS ?= parse scene ply image bsdf filter

.PHONY: all build deps configure demo test bench paper-figures results fuzz clean

all: build

deps:
	@bash scripts/setup-deps.sh

configure:
	@test -f $(BUILD)/build.ninja || cmake --preset release >/dev/null

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
	@cmake --preset release >/dev/null
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
