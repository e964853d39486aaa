#pragma once
// Which receivers a scan recomputes, for change-driven GI: when the terrain
// changes locally, only the receivers whose results can have changed are
// scanned again, the others keep their cached values. Deciding which tiles
// are dirty is the caller's (gi/change_bound.h gives the bounds); the scans
// (computeVisibility, the Lambert indirect scan) take the tiles and
// recompute exactly the receivers of the dirty ones, bit-identical to a full
// computation, leaving every other receiver's output untouched.
//
// Tiles: tileSize x tileSize receivers, tile (tx, ty) holding receivers X in
// [tileSize tx, tileSize (tx + 1)), Y in [tileSize ty, tileSize (ty + 1)),
// the last tile column and row cut by the grid; row-major, tilesX per row
// (the layout of gi/change_bound.h's per-tile bounds). tileSize is a multiple
// of 16 (kTileAlign): the scan kernels run over groups of 16 receivers (8 for
// Eq. 16's visitor, 4 or 8 SIMD lanes) starting at multiples of 16, so a
// tile's columns are whole groups of the full computation (the last tile's
// end is the row's end, whose group is padded as in the full computation),
// and every receiver is computed by the same lanes, in the same order, as in
// a full computation.
//
// The scans read the dirty tiles as column spans per receiver row
// (DirtySpans): the [x0, x1) runs of dirty tiles, adjacent tiles merged.
// A null ReceiverTiles means every receiver (one span [0, nxr) per row).
#include <cstdint>
#include <span>
#include <vector>

namespace terrain::gi {

/// Tiles of tileReceivers along an axis of `receivers` (the last one partial).
inline int tileCount(int receivers, int tileReceivers) { return (receivers + tileReceivers - 1) / tileReceivers; }

/// Receiver tiles of a tile-restricted scan and their dirty flags.
struct ReceiverTiles {
    static constexpr int kTileAlign = 16;  // tileSize must be a multiple of it (the kernels' receiver groups)

    int nxr = 0, nyr = 0;  // the receiver grid
    int tileSize = 32;     // receivers per tile side
    int tilesX = 0, tilesY = 0;
    std::vector<std::uint8_t> dirty;  // tilesX x tilesY, row-major: non-zero = recompute

    /// Sizes the tiles for an nxr x nyr receiver grid, every flag set to
    /// `allDirty`. Throws InputError unless tileSize is a positive multiple
    /// of kTileAlign and the grid is not negative.
    void reset(int receiversX, int receiversY, int size, bool allDirty);

    bool isDirty(int tx, int ty) const { return dirty[static_cast<std::size_t>(ty) * tilesX + tx] != 0; }
    void setDirty(int tx, int ty, bool on = true) { dirty[static_cast<std::size_t>(ty) * tilesX + tx] = on ? 1 : 0; }
    /// Number of dirty tiles.
    int dirtyCount() const;
    /// Fraction of the receivers in dirty tiles (0 for an empty grid).
    double dirtyFraction() const;
};

/// A run [x0, x1) of receiver columns in one receiver row.
struct ColumnSpan {
    int x0 = 0, x1 = 0;
    bool operator==(const ColumnSpan&) const = default;
};

/// The dirty column spans of every tile row (receiver row Y belongs to tile
/// row Y / rowsPerTile), left to right, adjacent dirty tiles merged; each
/// x0 is a multiple of ReceiverTiles::kTileAlign, each x1 one too or nxr.
struct DirtySpans {
    int rowsPerTile = 1;
    std::vector<int> first;         // tile rows + 1: tile row t's spans are spans[first[t], first[t + 1])
    std::vector<ColumnSpan> spans;  // every tile row's spans, in order
    std::span<const ColumnSpan> ofRow(int Y) const {
        const std::size_t t = static_cast<std::size_t>(Y / rowsPerTile);
        return {spans.data() + first[t], spans.data() + first[t + 1]};
    }
    /// True when no receiver row has a span.
    bool empty() const { return spans.empty(); }
};

/// The spans of `only` over an nxr x nyr receiver grid into out (its
/// buffers reused); null `only`: one span [0, nxr) for every row. Throws
/// InputError when only's grid is not nxr x nyr or its flags are not
/// tilesX x tilesY.
void dirtySpans(const ReceiverTiles* only, int nxr, int nyr, DirtySpans& out);

}  // namespace terrain::gi
