#!/usr/bin/env bash
# The meshes of the scale and grid I/O benchmarks (bench/scale_bench.cpp, bench/grid_io_bench.cpp),
# made with sdftrace itself: closed remeshes of the open scans in data/meshes (baked exactly with
# winding-number signs, then contoured by `sdftrace mesh`: OpenVDB's meshToLevelSet needs closed
# meshes for a signed level set), a 1.1M-triangle displaced rock from examples/rock.json, and two
# of a few million triangles: the rock at 4.1M and the Stanford bunny's remesh at 5.5M.
#   scripts/make-scale-meshes.sh [OUT_DIR]   (default /tmp/sdftrace-meshes)
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-/tmp/sdftrace-meshes}"
bin=build/release/apps/sdftrace/sdftrace
mkdir -p "$out"
for m in stanford-bunny teapot elephant-with-holes; do
    "$bin" mesh -q "data/meshes/$m.obj" --res 320 -o "$out/$m-closed.ply"
done
"$bin" mesh -q examples/rock.json --res 600 -o "$out/rock.ply"
"$bin" mesh -q examples/rock.json --res 1150 -o "$out/rock-4m.ply"
"$bin" mesh -q data/meshes/stanford-bunny.obj --res 900 -o "$out/stanford-bunny-5m.ply"
ls -l "$out"
