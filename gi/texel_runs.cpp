#include "gi/texel_runs.h"

#include <algorithm>
#include <cstring>
#include <string>
#include <utility>

#include "core/error.h"
#include "gi/shading.h"

namespace terrain::gi {

namespace {

// first[X]: the first texel (column or row) whose lower receiver is X or a
// later one (nothing: `count`), X = 0..n; the lower receiver grows with the texel.
void firstTexels(int count, int s, int n, std::vector<int>& first) {
    first.assign(static_cast<std::size_t>(n) + 1, count);
    for (int x = count - 1; x >= 0; --x) first[static_cast<std::size_t>(receiverLerp(x, s, n).i0)] = x;
    for (int X = n - 1; X >= 0; --X)
        first[static_cast<std::size_t>(X)] =
            std::min(first[static_cast<std::size_t>(X)], first[static_cast<std::size_t>(X) + 1]);
}

}  // namespace

void texelsReadingTiles(int count, int s, int n, int T, std::vector<int>& first, std::vector<int>& last) {
    std::vector<int> lowerFrom;
    firstTexels(count, s, n, lowerFrom);
    const int tiles = (n + T - 1) / T;
    first.resize(static_cast<std::size_t>(tiles));
    last.resize(static_cast<std::size_t>(tiles));
    for (int t = 0; t < tiles; ++t) {
        // lower receivers from the one before the tile (whose next is the tile's first) to its last
        first[static_cast<std::size_t>(t)] = lowerFrom[static_cast<std::size_t>(std::max(0, t * T - 1))];
        last[static_cast<std::size_t>(t)] = lowerFrom[static_cast<std::size_t>(std::min(n, (t + 1) * T))] - 1;
    }
}

void texelRunsOfTiles(const ReceiverTiles* tiles, int nx, int ny, int subsample, TexelRuns& out) {
    const int s = subsample, nxr = (nx + s - 1) / s, nyr = (ny + s - 1) / s;
    out.ny = ny;
    out.first.assign(static_cast<std::size_t>(ny) + 1, 0);
    out.runs.clear();
    if (!tiles) {
        for (int y = 0; y < ny; ++y) {
            if (nx > 0) out.runs.push_back({0, nx});
            out.first[static_cast<std::size_t>(y) + 1] = static_cast<int>(out.runs.size());
        }
        return;
    }
    if (tiles->nxr != nxr || tiles->nyr != nyr)
        throw InputError("texel runs: tiles of a " + std::to_string(tiles->nxr) + " x " + std::to_string(tiles->nyr) +
                         " receiver grid, not " + std::to_string(nxr) + " x " + std::to_string(nyr));
    std::vector<int> col;
    firstTexels(nx, s, nxr, col);
    const int T = tiles->tileSize;
    for (int y = 0; y < ny; ++y) {
        const int ty = receiverLerp(y, s, nyr).i0 / T;
        for (int tx = 0; tx < tiles->tilesX; ++tx) {
            if (!tiles->isDirty(tx, ty)) continue;
            const int x0 = col[static_cast<std::size_t>(tx * T)];
            const int x1 = col[static_cast<std::size_t>(std::min(nxr, (tx + 1) * T))];
            if (x0 >= x1) continue;
            const bool joins =
                static_cast<int>(out.runs.size()) > out.first[static_cast<std::size_t>(y)] && out.runs.back().x1 == x0;
            if (joins)
                out.runs.back().x1 = x1;
            else
                out.runs.push_back({x0, x1});
        }
        out.first[static_cast<std::size_t>(y) + 1] = static_cast<int>(out.runs.size());
    }
}

namespace {

// A cell box, inclusive (it may reach outside the grid).
struct InclusiveCells {
    int x0, y0, x1, y1;
};

// The cells of tile (tx, ty)'s texels (on `tiles`' receiver grid, an nx x
// ny field at sub-sampling s), dilated by `reach` cells.
InclusiveCells texelCellsOfTile(const ReceiverTiles& tiles, int tx, int ty, int nx, int ny, int subsample, int reach) {
    const int s = subsample, T = tiles.tileSize;
    // receivers [X0, X1) take the texels [s X0, s X1), and the tile holding
    // receiver n - 2 (the largest lower receiver) the texels up to the end
    const auto span = [&](int t, int n, int cells) {
        const int X0 = t * T, X1 = std::min(n, (t + 1) * T);
        const int hi = X1 > n - 2 ? cells - 1 : s * X1 - 1;
        return std::pair<int, int>{s * X0 - reach, hi + reach};
    };
    const auto [x0, x1] = span(tx, tiles.nxr, nx);
    const auto [y0, y1] = span(ty, tiles.nyr, ny);
    return {x0, y0, x1, y1};
}

// Whether any cell of the box (clamped to the grids) differs bit for bit.
bool cellsDiffer(ConstGridView before, ConstGridView after, InclusiveCells box) {
    const int x0 = std::max(0, box.x0), x1 = std::min(after.nx - 1, box.x1);
    const int y0 = std::max(0, box.y0), y1 = std::min(after.ny - 1, box.y1);
    if (x0 > x1) return false;
    const std::size_t bytes = sizeof(float) * static_cast<std::size_t>(x1 - x0 + 1);
    for (int y = y0; y <= y1; ++y)
        if (std::memcmp(before.row(y) + x0, after.row(y) + x0, bytes) != 0) return true;
    return false;
}

}  // namespace

CellBox boundingBox(const TexelRuns& runs) {
    CellBox box = CellBox::none();
    for (int y = 0; y < runs.ny; ++y) {
        const std::span<const ColumnSpan> row = runs.ofRow(y);
        if (row.empty()) continue;  // runs are not empty, left to right
        box = box.joined({row.front().x0, y, row.back().x1, y + 1});
    }
    return box;
}

void copyRuns(ConstGridView grid, const TexelRuns& runs, std::vector<float>& out) {
    out.resize(static_cast<std::size_t>(texelCount(runs)));
    float* to = out.data();
    for (int y = 0; y < runs.ny; ++y)
        for (const ColumnSpan& r : runs.ofRow(y)) to = std::copy(grid.row(y) + r.x0, grid.row(y) + r.x1, to);
}

CellBox differingInRuns(const std::vector<float>& before, ConstGridView grid, const TexelRuns& runs) {
    if (before.size() != static_cast<std::size_t>(texelCount(runs)))
        throw InputError("differingInRuns: the copy is not of these runs");
    CellBox box = CellBox::none();
    const float* was = before.data();
    for (int y = 0; y < runs.ny; ++y)
        for (const ColumnSpan& r : runs.ofRow(y)) {
            const float* now = grid.row(y);
            const auto same = [&](int x) { return std::memcmp(now + x, was + (x - r.x0), sizeof(float)) == 0; };
            int first = r.x0, last = r.x1;
            while (first < last && same(first)) ++first;
            while (last > first && same(last - 1)) --last;
            if (first < last) box = box.joined({first, y, last, y + 1});
            was += r.x1 - r.x0;
        }
    return box;
}

void texelRunsOfRects(std::span<const TexelRect> rects, int nx, int ny, TexelRuns& out) {
    out.ny = ny;
    out.first.assign(static_cast<std::size_t>(ny) + 1, 0);
    out.runs.clear();
    std::vector<ColumnSpan> row;
    for (int y = 0; y < ny; ++y) {
        row.clear();
        for (const TexelRect& r : rects)
            if (r.y0 <= y && y < r.y1 && std::max(r.x0, 0) < std::min(r.x1, nx))
                row.push_back({std::max(r.x0, 0), std::min(r.x1, nx)});
        std::sort(row.begin(), row.end(), [](const ColumnSpan& a, const ColumnSpan& b) { return a.x0 < b.x0; });
        const std::size_t rowStart = out.runs.size();
        for (const ColumnSpan& c : row)
            if (out.runs.size() > rowStart && c.x0 <= out.runs.back().x1)
                out.runs.back().x1 = std::max(out.runs.back().x1, c.x1);
            else
                out.runs.push_back(c);
        out.first[static_cast<std::size_t>(y) + 1] = static_cast<int>(out.runs.size());
    }
}

long long texelCount(const TexelRuns& runs) {
    long long n = 0;
    for (const ColumnSpan& r : runs.runs) n += r.x1 - r.x0;
    return n;
}

void appendTexelsToRedo(const ReceiverTiles& recomputed, const ConstGridView* before, ConstGridView after,
                        int subsample, int reach, std::vector<TexelRect>& out, ReceiverTiles* flagged,
                        CellBox differing) {
    differing = differing.cut(after.nx, after.ny);
    const ReceiverTiles& t = recomputed;
    if (flagged) flagged->reset(t.nxr, t.nyr, t.tileSize, false);
    const int s = subsample, T = t.tileSize;
    std::vector<int> readX0, readX1, readY0, readY1;
    texelsReadingTiles(after.nx, s, t.nxr, T, readX0, readX1);
    texelsReadingTiles(after.ny, s, t.nyr, T, readY0, readY1);
    std::vector<int> ownX, ownY;  // the texels of each tile: those whose lower receiver it holds
    firstTexels(after.nx, s, t.nxr, ownX);
    firstTexels(after.ny, s, t.nyr, ownY);
    for (int ty = 0; ty < t.tilesY; ++ty)
        for (int tx = 0; tx < t.tilesX; ++tx) {
            const auto x = static_cast<std::size_t>(tx), y = static_cast<std::size_t>(ty);
            if (t.isDirty(tx, ty)) {
                out.push_back({readX0[x], readY0[y], readX1[x] + 1, readY1[y] + 1});
                if (flagged) flagged->setDirty(tx, ty);
                continue;
            }
            // only the cells of `differing` can differ
            const InclusiveCells c = texelCellsOfTile(t, tx, ty, after.nx, after.ny, s, reach);
            const InclusiveCells maybe{std::max(c.x0, differing.x0), std::max(c.y0, differing.y0),
                                       std::min(c.x1, differing.x1 - 1), std::min(c.y1, differing.y1 - 1)};
            if (!before || !cellsDiffer(*before, after, maybe)) continue;
            if (flagged) flagged->setDirty(tx, ty);
            out.push_back({ownX[static_cast<std::size_t>(tx * T)], ownY[static_cast<std::size_t>(ty * T)],
                           ownX[static_cast<std::size_t>(std::min(t.nxr, (tx + 1) * T))],
                           ownY[static_cast<std::size_t>(std::min(t.nyr, (ty + 1) * T))]});
        }
}

}  // namespace terrain::gi
