#pragma once
// Between the engine's grids and numpy arrays: read-only views of a grid
// that some Python object owns (no copy), arrays that take a grid over, and
// checked height arrays in.
#include <array>
#include <string>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "core/grid.h"

namespace terrain::python {

namespace py = pybind11;

/// A read-only float32 array of shape (ny, nx) over g's storage, without a
/// copy; `owner` (the Python object that holds g) becomes its base, so the
/// storage lives as long as the array.
py::array readOnlyView(const Grid& g, py::handle owner);

/// A float32 array of shape (ny, nx) that takes the grid over (no copy).
py::array adoptGrid(Grid&& g);

/// A new float32 array of shape (ny, nx, 3) holding the three planes.
py::array interleaveRgb(const std::array<Grid, 3>& rgb);

/// A float32 array (any strides) with `ndim` dimensions, checked: TypeError
/// for another dtype (nothing is converted silently: call .astype(np.float32)),
/// ValueError for another number of dimensions. `what` names it in messages.
py::array checkedFloat32(const py::handle& object, int ndim, const std::string& what);

/// The (ny, nx) float32 array copied into a grid (any strides). ValueError
/// when a side is below minSide, above the largest grid side, or a value is
/// NaN or infinite (naming the first such cell).
Grid gridFromArray(const py::handle& object, const std::string& what, int minSide = 1);

/// Plane k of an (ny, nx, channels) float32 array as a grid.
Grid planeOf(const py::array& image, py::ssize_t k);

}  // namespace terrain::python
