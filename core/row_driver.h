#pragma once
// The row driver of the grid passes whose cell kernels are written once over
// a lane type (core/simd.h): which cells of a row take which path.
//
// Cells on the grid's border (the first and last row, the first and last
// column, and every cell of a grid less than 3 wide) lack neighbours and take
// the scalar edge path. Interior cells run kLaneCount<V> at a time, and the
// interior cells left over at the end of the row one at a time on the scalar
// interior path. The order is fixed: left edge cell, lane groups left to
// right, remainder, right edge cell. The kernels use the same arithmetic on
// every path, so a cell's result does not depend on the path that computed
// it.
#include "core/simd.h"

namespace terrain {

/// The path a cell takes: lane type T (float: one cell; V: kLaneCount<V>
/// cells from the given x on) and whether it is an edge cell.
template <class T, bool kEdge>
struct CellPath {
    using Lanes = T;
    static constexpr bool edge = kEdge;
};

/// Calls visit(CellPath<T, kEdge>{}, x) for the cells of row y of an nx x ny
/// grid: each edge cell with CellPath<float, true>, interior cells in groups of
/// kLaneCount<V> with CellPath<V, false>, the interior remainder with
/// CellPath<float, false>.
template <class V, class Visit>
[[gnu::always_inline]] inline void forEachCellOfRow(int y, int nx, int ny, Visit&& visit) {
    constexpr int kLanes = simd::kLaneCount<V>;
    if (y == 0 || y == ny - 1 || nx < 3) {
        for (int x = 0; x < nx; ++x) visit(CellPath<float, true>{}, x);
        return;
    }
    visit(CellPath<float, true>{}, 0);
    int x = 1;
    for (; x + kLanes <= nx - 1; x += kLanes) visit(CellPath<V, false>{}, x);
    for (; x < nx - 1; ++x) visit(CellPath<float, false>{}, x);
    visit(CellPath<float, true>{}, nx - 1);
}

}  // namespace terrain
