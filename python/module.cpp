// The `sdftrace` Python module (pybind11): scenes, fields, grids, mesh bakes and renders as numpy
// arrays (docs/python.md). The library's InputError (bad input a user can fix) is raised as
// ValueError with the same one-line message.
#include <pybind11/pybind11.h>

#include "bindings.h"
#include "sdftrace/core/error.h"

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
}
