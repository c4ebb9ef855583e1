#!/usr/bin/env bash
# The GPU check: everything the CUDA backend must show on a real GPU, in one run that fits the few
# minutes a GPU machine is lent for (../shared/device/README.md says how to get one there).
#
#   bash scripts/gpu-check.sh OUTDIR                 # on the GPU machine, .gpu carried
#   bash scripts/gpu-check.sh --dry-run OUTDIR       # anywhere nvcc is: every step, no GPU
#   bash scripts/gpu-check.sh --dry-run --build-dir build/release OUTDIR   # reuse a CUDA build
#
# Steps: configure (CUDA on; skipped when --build-dir names a configured CUDA build), build only
# the kernels, the test binaries and the GPU benches, then every GPU test suite in its own process
# (a fault poisons only its own CUDA context; SDFT_CUDA_SYNC=1 names the kernel that faulted),
# the CPU side of the shared kernels (the per-pixel functions the GPU runs), `render --device`
# through the CLI, and the three GPU benches. Each step has its own time limit; the whole run is
# meant to finish in under 5 minutes on a 16-core GPU machine. In a dry run the GPU tests skip, the
# benches say "no GPU", and the CPU suites are only listed (ctest runs them): it proves that the
# script, its filters and its targets still work.
#
# OUTDIR gets one log per step and summary.md: one table of the steps and test suites (passed,
# failed, skipped, timed out, with seconds), then each figure against its target. Exits non-zero
# when a step fails.
set -uo pipefail

dry=0
build="build-gpu"
while [ $# -gt 1 ]; do
    case "$1" in
        --dry-run) dry=1; shift ;;
        --build-dir) build=$2; shift 2 ;;
        *) break ;;
    esac
done
out=${1:?usage: scripts/gpu-check.sh [--dry-run] [--build-dir DIR] OUTDIR}
mkdir -p "$out"
start=$(date +%s)
summary="$out/summary.md"
table="$out/.steps"
: > "$table"
failed=0
jobs=$(nproc)

# One row of the steps table: name, status, seconds.
row() { printf '| %s | %s | %s |\n' "$1" "$2" "$3" >> "$table"; }
now() { date +%s; }

# run NAME LIMIT CMD...: the command under a time limit, its output in OUTDIR/NAME.log; the row
# says passed, failed (status N), timed out, or skipped (a gtest run whose tests all skipped).
run() {
    local name=$1 limit=$2
    shift 2
    local t0 log="$out/$name.log" status
    t0=$(now)
    timeout "$limit" "$@" > "$log" 2>&1
    status=$?
    local seconds=$(($(now) - t0)) result
    if [ $status -eq 124 ]; then
        result="timed out after ${limit} s"
    elif [ $status -ne 0 ]; then
        result="FAILED (status $status)"
    elif grep -q '^\[  PASSED  \]' "$log"; then
        # gtest: how many ran and how many skipped (the GPU's tests skip without one)
        local passed skipped
        passed=$(grep -m1 '^\[  PASSED  \]' "$log" | grep -o '[0-9]\+' | head -1)
        skipped=$(grep -m1 '^\[  SKIPPED \] [0-9]' "$log" | grep -o '[0-9]\+' | head -1)
        result="passed (${passed:-0} ran${skipped:+, $skipped skipped})"
    else
        result="passed"
    fi
    case $result in passed*) ;; *) failed=1 ;; esac
    row "$name" "$result" "$seconds"
    echo "$(($(now) - start)) s: $name: $result" >&2
    return $status
}

finish() {
    {
        echo "# GPU check$([ $dry -eq 1 ] && echo ' (dry run: no GPU used)')"
        echo
        echo "$(date -u '+%Y-%m-%d %H:%M UTC'), $(($(now) - start)) s in all, $jobs cores"
        [ -n "${gpu_line:-}" ] && echo "GPU: $gpu_line"
        echo
        echo "| step | result | s |"
        echo "| --- | --- | --- |"
        cat "$table"
        if [ -s "$out/.figures" ]; then
            echo
            echo "| figure | measured | target | met |"
            echo "| --- | --- | --- | --- |"
            cat "$out/.figures"
        fi
    } > "$summary"
    rm -f "$table" "$out/.figures"
    cat "$summary"
    exit $failed
}

# --- set-up ---------------------------------------------------------------------------------
if [ $dry -eq 0 ]; then
    if [ ! -f .gpu/setup.sh ]; then
        row setup "FAILED: .gpu/setup.sh missing (run ../shared/device/fetch-debs.sh here, carry .gpu)" 0
        failed=1
        finish
    fi
    # shellcheck disable=SC1091
    source .gpu/setup.sh
    gpu_line=$(nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader 2>&1 |
        head -1)
fi
if [ -d "$build/CMakeFiles/sdftrace_gpu_kernels.dir" ]; then
    row configure "skipped: $build is a configured CUDA build" 0
else
    command -v nvcc > /dev/null || [ -x /usr/local/cuda/bin/nvcc ] || {
        row configure "FAILED: no nvcc" 0
        failed=1
        finish
    }
    # shellcheck disable=SC2086
    run configure 120 cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release -DSDFT_CUDA=ON \
        -DSDFT_MPI=OFF -DSDFT_PYTHON=OFF ${SDFT_CMAKE_ARGS:-} || finish
fi

# --- build: the kernels, the test binaries and the GPU benches, nothing else ----------------
run build 300 cmake --build "$build" -j "$jobs" --target sdftrace_gpu_kernels \
    sdftrace_unit_tests sdftrace_e2e_tests sdftrace_gpu_primary_bench sdftrace_gpu_direct_bench \
    sdftrace_gpu_bake_bench || { tail -30 "$out/build.log" >&2; finish; }

unit=$build/sdftrace_unit_tests
e2e=$build/tests/sdftrace_e2e_tests
export SDFT_CUDA_SYNC=1  # a fault is reported under the kernel that caused it

# --- GPU tests: each suite in its own process -----------------------------------------------
suites=$("$unit" --gtest_list_tests --gtest_filter='Gpu*' | grep -E '^[A-Za-z]' | grep -v '^Running' |
    tr -d '.')
[ -n "$suites" ] || { row "GPU suites" "FAILED: none found" 0; failed=1; }
for suite in $suites; do
    run "test-$suite" 90 "$unit" --gtest_filter="$suite.*"
done
run "test-DeviceCli" 90 "$e2e" --gtest_filter='DeviceCli.*'

# --- the CPU side of the shared kernels -----------------------------------------------------
cpu='PrimaryPixel.*:DirectPixel.*:WhittedPixel.*:PathPixel.*:PrimaryTriangles.*:Texture.*:SoftShadows.*:AmbientOcclusion.*:Tape.*:FieldTracer.*:GridDistance.*:GridTracer.MinMax*:Lbvh.*:LbvhWinding.*:WindingNumber.*:JumpFlood.*:RtsdfBake.*:RtsdfAccumulation.*:CompleteGrid.*'
if [ $dry -eq 1 ]; then
    count=$("$unit" --gtest_list_tests --gtest_filter="$cpu" | grep -c '^  ')
    if [ "$count" -gt 0 ]; then
        row "test-cpu-side" "listed: $count tests (ctest runs them)" 0
    else
        row "test-cpu-side" "FAILED: the filter matches no test" 0
        failed=1
    fi
else
    run "test-cpu-side" 120 "$unit" --gtest_filter="$cpu"
fi

# --- benches ----------------------------------------------------------------------------------
if [ $dry -eq 1 ]; then bench_args=(--runs 1 --cpu-runs 1); else bench_args=(--runs 20 --cpu-runs 3); fi
run bench-primary 120 "$build/bench/sdftrace_gpu_primary_bench" "${bench_args[@]}"
run bench-direct 150 "$build/bench/sdftrace_gpu_direct_bench" "${bench_args[@]}"
run bench-bake 120 "$build/bench/sdftrace_gpu_bake_bench" "${bench_args[@]}"
for b in primary direct bake; do
    grep -q 'no GPU: nothing to time' "$out/bench-$b.log" 2>/dev/null &&
        sed -i "s/^| bench-$b | passed |/| bench-$b | no GPU: nothing timed |/" "$table"
done

# --- figures against their targets ------------------------------------------------------------
# RTSDF's whole frame on the device (1920x1080, teapot regenerated, soft shadows, triangle
# primaries): at most 2 ms. Every GPU row of the primary and direct benches: faster than the CPU.
: > "$out/.figures"
if [ -f "$out/bench-direct.log" ]; then
    whole=$(grep -A2 '^| pose ms' "$out/bench-direct.log" | tail -1 | awk -F'|' '{v = $(NF-1); gsub(/ /, "", v); print v}')
    if [ -n "$whole" ]; then
        met=$(awk -v w="$whole" 'BEGIN { print (w <= 2.0) ? "yes" : "NO" }')
        echo "| RTSDF whole frame, ms | $whole | <= 2 | $met |" >> "$out/.figures"
    fi
fi
for b in primary direct; do
    [ -f "$out/bench-$b.log" ] || continue
    awk -F'|' -v bench="$b" '
        /^\| / && $(NF-1) ~ /[0-9.]+x *$/ {
            x = $(NF-1); gsub(/[ x]/, "", x)
            name = $2; gsub(/^ +| +$/, "", name)
            if (bench == "direct") { s = $3; gsub(/^ +| +$/, "", s); name = name " (" s ")" }
            printf "| %s %s, GPU / CPU | %sx | > 1x | %s |\n", bench, name, x, (x > 1 ? "yes" : "NO")
        }' "$out/bench-$b.log" >> "$out/.figures"
done
finish
