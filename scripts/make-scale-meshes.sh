#!/usr/bin/env bash
# The meshes of the issue-15 scale benchmark (bench/scale_bench.cpp), made with sdftrace itself:
# closed remeshes of the open scans in data/meshes (baked exactly with winding-number signs, then
# contoured by `sdftrace mesh`: OpenVDB's meshToLevelSet needs closed meshes for a signed level
# set), and a 1.1M-triangle displaced rock from examples/rock.json.
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
ls -l "$out"
