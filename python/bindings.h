#pragma once
// The parts of the module `terrain`, each adding its classes and functions
// (python/module.cpp calls them in order).
#include <pybind11/pybind11.h>

namespace terrain::python {

void addSimulation(pybind11::module_& m);  // scenes, Simulation, layers (py_sim.cpp)
void addGi(pybind11::module_& m);          // gi() with the options of `terrain gi` (py_gi.cpp)
void addIo(pybind11::module_& m);          // the engine's readers and writers (py_io.cpp)

}  // namespace terrain::python
