# rll: the two front-door commands. `make demo` and `make test` install what is missing
# (Debian packages), configure, build Release and run.
SHELL := /bin/bash
BUILD ?= build
JOBS ?= $(shell nproc)
CMAKE_FLAGS ?=

.PHONY: all deps test-deps build demo test test-asan test-tsan bench fuzz clean format install

all: build

deps:
	@scripts/install-deps.sh

# What only the tests need (chromium, to load the HTML reports; Slurm and munge, for the job-array test).
test-deps:
	@scripts/install-deps.sh --test

$(BUILD)/build.ninja: CMakeLists.txt | deps
	cmake -S . -B $(BUILD) -G Ninja -DCMAKE_BUILD_TYPE=Release $(CMAKE_FLAGS)

build: deps $(BUILD)/build.ninja
	cmake --build $(BUILD) -j $(JOBS)

demo: build
	@scripts/demo.sh $(BUILD)

# The program into $(PREFIX)/bin and the Python module rll (with its type stub) into
# $(PREFIX)/lib/python3.X/dist-packages, where Debian's python3 finds it for /usr/local.
PREFIX ?= /usr/local
install: build
	cmake --install $(BUILD) --prefix $(PREFIX)

test: build test-deps
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

# AddressSanitizer + UndefinedBehaviorSanitizer build of the whole tree, running the fast tests:
# unit, cli and render (about 40 s under the sanitizers on 2 cores; stat takes 4 minutes there).
# Without the CUDA backend: nvcc takes no sanitizer and no GPU runs it here, so its compile (a
# sixth of the build) would buy nothing; `make test` builds and checks it.
test-asan: deps
	cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DRLL_SANITIZE=ON -DRLL_CUDA=OFF
	cmake --build build-asan -j $(JOBS)
	cd build-asan && ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 LSAN_OPTIONS=suppressions=$(CURDIR)/tests/lsan.supp UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
		ctest --output-on-failure -j $(JOBS) -L 'unit|cli|render'

# ThreadSanitizer on the cell table's lock-free insert: its race test compiled alone against the
# header-only table (no second build of the tree).
test-tsan: deps
	scripts/tsan-cell-table.sh $(BUILD)/tsan

bench: build
	@scripts/bench.sh $(BUILD)

# libFuzzer targets for the PLY, glTF, pbrt, JSON and OBJ (with its MTL) parsers, the gzip
# inflater and the EXR reader (clang, ASan + UBSan), each run for FUZZ_SECONDS from a corpus
# seeded with generated files and the regression inputs in tests/fuzz/, each input held to 1 GiB
# of memory and 10 s. A crash stops the run; its input is left in $(FUZZ_BUILD)/crashes.
FUZZ_BUILD ?= build-fuzz
FUZZ_SECONDS ?= 60
fuzz: deps
	CC=clang CXX=clang++ cmake -S . -B $(FUZZ_BUILD) -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
		-DRLL_FUZZ=ON -DRLL_TESTS=OFF -DRLL_BENCH=OFF -DRLL_CUDA=OFF
	cmake --build $(FUZZ_BUILD) -j $(JOBS)
	@scripts/fuzz.sh $(FUZZ_BUILD) $(FUZZ_SECONDS)

clean:
	rm -rf $(BUILD) build-asan $(FUZZ_BUILD)

format:
	clang-format -i $$(git ls-files '*.h' '*.cpp')
