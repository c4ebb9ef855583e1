// The Python module's pieces (docs/python.md): each bind*() adds one part of the API to the module;
// the helpers here turn numpy arrays into the library's inputs with the errors the CLI gives.
#pragma once
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <functional>
#include <initializer_list>
#include <memory>
#include <optional>
#include <string>

#include "sdftrace/field/grid.h"
#include "sdftrace/field/tape.h"
#include "sdftrace/gpu/device.h"
#include "sdftrace/scene/scene.h"

namespace sdft::py {

namespace pyb = pybind11;
using FloatArray = pyb::array_t<float, pyb::array::c_style | pyb::array::forcecast>;

// A compiled field (the tape) and what keeps its inputs alive.
struct Field {
    std::shared_ptr<const Tape> tape;
    std::string what;  // "scene field", "grid field", ... for messages and repr
};

// A scene as loaded: described and prepared (its grids baked), ready to render or evaluate.
struct PyScene {
    std::shared_ptr<const Scene> scene;
    std::string source;
};

struct PyGrid {
    std::shared_ptr<const Grid> grid;
};

// An N x 3 array of points (any float dtype, converted to float32), checked: `what` names the
// argument in the ValueError.
FloatArray pointsArgument(const pyb::handle& points, const std::string& what);

// values[i] = f(point i) for n points, the GIL released, in parallel: `chunk(first, count, xyz,
// out)` evaluates `count` interleaved points. With gradients, grads[i] is the central difference of
// f at point i with step h (6 more evaluations per point).
using ChunkEvaluator = std::function<void(const float* xyz, float* out, size_t count)>;
pyb::object evaluatePoints(const FloatArray& points, bool gradients, float h,
                           const ChunkEvaluator& chunk);

// A path argument: a str or any os.PathLike.
std::string pathArgument(const pyb::handle& path);

// The finite-difference step of `what` (evaluate, sample): h if given (checked: finite, > 0),
// else `fallback`.
float stepArgument(std::optional<float> h, float fallback, const std::string& what);

// ((x0, y0, z0), (x1, y1, z1)), or None for empty or unbounded boxes.
pyb::object boundsToPython(const Bounds3& b);

// The bake option table's defaults and docs (bake/bake_options.h) for keyword arguments: the
// default as a number, or as the text the user writes; "key: doc; accepted [default].\n" lines.
double bakeDefaultNumber(const char* key);
std::string bakeDefaultText(const char* key);
template <class T>
T bakeDefault(const char* key) {
    return static_cast<T>(bakeDefaultNumber(key));
}
std::string bakeOptionsDoc(std::initializer_list<const char*> keys);

// The `device` keyword ("cpu", "cuda", "auto"; gpu/device.h), named in the error by `where`.
Device deviceArgument(const std::string& name, const std::string& where);
// Where `auto` fell back to the CPU: a Python warning saying why (the GIL held).
void warnCpuFallback(const std::string& where, const std::string& why);

void bindField(pyb::module_& m);
void bindGrid(pyb::module_& m);
void bindScene(pyb::module_& m);
void bindImages(pyb::module_& m);
void bindQuery(pyb::module_& m);

}  // namespace sdft::py
