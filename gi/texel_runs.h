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
#include "core/parallel.h"
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

/// The smallest box of texels holding every run (empty without runs).
CellBox boundingBox(const TexelRuns& runs);

/// A rectangle of texels, columns [x0, x1) of rows [y0, y1).
struct TexelRect {
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};

/// The runs of the union of `rects` (cut to an nx x ny field): per row the
/// columns of the rectangles holding it, sorted, overlapping and adjacent
/// ones merged.
void texelRunsOfRects(std::span<const TexelRect> rects, int nx, int ny, TexelRuns& out);

/// Texels in the runs.
long long texelCount(const TexelRuns& runs);

/// The values of `grid` at the runs' texels, run after run, into out (for
/// differingInRuns after a restricted pass).
void copyRuns(ConstGridView grid, const TexelRuns& runs, std::vector<float>& out);

/// The smallest box of the runs' texels where `grid` differs bit for bit
/// from `before` (copyRuns of the same runs); empty when none does. A pass
/// restricted to the runs costs this by its texels, not by their bounding
/// box (changes at several places far apart).
CellBox differingInRuns(const std::vector<float>& before, ConstGridView grid, const TexelRuns& runs);

/// The blocks of [0, nBlocks) holding a row with a run, block b being the
/// rows rowsOf(b) (a RowSpan), in order, into out (every block with a row
/// when `runs` is null): a pass over fixed row blocks hands out only these
/// (parallelForEach), so that a local change's few blocks are shared among
/// the threads.
template <class RowsOf>
void blocksWithRuns(const TexelRuns* runs, int nBlocks, RowsOf&& rowsOf, std::vector<int>& out) {
    blocksWithRows(
        nBlocks, rowsOf, [&](int y) { return !runs || runs->hasRow(y); }, out);
}

/// Row y's runs, or `whole` (a caller's run [0, nx)) when there are no runs
/// (null: every texel).
inline std::span<const ColumnSpan> runsOfRow(const TexelRuns* runs, int y, const ColumnSpan& whole) {
    return runs ? runs->ofRow(y) : std::span<const ColumnSpan>(&whole, 1);
}

/// Along one axis of `count` texels at sub-sampling s (n receivers, tiles
/// of T): per tile t, the first and last texel that reads one of its
/// receivers [T t, T t + T) (a texel reads its lower receiver and the next).
void texelsReadingTiles(int count, int s, int n, int T, std::vector<int>& first, std::vector<int>& last);

/// The receivers [a, b) a stretch of texels reads along one axis of n
/// receivers, from the lower receivers (receiverLerp's i0) of its first and
/// last texel: each texel reads its lower receiver and the next one, clamped.
inline ColumnSpan receiversReadBy(int firstLower, int lastLower, int n) {
    return {firstLower, lastLower + 2 < n ? lastLower + 2 : n};
}

/// The receiver columns the runs of texel rows [y0, y1) read, of n;
/// lowerOf(x) is texel column x's lower receiver. Every column without runs;
/// an empty span when none of the rows has a run.
template <class LowerOf>
ColumnSpan receiverColumnsRead(const TexelRuns* runs, int y0, int y1, int n, LowerOf lowerOf) {
    if (!runs) return {0, n};
    ColumnSpan cols{n, 0};
    for (int y = y0; y < y1; ++y) {
        const std::span<const ColumnSpan> r = runs->ofRow(y);
        if (r.empty()) continue;
        const ColumnSpan read = receiversReadBy(lowerOf(r.front().x0), lowerOf(r.back().x1 - 1), n);
        cols = {cols.x0 < read.x0 ? cols.x0 : read.x0, cols.x1 > read.x1 ? cols.x1 : read.x1};
    }
    return {cols.x0, cols.x1 > cols.x0 ? cols.x1 : cols.x0};
}

/// The texels to redo as rectangles, appended to `out`: per dirty tile of
/// `recomputed`, the texels that read one of its receivers (its own, and
/// those of the last receiver column and row of the tiles before it:
/// texelsReadingTiles along each axis), and, with `before`, per texel tile
/// within `reach` cells of a height that differs bit for bit (-0 is not 0:
/// it can change a result's sign), its texels. With `flagged` (null: not
/// wanted), on recomputed's layout, the tiles of either kind. The heights
/// are an nx x ny field at sub-sampling s of the tiles' grid. `differing`
/// holds every cell where before and after may differ (every cell by
/// default): tiles whose cells lie outside it are not compared.
void appendTexelsToRedo(const ReceiverTiles& recomputed, const ConstGridView* before, ConstGridView after,
                        int subsample, int reach, std::vector<TexelRect>& out, ReceiverTiles* flagged = nullptr,
                        CellBox differing = {});

}  // namespace terrain::gi
