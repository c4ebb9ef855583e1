#!/usr/bin/env bash
# Installs the build tree BUILD into a temporary prefix, then uses it as a user would from a new
# shell: the CLI from PATH, `import sdftrace` from another directory, and a CMake project outside
# the source tree built against find_package(sdftrace). Run by ctest as Install.*.
#   tests/install/install_test.sh BUILD_DIR
set -euo pipefail
build=$(cd "$1" && pwd)
here=$(cd "$(dirname "$0")" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
prefix=$work/prefix

cmake --install "$build" --prefix "$prefix" > "$work/install.log"
for f in bin/sdftrace include/sdftrace/scene/parse_scene.h lib/cmake/sdftrace/sdftraceConfig.cmake \
         lib/libsdftrace.a lib/sdftrace/libsdftrace_openvdb.so share/sdftrace/examples/demo.json \
         share/doc/sdftrace/README.md; do
    [ -e "$prefix/$f" ] || { echo "install_test: $f was not installed"; exit 1; }
done
if [ -e "$build/apps/sdftrace/libsdftrace_video.so" ] && \
   [ ! -e "$prefix/lib/sdftrace/libsdftrace_video.so" ]; then
    echo "install_test: lib/sdftrace/libsdftrace_video.so was not installed"; exit 1
fi
# Internals stay out of the installed headers.
for f in gpu/gpu_render.h render/direct_pixel.h trace/grid_dda.h; do
    [ ! -e "$prefix/include/sdftrace/$f" ] || { echo "install_test: internal $f installed"; exit 1; }
done

# A new shell: nothing of the build tree on any path, the installed CLI from PATH.
cd "$work"
env -i HOME="$work" PATH="$prefix/bin:/usr/bin:/bin" bash -c '
    set -euo pipefail
    sdftrace --version | head -1 | grep -q "^sdftrace [0-9]"
    sdftrace render --width 80 --height 45 -o demo.png
    [ -s demo.png ]
    sdftrace bake '"$prefix"'/share/sdftrace/examples/csg.json --bounds -4,0,-1,4,2,3 --res 32 -o csg.sdfg
    sdftrace convert csg.sdfg csg.vdb   # the OpenVDB plugin, found from the installed tree
    [ -s csg.vdb ]
    if [ -e '"$prefix"'/lib/sdftrace/libsdftrace_video.so ]; then   # the video plugin, likewise
        sdftrace render --width 64 --height 36 --time 0:0.1 --fps 20 -o demo.mp4
        [ -s demo.mp4 ]
    fi
'
echo "install_test: CLI ok"

pydir=$(ls -d "$prefix"/lib/python3*/dist-packages 2>/dev/null | head -1 || true)
if [ -n "$pydir" ] && [ -d "$pydir/sdftrace" ]; then
    env -i HOME="$work" PATH=/usr/bin:/bin PYTHONPATH="$pydir" python3 -c '
import os, sdftrace
assert sdftrace.__file__.startswith(os.environ["PYTHONPATH"]), sdftrace.__file__
s = sdftrace.Scene.from_dict({"objects": [{"type": "sphere", "radius": 1}]})
import numpy as np
d = s.field.evaluate(np.array([[0, 0, 2]], dtype=np.float32))
assert abs(float(np.ravel(d)[0]) - 1) < 1e-5, d
print("install_test: python", sdftrace.__version__, "ok")
'
fi

cmake -S "$here/consumer" -B "$work/consumer" -DCMAKE_PREFIX_PATH="$prefix" \
      -DCMAKE_BUILD_TYPE=Release > "$work/consumer.log" 2>&1 || { cat "$work/consumer.log"; exit 1; }
cmake --build "$work/consumer" -j 2 >> "$work/consumer.log" 2>&1 || { cat "$work/consumer.log"; exit 1; }
"$work/consumer/consumer" "$work/consumer.png"
[ -s "$work/consumer.png" ]
echo "install_test: consumer project ok"
