#!/usr/bin/env bash
# Installs every Debian 12 package sdftrace needs to build, test and benchmark. Idempotent.
set -euo pipefail
packages=(
    build-essential cmake make pkg-config
    ninja-build           # the build (make uses it where present)
    libtbb-dev            # parallel tiles (oneTBB)
    libopenexr-dev        # EXR output
    libstb-dev            # PNG output (stb_image_write), legend text (stb_easy_font)
    nlohmann-json3-dev    # scene files
    libcli11-dev          # command line
    libopenvdb-dev        # .vdb level sets (interop) and the OpenVDB baseline in bench/
    libboost-iostreams-dev libblosc-dev  # OpenVDB's CMake module needs them; sdftrace's .vdb reader too
    zlib1g-dev            # sdftrace's .vdb reader (zip-compressed level sets)
    libzstd-dev           # compressed .sdfg files (version 3)
    libassimp-dev         # mesh loading (OBJ, PLY, STL, OFF, glTF; skinned and morph animation)
    assimp-testmodels     # tests: third-party animated meshes (glTF morph targets, a skinned .x)
    libembree-dev         # BVH closest-point queries and ray casts for mesh baking
    libavcodec-dev libavformat-dev libswscale-dev libavutil-dev  # video output (H.264, FFmpeg)
    pybind11-dev python3-dev python3-numpy  # the Python module (python/)
    python3-pytest        # its tests
    python3-pip python3-venv python3-setuptools  # pip install . (offline, --no-build-isolation)
    libglfw3-dev libimgui-dev  # the viewer (sdftrace view): GLFW + OpenGL, Dear ImGui
    xvfb xauth libgl1-mesa-dri  # its tests: a virtual X server with Mesa's software OpenGL
    libopenmpi-dev openmpi-bin  # mpirun -np N sdftrace render|bake (SDFT_MPI)
    libgtest-dev          # tests
    libbenchmark-dev      # bench/
)
missing=()
for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
    echo "install-deps: all packages present"
    exit 0
fi
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
