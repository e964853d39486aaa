#include "gi/visibility_cache.h"

#include <algorithm>
#include <limits>

#include "core/error.h"

namespace terrain::gi {

void resetVisibilityCache(const HeightPyramid& pyr, ConstGridView heights, VisibilityCache& cache) {
    cache.tiles.reset(pyr.nxr, pyr.nyr, kVisibilityTile, true);
    cache.keyTiles.reset(pyr.nxr, pyr.nyr, kVisibilityTile, true);
    cache.geometryTiles.reset(pyr.nxr, pyr.nyr, kVisibilityTile, true);
    cache.drift.reset(cache.tiles.dirty.size());
    cache.keyDrift.reset(cache.tiles.dirty.size());
    cache.geometryDrift.reset(cache.tiles.dirty.size());
    copyGrid(heights, cache.anchorHeights);
    cache.anchorDiffers = CellBox{};  // the next plan compares every cell once
}

void forgetEnvironmentDrift(VisibilityCache& cache) { cache.drift.recomputedAll(); }

bool shouldPlanTiles(VisibilityCache& cache) { return !skipsPlan(cache.skips); }

namespace {

// Per tile, the largest over the key lights of the bound on each one's
// visible fraction (keyLightFractionBound; an SH-shaded light: infinite
// where its slopes may have moved at all). 0 without key lights.
void boundKeyFractions(const HeightPyramid& pyr, const std::vector<KeyLightRegion>& keys, float lipschitz,
                       VisibilityCache& cache) {
    cache.keyBound.assign(cache.slopeBound.size(), 0.0f);
    for (const KeyLightRegion& k : keys) {
        boundSlopeChangeOverRange(cache.change, pyr, kVisibilityTile, k.phi0, k.phi1, cache.rangeBound);
        for (std::size_t t = 0; t < cache.keyBound.size(); ++t) {
            float f = keyLightFractionBound(lipschitz * cache.rangeBound[t], cache.gradBound[t], k.sinLow, k.sinHigh);
            if (!k.exactCosine && f > 0.0f) f = std::numeric_limits<float>::infinity();
            cache.keyBound[t] = std::max(cache.keyBound[t], f);
        }
    }
}

// The key lights' shade per unit of visible fraction: the sum of their
// largest channels (a texel's key shade is sum_k rgb_k f_k max(0, N . l_k)).
float keyShadePerFraction(const std::vector<KeyLightRegion>& keys) {
    double sum = 0.0;
    for (const KeyLightRegion& k : keys) sum += k.maxRgb;  // >= 0 (validateKeyLight)
    return static_cast<float>(sum);
}

}  // namespace

bool planKeyBrightness(const std::vector<KeyLightRegion>& keys, float tolerance, VisibilityCache& cache) {
    return markDriftAgain(keyShadePerFraction(keys), tolerance, cache.keyDrift, cache.keyTiles.dirty);
}

void environmentBoundPerTile(std::span<const float> azimuthBound, std::span<const float> gradBound, int azimuths,
                             float lipschitz, std::vector<float>& scratch, std::vector<float>& out) {
    const std::size_t m = static_cast<std::size_t>(azimuths), tiles = gradBound.size();
    if (azimuths < 1 || azimuthBound.size() != tiles * m)
        throw InputError("environmentBoundPerTile: one slope bound per tile and azimuth, at least one azimuth");
    scratch.resize(m);  // no allocation after the first frame of these settings
    out.resize(tiles);
    for (std::size_t t = 0; t < tiles; ++t) {
        for (std::size_t j = 0; j < m; ++j) scratch[j] = lipschitz * azimuthBound[t * m + j];
        out[t] = ambientChangeBoundPerAzimuth(scratch.data(), azimuths, gradBound[t], 1.0f, false);
    }
}

void geometryBoundPerTile(std::span<const float> slopeBound, std::span<const float> gradBound, float lipschitz,
                          std::vector<float>& out) {
    if (slopeBound.size() != gradBound.size())
        throw InputError("geometryBoundPerTile: one slope bound and one gradient bound per tile");
    out.resize(slopeBound.size());
    for (std::size_t t = 0; t < out.size(); ++t)
        out[t] = ambientChangeBound(lipschitz * slopeBound[t], gradBound[t], 1.0f, false);
}

void planVisibilityTiles(ConstGridView before, ConstGridView after, const HeightPyramid& pyr,
                         const VisibilitySettings& vis, const std::vector<KeyLightRegion>& keys, float tolerance,
                         VisibilityCache& cache, CellBox sinceBefore) {
    if (cache.tiles.nxr != pyr.nxr || cache.tiles.nyr != pyr.nyr || !cache.drift.fits(cache.tiles.dirty.size()) ||
        cache.anchorHeights.nx != after.nx || cache.anchorHeights.ny != after.ny)
        resetVisibilityCache(pyr, before, cache);
    // outside the cells that differ from the anchor's, |dh| is 0 (and the
    // anchor's rows the same as this frame's); they lie where the anchor
    // differs from `before` or `before` from `after`
    const CellBox mayDiffer = cache.anchorDiffers.joined(sinceBefore).cut(after.nx, after.ny);
    const CellBox differing = differingCellsIn(cache.anchorHeights.cview(), after, mayDiffer);
    buildMaxChangePyramid(cache.anchorHeights.cview(), after, cache.change, differing);
    boundSlopeChange(cache.change, pyr, kVisibilityTile, cache.slopeBound);
    boundSlopeChangePerAzimuth(cache.change, pyr, kVisibilityTile, vis.azimuths, cache.azimuthBound);
    boundGradientChange(cache.change, pyr, kVisibilityTile, cache.gradBound);
    // V depends on the heights through the maximum blocking slope and, below
    // it, the tangent plane's slope along the azimuth (moving by at most
    // sqrt2 times a gradient component's bound); shading reruns at the new
    // normals every frame, so only V's own change counts.
    const float lipschitz = blockingMaxLipschitz(vis.blockingMax);
    boundKeyFractions(pyr, keys, lipschitz, cache);
    environmentBoundPerTile(cache.azimuthBound, cache.gradBound, vis.azimuths, lipschitz, cache.tileAzimuths,
                            cache.envBound);
    geometryBoundPerTile(cache.slopeBound, cache.gradBound, lipschitz, cache.geometryBound);
    // one anchor for the three drifts: they vote together on moving it
    AnchorVotes votes;
    markAnchoredDrift(cache.envBound, {}, 1.0f, tolerance, cache.drift, cache.tiles.dirty, votes);
    markAnchoredDrift(cache.keyBound, {}, keyShadePerFraction(keys), tolerance, cache.keyDrift, cache.keyTiles.dirty,
                      votes);
    markAnchoredDrift(cache.geometryBound, {}, 1.0f, tolerance, cache.geometryDrift, cache.geometryTiles.dirty, votes);
    const bool reanchor = votes.reanchor();
    advanceAnchoredDrift(cache.envBound, cache.tiles.dirty, reanchor, cache.drift);
    advanceAnchoredDrift(cache.keyBound, cache.keyTiles.dirty, reanchor, cache.keyDrift);
    advanceAnchoredDrift(cache.geometryBound, cache.geometryTiles.dirty, reanchor, cache.geometryDrift);
    // the anchor becomes `after`, which differs from `before` within
    // sinceBefore; else it differs from `before` and from `after` (the
    // next plan's `before`, if this frame is recorded) within mayDiffer
    if (reanchor) copyGrid(after, cache.anchorHeights, differing.rows());
    cache.anchorDiffers = reanchor ? sinceBefore : mayDiffer;
    const int all = static_cast<int>(cache.slopeBound.size());
    // the indirect light re-gathers the geometry's dirty tiles: both count
    countAfterPlan(std::min(cache.tiles.dirtyCount(), cache.geometryTiles.dirtyCount()), all, cache.skips);
}

}  // namespace terrain::gi
