#include "gi/receiver_tiles.h"

#include <algorithm>
#include <string>

#include "core/error.h"

namespace terrain::gi {

namespace {

void checkTileSize(int size) {
    if (size <= 0 || size % ReceiverTiles::kTileAlign != 0)
        throw InputError("receiver tiles: tile size " + std::to_string(size) + " is not a positive multiple of " +
                         std::to_string(ReceiverTiles::kTileAlign));
}

}  // namespace

void ReceiverTiles::reset(int receiversX, int receiversY, int size, bool allDirty) {
    checkTileSize(size);
    if (receiversX < 0 || receiversY < 0) throw InputError("receiver tiles: negative receiver grid");
    nxr = receiversX;
    nyr = receiversY;
    tileSize = size;
    tilesX = tileCount(nxr, size);
    tilesY = tileCount(nyr, size);
    dirty.assign(static_cast<std::size_t>(tilesX) * tilesY, allDirty ? 1 : 0);
}

int ReceiverTiles::dirtyCount() const {
    return static_cast<int>(std::count_if(dirty.begin(), dirty.end(), [](std::uint8_t d) { return d != 0; }));
}

double ReceiverTiles::dirtyFraction() const {
    if (nxr <= 0 || nyr <= 0) return 0.0;
    long long covered = 0;
    for (int ty = 0; ty < tilesY; ++ty)
        for (int tx = 0; tx < tilesX; ++tx)
            if (isDirty(tx, ty)) {
                const long long w = std::min(nxr, (tx + 1) * tileSize) - tx * tileSize;
                const long long h = std::min(nyr, (ty + 1) * tileSize) - ty * tileSize;
                covered += w * h;
            }
    return static_cast<double>(covered) / (static_cast<double>(nxr) * nyr);
}

void dirtySpans(const ReceiverTiles* only, int nxr, int nyr, DirtySpans& out) {
    out.first.clear();
    out.spans.clear();
    if (!only) {
        // everything: one tile row of all receiver rows, one span each
        out.rowsPerTile = std::max(1, nyr);
        out.first = {0, nxr > 0 && nyr > 0 ? 1 : 0};
        if (nxr > 0 && nyr > 0) out.spans.push_back({0, nxr});
        return;
    }
    checkTileSize(only->tileSize);
    if (only->nxr != nxr || only->nyr != nyr || only->tilesX != tileCount(nxr, only->tileSize) ||
        only->tilesY != tileCount(nyr, only->tileSize) ||
        only->dirty.size() != static_cast<std::size_t>(only->tilesX) * only->tilesY)
        throw InputError("receiver tiles: made for a " + std::to_string(only->nxr) + " x " + std::to_string(only->nyr) +
                         " receiver grid, not " + std::to_string(nxr) + " x " + std::to_string(nyr));
    const int size = only->tileSize;
    out.rowsPerTile = size;
    out.first.push_back(0);
    for (int ty = 0; ty < only->tilesY; ++ty) {
        for (int tx = 0; tx < only->tilesX; ++tx) {
            if (!only->isDirty(tx, ty)) continue;
            const int x0 = tx * size, x1 = std::min(nxr, x0 + size);
            if (static_cast<int>(out.spans.size()) > out.first.back() && out.spans.back().x1 == x0)
                out.spans.back().x1 = x1;  // adjacent to the previous dirty tile of this row: merged
            else
                out.spans.push_back({x0, x1});
        }
        out.first.push_back(static_cast<int>(out.spans.size()));
    }
}

}  // namespace terrain::gi
