// sdftrace.Grid and sdftrace.bake: sampled fields as numpy arrays, mesh bakes from arrays or files,
// grid files, and the way back to triangles.
#include <pybind11/stl.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <memory>
#include <optional>
#include <vector>

#include "bindings.h"
#include "sdftrace/bake/bake_options.h"
#include "sdftrace/bake/extract_surface.h"
#include "sdftrace/bake/mesh_bake.h"
#include "sdftrace/core/error.h"
#include "sdftrace/core/memory_budget.h"
#include "sdftrace/io/grid_file.h"
#include "sdftrace/io/mesh_io.h"
#include "sdftrace/scene/prepare_scene.h"

namespace sdft::py {

namespace {

// A read-only numpy view of `data` that keeps `owner` alive (no copy).
template <typename Owner>
pyb::array_t<float> viewOf(std::shared_ptr<Owner> owner, const float* data,
                           std::vector<pyb::ssize_t> shape, std::vector<pyb::ssize_t> strides) {
    auto* keep = new std::shared_ptr<Owner>(std::move(owner));
    pyb::capsule base(keep, [](void* p) { delete static_cast<std::shared_ptr<Owner>*>(p); });
    pyb::array_t<float> a(shape, strides, data, base);
    a.attr("setflags")(pyb::arg("write") = false);
    return a;
}

// The vertex values as an (nx+1) x (ny+1) x (nz+1) array indexed [i, j, k]: the grid's own
// samples for a dense grid (x fastest: Fortran order), a copy for a sparse one.
pyb::array_t<float> gridArray(const PyGrid& g) {
    const GridShape& s = g.grid->shape();
    const pyb::ssize_t nx = s.vertices(0), ny = s.vertices(1), nz = s.vertices(2);
    const std::vector<pyb::ssize_t> shape{nx, ny, nz};
    const std::vector<pyb::ssize_t> strides{4, 4 * nx, 4 * nx * ny};
    if (g.grid->kind() == GridKind::Dense)
        return viewOf(g.grid, g.grid->samples().data(), shape, strides);
    checkMemoryBudget(4.0 * static_cast<double>(s.vertexCount()), "Grid.to_numpy",
                      "every vertex of a sparse grid",
                      "sample the region you need with Grid.sample");
    std::shared_ptr<std::vector<float>> values;
    {
        pyb::gil_scoped_release release;
        values = std::make_shared<std::vector<float>>(g.grid->vertexSamples());
    }
    return viewOf(values, values->data(), shape, strides);
}

pyb::dict gridInfo(const PyGrid& g) {
    const Grid& grid = *g.grid;
    const GridShape& s = grid.shape();
    pyb::dict d;
    d["kind"] = grid.kind() == GridKind::Dense ? "dense" : "sparse";
    d["cells"] = pyb::make_tuple(s.cells[0], s.cells[1], s.cells[2]);
    d["origin"] = pyb::make_tuple(s.origin.x, s.origin.y, s.origin.z);
    d["voxel_size"] = s.voxelSize;
    d["bounds"] = boundsToPython(s.bounds());
    d["surface_bounds"] = boundsToPython(grid.surfaceBounds());
    d["lipschitz"] = grid.lipschitz();
    d["memory_bytes"] = grid.memoryBytes();
    d["stored_samples"] = grid.storedSamples();
    d["texcoords"] = !grid.texcoords().empty();
    if (grid.kind() == GridKind::Sparse) {
        size_t inside = 0, outside = 0, surface = 0;
        grid.blockCounts(inside, outside, surface);
        d["block_size"] = grid.blockSize();
        d["blocks"] = pyb::dict(pyb::arg("inside") = inside, pyb::arg("outside") = outside,
                                pyb::arg("surface") = surface);
        d["background"] = grid.background();
    }
    return d;
}

// The mesh of bake(): a file path, or vertices (N x 3) and faces (M x 3 indices into them).
TriangleMesh meshArgument(const pyb::handle& mesh, const pyb::handle& faces, MeshReport& report) {
    if (pyb::isinstance<pyb::str>(mesh) || pyb::hasattr(mesh, "__fspath__")) {
        if (!faces.is_none())
            throw InputError("bake: faces: give a mesh file or vertices and faces, not both");
        const std::string path = pathArgument(mesh);
        return loadMesh(path, &report);
    }
    if (faces.is_none())
        throw InputError(
            "bake: faces: expected an M x 3 array of vertex indices with the "
            "vertices (or a mesh file path instead of both)");
    const FloatArray v = pointsArgument(mesh, "bake: vertices");
    using IndexArray = pyb::array_t<int64_t, pyb::array::c_style | pyb::array::forcecast>;
    IndexArray f = IndexArray::ensure(faces);
    if (!f) {
        PyErr_Clear();
        throw InputError("bake: faces: expected an M x 3 array of integer vertex indices");
    }
    if (f.ndim() != 2 || f.shape(1) != 3)
        throw InputError("bake: faces: expected an M x 3 array of vertex indices, got " +
                         std::to_string(f.ndim()) + " dimensions");
    const int64_t n = v.shape(0);
    std::vector<Vec3> positions(static_cast<size_t>(n));
    for (int64_t i = 0; i < n; ++i)
        positions[i] = Vec3(v.data()[3 * i], v.data()[3 * i + 1], v.data()[3 * i + 2]);
    std::vector<std::array<uint32_t, 3>> triangles(static_cast<size_t>(f.shape(0)));
    const int64_t* idx = f.data();
    for (size_t t = 0; t < triangles.size(); ++t) {
        for (int c = 0; c < 3; ++c) {
            const int64_t k = idx[3 * t + c];
            if (k < 0 || k >= n)
                throw InputError("bake: faces: face " + std::to_string(t) + " names vertex " +
                                 std::to_string(k) + "; expected indices in [0, " +
                                 std::to_string(n) + ")");
            triangles[t][c] = static_cast<uint32_t>(k);
        }
    }
    TriangleMesh clean = cleanMesh(positions, triangles, report);
    if (clean.triangles.empty())
        throw InputError("bake: faces: no triangle with area remains after cleaning (" +
                         report.summary() + ")");
    if (std::string problem = meshRangeProblem(clean); !problem.empty())
        throw InputError("bake: vertices: " + problem);
    return clean;
}

PyGrid bake(const pyb::handle& mesh, const pyb::handle& faces, int resolution,
            const std::string& method, float band, bool dense, const std::string& sign, int block,
            float padding, bool progress, const std::string& closest, const std::string& jfaVariant,
            float beta, int rays, float mask, const std::string& device) {
    const Device asked = deviceArgument(device, "bake");
    // Checked by the bake option table (bake/bake_options.h), as the CLI's flags and scene files.
    MeshBakeOptions o;
    setBakeOption(o, "resolution", resolution, "bake");
    setBakeOption(o, "method", method, "bake");
    setBakeOption(o, "band", band, "bake");
    setBakeOption(o, "dense", dense ? 1 : 0, "bake");
    setBakeOption(o, "sign", sign, "bake");
    setBakeOption(o, "block", block, "bake");
    setBakeOption(o, "padding", padding, "bake");
    setBakeOption(o, "closest", closest, "bake");
    setBakeOption(o, "jfa_variant", jfaVariant, "bake");
    setBakeOption(o, "beta", beta, "bake");
    setBakeOption(o, "rays", rays, "bake");
    setBakeOption(o, "mask", mask, "bake");
    o.progress = progress;
    validateMeshBakeOptions(o);
    const DeviceChoice choice = chooseBakeDevice(asked, o, "bake: device = '" + device + "'");
    if (asked == Device::Auto && !choice.gpu) warnCpuFallback("bake", choice.why);
    MeshReport report;
    const TriangleMesh m = meshArgument(mesh, faces, report);
    pyb::gil_scoped_release release;
    return PyGrid{sceneGrid(bakeMeshOn(choice.gpu, m, o).grid)};
}

PyGrid gridFromNumpy(const pyb::handle& values, std::array<float, 3> origin, float voxelSize,
                     bool sparse, int block, float band) {
    FloatArray a = FloatArray::ensure(values);
    if (!a || a.ndim() != 3 || a.shape(0) < 2 || a.shape(1) < 2 || a.shape(2) < 2) {
        PyErr_Clear();
        throw InputError(
            "Grid.from_numpy: values: expected a 3-D array of at least "
            "2 x 2 x 2 vertex distances indexed [i, j, k]");
    }
    if (!(voxelSize > 0) || !std::isfinite(voxelSize))
        throw InputError("Grid.from_numpy: voxel_size: expected a finite size > 0");
    if (block != 4 && block != 8) throw InputError("Grid.from_numpy: block: expected 4 or 8");
    GridShape s;
    for (int i = 0; i < 3; ++i) s.cells[i] = static_cast<int>(a.shape(i)) - 1;
    s.origin = Vec3(origin[0], origin[1], origin[2]);
    s.voxelSize = voxelSize;
    std::vector<float> samples(s.vertexCount());
    const float* src = a.data();  // C order: [i][j][k], k fastest
    const size_t nx = a.shape(0), ny = a.shape(1), nz = a.shape(2);
    for (size_t i = 0; i < nx; ++i)
        for (size_t j = 0; j < ny; ++j)
            for (size_t k = 0; k < nz; ++k) {
                const float v = src[(i * ny + j) * nz + k];
                if (!std::isfinite(v))
                    throw InputError("Grid.from_numpy: values[" + std::to_string(i) + ", " +
                                     std::to_string(j) + ", " + std::to_string(k) +
                                     "] is not finite (expected distances)");
                samples[(k * ny + j) * nx + i] = v;
            }
    pyb::gil_scoped_release release;
    return PyGrid{sceneGrid(sparse ? Grid::sparseFromDense(s, samples, block, band)
                                   : Grid::dense(s, std::move(samples)))};
}

pyb::object gridSample(const PyGrid& g, const pyb::handle& points, bool gradients,
                       std::optional<float> h) {
    const FloatArray p = pointsArgument(points, "sample: points");
    const float step = stepArgument(h, 0.5f * g.grid->shape().voxelSize, "sample");
    const GridView view = g.grid->view();
    return evaluatePoints(p, gradients, step, [view](const float* xyz, float* out, size_t count) {
        for (size_t i = 0; i < count; ++i)
            out[i] = view.sample(Vec3(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]));
    });
}

pyb::tuple gridToMesh(const PyGrid& g, float adaptivity, float isovalue) {
    if (!(adaptivity >= 0 && adaptivity <= 1))
        throw InputError("to_mesh: adaptivity: expected a number in [0, 1]");
    ExtractOptions o;
    o.adaptivity = adaptivity;
    o.isovalue = isovalue;
    TriangleMesh mesh;
    {
        pyb::gil_scoped_release release;
        mesh = extractSurface(*g.grid, o, "to_mesh");
    }
    pyb::array_t<float> v(
        std::vector<pyb::ssize_t>{static_cast<pyb::ssize_t>(mesh.positions.size()), 3});
    pyb::array_t<int32_t> f(
        std::vector<pyb::ssize_t>{static_cast<pyb::ssize_t>(mesh.triangles.size()), 3});
    float* vp = v.mutable_data();
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
        vp[3 * i] = mesh.positions[i].x;
        vp[3 * i + 1] = mesh.positions[i].y;
        vp[3 * i + 2] = mesh.positions[i].z;
    }
    int32_t* fp = f.mutable_data();
    for (size_t t = 0; t < mesh.triangles.size(); ++t)
        for (int c = 0; c < 3; ++c) fp[3 * t + c] = static_cast<int32_t>(mesh.triangles[t][c]);
    return pyb::make_tuple(v, f);
}

}  // namespace

Device deviceArgument(const std::string& name, const std::string& where) {
    Device d = Device::Cpu;
    if (!parseDevice(name, d))
        throw InputError(where + ": device = '" + name + "': expected one of " + kDevices);
    return d;
}

void warnCpuFallback(const std::string& where, const std::string& why) {
    const std::string message = where + ": device = 'auto': running on the CPU (" + why + ")";
    if (PyErr_WarnEx(PyExc_RuntimeWarning, message.c_str(), 1) < 0) throw pyb::error_already_set();
}

double bakeDefaultNumber(const char* key) { return findBakeOption(key)->defaultValue(); }

std::string bakeDefaultText(const char* key) { return findBakeOption(key)->defaultText(); }

std::string bakeOptionsDoc(std::initializer_list<const char*> keys) {
    std::string doc;
    for (const char* key : keys) {
        const BakeOption* o = findBakeOption(key);
        std::string accepted = o->accepted();
        if (o->type == OptionType::Bool) accepted = "True or False";
        doc += std::string(key) + ": " + o->doc + "; " + accepted + " [" +
               (o->type == OptionType::Bool ? (o->defaultValue() != 0 ? "True" : "False")
                                            : o->defaultText()) +
               "].\n";
    }
    return doc;
}

namespace {

// sdftrace.bake: its keywords, defaults and docstring from the bake option table.
void bindBake(pyb::module_& m) {
    static const std::string bakeDoc =
        "Bakes a triangle mesh to a signed distance Grid.\n\n"
        "mesh: a file path (OBJ, PLY, STL, OFF, glTF), or an N x 3 array of vertex positions.\n"
        "faces: with a vertex array, the M x 3 array of triangle vertex indices; None with a "
        "path.\n" +
        bakeOptionsDoc({"resolution", "method", "band", "dense", "sign", "block", "padding"}) +
        "progress: print the bake's stages and percentage on stderr.\n" +
        bakeOptionsDoc({"closest", "jfa_variant", "beta", "rays", "mask"}) +
        "device: where the bake runs: 'cpu'; 'cuda' (the GPU: method 'jfa' or 'rtsdf', signs by "
        "winding, or beta for jfa; ValueError saying why not); 'auto' (the GPU where it bakes "
        "the method, else the CPU with a warning saying why).\n"
        "\nRaises ValueError naming the argument for bad input.";
    m.def(
        "bake", &bake, pyb::arg("mesh"), pyb::arg("faces") = pyb::none(),
        pyb::arg("resolution") = bakeDefault<int>("resolution"),
        pyb::arg("method") = bakeDefaultText("method"),
        pyb::arg("band") = bakeDefault<float>("band"),
        pyb::arg("dense") = bakeDefault<bool>("dense"), pyb::arg("sign") = bakeDefaultText("sign"),
        pyb::arg("block") = std::stoi(bakeDefaultText("block")),
        pyb::arg("padding") = bakeDefault<float>("padding"), pyb::arg("progress") = false,
        pyb::arg("closest") = bakeDefaultText("closest"),
        pyb::arg("jfa_variant") = bakeDefaultText("jfa_variant"),
        pyb::arg("beta") = bakeDefault<float>("beta"), pyb::arg("rays") = bakeDefault<int>("rays"),
        pyb::arg("mask") = bakeDefault<float>("mask"), pyb::arg("device") = "cpu", bakeDoc.c_str());
}

}  // namespace

void bindGrid(pyb::module_& m) {
    pyb::class_<PyGrid>(m, "Grid",
                        "A sampled signed distance field: dense, or a sparse block grid with "
                        "per-block cell bit masks (Jamriska 2010, §3)")
        .def_static(
            "load",
            [](const pyb::handle& path) {
                const std::string p = pathArgument(path);
                pyb::gil_scoped_release release;
                return PyGrid{sceneGrid(loadGridFile(p))};
            },
            pyb::arg("path"),
            "Reads a grid file: `path` names a .sdfg, .vdb (OpenVDB float level set), .sdf "
            "(SDFGen) or .raw (with its .raw.json sidecar)")
        .def(
            "save",
            [](const PyGrid& g, const pyb::handle& path) {
                const std::string p = pathArgument(path);
                pyb::gil_scoped_release release;
                saveGridFile(*g.grid, p);
            },
            pyb::arg("path"),
            "Writes the grid to `path`: .sdfg, .vdb, .sdf (SDFGen) or .raw (+ .raw.json), by the "
            "extension; atomic "
            "(a temporary file renamed into place)")
        .def_static(
            "from_numpy", &gridFromNumpy, pyb::arg("values"),
            pyb::arg("origin") = std::array<float, 3>{0, 0, 0}, pyb::arg("voxel_size") = 1.0f,
            pyb::arg("sparse") = false, pyb::arg("block") = 4, pyb::arg("band") = 3.0f,
            "A grid from vertex distances values[i, j, k] at origin + voxel_size * (i, j, k); "
            "sparse=True keeps the blocks within `band` voxels of the surface, in blocks of "
            "`block` (4 or 8) cells per edge")
        .def("to_numpy", &gridArray,
             "The vertex distances as an (nx+1) x (ny+1) x (nz+1) float32 array indexed "
             "[i, j, k] (vertex at origin + voxel_size * (i, j, k)): a read-only view of a dense "
             "grid's own samples (no copy), a copy for a sparse grid (dropped blocks read "
             "+-background)")
        .def("sample", &gridSample, pyb::arg("points"), pyb::arg("gradients") = false,
             pyb::arg("h") = pyb::none(),
             "Trilinear reconstruction at an N x 3 array of points (outside the grid: a distance "
             "bound through the nearest grid point); gradients=True adds central differences of "
             "step h (default half a voxel)")
        .def_property_readonly("info", &gridInfo,
                               "kind, cells, origin, voxel_size, bounds, surface_bounds, "
                               "lipschitz, memory_bytes, stored_samples (sparse: block_size, "
                               "blocks, background)")
        .def_property_readonly(
            "field",
            [](const PyGrid& g) {
                return Field{std::make_shared<const Tape>(compileTape(node::grid(g.grid))),
                             "grid field"};
            },
            "The grid as a Field (its tape: one grid primitive), reading the samples divided by "
            "info['lipschitz'] so that the field is 1-Lipschitz for the tracer (a sparse grid, "
            "beyond its band: a bound of the distance to its surface, as in scenes)")
        .def("to_mesh", &gridToMesh, pyb::arg("adaptivity") = 0.0f, pyb::arg("isovalue") = 0.0f,
             "The surface (or the offset surface `isovalue`), simplified where flat by "
             "`adaptivity` in [0, 1] (0: none), as (vertices N x 3 float32, faces "
             "M x 3 int32), counter-clockwise seen from outside (OpenVDB's volumeToMesh)")
        .def("__repr__", [](const PyGrid& g) {
            const GridShape& s = g.grid->shape();
            return std::string("<sdftrace.Grid: ") +
                   (g.grid->kind() == GridKind::Dense ? "dense " : "sparse ") +
                   std::to_string(s.cells[0]) + "x" + std::to_string(s.cells[1]) + "x" +
                   std::to_string(s.cells[2]) + " cells, voxel " + std::to_string(s.voxelSize) +
                   ">";
        });
    bindBake(m);
}

}  // namespace sdft::py
