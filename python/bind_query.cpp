// sdftrace.MeshQuery: exact distances, closest points, signs, winding numbers and ray casts of a
// triangle mesh at numpy arrays of points, and DeepSDF-style sampling (query/mesh_query.h,
// query/mesh_sampling.h). Float32 in, float32 out; float64 (or any other numbers) in, float64 out.
#include <pybind11/stl.h>

#include <cmath>
#include <memory>
#include <optional>
#include <vector>

#include "bindings.h"
#include "sdftrace/core/error.h"
#include "sdftrace/query/mesh_query.h"
#include "sdftrace/query/mesh_sampling.h"

namespace sdft::py {

namespace {

using F32 = pyb::array_t<float, pyb::array::c_style | pyb::array::forcecast>;
using F64 = pyb::array_t<double, pyb::array::c_style | pyb::array::forcecast>;

std::string shapeText(const pyb::array& a) {
    std::string s = "(";
    for (pyb::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
    return s + (a.ndim() == 1 ? ",)" : ")");
}

// An N x 3 array of numbers as float32 (when given float32) or float64 (anything else), C order.
struct Points {
    pyb::array array;  // F32 or F64
    bool single = false;
    size_t n = 0;
};
Points pointsOf(const pyb::handle& h, const std::string& what) {
    Points p;
    pyb::array raw;
    try {
        raw = pyb::array::ensure(h);
    } catch (const pyb::error_already_set&) {
    }
    if (!raw) {
        PyErr_Clear();
        throw InputError(what + ": expected an N x 3 array of numbers");
    }
    const char kind = raw.dtype().kind();
    if (kind != 'f' && kind != 'i' && kind != 'u')
        throw InputError(what + ": expected an N x 3 array of numbers, got dtype " +
                         std::string(pyb::str(raw.dtype())));
    if (raw.ndim() != 2 || raw.shape(1) != 3)
        throw InputError(what + ": expected an N x 3 array of points, got shape " + shapeText(raw));
    p.single = kind == 'f' && raw.dtype().itemsize() == 4;
    if (p.single)
        p.array = F32::ensure(raw);
    else
        p.array = F64::ensure(raw);
    if (!p.array) {
        PyErr_Clear();
        throw InputError(what + ": cannot be read as floating-point numbers");
    }
    p.n = static_cast<size_t>(raw.shape(0));
    return p;
}

// An array of n rows of `cols` (0: a vector) of the points' precision.
pyb::array result(const Points& p, size_t cols) {
    std::vector<pyb::ssize_t> shape{static_cast<pyb::ssize_t>(p.n)};
    if (cols) shape.push_back(static_cast<pyb::ssize_t>(cols));
    if (p.single) return pyb::array_t<float>(shape);
    return pyb::array_t<double>(shape);
}

MeshSign signOf(const std::string& name, const std::string& where) {
    MeshSign s;
    if (!parseMeshSign(name, s))
        throw InputError(where + ": sign = '" + name + "': expected one of " + kMeshSigns);
    return s;
}

// Runs f(const T* xyz) on the points' own type, the GIL released.
template <class Fn>
void onPoints(const Points& p, Fn&& fn) {
    pyb::gil_scoped_release release;
    if (p.single)
        fn(static_cast<const float*>(p.array.data()));
    else
        fn(static_cast<const double*>(p.array.data()));
}

struct PyMeshQuery {
    std::shared_ptr<const MeshQuery> query;
};

PyMeshQuery makeQuery(const pyb::handle& vertices, const pyb::handle& faces) {
    const Points v = pointsOf(vertices, "MeshQuery: vertices");
    using IndexArray = pyb::array_t<int64_t, pyb::array::c_style | pyb::array::forcecast>;
    pyb::array rawFaces;
    try {
        rawFaces = pyb::array::ensure(faces);
    } catch (const pyb::error_already_set&) {
    }
    if (!rawFaces || (rawFaces.dtype().kind() != 'i' && rawFaces.dtype().kind() != 'u')) {
        PyErr_Clear();
        throw InputError("MeshQuery: faces: expected an M x 3 array of integer vertex indices");
    }
    if (rawFaces.ndim() != 2 || rawFaces.shape(1) != 3)
        throw InputError("MeshQuery: faces: expected an M x 3 array of vertex indices, got shape " +
                         shapeText(rawFaces));
    const IndexArray f = IndexArray::ensure(rawFaces);
    std::vector<Vec3d> positions(v.n);
    for (size_t i = 0; i < v.n; ++i)
        for (int a = 0; a < 3; ++a) {
            const double x = v.single ? static_cast<const float*>(v.array.data())[3 * i + a]
                                      : static_cast<const double*>(v.array.data())[3 * i + a];
            (a == 0 ? positions[i].x : a == 1 ? positions[i].y : positions[i].z) = x;
        }
    std::vector<std::array<uint32_t, 3>> triangles(static_cast<size_t>(f.shape(0)));
    const int64_t* idx = f.data();
    for (size_t t = 0; t < triangles.size(); ++t)
        for (int c = 0; c < 3; ++c) {
            const int64_t k = idx[3 * t + c];
            if (k < 0 || k >= static_cast<int64_t>(v.n))
                throw InputError("MeshQuery: faces: face " + std::to_string(t) + " names vertex " +
                                 std::to_string(k) + "; expected indices in [0, " +
                                 std::to_string(v.n) + ")");
            triangles[t][c] = static_cast<uint32_t>(k);
        }
    pyb::gil_scoped_release release;
    return {
        std::make_shared<const MeshQuery>(std::move(positions), std::move(triangles), "MeshQuery")};
}

// Prefixes the library's "points: row I ..." with the method's name.
template <class Fn>
void withName(const std::string& method, Fn&& fn) {
    try {
        fn();
    } catch (const InputError& e) {
        throw InputError(method + ": " + e.what());
    }
}

pyb::array distances(const PyMeshQuery& q, const pyb::handle& points, bool isSigned,
                     const std::string& sign, const char* method) {
    const Points p = pointsOf(points, std::string(method) + ": points");
    const MeshSign s = signOf(sign, method);
    pyb::array d = result(p, 0);
    void* out = d.mutable_data();
    withName(method, [&] {
        onPoints(p, [&](const auto* xyz) {
            q.query->queryPoints(xyz, p.n, {out}, {isSigned, s, ""});
        });
    });
    return d;
}

pyb::tuple closestPoints(const PyMeshQuery& q, const pyb::handle& points) {
    const Points p = pointsOf(points, "closest_points: points");
    pyb::array c = result(p, 3), b = result(p, 3);
    pyb::array_t<int64_t> f(std::vector<pyb::ssize_t>{static_cast<pyb::ssize_t>(p.n)});
    MeshQuery::PointOutputs out;
    out.closest = c.mutable_data();
    out.face = f.mutable_data();
    out.bary = b.mutable_data();
    withName("closest_points", [&] {
        onPoints(p, [&](const auto* xyz) { q.query->queryPoints(xyz, p.n, out, {}); });
    });
    return pyb::make_tuple(c, f, b);
}

pyb::array windingNumbers(const PyMeshQuery& q, const pyb::handle& points) {
    const Points p = pointsOf(points, "winding_number: points");
    pyb::array w = result(p, 0);
    MeshQuery::PointOutputs out;
    out.winding = w.mutable_data();
    withName("winding_number", [&] {
        onPoints(p, [&](const auto* xyz) { q.query->queryPoints(xyz, p.n, out, {}); });
    });
    return w;
}

pyb::array contains(const PyMeshQuery& q, const pyb::handle& points, const std::string& sign) {
    const Points p = pointsOf(points, "contains: points");
    const MeshSign s = signOf(sign, "contains");
    pyb::array_t<bool> in(std::vector<pyb::ssize_t>{static_cast<pyb::ssize_t>(p.n)});
    MeshQuery::PointOutputs out;
    out.inside = in.mutable_data();
    withName("contains", [&] {
        onPoints(p, [&](const auto* xyz) { q.query->queryPoints(xyz, p.n, out, {false, s, ""}); });
    });
    return in;
}

pyb::tuple rayCast(const PyMeshQuery& q, const pyb::handle& origins, const pyb::handle& directions,
                   double tMax) {
    Points o = pointsOf(origins, "ray_cast: origins");
    Points d = pointsOf(directions, "ray_cast: directions");
    if (o.n != d.n)
        throw InputError("ray_cast: directions: " + std::to_string(d.n) + " rows for " +
                         std::to_string(o.n) + " origins; expected one direction per origin");
    if (std::isnan(tMax) || tMax <= 0)
        throw InputError("ray_cast: t_max: expected a number > 0 (inf: no limit)");
    if (o.single != d.single) {  // one precision for both: the wider
        o.single = d.single = false;
        o.array = F64::ensure(o.array);
        d.array = F64::ensure(d.array);
    }
    pyb::array t = result(o, 0), b = result(o, 2), nrm = result(o, 3);
    pyb::array_t<int64_t> f(std::vector<pyb::ssize_t>{static_cast<pyb::ssize_t>(o.n)});
    MeshQuery::RayOutputs out{t.mutable_data(), f.mutable_data(), b.mutable_data(),
                              nrm.mutable_data()};
    const void* dirs = d.array.data();
    withName("ray_cast", [&] {
        onPoints(o, [&](const auto* xyz) {
            using T = std::remove_cv_t<std::remove_pointer_t<decltype(xyz)>>;
            q.query->castRays(xyz, static_cast<const T*>(dirs), o.n, tMax, out);
        });
    });
    return pyb::make_tuple(t, f, b, nrm);
}

// float32 or float64 from a dtype argument.
bool singleOf(const pyb::handle& dtype, const std::string& where) {
    const pyb::dtype dt = pyb::dtype::from_args(pyb::reinterpret_borrow<pyb::object>(dtype));
    if (dt.kind() == 'f' && dt.itemsize() == 4) return true;
    if (dt.kind() == 'f' && dt.itemsize() == 8) return false;
    throw InputError(where + ": dtype: expected float32 or float64");
}

size_t countOf(int64_t n, const std::string& where) {
    if (n < 0) throw InputError(where + ": n: expected a count >= 0");
    return static_cast<size_t>(n);
}

// Signed distances at freshly sampled points (p.array filled): the second array of the samplers.
pyb::array signedAt(const PyMeshQuery& q, const Points& p, MeshSign sign) {
    pyb::array d = result(p, 0);
    void* out = d.mutable_data();
    onPoints(p, [&](const auto* xyz) { q.query->queryPoints(xyz, p.n, {out}, {true, sign, ""}); });
    return d;
}

pyb::tuple sampleSurfacePy(const PyMeshQuery& q, int64_t n, uint64_t seed,
                           const pyb::handle& dtype) {
    Points p;
    p.n = countOf(n, "sample_surface");
    p.single = singleOf(dtype, "sample_surface");
    p.array = result(p, 3);
    pyb::array normals = result(p, 3);
    pyb::array_t<int64_t> faces(std::vector<pyb::ssize_t>{static_cast<pyb::ssize_t>(p.n)});
    void *pp = p.array.mutable_data(), *np = normals.mutable_data();
    int64_t* fp = faces.mutable_data();
    {
        pyb::gil_scoped_release release;
        if (p.single)
            sampleSurface(*q.query, p.n, seed, static_cast<float*>(pp), static_cast<float*>(np),
                          fp);
        else
            sampleSurface(*q.query, p.n, seed, static_cast<double*>(pp), static_cast<double*>(np),
                          fp);
    }
    return pyb::make_tuple(p.array, normals, faces);
}

pyb::tuple sampleNearSurfacePy(const PyMeshQuery& q, int64_t n,
                               std::optional<std::vector<double>> sigmas, uint64_t seed,
                               const std::string& sign, const pyb::handle& dtype) {
    Points p;
    p.n = countOf(n, "sample_near_surface");
    p.single = singleOf(dtype, "sample_near_surface");
    const MeshSign s = signOf(sign, "sample_near_surface");
    const std::vector<double> widths = sigmas ? *sigmas : defaultNearSurfaceSigmas(*q.query);
    p.array = result(p, 3);
    void* pp = p.array.mutable_data();
    {
        pyb::gil_scoped_release release;
        if (p.single)
            sampleNearSurface(*q.query, p.n, widths, seed, static_cast<float*>(pp));
        else
            sampleNearSurface(*q.query, p.n, widths, seed, static_cast<double*>(pp));
    }
    return pyb::make_tuple(p.array, signedAt(q, p, s));
}

pyb::tuple sampleVolumePy(
    const PyMeshQuery& q, int64_t n,
    std::optional<std::pair<std::array<double, 3>, std::array<double, 3>>> bounds, uint64_t seed,
    const std::string& sign, const pyb::handle& dtype) {
    Points p;
    p.n = countOf(n, "sample_volume");
    p.single = singleOf(dtype, "sample_volume");
    const MeshSign s = signOf(sign, "sample_volume");
    auto [lo, hi] = q.query->bounds();
    if (bounds) {
        lo = {bounds->first[0], bounds->first[1], bounds->first[2]};
        hi = {bounds->second[0], bounds->second[1], bounds->second[2]};
        for (int a = 0; a < 3; ++a)
            if (!std::isfinite(lo[a]) || !std::isfinite(hi[a]) || lo[a] > hi[a])
                throw InputError(
                    "sample_volume: bounds: expected ((x0, y0, z0), (x1, y1, z1)) "
                    "finite with x0 <= x1, y0 <= y1, z0 <= z1");
    } else {  // the box grown by 5 % of its diagonal
        const double g = 0.05 * q.query->diagonal();
        lo = lo - Vec3d{g, g, g};
        hi = hi + Vec3d{g, g, g};
    }
    p.array = result(p, 3);
    void* pp = p.array.mutable_data();
    {
        pyb::gil_scoped_release release;
        if (p.single)
            sampleVolume(p.n, lo, hi, seed, static_cast<float*>(pp));
        else
            sampleVolume(p.n, lo, hi, seed, static_cast<double*>(pp));
    }
    return pyb::make_tuple(p.array, signedAt(q, p, s));
}

void bindSampling(pyb::class_<PyMeshQuery>& c) {
    c.def("sample_surface", &sampleSurfacePy, pyb::arg("n"), pyb::arg("seed") = 0,
          pyb::arg("dtype") = "float32",
          "n points on the surface, uniform by area: (points n x 3, the faces' unit normals "
          "n x 3, face ids n), in dtype (float32 or float64). The same seed gives the same "
          "points on any number of threads.")
        .def("sample_near_surface", &sampleNearSurfacePy, pyb::arg("n"),
             pyb::arg("sigmas") = pyb::none(), pyb::arg("seed") = 0, pyb::arg("sign") = "winding",
             pyb::arg("dtype") = "float32",
             "DeepSDF's near-surface samples (Park et al. 2019): n surface points, point i moved "
             "by an isotropic Gaussian of standard deviation sigmas[i % len(sigmas)] (mesh units; "
             "default: DeepSDF's 0.05 and 0.0158 times half the bounding box's diagonal), with "
             "their signed distances by sign: (points n x 3, sdf n) in dtype (float32 or "
             "float64); the same seed gives the same points.")
        .def("sample_volume", &sampleVolumePy, pyb::arg("n"), pyb::arg("bounds") = pyb::none(),
             pyb::arg("seed") = 0, pyb::arg("sign") = "winding", pyb::arg("dtype") = "float32",
             "n points uniform in bounds ((x0, y0, z0), (x1, y1, z1)) (default: the mesh's box "
             "grown by 5 % of its diagonal) with their signed distances by sign: (points n x 3, "
             "sdf n) in dtype (float32 or float64); the same seed gives the same points.");
}

}  // namespace

void bindQuery(pyb::module_& m) {
    pyb::class_<PyMeshQuery> c(
        m, "MeshQuery",
        "Exact queries of a triangle mesh at arbitrary points (docs/guide/10-mesh-queries.md): "
        "distances, "
        "closest points, signed distances, winding numbers, ray casts and sampling. Built once "
        "from vertices (N x 3) and faces (M x 3 indices); every method releases the GIL, runs on "
        "all cores and may be called from several threads. float32 points give float32 results, "
        "float64 (or other numbers) float64. Signs: 'winding' (the generalized winding number "
        "of the mesh with its holes spanned, > 1/2 inside: right on closed meshes, robust on "
        "open scans), 'parity' (three rays' crossings), 'pseudonormal' (the closest feature's "
        "angle-weighted normal: closed, manifold meshes only).");
    c.def(pyb::init(&makeQuery), pyb::arg("vertices"), pyb::arg("faces"))
        .def(
            "distance",
            [](const PyMeshQuery& q, const pyb::handle& points) {
                return distances(q, points, false, "winding", "distance");
            },
            pyb::arg("points"), "Unsigned distances from points (N x 3) to the mesh (N).")
        .def(
            "signed_distance",
            [](const PyMeshQuery& q, const pyb::handle& points, const std::string& sign) {
                return distances(q, points, true, sign, "signed_distance");
            },
            pyb::arg("points"), pyb::arg("sign") = "winding",
            "Distances from points (N x 3), negative inside by sign ('winding', 'parity' or "
            "'pseudonormal') (N).")
        .def("closest_points", &closestPoints, pyb::arg("points"),
             "For points (N x 3): (closest points N x 3, face ids N, barycentric coordinates "
             "N x 3 of the face's corners)")
        .def("winding_number", &windingNumbers, pyb::arg("points"),
             "The generalized winding number of the mesh (Jacobson et al. 2013) at points "
             "(N x 3), about 1 inside and 0 outside, fractional near holes (N).")
        .def("contains", &contains, pyb::arg("points"), pyb::arg("sign") = "winding",
             "Whether points (N x 3) are inside by sign ('winding', 'parity' or "
             "'pseudonormal') (N booleans).")
        .def("ray_cast", &rayCast, pyb::arg("origins"), pyb::arg("directions"),
             pyb::arg("t_max") = INFINITY,
             "First hits of rays origins + t directions (N x 3 each), 0 < t <= t_max (t in "
             "units of the "
             "direction's length): (t N (inf: miss), face ids N (-1: miss), barycentrics N x 2 "
             "(u, v of corners 1 and 2), unit face normals N x 3).")
        .def_property_readonly(
            "vertex_count", [](const PyMeshQuery& q) { return q.query->vertices().size(); },
            "Vertices of the mesh, as given")
        .def_property_readonly(
            "face_count", [](const PyMeshQuery& q) { return q.query->faces().size(); },
            "Faces of the mesh, as given (face ids index them)")
        .def_property_readonly(
            "bounds",
            [](const PyMeshQuery& q) {
                auto [lo, hi] = q.query->bounds();
                return pyb::make_tuple(pyb::make_tuple(lo.x, lo.y, lo.z),
                                       pyb::make_tuple(hi.x, hi.y, hi.z));
            },
            "The mesh's bounding box ((x0, y0, z0), (x1, y1, z1))")
        .def_property_readonly(
            "watertight", [](const PyMeshQuery& q) { return q.query->watertight(); },
            "Every edge shared by two faces, once each way (vertices welded by position)")
        .def("__repr__", [](const PyMeshQuery& q) {
            return "<sdftrace.MeshQuery: " + std::to_string(q.query->vertices().size()) +
                   " vertices, " + std::to_string(q.query->faces().size()) + " faces>";
        });
    bindSampling(c);
}

}  // namespace sdft::py
