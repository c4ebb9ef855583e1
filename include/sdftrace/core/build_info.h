// What this build of sdftrace is and what it includes (`sdftrace --version`,
// `sdftrace.build_info()` in Python).
#pragma once

#include <string>

namespace sdft {

struct BuildInfo {
    const char* version;            // the project's version, "0.1.0"
    const char* revision;           // git revision at build time ("abc1234", "+" if modified), or
                                    // "unknown" outside a git checkout
    const char* buildType;          // CMake's build type
    const char* compiler;           // the C++ compiler and its version
    bool cuda;                      // the CUDA backend (--device cuda)
    const char* cudaVersion;        // the CUDA toolkit's version, "" without CUDA
    const char* cudaArchitectures;  // the GPU architectures compiled for, "" without CUDA
    const char* openvdbVersion;     // OpenVDB, loaded as a plugin for .vdb output and meshing
    const char* embreeVersion;      // Embree 3: mesh bakes' BVH, triangle primaries
    const char* tbbVersion;         // oneTBB: the CPU's threads
    bool mpi;                       // distributed renders and bakes under mpirun
    bool video;                     // H.264 output through FFmpeg's libraries
    bool viewer;                    // `sdftrace view` (GLFW, OpenGL, Dear ImGui)
    bool python;                    // the Python module was built beside this library
};

const BuildInfo& buildInfo();

// The version line and one line per component, as `sdftrace --version` prints it; `simd` names
// the SIMD level chosen at run time (exec/simd.h).
std::string describeBuild(const std::string& simd);

}  // namespace sdft
