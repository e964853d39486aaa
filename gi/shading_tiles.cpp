#include "gi/shading_tiles.h"

#include <algorithm>
#include <bit>
#include <cstdint>
#include <limits>

#include "core/error.h"

namespace terrain::gi {

namespace {

void checkSizes(ConstGridView before, ConstGridView after, const ReceiverTiles& env,
                std::span<const ReceiverRun> keys) {
    if (before.nx != after.nx || before.ny != after.ny)
        throw InputError("shading tiles: the heights before and after differ in size");
    for (const ReceiverRun& r : keys)
        if (r.y < 0 || r.y >= env.nyr || r.x0 < 0 || r.x1 > env.nxr || r.x0 >= r.x1)
            throw InputError("shading tiles: a key receiver run outside the environment's receiver grid");
}

// The texels that read a receiver of each run (a texel reads its lower
// receiver and the next one, gi/texel_runs.h), into out.
void appendTexelsReading(std::span<const ReceiverRun> runs, int nx, int ny, int subsample, int nxr, int nyr,
                         std::vector<TexelRect>& out) {
    if (runs.empty()) return;
    std::vector<int> x0, x1, y0, y1;  // per receiver: its first and last reading texel
    texelsReadingTiles(nx, subsample, nxr, 1, x0, x1);
    texelsReadingTiles(ny, subsample, nyr, 1, y0, y1);
    for (const ReceiverRun& r : runs) {
        const auto y = static_cast<std::size_t>(r.y);
        out.push_back(
            {x0[static_cast<std::size_t>(r.x0)], y0[y], x1[static_cast<std::size_t>(r.x1 - 1)] + 1, y1[y] + 1});
    }
}

// Whether the key fields have the layout of `tiles`' receivers, holding
// their planes.
bool fieldsFit(const std::vector<VisibilityField>& keys, const ReceiverTiles& tiles) {
    return std::all_of(keys.begin(), keys.end(), [&](const VisibilityField& v) {
        return v.nxr == tiles.nxr && v.nyr == tiles.nyr &&
               v.sh.size() >= static_cast<std::size_t>(v.planes) * v.nxr * v.nyr;
    });
}

// Calls f(first receiver column, receiver row, first value, count) for
// each receiver row of each dirty tile, in each light's each plane: tile by
// tile, in one order; done(tx, ty, x0, y0, y1) after each tile's rows.
template <class F, class Done>
void forEachKeySpan(const std::vector<VisibilityField>& keys, const ReceiverTiles& tiles, F&& f, Done&& done) {
    const int T = tiles.tileSize;
    for (int ty = 0; ty < tiles.tilesY; ++ty)
        for (int tx = 0; tx < tiles.tilesX; ++tx) {
            if (!tiles.isDirty(tx, ty)) continue;
            const int x0 = tx * T, x1 = std::min(tiles.nxr, x0 + T);
            const int y0 = ty * T, y1 = std::min(tiles.nyr, (ty + 1) * T);
            for (const VisibilityField& v : keys)
                for (int p = 0; p < v.planes; ++p)
                    for (int Y = y0; Y < y1; ++Y)
                        f(x0, Y, v.plane(p) + static_cast<std::size_t>(Y) * v.nxr + x0, x1 - x0);
            done(x0, x1, y0, y1);
        }
}

std::vector<std::array<int, 3>> layoutOf(const std::vector<VisibilityField>& keys) {
    std::vector<std::array<int, 3>> out;
    for (const VisibilityField& v : keys) out.push_back({v.nxr, v.nyr, v.planes});
    return out;
}

}  // namespace

void changedDirectTexels(ConstGridView before, ConstGridView after, const ReceiverTiles& env,
                         std::span<const ReceiverRun> keys, int subsample, std::vector<TexelRect>& rects,
                         TexelRuns& ambient, TexelRuns& shading, CellBox differing) {
    checkSizes(before, after, env, keys);
    rects.clear();
    appendTexelsToRedo(env, &before, after, subsample, shadingReach(subsample), rects, nullptr, differing);
    texelRunsOfRects(rects, after.nx, after.ny, ambient);
    if (keys.empty()) {
        shading = ambient;
        return;
    }
    appendTexelsReading(keys, after.nx, after.ny, subsample, env.nxr, env.nyr, rects);
    texelRunsOfRects(rects, after.nx, after.ny, shading);
}

void keepKeyVisibility(const std::vector<VisibilityField>& keys, const ReceiverTiles& tiles, KeyVisibilityBefore& out) {
    out.values.clear();
    out.layout.clear();
    if (!fieldsFit(keys, tiles)) return;
    out.layout = layoutOf(keys);
    forEachKeySpan(
        keys, tiles, [&](int, int, const float* v, int n) { out.values.insert(out.values.end(), v, v + n); },
        [](int, int, int, int) {});
}

void keyReceiversChanged(const std::vector<VisibilityField>& keys, const ReceiverTiles& tiles,
                         const KeyVisibilityBefore& before, std::vector<ReceiverRun>& changed) {
    changed.clear();
    const bool kept = fieldsFit(keys, tiles) && !before.layout.empty() && layoutOf(keys) == before.layout;
    // per row of the tile: the first and last column whose bits differ (none: x0 > x1)
    constexpr ColumnSpan kNone{std::numeric_limits<int>::max(), std::numeric_limits<int>::min()};
    std::vector<ColumnSpan> differ(static_cast<std::size_t>(tiles.tileSize), kNone);
    std::size_t at = 0;
    forEachKeySpan(
        keys, tiles,
        [&](int x0, int Y, const float* v, int n) {
            if (!kept) return;
            ColumnSpan& d = differ[static_cast<std::size_t>(Y % tiles.tileSize)];
            const float* was = before.values.data() + at;
            for (int i = 0; i < n; ++i)
                if (std::bit_cast<std::uint32_t>(v[i]) != std::bit_cast<std::uint32_t>(was[i])) {
                    d.x0 = std::min(d.x0, x0 + i);
                    d.x1 = std::max(d.x1, x0 + i);
                }
            at += static_cast<std::size_t>(n);
        },
        [&](int x0, int x1, int y0, int y1) {
            for (int Y = y0; Y < y1; ++Y) {
                ColumnSpan& d = differ[static_cast<std::size_t>(Y - y0)];
                if (!kept)
                    changed.push_back({Y, x0, x1});
                else if (d.x0 <= d.x1)
                    changed.push_back({Y, d.x0, d.x1 + 1});
                d = kNone;  // for the next tile
            }
        });
}

}  // namespace terrain::gi
