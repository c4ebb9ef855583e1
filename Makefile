# Thin wrapper over CMake. `make run` renders the demo; `make test` builds and runs every test.
BUILD ?= build/release
JOBS ?= $(shell nproc)

.PHONY: deps configure build run test test-sanitize bench clean

deps:
	bash scripts/install-deps.sh

configure:
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release

build: configure
	cmake --build $(BUILD) -j $(JOBS)

run: build
	$(BUILD)/apps/sdftrace/sdftrace render -o demo.png

test: build
	ctest --test-dir $(BUILD) --output-on-failure -j $(JOBS)

# Every test built with AddressSanitizer and UndefinedBehaviorSanitizer (a separate build tree).
test-sanitize:
	cmake -S . -B build/sanitize -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSDFT_SANITIZE=ON -DSDFT_BUILD_BENCH=OFF
	cmake --build build/sanitize -j $(JOBS)
	ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 \
		ctest --test-dir build/sanitize --output-on-failure -j $(JOBS)

bench: build
	$(BUILD)/bench/sdftrace_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only=true

clean:
	rm -rf build
