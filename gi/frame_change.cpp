#include "gi/frame_change.h"

#include <algorithm>
#include <array>
#include <cstring>

#include "core/parallel.h"

namespace terrain::gi {
namespace {

// differingCells (core/grid.h), its search for the first and the last
// differing row split over row chunks side by side: every frame compares
// the whole field, where a local change leaves most rows the same.
CellBox differingHeights(ConstGridView a, ConstGridView b) {
    constexpr int kChunks = 16;
    std::array<RowSpan, kChunks> differing;  // per chunk: its first and one past its last differing row
    parallelFor(0, kChunks, 1, [&](int c0, int c1) {
        for (int c = c0; c < c1; ++c)
            differing[static_cast<std::size_t>(c)] =
                differingRows(a, b, RowSpan{b.ny * c / kChunks, b.ny * (c + 1) / kChunks});
    });
    RowSpan rows{b.ny, 0};
    for (const RowSpan& r : differing)
        if (r.y0 < r.y1) rows = {std::min(rows.y0, r.y0), std::max(rows.y1, r.y1)};
    if (rows.y0 >= rows.y1) return CellBox::none();
    return differingCellsIn(a, b, {0, rows.y0, b.nx, rows.y1});
}

bool sameGrid(const Grid& a, ConstGridView b) {
    if (a.nx != b.nx || a.ny != b.ny) return false;
    for (int y = 0; y < b.ny; ++y)
        if (!sameRow(a.cview(), b, y)) return false;
    return true;
}

bool sameGrid(const Grid& a, const Grid& b) { return sameGrid(a, b.cview()); }

bool sameAlbedo(const FrameInputs& last, const AlbedoMap* albedo) {
    if (last.hasAlbedo != (albedo != nullptr)) return false;
    if (!albedo) return true;
    for (std::size_t c = 0; c < 3; ++c)
        if (!sameGrid(last.albedo.channel[c], albedo->channel[c]) ||
            !sameGrid(last.albedo.phongLobe[c], albedo->phongLobe[c]))
            return false;
    return sameGrid(last.albedo.phongExponent, albedo->phongExponent);
}

bool sameKeyRadiance(const KeyLight& a, const KeyLight& b) {
    return a.rgb[0] == b.rgb[0] && a.rgb[1] == b.rgb[1] && a.rgb[2] == b.rgb[2];
}

}  // namespace

bool FrameChange::any() const {
    return geometry || radiance || std::find(keyRegion.begin(), keyRegion.end(), true) != keyRegion.end();
}

FrameChange everythingChanged(std::size_t keys) {
    FrameChange c;
    c.keyRegion.assign(keys, true);
    return c;
}

FrameChange compareFrameInputs(const FrameInputs& last, ConstGridView heights, float cellSize,
                               const GiLighting& lighting, const GiSettings& settings, const AlbedoMap* albedo) {
    const std::size_t nKeys = lighting.keys.size();
    if (!last.valid) return everythingChanged(nKeys);
    FrameChange c;
    const bool sameSize = last.heights.nx == heights.nx && last.heights.ny == heights.ny;
    if (sameSize) c.newHeights = differingHeights(last.heights.cview(), heights);
    const bool sameFrame = sameSize && cellSize == last.cellSize && settings == last.settings;
    if (sameFrame) {
        c.heightBox = c.newHeights;
        c.geometry = !c.heightBox.empty();
    }
    c.heightsOnly = sameFrame && c.geometry;
    if (!c.heightsOnly) c.heightBox = {};
    c.keyRegion.assign(nKeys, true);
    bool keyRadiance = nKeys != last.keys.size();
    for (std::size_t k = 0; k < nKeys; ++k) {
        const bool known = k < last.keys.size();
        c.keyRegion[k] = !known || !sameSkyRegion(lighting.keys[k], last.keys[k]);
        keyRadiance = keyRadiance || !known || !sameKeyRadiance(lighting.keys[k], last.keys[k]);
    }
    const bool environment = lighting.environment.c != last.environment.c || lighting.gradient != last.gradient;
    c.radiance = environment || keyRadiance || !sameAlbedo(last, albedo);
    return c;
}

void recordFrameInputs(ConstGridView heights, float cellSize, const GiLighting& lighting, const GiSettings& settings,
                       const AlbedoMap* albedo, const FrameChange& change, FrameInputs& out) {
    if (change.geometry) copyGrid(heights, out.heights, change.heightBox.rows());  // every row unless heightsOnly
    out.cellSize = cellSize;
    out.settings = settings;
    out.environment = lighting.environment;
    out.gradient = lighting.gradient;
    out.keys = lighting.keys;
    out.hasAlbedo = albedo != nullptr;
    if (albedo && change.radiance) out.albedo = *albedo;
    out.valid = true;
}

}  // namespace terrain::gi
