#include "python/numpy_grids.h"

#include <cmath>
#include <cstring>

#include "core/size_limits.h"

namespace terrain::python {
namespace {

// Element (y, x[, k]) of a float32 array of any strides.
float at(const py::array& a, py::ssize_t y, py::ssize_t x, py::ssize_t k = 0) {
    const char* base = static_cast<const char*>(a.data());
    const py::ssize_t offset = y * a.strides(0) + x * a.strides(1) + (a.ndim() > 2 ? k * a.strides(2) : 0);
    float v;
    std::memcpy(&v, base + offset, sizeof v);
    return v;
}

void checkSides(const py::array& a, const std::string& what, int minSide) {
    for (int d = 0; d < 2; ++d)
        if (a.shape(d) < minSide || a.shape(d) > kMaxGridSide)
            throw py::value_error(what + ": each side must be " + std::to_string(minSide) + " to " +
                                  std::to_string(kMaxGridSide) + " cells (shape " + std::to_string(a.shape(0)) + " x " +
                                  std::to_string(a.shape(1)) + ")");
}

}  // namespace

py::array readOnlyView(const Grid& g, py::handle owner) {
    const py::ssize_t row = static_cast<py::ssize_t>(g.nx) * static_cast<py::ssize_t>(sizeof(float));
    // pybind11 takes a non-const pointer; the array is made read-only at once
    py::array view(py::dtype::of<float>(), {static_cast<py::ssize_t>(g.ny), static_cast<py::ssize_t>(g.nx)},
                   {row, static_cast<py::ssize_t>(sizeof(float))}, const_cast<float*>(g.data()), owner);
    view.attr("flags").attr("writeable") = false;
    return view;
}

py::array adoptGrid(Grid&& g) {
    auto* owned = new Grid(std::move(g));
    py::capsule free(owned, [](void* p) { delete static_cast<Grid*>(p); });
    return py::array_t<float>({static_cast<py::ssize_t>(owned->ny), static_cast<py::ssize_t>(owned->nx)}, owned->data(),
                              free);
}

py::array interleaveRgb(const std::array<Grid, 3>& rgb) {
    py::array_t<float> out(
        {static_cast<py::ssize_t>(rgb[0].ny), static_cast<py::ssize_t>(rgb[0].nx), static_cast<py::ssize_t>(3)});
    float* px = out.mutable_data();
    for (std::size_t i = 0; i < rgb[0].size(); ++i)
        for (std::size_t c = 0; c < 3; ++c) px[3 * i + c] = rgb[c].v[i];
    return out;
}

py::array checkedFloat32(const py::handle& object, int ndim, const std::string& what) {
    if (!py::isinstance<py::array>(object))
        throw py::type_error(what + ": expected a numpy array, got " + std::string(py::str(py::type::of(object))));
    py::array a = py::reinterpret_borrow<py::array>(object);
    if (!a.dtype().is(py::dtype::of<float>()))
        throw py::type_error(what + ": expected dtype float32, got " + std::string(py::str(a.dtype())) +
                             " (convert explicitly, e.g. .astype(np.float32))");
    if (a.ndim() != ndim)
        throw py::value_error(what + ": expected " + std::to_string(ndim) + " dimensions, got " +
                              std::to_string(a.ndim()));
    return a;
}

Grid gridFromArray(const py::handle& object, const std::string& what, int minSide) {
    const py::array a = checkedFloat32(object, 2, what);
    checkSides(a, what, minSide);
    Grid g(static_cast<int>(a.shape(1)), static_cast<int>(a.shape(0)));
    const bool cOrder = (a.flags() & py::array::c_style) != 0;
    if (cOrder)
        std::memcpy(g.data(), a.data(), g.size() * sizeof(float));
    else
        for (int y = 0; y < g.ny; ++y)
            for (int x = 0; x < g.nx; ++x) g(x, y) = at(a, y, x);
    for (int y = 0; y < g.ny; ++y)
        for (int x = 0; x < g.nx; ++x)
            if (!std::isfinite(g(x, y)))
                throw py::value_error(what + ": value " + std::to_string(g(x, y)) + " at row " + std::to_string(y) +
                                      ", column " + std::to_string(x) + " is not finite");
    return g;
}

Grid planeOf(const py::array& image, py::ssize_t k) {
    Grid g(static_cast<int>(image.shape(1)), static_cast<int>(image.shape(0)));
    for (int y = 0; y < g.ny; ++y)
        for (int x = 0; x < g.nx; ++x) g(x, y) = at(image, y, x, k);
    return g;
}

}  // namespace terrain::python
