#pragma once
// The texels a restricted texel pass redoes, for change-driven GI: the
// passes that shade full-resolution texels from their receivers (the direct
// shading, the exact ambient, the indirect light's texel passes) redo only
// the texels whose inputs can have changed, as runs of columns per texel
// row, and leave the others' values as they are.
//
// A texel belongs to the receiver tile of its lower receiver along each axis
// (receiverLerp's i0: the receiver it interpolates from, the next one being
// the other); it reads that receiver and the next along x, y or both, so it
// may read a receiver of the tile after its own. The texels of a tile are
// then one run of columns in each of a block of rows (receiverLerp clamps the
// lower receiver to n - 2, so the tile holding receiver n - 2 takes the
// texels up to the grid's end, and a last tile holding only receiver n - 1
// has none). A pass computes each texel by the same arithmetic whatever the
// runs; its whole-lane groups may take a few texels more on either side,
// whose values it then leaves where they were.
#include <span>
#include <vector>

#include "core/grid.h"
#include "gi/receiver_tiles.h"

namespace terrain::gi {

/// Column runs of texels per texel row.
struct TexelRuns {
    int ny = 0;
    std::vector<int> first;        // ny + 1: row y's runs are runs[first[y], first[y + 1])
    std::vector<ColumnSpan> runs;  // [x0, x1) texel columns, left to right, not empty
    std::span<const ColumnSpan> ofRow(int y) const {
        const std::size_t a = static_cast<std::size_t>(first[static_cast<std::size_t>(y)]);
        const std::size_t b = static_cast<std::size_t>(first[static_cast<std::size_t>(y) + 1]);
        return {runs.data() + a, b - a};
    }
    bool hasRow(int y) const { return first[static_cast<std::size_t>(y)] < first[static_cast<std::size_t>(y) + 1]; }
};

/// The texels of the dirty tiles of `tiles` (on the receiver grid of an nx x
/// ny field at sub-sampling s); null: every texel, one run [0, nx) per row.
/// Throws InputError when the tiles are not of that receiver grid.
void texelRunsOfTiles(const ReceiverTiles* tiles, int nx, int ny, int subsample, TexelRuns& out);

/// A cell box, inclusive (it may reach outside the grid).
struct CellBox {
    int x0, y0, x1, y1;
};

/// The cells of tile (tx, ty)'s texels (on `tiles`' receiver grid, an nx x
/// ny field at sub-sampling s), dilated by `reach` cells.
CellBox texelCellsOfTile(const ReceiverTiles& tiles, int tx, int ty, int nx, int ny, int subsample, int reach);

/// Whether a texel of tile (tx, ty) reads a receiver of a dirty tile of
/// `tiles`: its own, or the next one along x, y or both.
bool readsDirtyReceivers(const ReceiverTiles& tiles, int tx, int ty);

/// Whether any cell of the box (clamped to the grids, of one size) differs
/// between the two grids, bit for bit (-0 is not 0: it can change a result's sign).
bool cellsDiffer(ConstGridView before, ConstGridView after, CellBox box);

}  // namespace terrain::gi
