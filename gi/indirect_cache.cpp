#include "gi/indirect_cache.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/parallel.h"
#include "gi/visibility_cache.h"

namespace terrain::gi {

namespace {

// The cache describes a result of this grid, with the tiles and a radiance
// pyramid of the same receivers and steps.
bool cacheFits(const IndirectPlanInputs& in, const IndirectCache& cache) {
    const HeightPyramid& h = in.heights;
    if (!cache.valid || in.lastPyramid.fields.empty()) return false;
    const HeightPyramid& r = in.lastPyramid.fields[0];
    const Grid& last = cache.lastSource[0];
    return r.nx == h.nx && r.ny == h.ny && r.nxr == h.nxr && r.nyr == h.nyr && r.steps.size() == h.steps.size() &&
           last.nx == h.nx && last.ny == h.ny && in.source[0].nx == h.nx && in.source[0].ny == h.ny &&
           cache.tiles.nxr == h.nxr && cache.tiles.nyr == h.nyr && cache.drift.size() == cache.tiles.dirty.size() &&
           (!in.geometryTiles || in.geometryTiles->dirty.size() == cache.tiles.dirty.size());
}

// max over the channels of |source - last|, each rounded up to the next
// float so that it bounds the real difference of the two floats.
void sourceChange(const std::array<Grid, 3>& source, const std::array<Grid, 3>& last, Grid& out) {
    out.ensureSize(source[0].nx, source[0].ny);
    parallelForRows(out.ny, out.nx, [&](int y0, int y1) {
        const std::size_t a = static_cast<std::size_t>(y0) * out.nx, e = static_cast<std::size_t>(y1) * out.nx;
        for (std::size_t i = a; i < e; ++i) {
            float m = 0.0f;
            for (std::size_t c = 0; c < 3; ++c) {
                const double d = std::fabs(static_cast<double>(source[c].v[i]) - last[c].v[i]);
                float f = static_cast<float>(d);
                if (static_cast<double>(f) < d) f = std::nextafter(f, std::numeric_limits<float>::infinity());
                m = std::max(m, f);
            }
            out.v[i] = m;
        }
    });
}

// Adds this frame's radiance bounds (per tile: the largest over the
// azimuths) to the drifts; none when L_0 did not change at all.
void addRadianceDrift(const IndirectPlanInputs& in, IndirectCache& cache) {
    sourceChange(in.source, cache.lastSource, cache.sourceChange);
    buildMaxChangePyramid(cache.sourceChange.cview(), cache.change);
    if (maxChangeAll(cache.change) == 0.0f) return;
    boundSampleChangePerAzimuth(cache.change, in.lastPyramid.fields[0], kVisibilityTile, in.azimuths,
                                cache.azimuthBound);
    const std::size_t m = static_cast<std::size_t>(in.azimuths);
    for (std::size_t t = 0; t < cache.drift.size(); ++t) {
        const float* az = cache.azimuthBound.data() + t * m;
        cache.drift[t] += *std::max_element(az, az + m);
    }
}

}  // namespace

const ReceiverTiles* planIndirectTiles(const IndirectPlanInputs& in, IndirectCache& cache) {
    const bool allGeometry =
        in.geometryTiles && in.geometryTiles->dirtyCount() == static_cast<int>(in.geometryTiles->dirty.size());
    if (!cacheFits(in, cache) || allGeometry) {
        cache.valid = false;
        return nullptr;
    }
    addRadianceDrift(in, cache);
    for (std::size_t t = 0; t < cache.drift.size(); ++t) {
        const bool geometry = in.geometryTiles && in.geometryTiles->dirty[t] != 0;
        const bool dirty = geometry || cache.drift[t] > in.tolerance;
        if (dirty) cache.drift[t] = 0.0f;
        cache.tiles.dirty[t] = dirty ? 1 : 0;
    }
    return &cache.tiles;
}

void recordIndirectSource(const std::array<Grid, 3>& source, const HeightPyramid& heights, bool all,
                          IndirectCache& cache) {
    cache.lastSource = source;
    if (!all) return;
    cache.tiles.reset(heights.nxr, heights.nyr, kVisibilityTile, false);
    cache.drift.assign(cache.tiles.dirty.size(), 0.0f);
    cache.valid = true;
}

}  // namespace terrain::gi
