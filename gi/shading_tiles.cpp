#include "gi/shading_tiles.h"

#include <algorithm>
#include <cstring>

#include "core/error.h"

namespace terrain::gi {

namespace {

void checkSizes(ConstGridView before, ConstGridView after, const ReceiverTiles& env, const ReceiverTiles& keys) {
    if (before.nx != after.nx || before.ny != after.ny)
        throw InputError("shading tiles: the heights before and after differ in size");
    if (keys.nxr != env.nxr || keys.nyr != env.nyr || keys.tileSize != env.tileSize)
        throw InputError("shading tiles: the environment's and the key lights' tiles differ");
}

// Whether the key fields have the layout of `tiles`' receivers, holding
// their planes.
bool fieldsFit(const std::vector<VisibilityField>& keys, const ReceiverTiles& tiles) {
    return std::all_of(keys.begin(), keys.end(), [&](const VisibilityField& v) {
        return v.nxr == tiles.nxr && v.nyr == tiles.nyr &&
               v.sh.size() >= static_cast<std::size_t>(v.planes) * v.nxr * v.nyr;
    });
}

// Calls f(tx, ty, first value, count) for each receiver row of each dirty
// tile, in each light's each plane: tile by tile, in one order.
template <class F>
void forEachKeySpan(const std::vector<VisibilityField>& keys, const ReceiverTiles& tiles, F&& f) {
    const int T = tiles.tileSize;
    for (int ty = 0; ty < tiles.tilesY; ++ty)
        for (int tx = 0; tx < tiles.tilesX; ++tx) {
            if (!tiles.isDirty(tx, ty)) continue;
            const int x0 = tx * T, x1 = std::min(tiles.nxr, x0 + T);
            for (const VisibilityField& v : keys)
                for (int p = 0; p < v.planes; ++p)
                    for (int Y = ty * T; Y < std::min(tiles.nyr, (ty + 1) * T); ++Y)
                        f(tx, ty, v.plane(p) + static_cast<std::size_t>(Y) * v.nxr + x0, x1 - x0);
        }
}

std::vector<std::array<int, 3>> layoutOf(const std::vector<VisibilityField>& keys) {
    std::vector<std::array<int, 3>> out;
    for (const VisibilityField& v : keys) out.push_back({v.nxr, v.nyr, v.planes});
    return out;
}

}  // namespace

void changedDirectTexels(ConstGridView before, ConstGridView after, const ReceiverTiles& env, const ReceiverTiles& keys,
                         int subsample, std::vector<TexelRect>& rects, TexelRuns& ambient, TexelRuns& shading,
                         CellBox differing) {
    checkSizes(before, after, env, keys);
    rects.clear();
    appendTexelsToRedo(env, &before, after, subsample, shadingReach(subsample), rects, nullptr, differing);
    texelRunsOfRects(rects, after.nx, after.ny, ambient);
    if (keys.dirtyCount() == 0) {
        shading = ambient;
        return;
    }
    appendTexelsToRedo(keys, nullptr, after, subsample, 0, rects);  // the heights are counted already
    texelRunsOfRects(rects, after.nx, after.ny, shading);
}

void keepKeyVisibility(const std::vector<VisibilityField>& keys, const ReceiverTiles& tiles, KeyVisibilityBefore& out) {
    out.values.clear();
    out.layout.clear();
    if (!fieldsFit(keys, tiles)) return;
    out.layout = layoutOf(keys);
    forEachKeySpan(keys, tiles,
                   [&](int, int, const float* v, int n) { out.values.insert(out.values.end(), v, v + n); });
}

void keyTilesChanged(const std::vector<VisibilityField>& keys, const ReceiverTiles& tiles,
                     const KeyVisibilityBefore& before, ReceiverTiles& changed) {
    changed = tiles;
    if (!fieldsFit(keys, tiles) || before.layout.empty() || layoutOf(keys) != before.layout) return;
    std::fill(changed.dirty.begin(), changed.dirty.end(), std::uint8_t{0});
    std::size_t at = 0;
    forEachKeySpan(keys, tiles, [&](int tx, int ty, const float* v, int n) {
        if (std::memcmp(v, before.values.data() + at, sizeof(float) * static_cast<std::size_t>(n)) != 0)
            changed.setDirty(tx, ty);
        at += static_cast<std::size_t>(n);
    });
}

}  // namespace terrain::gi
