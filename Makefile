# What people type. Each target installs missing Debian packages and builds what it needs.
#   make            build build/bin/qdemsph (CPU + CUDA backend when nvcc is present)
#   make run        the demo: a viscoelastic cantilever released from a deflected state
#   make run-fsi    a fluid-structure demo (SCENE=dambreak_cubes|debris_flow, RUN_ARGS=...)
#   make test       unit tests + the quick tier of the verification suite
#   make verify     the verification suite (FULL=1: the long tier)
#   make references regenerate the stored FEniCSx, YADE and rigid-body reference results
#   make sanitize   unit tests under ASan+UBSan (all; FILTER=... for some)
#   make fuzz       libFuzzer targets for the scene parser and mesh reader (FUZZ_SECONDS each)
BUILD ?= build
JOBS ?= $(shell nproc)
PY := /usr/bin/python3
FULL ?= 0

.PHONY: all deps build run run-fsi test unit verify references sanitize fuzz clean
all: build

deps:
	@bash ci/install-deps.sh

build: deps
	@cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release $(CMAKE_ARGS) >/dev/null
	@cmake --build $(BUILD) -j $(JOBS)

run: build
	@bash ci/demo.sh $(BUILD)

run-fsi: build
	@bash ci/demo_fsi.sh $(BUILD) $(or $(SCENE),dambreak_cubes) $(RUN_ARGS)

unit: build
	@cd $(BUILD) && ctest --output-on-failure -j $(JOBS)
	@$(PY) -m pytest scaling/tests -q -p no:cacheprovider

verify: build
	@$(PY) -m pytest verification -q $(if $(filter 1,$(FULL)),--full,) --qdemsph $(BUILD)/bin/qdemsph \
	  --verify-out $(BUILD)/verify --junitxml $(BUILD)/verify/junit.xml ; rc=$$? ; \
	  $(PY) verification/report.py --out $(BUILD)/verify || rc=1 ; exit $$rc

test: unit verify

references: build
	@bash references/fenicsx/make_references.sh $(BUILD)/bin/qdemsph
	@bash references/yade/run_all.sh
	@$(PY) verification/cases/yade_shogi_chain/rigid_chain.py --all

sanitize: deps
	@bash ci/sanitize.sh $(FILTER)

fuzz: deps
	@bash ci/fuzz.sh $(or $(FUZZ_SECONDS),60)

clean:
	rm -rf $(BUILD)
