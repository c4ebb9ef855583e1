#!/usr/bin/env bash
# Fuzzes sdftrace's input paths with libFuzzer (clang from Debian) for SECONDS each:
#   scripts/fuzz.sh SECONDS [TARGET ...]      targets: scene sdfg vdb grid_text mesh mesh_anim points mesh_ply mesh_stl
#                                             mesh_off mesh_obj mesh_gltf (default: all)
# Builds build/fuzz (clang, coverage instrumentation, AddressSanitizer, UndefinedBehaviorSanitizer),
# runs the targets side by side (FUZZ_JOBS at a time, default: the number of cores), each on a
# working copy of its stored corpus (fuzz/corpus/TARGET). Prints executions per target and exits
# non-zero on any finding: the crashing or slow input is saved under build/fuzz/findings/TARGET/
# (add it to fuzz/corpus/TARGET once fixed: the corpora run as ordinary tests). With FUZZ_MERGE=1
# the inputs that found new coverage are merged back into fuzz/corpus/TARGET.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:?usage: scripts/fuzz.sh SECONDS [TARGET ...]}
shift
targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=(scene sdfg vdb grid_text mesh mesh_anim points mesh_ply mesh_stl mesh_off mesh_obj mesh_gltf)
build=build/fuzz
jobs=${FUZZ_JOBS:-$(nproc)}

# clang and libFuzzer come from Debian (not part of make deps: only fuzzing needs them).
if ! command -v clang++ >/dev/null || ! ls /usr/lib/llvm-*/lib/clang/*/lib/linux/libclang_rt.fuzzer-x86_64.a >/dev/null 2>&1; then
    echo "fuzz.sh: needs clang and libFuzzer: sudo apt-get install clang libclang-rt-14-dev" >&2
    exit 2
fi

CC=clang CXX=clang++ cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSDFT_FUZZ=ON \
    -DSDFT_BUILD_TESTS=OFF -DSDFT_BUILD_BENCH=OFF >/dev/null
cmake --build "$build" -j "$(nproc)" --target "${targets[@]/#/fuzz_}"

run() {
    local t=$1 work="$build/corpus/$1" findings="$build/findings/$1/"
    mkdir -p "$work" "$findings"
    cp -n fuzz/corpus/"$t"/* "$work"/ 2>/dev/null || true
    # Leaks are not findings here (OpenVDB keeps process-lifetime registries); timeouts and
    # inputs over 2 GB of memory are. The targets replace operator new with the allocation guard
    # (apps/sdftrace/allocation_guard.cpp) while libFuzzer's own code keeps ASan's, so ASan's
    # new/free pairing check cannot apply. A target's dictionary is fuzz/dict/TARGET.dict.
    local dict=()
    [ -f fuzz/dict/"$t".dict ] && dict=(-dict=fuzz/dict/"$t".dict)
    ASAN_OPTIONS=detect_leaks=0:abort_on_error=1:alloc_dealloc_mismatch=0 UBSAN_OPTIONS=print_stacktrace=1 \
        "$build/fuzz_$t" "${dict[@]}" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
        -print_final_stats=1 -artifact_prefix="$findings" "$work" >"$build/$t.log" 2>&1
}

pids=()
status=0
for t in "${targets[@]}"; do
    run "$t" &
    pids+=($!)
    if [ ${#pids[@]} -ge "$jobs" ]; then
        wait "${pids[0]}" || status=1
        pids=("${pids[@]:1}")
    fi
done
for p in "${pids[@]}"; do wait "$p" || status=1; done

echo "revision $(git describe --always --dirty 2>/dev/null || echo unknown), $(date -u +%Y-%m-%d), ${seconds} s per target"
printf '%-10s %14s %10s %9s  %s\n' target executions exec/s corpus result
for t in "${targets[@]}"; do
    log="$build/$t.log"
    execs=$(grep -o 'stat::number_of_executed_units: [0-9]*' "$log" | grep -o '[0-9]*$' || echo 0)
    rate=$(grep -o 'stat::average_exec_per_sec: [0-9]*' "$log" | grep -o '[0-9]*$' || echo 0)
    corpus=$(find "$build/corpus/$t" -type f | wc -l)
    result="no finding"
    if ls "$build/findings/$t/"* >/dev/null 2>&1; then result="FINDING: $(ls "$build/findings/$t/")"; status=1; fi
    printf '%-10s %14s %10s %9s  %s\n' "$t" "$execs" "$rate" "$corpus" "$result"
    if [ "${FUZZ_MERGE:-0}" = 1 ]; then
        ASAN_OPTIONS=detect_leaks=0:alloc_dealloc_mismatch=0 "$build/fuzz_$t" -merge=1 fuzz/corpus/"$t" "$build/corpus/$t" \
            >>"$log" 2>&1
    fi
done
exit $status
