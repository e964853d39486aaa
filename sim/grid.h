#pragma once
// Plain float grids: one contiguous std::vector<float> per quantity, row-major
// (i = y * stride + x). Kernels take the non-owning views below and never
// allocate.
#include <cassert>
#include <cstddef>
#include <vector>

namespace terrain {

/// Mutable non-owning view of a row-major float grid.
struct GridView {
    float* data = nullptr;
    int nx = 0;
    int ny = 0;
    std::ptrdiff_t stride = 0;  // elements between rows

    float& operator()(int x, int y) const { return data[y * stride + x]; }
    float* row(int y) const { return data + y * stride; }
};

/// Read-only non-owning view of a row-major float grid.
struct ConstGridView {
    const float* data = nullptr;
    int nx = 0;
    int ny = 0;
    std::ptrdiff_t stride = 0;

    ConstGridView() = default;
    ConstGridView(const float* d, int x, int y, std::ptrdiff_t s) : data(d), nx(x), ny(y), stride(s) {}
    ConstGridView(const GridView& v) : data(v.data), nx(v.nx), ny(v.ny), stride(v.stride) {}  // NOLINT

    float operator()(int x, int y) const { return data[y * stride + x]; }
    const float* row(int y) const { return data + y * stride; }
    /// Clamp-to-edge access, for stencils at the border.
    float clamped(int x, int y) const {
        x = x < 0 ? 0 : (x >= nx ? nx - 1 : x);
        y = y < 0 ? 0 : (y >= ny ? ny - 1 : y);
        return data[y * stride + x];
    }
};

/// An owning float grid (nx columns, ny rows, tightly packed).
struct Grid {
    int nx = 0;
    int ny = 0;
    std::vector<float> v;

    Grid() = default;
    Grid(int w, int h, float fill = 0.0f) { resize(w, h, fill); }

    void resize(int w, int h, float fill = 0.0f) {
        nx = w;
        ny = h;
        v.assign(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), fill);
    }
    bool empty() const { return v.empty(); }
    std::size_t size() const { return v.size(); }

    float& operator()(int x, int y) { return v[static_cast<std::size_t>(y) * nx + x]; }
    float operator()(int x, int y) const { return v[static_cast<std::size_t>(y) * nx + x]; }
    float* data() { return v.data(); }
    const float* data() const { return v.data(); }

    GridView view() { return {v.data(), nx, ny, nx}; }
    ConstGridView view() const { return {v.data(), nx, ny, nx}; }
    ConstGridView cview() const { return {v.data(), nx, ny, nx}; }
};

}  // namespace terrain
