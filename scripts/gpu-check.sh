#!/usr/bin/env bash
# The GPU check of issue 14, run on the GPU machine (../shared/device/README.md) from the project's
# root with .gpu carried (`bash ../shared/device/fetch-debs.sh libzstd-dev` here makes it):
#
#   bash scripts/gpu-check.sh "$OUT"
#
# Configures with CUDA, builds the unit tests, the CLI with its end-to-end tests and the GPU
# benches, runs the GPU tests (and the CPU tests of the code the kernels share), `render --device`
# through the CLI, then the benches; everything goes to OUTDIR: configure.log, build.log,
# tests.log, cli.log, bench.md, direct.md, bake.md, summary.txt. Meant to finish in well under 6 minutes
# (the build is most of it). Exits non-zero when a step fails; summary.txt says which.
set -uo pipefail
out=${1:?usage: scripts/gpu-check.sh OUTDIR}
mkdir -p "$out"
start=$(date +%s)
summary="$out/summary.txt"
: > "$summary"
step() { echo "$(($(date +%s) - start)) s: $*" | tee -a "$summary"; }
fail() { step "FAILED: $*"; exit 1; }

[ -f .gpu/setup.sh ] || fail ".gpu/setup.sh missing: run ../shared/device/fetch-debs.sh here and carry .gpu"
# shellcheck disable=SC1091
source .gpu/setup.sh
nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader >> "$summary" 2>&1 ||
    step "nvidia-smi did not answer"
nvcc --version | tail -1 >> "$summary"

step "configure"
# shellcheck disable=SC2086
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DSDFT_CUDA=ON -DSDFT_MPI=OFF -DSDFT_PYTHON=OFF \
    $SDFT_CMAKE_ARGS > "$out/configure.log" 2>&1 || fail "configure (configure.log)"
step "build"
cmake --build build-gpu -j"$(nproc)" --target sdftrace_gpu_kernels sdftrace_unit_tests sdftrace_e2e_tests \
    sdftrace_gpu_primary_bench sdftrace_gpu_direct_bench sdftrace_gpu_bake_bench \
    > "$out/build.log" 2>&1 || { tail -40 "$out/build.log" >> "$summary"; fail "build (build.log)"; }

step "tests"
status=0
timeout 120 build-gpu/sdftrace_unit_tests \
    --gtest_filter='Gpu*:PrimaryPixel.*:DirectPixel.*:WhittedPixel.*:PathPixel.*:PrimaryTriangles.*:Texture.*:SoftShadows.*:AmbientOcclusion.*:Tape.*:FieldTracer.*:GridDistance.*:GridTracer.MinMax*:Lbvh.*:LbvhWinding.*:WindingNumber.*:WindingPacket.*:JumpFlood.*:RtsdfBake.*:RtsdfAccumulation.*:CompleteGrid.*' \
    > "$out/tests.log" 2>&1 || status=$?
grep -E "^\[  (PASSED|FAILED|SKIPPED) " "$out/tests.log" >> "$summary"
grep -E "near:|far :|variant [0-9]:|\[ gpu bake \]" "$out/tests.log" >> "$summary"
[ $status -eq 0 ] || step "FAILED: tests (tests.log), status $status"
cli=0
timeout 60 build-gpu/tests/sdftrace_e2e_tests --gtest_filter='DeviceCli.*' > "$out/cli.log" 2>&1 ||
    cli=$?
grep -E "^\[  (PASSED|FAILED|SKIPPED) " "$out/cli.log" >> "$summary"
[ $cli -eq 0 ] || { step "FAILED: render --device (cli.log), status $cli"; status=1; }

step "bench"
timeout 150 build-gpu/bench/sdftrace_gpu_primary_bench --runs 20 --cpu-runs 3 > "$out/bench.md" 2>&1 ||
    { step "FAILED: bench (bench.md)"; status=1; }
cat "$out/bench.md" >> "$summary"
timeout 120 build-gpu/bench/sdftrace_gpu_direct_bench --runs 10 --cpu-runs 3 > "$out/direct.md" 2>&1 ||
    { step "FAILED: direct bench (direct.md)"; status=1; }
cat "$out/direct.md" >> "$summary"
timeout 120 build-gpu/bench/sdftrace_gpu_bake_bench --runs 10 --cpu-runs 1 > "$out/bake.md" 2>&1 ||
    { step "FAILED: bake bench (bake.md)"; status=1; }
cat "$out/bake.md" >> "$summary"
step "done"
exit $status
