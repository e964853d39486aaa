#include "gi/visibility_cache.h"

#include <algorithm>
#include <limits>

namespace terrain::gi {

namespace {

// Adds one frame's bound to a tile's drift; true (drift reset) when the tile recomputes.
bool addDrift(float bound, float tolerance, float& drift) {
    drift += bound;
    const bool recompute = drift > tolerance;
    if (recompute) drift = 0.0f;
    return recompute;
}

}  // namespace

void resetVisibilityCache(const HeightPyramid& pyr, VisibilityCache& cache) {
    cache.tiles.reset(pyr.nxr, pyr.nyr, kVisibilityTile, true);
    cache.keyTiles.reset(pyr.nxr, pyr.nyr, kVisibilityTile, true);
    cache.geometryTiles.reset(pyr.nxr, pyr.nyr, kVisibilityTile, true);
    cache.drift.assign(cache.tiles.dirty.size(), 0.0f);
    cache.keyDrift.assign(cache.tiles.dirty.size(), 0.0f);
    cache.geometryDrift.assign(cache.tiles.dirty.size(), 0.0f);
}

void forgetEnvironmentDrift(VisibilityCache& cache) { std::fill(cache.drift.begin(), cache.drift.end(), 0.0f); }

bool shouldPlanTiles(VisibilityCache& cache) { return !skipsPlan(cache.framesWithoutPlan); }

namespace {

// Per tile, the sum over the key lights of the bound on each one's shade
// (keyLightChangeBound; an SH-shaded light: infinite where its slopes may
// have moved at all). 0 without key lights.
void boundKeyShades(const HeightPyramid& pyr, const std::vector<KeyLightRegion>& keys, float lipschitz,
                    VisibilityCache& cache) {
    cache.keyBound.assign(cache.slopeBound.size(), 0.0f);
    for (const KeyLightRegion& k : keys) {
        boundSlopeChangeOverRange(cache.change, pyr, kVisibilityTile, k.phi0, k.phi1, cache.rangeBound);
        for (std::size_t t = 0; t < cache.keyBound.size(); ++t) {
            const float slope = lipschitz * cache.rangeBound[t], grad = cache.gradBound[t];
            float shade = keyLightChangeBound(slope, grad, k.maxRgb, k.sinLow, k.sinHigh);
            if (!k.exactCosine && shade > 0.0f) shade = std::numeric_limits<float>::infinity();
            cache.keyBound[t] += shade;
        }
    }
}

}  // namespace

void planVisibilityTiles(ConstGridView before, ConstGridView after, const HeightPyramid& pyr,
                         const VisibilitySettings& vis, const std::vector<KeyLightRegion>& keys, float tolerance,
                         VisibilityCache& cache) {
    if (cache.tiles.nxr != pyr.nxr || cache.tiles.nyr != pyr.nyr || cache.drift.size() != cache.tiles.dirty.size())
        resetVisibilityCache(pyr, cache);
    buildMaxChangePyramid(before, after, cache.change);
    boundSlopeChange(cache.change, pyr, kVisibilityTile, cache.slopeBound);
    boundSlopeChangePerAzimuth(cache.change, pyr, kVisibilityTile, vis.azimuths, cache.azimuthBound);
    boundGradientChange(cache.change, pyr, kVisibilityTile, cache.gradBound);
    // V depends on the heights through the maximum blocking slope and, below
    // it, the tangent plane's slope along the azimuth (moving by at most
    // sqrt2 times a gradient component's bound); shading reruns at the new
    // normals every frame, so only V's own change counts.
    const float lipschitz = blockingMaxLipschitz(vis.blockingMax);
    boundKeyShades(pyr, keys, lipschitz, cache);
    const std::size_t m = static_cast<std::size_t>(vis.azimuths);
    std::vector<float>& perAzimuth = cache.tileAzimuths;
    perAzimuth.resize(m);  // no allocation after the first frame of these settings
    for (std::size_t t = 0; t < cache.drift.size(); ++t) {
        for (std::size_t j = 0; j < m; ++j) perAzimuth[j] = lipschitz * cache.azimuthBound[t * m + j];
        const float env =
            ambientChangeBoundPerAzimuth(perAzimuth.data(), vis.azimuths, cache.gradBound[t], 1.0f, false);
        cache.tiles.dirty[t] = addDrift(env, tolerance, cache.drift[t]) ? 1 : 0;
        cache.keyTiles.dirty[t] = addDrift(cache.keyBound[t], tolerance, cache.keyDrift[t]) ? 1 : 0;
        const float any = ambientChangeBound(lipschitz * cache.slopeBound[t], cache.gradBound[t], 1.0f, false);
        cache.geometryTiles.dirty[t] = addDrift(any, tolerance, cache.geometryDrift[t]) ? 1 : 0;
    }
    const int all = static_cast<int>(cache.drift.size());
    countAfterPlan(cache.tiles.dirtyCount() == all && cache.geometryTiles.dirtyCount() == all, cache.framesWithoutPlan);
}

}  // namespace terrain::gi
