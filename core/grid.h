#pragma once
// Plain float grids: one contiguous std::vector<float> per quantity, row-major
// (i = y * stride + x). Kernels take the non-owning views below and never
// allocate.
#include <algorithm>
#include <atomic>
#include <cassert>
#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <new>
#include <vector>

namespace terrain {

/// Allocator for grid storage that starts each large buffer at a different
/// offset within a 64 KiB window. Every layer of a 1024-wide terrain is a
/// 4 MiB buffer, and the system allocator hands those out page aligned, so
/// the same cell of every layer (and, with 4 KiB rows, of neighbouring rows)
/// would map to the same cache sets; a stencil reading ~16 rows of several
/// layers then thrashes L1 and L2. Staggering the starts removes that without
/// touching any kernel (results are unchanged: only addresses move).
template <class T>
struct StaggeredAllocator {
    using value_type = T;
    StaggeredAllocator() = default;
    template <class U>
    StaggeredAllocator(const StaggeredAllocator<U>&) noexcept {}  // NOLINT

    T* allocate(std::size_t n) {
        const std::size_t bytes = n * sizeof(T);
        static std::atomic<unsigned> counter{0};
        // 64-byte cache lines; 17 lines apart modulo 37 steps spreads starts
        // over ~39 KiB. Small buffers need no staggering.
        const std::size_t offset = bytes >= (256u << 10) ? 64u * (17u * (counter++ % 37u) + 1u) : 64u;
        void* base = std::aligned_alloc(64, (bytes + offset + 63) / 64 * 64);
        if (!base) throw std::bad_alloc();
        char* p = static_cast<char*>(base) + offset;
        std::memcpy(p - sizeof(void*), &base, sizeof(void*));  // remember the block for deallocate
        return reinterpret_cast<T*>(p);
    }
    void deallocate(T* p, std::size_t) noexcept {
        void* base;
        std::memcpy(&base, reinterpret_cast<char*>(p) - sizeof(void*), sizeof(void*));
        std::free(base);
    }
    template <class U>
    bool operator==(const StaggeredAllocator<U>&) const noexcept {
        return true;
    }
};

/// Storage of one grid layer.
using FloatVector = std::vector<float, StaggeredAllocator<float>>;

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
    FloatVector v;

    Grid() = default;
    Grid(int w, int h, float fill = 0.0f) { resize(w, h, fill); }

    void resize(int w, int h, float fill = 0.0f) {
        nx = w;
        ny = h;
        v.assign(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), fill);
    }
    /// Resizes (zero-filled) only when the size differs: buffers kept from
    /// call to call keep their storage and contents.
    void ensureSize(int w, int h) {
        if (nx != w || ny != h || v.size() != static_cast<std::size_t>(w) * static_cast<std::size_t>(h)) resize(w, h);
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

/// Rows [y0, y1) of a grid, cut to it where used; by default every row.
struct RowSpan {
    int y0 = 0, y1 = std::numeric_limits<int>::max();
    RowSpan cut(int ny) const { return {std::max(y0, 0), std::max(std::max(y0, 0), std::min(y1, ny))}; }
    /// d more rows on each side (every row stays every row).
    RowSpan grown(int d) const { return {y0 - d, y1 > std::numeric_limits<int>::max() - d ? y1 : y1 + d}; }
};

/// Cells [x0, x1) x [y0, y1) of a grid, cut to it where used; by default
/// every cell. Empty when x0 >= x1 or y0 >= y1.
struct CellBox {
    static constexpr int kAll = std::numeric_limits<int>::max();
    int x0 = 0, y0 = 0, x1 = kAll, y1 = kAll;
    static constexpr CellBox none() { return {0, 0, 0, 0}; }
    RowSpan rows() const { return {y0, y1}; }
    bool empty() const { return x0 >= x1 || y0 >= y1; }
    /// The cells of a 2 x 2 decimation (cell k of the next level holds cells
    /// 2k and 2k + 1) that hold a cell of this box; empty stays empty.
    CellBox halved() const {
        if (empty()) return none();
        return {x0 / 2, y0 / 2, (x1 - 1) / 2 + 1, (y1 - 1) / 2 + 1};
    }
    CellBox cut(int nx, int ny) const {
        const RowSpan c = RowSpan{x0, x1}.cut(nx), r = RowSpan{y0, y1}.cut(ny);
        return {c.y0, r.y0, c.y1, r.y1};
    }
    /// The box moved by (dx, dy) cells (empty stays empty).
    CellBox shifted(int dx, int dy) const {
        if (empty()) return none();
        return {x0 + dx, y0 + dy, x1 + dx, y1 + dy};
    }
    /// The smallest box holding both (an empty one adds nothing).
    CellBox joined(const CellBox& o) const {
        if (o.empty()) return *this;
        if (empty()) return o;
        return {std::min(x0, o.x0), std::min(y0, o.y0), std::max(x1, o.x1), std::max(y1, o.y1)};
    }
};

/// Copies a view into an owning grid (its storage kept when the size is the
/// same), only `rows` when the size is the same.
inline void copyGrid(ConstGridView from, Grid& to, RowSpan rows = {}) {
    if (to.nx != from.nx || to.ny != from.ny) rows = {};
    to.ensureSize(from.nx, from.ny);
    rows = rows.cut(from.ny);
    for (int y = rows.y0; y < rows.y1; ++y)
        std::memcpy(to.data() + static_cast<std::size_t>(y) * from.nx, from.row(y), sizeof(float) * from.nx);
}

/// The cells of `box` (inside the view) as a view of their own: its cell
/// (0, 0) is the view's (box.x0, box.y0).
inline ConstGridView subView(ConstGridView v, CellBox box) {
    return {v.row(box.y0) + box.x0, box.x1 - box.x0, box.y1 - box.y0, v.stride};
}

/// Whether row y of `a` and `b` (the same width) holds the same bits.
inline bool sameRow(ConstGridView a, ConstGridView b, int y) {
    return std::memcmp(a.row(y), b.row(y), sizeof(float) * b.nx) == 0;
}

/// The rows of `rows` (cut to the views) from the first to the last that
/// differ; empty (y0 == y1) when none does.
inline RowSpan differingRows(ConstGridView a, ConstGridView b, RowSpan rows) {
    rows = rows.cut(b.ny);
    while (rows.y0 < rows.y1 && sameRow(a, b, rows.y0)) ++rows.y0;
    while (rows.y1 > rows.y0 && sameRow(a, b, rows.y1 - 1)) --rows.y1;
    return rows;
}

/// The box from the first to the last row of `a` and `b` (the same size)
/// that differ, and in those rows from the first to the last differing
/// column; empty when no cell differs. Bits are compared, so -0 and 0 differ.
inline CellBox differingCells(ConstGridView a, ConstGridView b) {
    const auto [y0, y1] = differingRows(a, b, RowSpan{0, b.ny});
    if (y0 == y1) return CellBox::none();
    const auto same = [&](int x, int y) { return std::memcmp(a.row(y) + x, b.row(y) + x, sizeof(float)) == 0; };
    int x0 = b.nx, x1 = 0;
    for (int y = y0; y < y1; ++y) {
        int first = 0, last = b.nx;
        while (first < std::min(x0, last) && same(first, y)) ++first;
        while (last > std::max(x1, first) && same(last - 1, y)) --last;
        if (first < last) {
            x0 = std::min(x0, first);
            x1 = std::max(x1, last);
        }
    }
    return {x0, y0, x1, y1};
}

/// differingCells over the cells of `box` alone (the views of one size), in
/// the views' coordinates: the cells outside it are known to be equal.
inline CellBox differingCellsIn(ConstGridView a, ConstGridView b, CellBox box) {
    box = box.cut(b.nx, b.ny);
    return differingCells(subView(a, box), subView(b, box)).shifted(box.x0, box.y0);
}

}  // namespace terrain
