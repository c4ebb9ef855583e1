// sdftrace.Field: a compiled field evaluated at numpy points, batched through the tape (DESIGN:
// tree -> tape -> batch evaluator), the GIL released, chunks in parallel (oneTBB).
#include <pybind11/stl.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

#include "bindings.h"
#include "sdftrace/bake/bake_options.h"
#include "sdftrace/core/error.h"
#include "sdftrace/field/sample_grid.h"
#include "sdftrace/scene/prepare_scene.h"

namespace sdft::py {

FloatArray pointsArgument(const pyb::handle& points, const std::string& what) {
    FloatArray a = FloatArray::ensure(points);
    if (!a) {
        PyErr_Clear();
        throw InputError(what + ": expected an N x 3 array of numbers");
    }
    if (a.ndim() != 2 || a.shape(1) != 3) {
        std::string shape = "(";
        for (pyb::ssize_t i = 0; i < a.ndim(); ++i)
            shape += (i ? ", " : "") + std::to_string(a.shape(i));
        throw InputError(what + ": expected an N x 3 array of points, got shape " + shape +
                         (a.ndim() == 1 ? ",)" : ")"));
    }
    const float* p = a.data();
    for (pyb::ssize_t i = 0; i < a.shape(0); ++i) {
        if (!std::isfinite(p[3 * i]) || !std::isfinite(p[3 * i + 1]) ||
            !std::isfinite(p[3 * i + 2]))
            throw InputError(what + ": point " + std::to_string(i) +
                             " is not finite (expected finite coordinates)");
    }
    return a;
}

pyb::object evaluatePoints(const FloatArray& points, bool gradients, float h,
                           const ChunkEvaluator& chunk) {
    const size_t n = static_cast<size_t>(points.shape(0));
    FloatArray values(static_cast<pyb::ssize_t>(n));
    FloatArray grads(std::vector<pyb::ssize_t>{static_cast<pyb::ssize_t>(gradients ? n : 0), 3});
    const float* in = points.data();
    float* out = values.mutable_data();
    float* g = grads.mutable_data();
    {
        pyb::gil_scoped_release release;
        constexpr size_t kChunk = 2048;
        tbb::parallel_for(tbb::blocked_range<size_t>(0, n, kChunk), [&](const auto& r) {
            const size_t count = r.size();
            chunk(in + 3 * r.begin(), out + r.begin(), count);
            if (!gradients) return;
            std::vector<float> shifted(3 * count), plus(count), minus(count);
            for (int axis = 0; axis < 3; ++axis) {
                std::copy(in + 3 * r.begin(), in + 3 * r.end(), shifted.begin());
                for (size_t i = 0; i < count; ++i) shifted[3 * i + axis] += h;
                chunk(shifted.data(), plus.data(), count);
                for (size_t i = 0; i < count; ++i) shifted[3 * i + axis] -= 2 * h;
                chunk(shifted.data(), minus.data(), count);
                for (size_t i = 0; i < count; ++i)
                    g[3 * (r.begin() + i) + axis] = (plus[i] - minus[i]) / (2 * h);
            }
        });
    }
    if (gradients) return pyb::make_tuple(values, grads);
    return values;
}

namespace {

// The tape's batch evaluator over interleaved points (one scratch per thread).
ChunkEvaluator tapeEvaluator(const Tape& tape) {
    return [&tape](const float* xyz, float* out, size_t count) {
        thread_local BatchScratch scratch;
        thread_local std::vector<float> x, y, z;
        x.resize(count);
        y.resize(count);
        z.resize(count);
        for (size_t i = 0; i < count; ++i) {
            x[i] = xyz[3 * i];
            y[i] = xyz[3 * i + 1];
            z[i] = xyz[3 * i + 2];
        }
        tape.evalBatch(x.data(), y.data(), z.data(), out, static_cast<int>(count), scratch);
    };
}

// The finite-difference step: 1e-3 of the field's extent (1e-3 where it is unbounded).
float defaultStep(const Bounds3& b) {
    if (b.empty() || !b.finite()) return 1e-3f;
    const Vec3 e = b.extent();
    return 1e-3f * std::max({e.x, e.y, e.z, 1e-3f});
}

pyb::object boundsTuple(const Bounds3& b) {
    if (b.empty() || !b.finite()) return pyb::none();
    return pyb::make_tuple(pyb::make_tuple(b.lo.x, b.lo.y, b.lo.z),
                           pyb::make_tuple(b.hi.x, b.hi.y, b.hi.z));
}

}  // namespace

pyb::object boundsToPython(const Bounds3& b) { return boundsTuple(b); }

std::string pathArgument(const pyb::handle& path) {
    return pyb::str(pyb::module_::import("os").attr("fspath")(path));
}

float stepArgument(std::optional<float> h, float fallback, const std::string& what) {
    if (!h) return fallback;
    if (!(*h > 0) || !std::isfinite(*h))
        throw InputError(what + ": h = " + std::to_string(*h) + ": expected a finite step > 0");
    return *h;
}

void bindField(pyb::module_& m) {
    static const std::string toGridDoc =
        "Samples f / L at the vertices of a grid over the field's bounds (or `bounds`), with "
        "`padding` voxels of margin: dense, or a sparse block grid keeping the blocks within "
        "`band` voxels of the surface.\n\n" +
        bakeOptionsDoc({"resolution", "dense", "band", "block", "padding"}) +
        "bounds: ((x0, y0, z0), (x1, y1, z1)), the region to sample; None: the field's bounds "
        "(an unbounded field needs it).\n";
    pyb::class_<Field>(m, "Field",
                       "A signed distance field compiled to sdftrace's tape: evaluate it at "
                       "points, or sample it into a Grid. Get one from Scene.field or Grid.field.")
        .def(
            "evaluate",
            [](const Field& f, const pyb::handle& points, bool gradients, std::optional<float> h) {
                const FloatArray p = pointsArgument(points, "evaluate: points");
                const float step = stepArgument(h, defaultStep(f.tape->bounds()), "evaluate");
                return evaluatePoints(p, gradients, step, tapeEvaluator(*f.tape));
            },
            pyb::arg("points"), pyb::arg("gradients") = false, pyb::arg("h") = pyb::none(),
            "Distances at an N x 3 array of points (float32, N). With gradients=True, also the "
            "N x 3 gradients by central differences of step h (default: 1e-3 of the field's "
            "extent), as a tuple (distances, gradients). Batched through the tape, in "
            "parallel, without the GIL.")
        .def_property_readonly(
            "lipschitz", [](const Field& f) { return f.tape->lipschitz(); },
            "The bound L with |f(p) - f(q)| <= L |p - q| that the tracer "
            "divides by")
        .def_property_readonly(
            "bounds", [](const Field& f) { return boundsTuple(f.tape->bounds()); },
            "((x0, y0, z0), (x1, y1, z1)) holding the surface, or None where it is unbounded")
        .def_property_readonly(
            "instructions", [](const Field& f) { return f.tape->size(); },
            "Instructions of the compiled tape")
        .def(
            "to_grid",
            [](const Field& f, int resolution, bool dense, float band, int block, float padding,
               std::optional<std::pair<std::array<float, 3>, std::array<float, 3>>> bounds) {
                // Checked by the bake option table (bake/bake_options.h).
                MeshBakeOptions bake;
                setBakeOption(bake, "resolution", resolution, "to_grid");
                setBakeOption(bake, "dense", dense ? 1 : 0, "to_grid");
                setBakeOption(bake, "band", band, "to_grid");
                setBakeOption(bake, "block", block, "to_grid");
                setBakeOption(bake, "padding", padding, "to_grid");
                Bounds3 region = f.tape->bounds();
                if (bounds) {
                    region.lo = Vec3(bounds->first[0], bounds->first[1], bounds->first[2]);
                    region.hi = Vec3(bounds->second[0], bounds->second[1], bounds->second[2]);
                    if (region.empty() || !region.finite())
                        throw InputError(
                            "to_grid: bounds: expected ((x0, y0, z0), (x1, y1, z1)) "
                            "with finite x0 <= x1, y0 <= y1, z0 <= z1");
                }
                if (region.empty() || !region.finite())
                    throw InputError("to_grid: the " + f.what +
                                     " is unbounded; give bounds=((x0, y0, z0), (x1, y1, z1))");
                const SampleOptions& o = bake.sampling;
                std::shared_ptr<const Grid> grid;
                {
                    pyb::gil_scoped_release release;
                    grid = sceneGrid(sampleGrid(*f.tape, region, o));
                }
                return PyGrid{grid};
            },
            pyb::arg("resolution") = bakeDefault<int>("resolution"),
            pyb::arg("dense") = bakeDefault<bool>("dense"),
            pyb::arg("band") = bakeDefault<float>("band"),
            pyb::arg("block") = std::stoi(bakeDefaultText("block")),
            pyb::arg("padding") = bakeDefault<float>("padding"), pyb::arg("bounds") = pyb::none(),
            toGridDoc.c_str())
        .def("__repr__", [](const Field& f) {
            return "<sdftrace.Field: " + f.what + ", " + std::to_string(f.tape->size()) +
                   " instructions, L = " + std::to_string(f.tape->lipschitz()) + ">";
        });
}

}  // namespace sdft::py
