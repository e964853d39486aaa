#include "gi/indirect_cache.h"

#include <algorithm>
#include <cstring>

#include "gi/texel_runs.h"
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

// Adds this frame's radiance bounds (per tile: the largest over the
// azimuths) to the drifts; none when L_0 did not change at all.
void addRadianceDrift(const IndirectPlanInputs& in, IndirectCache& cache) {
    const std::array<ConstGridView, 3> before{cache.lastSource[0].cview(), cache.lastSource[1].cview(),
                                              cache.lastSource[2].cview()};
    const std::array<ConstGridView, 3> after{in.source[0].cview(), in.source[1].cview(), in.source[2].cview()};
    buildMaxChangePyramid(before, after, cache.change);
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

namespace {

// The albedo channels equal the recorded ones (recorded when not).
bool sameAlbedoAsLastPass(const AlbedoMap* albedo, IndirectCache& cache) {
    bool same = cache.hadAlbedo == (albedo != nullptr);
    for (std::size_t c = 0; c < 3 && same && albedo; ++c) {
        const Grid& now = albedo->channel[c];
        const Grid& last = cache.lastAlbedo[c];
        // bits (-0 is not 0 here); an empty channel (albedo 1) has no data to compare
        same = now.nx == last.nx && now.ny == last.ny && now.v.size() == last.v.size() &&
               (now.v.empty() || std::memcmp(now.v.data(), last.v.data(), sizeof(float) * now.v.size()) == 0);
    }
    if (same) return true;
    cache.hadAlbedo = albedo != nullptr;
    for (std::size_t c = 0; c < 3; ++c) cache.lastAlbedo[c] = albedo ? albedo->channel[c] : Grid{};
    return false;
}

}  // namespace

const ReceiverTiles* planIndirectTexels(const IndirectTexelInputs& in, IndirectCache& cache) {
    const bool albedo = sameAlbedoAsLastPass(in.albedo, cache);
    if (!in.gathered || !albedo || (!in.sameGeometry && !in.lastHeights)) return nullptr;
    // the near samples reach s cells, the gradients one more
    const ConstGridView last = in.lastHeights ? in.lastHeights->cview() : ConstGridView{};
    const ReceiverTiles* recomputed[] = {in.gathered};
    texelTilesToRedo(recomputed, in.sameGeometry ? nullptr : &last, in.heights, in.pyramid.subsample,
                     in.pyramid.subsample + 1, cache.texels);
    return &cache.texels;
}

}  // namespace terrain::gi
