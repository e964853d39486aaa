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

// Marks key tile t when its drift, at this frame's brightness, exceeds the
// tolerance (its drift reset to 0); a light brightened since the tile's key
// V was computed counts at its new brightness.
bool markKeyTile(std::size_t t, float keyScale, float tolerance, VisibilityCache& cache) {
    const bool dirty = cache.keyDrift[t] * keyScale > tolerance;
    if (dirty) cache.keyDrift[t] = 0.0f;
    cache.keyTiles.dirty[t] = dirty ? 1 : 0;
    return dirty;
}

}  // namespace

bool planKeyBrightness(const std::vector<KeyLightRegion>& keys, float tolerance, VisibilityCache& cache) {
    if (cache.keyDrift.size() != cache.keyTiles.dirty.size()) return false;
    const float keyScale = keyShadePerFraction(keys);
    bool any = false;
    for (std::size_t t = 0; t < cache.keyDrift.size(); ++t) any = markKeyTile(t, keyScale, tolerance, cache) || any;
    return any;
}

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
    boundKeyFractions(pyr, keys, lipschitz, cache);
    const float keyScale = keyShadePerFraction(keys);
    const std::size_t m = static_cast<std::size_t>(vis.azimuths);
    std::vector<float>& perAzimuth = cache.tileAzimuths;
    perAzimuth.resize(m);  // no allocation after the first frame of these settings
    for (std::size_t t = 0; t < cache.drift.size(); ++t) {
        for (std::size_t j = 0; j < m; ++j) perAzimuth[j] = lipschitz * cache.azimuthBound[t * m + j];
        const float env =
            ambientChangeBoundPerAzimuth(perAzimuth.data(), vis.azimuths, cache.gradBound[t], 1.0f, false);
        cache.tiles.dirty[t] = addDrift(env, tolerance, cache.drift[t]) ? 1 : 0;
        cache.keyDrift[t] += cache.keyBound[t];
        markKeyTile(t, keyScale, tolerance, cache);
        const float any = ambientChangeBound(lipschitz * cache.slopeBound[t], cache.gradBound[t], 1.0f, false);
        cache.geometryTiles.dirty[t] = addDrift(any, tolerance, cache.geometryDrift[t]) ? 1 : 0;
    }
    const int all = static_cast<int>(cache.drift.size());
    // the indirect light re-gathers the geometry's dirty tiles: both count
    countAfterPlan(std::min(cache.tiles.dirtyCount(), cache.geometryTiles.dirtyCount()), all, cache.skips);
}

}  // namespace terrain::gi
