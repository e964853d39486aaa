// The Python module `terrain`: scenes and the simulation with zero-copy
// layers (py_sim.cpp), GI frames with the options of `terrain gi`
// (py_gi.cpp) and the engine's writers (py_io.cpp). The engine's errors
// become Python's: InputError ValueError, IoError OSError, each with the
// engine's one-line message.
#include <exception>

#include <pybind11/pybind11.h>

#include "core/error.h"
#include "python/bindings.h"

namespace py = pybind11;

PYBIND11_MODULE(terrain, m) {
    m.doc() =
        "The terrain engine from Python: scenes ticked as `terrain sim` ticks them, their layers as numpy arrays "
        "without a copy, GI frames on numpy height arrays with the options of `terrain gi`, and the engine's "
        "file writers.";
    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const terrain::IoError& e) {
            PyErr_SetString(PyExc_OSError, e.what());
        } catch (const terrain::InputError& e) {
            PyErr_SetString(PyExc_ValueError, e.what());
        } catch (const terrain::Error& e) {
            PyErr_SetString(PyExc_RuntimeError, e.what());
        }
    });
    terrain::python::addSimulation(m);
    terrain::python::addGi(m);
    terrain::python::addIo(m);
}
