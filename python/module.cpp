// The `sdftrace` Python module (pybind11): scenes, fields, grids, mesh bakes and renders as numpy
// arrays (docs/python.md). The library's InputError (bad input a user can fix) is raised as
// ValueError with the same one-line message.
#include <pybind11/pybind11.h>

#include "bindings.h"
#include "sdftrace/core/build_info.h"
#include "sdftrace/core/error.h"
#include "sdftrace/exec/simd.h"
#include "sdftrace/gpu/gpu_device.h"

PYBIND11_MODULE(_sdftrace, m) {
    m.doc() = "sdftrace: signed distance fields, baked and ray traced (C++ core)";
    pybind11::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const sdft::InputError& e) {
            PyErr_SetString(PyExc_ValueError, e.what());
        }
    });
    sdft::py::bindField(m);
    sdft::py::bindGrid(m);
    sdft::py::bindScene(m);
    sdft::py::bindImages(m);
    sdft::py::bindQuery(m);
    m.attr("__version__") = sdft::buildInfo().version;
    m.def(
        "build_info",
        [] {
            const sdft::BuildInfo& b = sdft::buildInfo();
            pybind11::dict d;
            d["version"] = b.version;
            d["revision"] = b.revision;
            d["build_type"] = b.buildType;
            d["compiler"] = b.compiler;
            d["cuda"] = b.cuda;
            d["cuda_version"] = b.cudaVersion;
            d["cuda_architectures"] = b.cudaArchitectures;
            d["openvdb"] = b.openvdbVersion;
            d["embree"] = b.embreeVersion;
            d["tbb"] = b.tbbVersion;
            d["mpi"] = b.mpi;
            d["video"] = b.video;
            d["viewer"] = b.viewer;
            d["simd"] = sdft::simdLevelName(sdft::simdLevel());
            return d;
        },
        "What this build of sdftrace is and includes, as `sdftrace --version` prints it: a dict "
        "with version, revision (git), build_type, compiler, cuda (bool), cuda_version, "
        "cuda_architectures, openvdb, embree, tbb (their versions), mpi, video, viewer (bool) and "
        "simd (the SIMD level chosen at run time).");
    m.def(
        "gpu_info",
        [] {
            const sdft::GpuInfo& g = sdft::gpuInfo();
            pybind11::dict d;
            d["present"] = g.present;
            d["name"] = g.name;
            d["memory_bytes"] = g.memoryBytes;
            d["compute_capability"] = pybind11::make_tuple(g.computeMajor, g.computeMinor);
            d["why"] = g.why;
            return d;
        },
        "The GPU that device='cuda' or 'auto' would use: a dict with present (bool), name, "
        "memory_bytes, compute_capability (major, minor) and why (when not present: what is "
        "missing, in one sentence).");
}
