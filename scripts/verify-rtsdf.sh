#!/usr/bin/env bash
# RTSDF's single bake (sdftrace bake --method rtsdf --dense --verify) against the exact bake on
# every mesh of data/meshes at x = 1, 2, 8, 64 rays: one line per case with the band error
# (mean, p99, max in voxels) and the wrong signs (all, and beyond half a voxel of the surface).
#
#   bash scripts/verify-rtsdf.sh [CELLS] [SDFTRACE]      (default 96, build/release/apps/sdftrace/sdftrace)
set -euo pipefail
cells=${1:-96}
sdftrace=${2:-build/release/apps/sdftrace/sdftrace}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
echo "| mesh | x | band mean / p99 / max (voxels) | wrong signs | beyond half a voxel |"
echo "| --- | --- | --- | --- | --- |"
for mesh in elephant-with-holes teapot bunny_npm suzanne stanford-bunny; do
    for rays in 1 2 8 64; do
        report=$("$sdftrace" bake "data/meshes/$mesh.obj" -o "$out/v.sdfg" --method rtsdf \
            --rays "$rays" --res "$cells" --dense --verify -q 2>&1)
        band=$(sed -nE 's/.*narrow band .*mean ([0-9.]+), p99 ([0-9.]+), max ([0-9.]+).*/\1 \/ \2 \/ \3/p' <<<"$report")
        signs=$(sed -nE 's/.*: ([0-9.]+)% of [0-9]+ vertices with the wrong sign \(([0-9.]+)%.*/\1% | \2%/p' <<<"$report")
        echo "| $mesh | $rays | $band | $signs |"
    done
done
