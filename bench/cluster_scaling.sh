#!/usr/bin/env bash
# Strong scaling of `mpirun -np N sdftrace render|bake` on this machine (README, "MPI";
# docs/cluster.md checks its model against these): 1, 2 and 4 ranks with one thread each (4 ranks
# oversubscribe a 2-core machine), the median of RUNS runs of each. Reports the whole job's wall
# time (mpirun's start and MPI's set-up included) and the phase sdftrace itself times (render:
# the summary's seconds; bake: its total, load to write), the speed-up against 1 rank and the efficiency
# speed-up / min(N, cores).
#   bash bench/cluster_scaling.sh [path/to/sdftrace]        RUNS=5 for steadier medians,
#   ONLY=bake for the jobs whose name holds "bake"
set -euo pipefail
cli=${1:-build/release/apps/sdftrace/sdftrace}
runs=${RUNS:-3}
root=$(cd "$(dirname "$0")/.." && pwd)
cores=$(nproc)
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

median() { sort -g | awk '{v[NR]=$1} END {print v[int((NR+1)/2)]}'; }

# job NAME PHASE-REGEX ARGS...: one row per rank count.
job() {
    local name=$1 phase=$2
    shift 2
    [[ -n "${ONLY:-}" && "$name" != *"$ONLY"* ]] && return 0
    local base_wall="" base_phase=""
    for n in 1 2 4; do
        local walls=() phases=()
        for ((r = 0; r < runs; ++r)); do
            local t0 t1
            t0=$(date +%s.%N)
            mpirun -np "$n" "$cli" "$@" --threads 1 >"$out/log" 2>&1
            t1=$(date +%s.%N)
            walls+=("$(echo "$t1 - $t0" | bc -l)")
            phases+=("$(grep -oE "$phase" "$out/log" | grep -oE '[0-9.]+' | tail -1)")
        done
        local wall ph
        wall=$(printf '%s\n' "${walls[@]}" | median)
        ph=$(printf '%s\n' "${phases[@]}" | median)
        [ -z "$base_wall" ] && base_wall=$wall && base_phase=$ph
        local ideal=$((n < cores ? n : cores))
        printf '| %s | %d | %.3f | %.3f | %.2f | %.2f |\n' "$name" "$n" "$wall" "$ph" \
            "$(echo "$base_phase / $ph" | bc -l)" "$(echo "$base_phase / $ph / $ideal" | bc -l)"
    done
}

echo "| job | ranks | wall s | phase s | speed-up | efficiency |"
echo "|---|---|---|---|---|---|"
job "render city 640x360" 'in [0-9.]+ s on' render "$root/examples/city.json" --width 640 \
    --height 360 -q -o "$out/city.png"
job "path trace 320x180, 16 spp" 'in [0-9.]+ s on' render "$root/examples/path.json" --width 320 \
    --height 180 --spp 16 -q -o "$out/path.png"
job "animation 16 frames 192x108" 'in [0-9.]+ s, render' render "$root/examples/animated.json" \
    --time 0:2 --fps 8 --width 192 --height 108 -q --frame-pattern "$out/f%03d.png"
job "bake bunny 256, sparse exact" 'total [0-9.]+ s' \
    bake "$root/data/meshes/stanford-bunny.obj" --res 256 -o "$out/bunny.sdfg"
job "bake elephant 384, open mesh" 'total [0-9.]+ s' \
    bake "$root/data/meshes/elephant-with-holes.obj" --res 384 -o "$out/elephant.sdfg"
