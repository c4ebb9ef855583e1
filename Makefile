# Thin wrapper over CMake. `make run` builds the CLI alone and renders the demo; `make test` builds
# and runs every test; `make install PREFIX=...` installs the CLI, library, headers, CMake package,
# Python package, examples and docs.
BUILD ?= build/release
JOBS ?= $(shell nproc)
PREFIX ?= /usr/local
# Ninja (Debian's ninja-build, which make deps installs) where present: it starts a target's units
# before the libraries it links are done, so both cores stay busy. A build tree keeps the
# generator it was configured with.
GENERATOR = $(if $(and $(shell command -v ninja),$(if $(wildcard $(1)/CMakeCache.txt),,yes)),-G Ninja)

.PHONY: deps configure build cli run test test-sanitize bench install clean

deps:
	bash scripts/install-deps.sh

configure:
	cmake -S . -B $(BUILD) $(call GENERATOR,$(BUILD)) -DCMAKE_BUILD_TYPE=Release

build: configure
	cmake --build $(BUILD) -j $(JOBS)

# The CLI and its OpenVDB plugin only: the first picture without the tests and benchmarks.
cli: configure
	cmake --build $(BUILD) -j $(JOBS) --target sdftrace_cli

run: cli
	$(BUILD)/apps/sdftrace/sdftrace render -o demo.png

test: build
	ctest --test-dir $(BUILD) --output-on-failure -j $(JOBS)

# Every test built with AddressSanitizer and UndefinedBehaviorSanitizer (a separate build tree).
# -O1 with line tables only: the optimisation level the sanitizers are made for, and it compiles
# in less than half the time of -O2 -g (OpenVDB's templates above all), while reports keep their
# file and line.
test-sanitize:
	cmake -S . -B build/sanitize $(call GENERATOR,build/sanitize) -DCMAKE_BUILD_TYPE=RelWithDebInfo \
		"-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG" -DSDFT_SANITIZE=ON -DSDFT_BUILD_BENCH=OFF
	cmake --build build/sanitize -j $(JOBS)
	ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 \
		ctest --test-dir build/sanitize --output-on-failure -j $(JOBS)

bench: build
	$(BUILD)/bench/sdftrace_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only=true

install: build
	cmake --install $(BUILD) --prefix $(PREFIX)

clean:
	rm -rf build
