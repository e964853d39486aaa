#include "gi/visibility_cache.h"

#include <algorithm>
#include <limits>

#include "core/error.h"
#include "core/parallel.h"
#include "gi/sh.h"

namespace terrain::gi {

namespace {

// The plans' change pyramid and the receivers' walks' |dh| pyramid and
// planes, built once per grid and settings (of no change) when the cache is
// reset for them: built by the first plan that refines, in the middle of a
// run, they took their memory then, and faulting its pages in made that
// one frame cost about a full frame's time.
void sizeChangeScratch(const HeightPyramid& pyr, ConstGridView heights, VisibilityCache& cache) {
    if (cache.change.nx == heights.nx && cache.change.ny == heights.ny && changeLevelsFit(cache.receiverLevels, pyr))
        return;
    buildMaxChangePyramid(heights, heights, cache.change, CellBox{});
    buildMaxChangePyramid(heights, heights, cache.lastChange, CellBox{});
    buildChangeLevels(cache.change, pyr, cache.receiverLevels);
    const std::size_t planeR = static_cast<std::size_t>(pyr.nxr) * pyr.nyr;
    cache.receiverBound.resize(planeR);
    cache.receiverGeometry.resize(planeR);
}

}  // namespace

void resetVisibilityCache(const HeightPyramid& pyr, ConstGridView heights, VisibilityCache& cache) {
    sizeChangeScratch(pyr, heights, cache);
    cache.tiles.reset(pyr.nxr, pyr.nyr, kCacheTile, true);
    cache.keyTiles.reset(pyr.nxr, pyr.nyr, kCacheTile, true);
    cache.geometryTiles.reset(pyr.nxr, pyr.nyr, kCacheTile, true);
    cache.drift.reset(cache.tiles.dirty.size());
    cache.keyDrift.reset(cache.tiles.dirty.size());
    cache.geometryDrift.reset(cache.tiles.dirty.size());
    copyGrid(heights, cache.anchorHeights);
    cache.anchorDiffers = CellBox{};  // the next plan compares every cell once
    cache.anchorIsLastPlan = true;
}

void forgetEnvironmentDrift(VisibilityCache& cache) { cache.drift.recomputedAll(); }

bool shouldPlanTiles(VisibilityCache& cache) { return !skipsPlan(cache.skips); }

namespace {

// The key lights' shade per unit of visible fraction: the sum of their
// largest channels (a texel's key shade is sum_k rgb_k f_k max(0, N . l_k)).
float keyShadePerFraction(const std::vector<KeyLightRegion>& keys) {
    double sum = 0.0;
    for (const KeyLightRegion& k : keys) sum += k.maxRgb;  // >= 0 (validateKeyLight)
    return static_cast<float>(sum);
}

// Each cache tile's value of `perTile` (one per visibility tile) into out.
void onCacheTiles(const std::vector<float>& perTile, const ReceiverTiles& tiles, std::vector<float>& out) {
    out.resize(tiles.dirty.size());
    for (int ty = 0; ty < tiles.tilesY; ++ty)
        for (int tx = 0; tx < tiles.tilesX; ++tx)
            out[static_cast<std::size_t>(ty) * tiles.tilesX + tx] = perTile[visibilityTileHolding(tx, ty, tiles.nxr)];
}

// Per cache tile, the largest over the key lights of the bound on each
// one's visible fraction (keyLightFractionBound; an SH-shaded light:
// infinite where its slopes may have moved at all) under the change
// `change`, into out: for the tiles `only` flags (null: every tile; the
// others keep their value), 0 without key lights. Each light's comes from
// its visibility tile's coarse slope bound (slopeBound) where that keeps the
// tile's key drift (driftSoFar plus it) within kCoarseBoundShare of the
// tolerance, else from the bound over the light's own azimuths, taken over
// the cache tile itself, not its visibility tile: a light's few azimuths see
// a change along a narrow strip, which a larger tile's reach widens (the 51²
// pit's key tiles: 20 instead of 36). gradBound: per cache tile.
void boundKeyFractions(const HeightPyramid& pyr, const std::vector<KeyLightRegion>& keys, float lipschitz,
                       float tolerance, const MaxChangePyramid& change, const std::vector<float>& slopeBound,
                       const std::vector<float>& gradBound, const std::vector<float>& driftSoFar,
                       const std::vector<std::uint8_t>* only, VisibilityCache& cache, std::vector<float>& out) {
    const std::size_t tiles = gradBound.size();
    const auto taken = [&](std::size_t t) { return !only || (*only)[t] != 0; };
    out.resize(tiles);
    for (std::size_t t = 0; t < tiles; ++t)
        if (taken(t)) out[t] = 0.0f;
    if (keys.empty()) return;
    const float shade = keyShadePerFraction(keys);
    const auto fraction = [&](const KeyLightRegion& k, float slope, std::size_t t) {
        const float f = keyLightFractionBound(lipschitz * slope, gradBound[t], k.sinLow, k.sinHigh);
        return !k.exactCosine && f > 0.0f ? std::numeric_limits<float>::infinity() : f;
    };
    onCacheTiles(slopeBound, cache.keyTiles, cache.cacheSlope);
    cache.overRange.resize(tiles);
    for (const KeyLightRegion& k : keys) {
        for (std::size_t t = 0; t < tiles; ++t)
            cache.overRange[t] = taken(t) && (driftSoFar[t] + fraction(k, cache.cacheSlope[t], t)) * shade >
                                                 kCoarseBoundShare * tolerance;
        boundSlopeChangeOverRange(change, pyr, kCacheTile, k.phi0, k.phi1, cache.rangeBound, cache.overRange);
        for (std::size_t t = 0; t < tiles; ++t) {
            if (!taken(t)) continue;
            const float slope = cache.overRange[t] ? cache.rangeBound[t] : cache.cacheSlope[t];
            out[t] = std::max(out[t], fraction(k, slope, t));
        }
    }
}

}  // namespace

bool planKeyBrightness(const std::vector<KeyLightRegion>& keys, float tolerance, VisibilityCache& cache) {
    return markDriftAgain(keyShadePerFraction(keys), tolerance, cache.keyDrift, cache.keyTiles.dirty);
}

void environmentBoundPerTile(std::span<const float> azimuthBound, std::span<const float> gradBound, int azimuths,
                             float lipschitz, std::vector<float>& scratch, std::vector<float>& out, int stride) {
    const std::size_t m = static_cast<std::size_t>(azimuths), tiles = gradBound.size();
    if (azimuths < 1 || azimuthBound.size() != tiles * m || stride < 1 || azimuths % stride != 0)
        throw InputError(
            "environmentBoundPerTile: one slope bound per tile and azimuth, at least one azimuth, a stride that "
            "divides them");
    const int taken = azimuths / stride;
    scratch.resize(static_cast<std::size_t>(taken));  // no allocation after the first frame of these settings
    out.resize(tiles);
    for (std::size_t t = 0; t < tiles; ++t) {
        for (int q = 0; q < taken; ++q)
            scratch[static_cast<std::size_t>(q)] =
                lipschitz * azimuthBound[t * m + static_cast<std::size_t>(q * stride)];
        out[t] = ambientChangeBoundPerAzimuth(scratch.data(), taken, gradBound[t], 1.0f, false);
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

namespace {

// Per visibility tile, the environment's bound from its per-azimuth slope
// bounds and gradient bound, and the geometry's over the indirect scan's
// own azimuths where those are every geometryStride-th of the
// environment's (each receiver's slope bounds along them are at most the
// tile's), else `coarse` (one slope bound over every direction).
void environmentAndGeometryBounds(const std::vector<float>& azimuthBound, const std::vector<float>& gradBound,
                                  const std::vector<float>& coarse, int azimuths, float lipschitz, int geometryStride,
                                  std::vector<float>& scratch, std::vector<float>& env, std::vector<float>& geometry) {
    environmentBoundPerTile(azimuthBound, gradBound, azimuths, lipschitz, scratch, env);
    if (geometryStride > 0)
        environmentBoundPerTile(azimuthBound, gradBound, azimuths, lipschitz, scratch, geometry, geometryStride);
    else
        geometry = coarse;
}

// Flags in `perAzimuth` the visibility tiles with a cache tile (of those
// `only` flags; null: every one) whose drift so far (the environment's,
// and the geometry's when that is taken per azimuth too: non-null) plus its
// visibility tile's coarse bound would pass kCoarseBoundShare of the
// tolerance.
void markPerAzimuthTiles(const ReceiverTiles& tiles, const std::vector<float>& coarse,
                         const std::vector<float>& envDrift, const std::vector<float>* geometryDrift,
                         const std::vector<std::uint8_t>* only, float tolerance,
                         std::vector<std::uint8_t>& perAzimuth) {
    const float share = kCoarseBoundShare * tolerance;
    perAzimuth.assign(coarse.size(), 0);
    for (int ty = 0; ty < tiles.tilesY; ++ty)
        for (int tx = 0; tx < tiles.tilesX; ++tx) {
            const std::size_t t = static_cast<std::size_t>(ty) * tiles.tilesX + tx;
            if (only && !(*only)[t]) continue;
            const std::size_t v = visibilityTileHolding(tx, ty, tiles.nxr);
            if (envDrift[t] + coarse[v] > share || (geometryDrift && (*geometryDrift)[t] + coarse[v] > share))
                perAzimuth[v] = 1;
        }
}

// The visibility tiles not taken per azimuth keep their coarse bound as
// their environment's and geometry's bounds (its slope bound holds along
// every azimuth).
void keepCoarseBounds(const std::vector<std::uint8_t>& perAzimuth, const std::vector<float>& coarse,
                      std::vector<float>& env, std::vector<float>& geometry) {
    for (std::size_t v = 0; v < perAzimuth.size(); ++v)
        if (!perAzimuth[v]) {
            env[v] = coarse[v];
            geometry[v] = coarse[v];
        }
}

// Which drifts' candidates a refinement takes (env, geometry), and whether a
// cache tile is over the tolerance for either.
struct Candidates {
    bool env = false, geometry = false;
    bool over(const VisibilityCache& cache, std::size_t t, float tolerance) const {
        return (env && driftNow(cache.drift, cache.envExcursion, cache.envSinceLast, t) > tolerance) ||
               (geometry &&
                driftNow(cache.geometryDrift, cache.geometryExcursion, cache.geometrySinceLast, t) > tolerance);
    }
};

// Takes off cache.refined the candidates that recompute whatever their
// receivers' walks find, for each drift they are a candidate for: those
// whose drift from the anchor plus their receivers' own gradient bounds
// alone put one of them over the tolerance (a tile recomputed since the
// anchor whose drift is past it already, among them). A receiver's bound is
// at least the one its gradient bound gives with every slope bound 0 (each
// azimuth's term is the larger of the two, and the sum and the rounding
// are monotone), the tile's refined bound is its receivers' largest and
// never above its present one, and the sum with the drift is monotone in
// it. Unwalked, such a tile keeps its visibility tile's bounds, which also
// put it over.
void skipSurelyRecomputed(const HeightPyramid& pyr, int azimuths, float tolerance, int geometryStride,
                          Candidates candidates, VisibilityCache& cache) {
    ReceiverTiles& refined = cache.refined;
    cache.tileAzimuths.assign(static_cast<std::size_t>(azimuths), 0.0f);
    const float* zeros = cache.tileAzimuths.data();
    for (int ty = 0; ty < refined.tilesY; ++ty)
        for (int tx = 0; tx < refined.tilesX; ++tx) {
            const std::size_t t = static_cast<std::size_t>(ty) * refined.tilesX + tx;
            if (!refined.dirty[t]) continue;
            const float g = largestReceiverGradientBound(cache.change, pyr, kCacheTile, tx, ty);
            // whether the least a walk can leave, with the drift, keeps the tile
            const auto keepable = [&](float drift, float excursion, int taken) {
                const float least = std::min(excursion, ambientChangeBoundPerAzimuth(zeros, taken, g, 1.0f, false));
                return drift + least <= tolerance;
            };
            Candidates open = candidates;  // the drifts a walk could still keep it for
            open.env = open.env && keepable(cache.drift.fromAnchor[t], cache.envExcursion[t], azimuths);
            open.geometry =
                open.geometry && geometryStride > 0 &&
                keepable(cache.geometryDrift.fromAnchor[t], cache.geometryExcursion[t], azimuths / geometryStride);
            refined.dirty[t] = open.over(cache, t, tolerance) ? 1 : 0;
        }
}

// Lowers the excursions of cache.refined's tiles to the tiles' own box
// bounds (those of their visibility tile over a smaller reach; a tile's
// bounds hold wherever they were taken, whichever drift asked for them) and
// keeps on it those still over the tolerance.
void lowerToOwnTileBounds(const HeightPyramid& pyr, int azimuths, float lipschitz, float tolerance, int geometryStride,
                          Candidates candidates, VisibilityCache& cache) {
    ReceiverTiles& refined = cache.refined;
    boundSlopeChangePerAzimuth(cache.change, pyr, kCacheTile, azimuths, cache.cacheAzimuthBound, refined.dirty);
    environmentBoundPerTile(cache.cacheAzimuthBound, cache.cacheGradBound, azimuths, lipschitz, cache.tileAzimuths,
                            cache.cacheEnvBound);
    if (geometryStride > 0)
        environmentBoundPerTile(cache.cacheAzimuthBound, cache.cacheGradBound, azimuths, lipschitz, cache.tileAzimuths,
                                cache.cacheGeometryBound, geometryStride);
    for (std::size_t t = 0; t < refined.dirty.size(); ++t) {
        if (!refined.dirty[t]) continue;
        cache.envExcursion[t] = std::min(cache.envExcursion[t], cache.cacheEnvBound[t]);
        if (geometryStride > 0)
            cache.geometryExcursion[t] = std::min(cache.geometryExcursion[t], cache.cacheGeometryBound[t]);
        refined.dirty[t] = candidates.over(cache, t, tolerance) ? 1 : 0;
    }
}

// The environment's ambient-map excursions of the cache tiles that they and
// their drift would recompute, and the geometry's where the indirect scan
// takes every k-th of the environment's azimuths (geometryStride k; 0:
// not), each lowered to the cache tile's own box bound where that is
// smaller, and then, for those still over the tolerance and not recomputed
// whatever their receivers' bounds, to the largest of those
// (gi/receiver_azimuth_bound.h) where that is smaller; the others keep
// their visibility tile's (each drift's all, when more than kRefineAtMost
// of the tiles would be refined for it). The receivers' walks stop where no
// step can add more than a sixteenth of the tolerance (tolerance 0: where
// no step sees a change).
void refinePerReceiver(const HeightPyramid& pyr, const VisibilitySettings& vis, float lipschitz, float tolerance,
                       int geometryStride, VisibilityCache& cache) {
    ReceiverTiles& refined = cache.refined;
    refined.reset(pyr.nxr, pyr.nyr, kCacheTile, false);
    const std::size_t tiles = refined.dirty.size();
    const auto count = [&](Candidates c) {
        std::size_t n = 0;
        for (std::size_t t = 0; t < tiles; ++t) n += c.over(cache, t, tolerance) ? 1 : 0;
        return n;
    };
    const auto worth = [&](std::size_t n) { return n > 0 && static_cast<double>(n) <= kRefineAtMost * tiles; };
    const Candidates candidates{worth(count({true, false})), geometryStride > 0 && worth(count({false, true}))};
    if (!candidates.env && !candidates.geometry) return;
    for (std::size_t t = 0; t < tiles; ++t) refined.dirty[t] = candidates.over(cache, t, tolerance) ? 1 : 0;
    const int m = vis.azimuths;
    skipSurelyRecomputed(pyr, m, tolerance, geometryStride, candidates, cache);
    if (refined.dirtyCount() == 0) return;
    lowerToOwnTileBounds(pyr, m, lipschitz, tolerance, geometryStride, candidates, cache);
    if (refined.dirtyCount() == 0) return;
    // the environment's scan's azimuths, as foldFullCircle takes them
    const double dphi = 2.0 * kPi / m;
    cache.azimuths.resize(static_cast<std::size_t>(m));
    for (int j = 0; j < m; ++j) cache.azimuths[static_cast<std::size_t>(j)] = dphi * j;
    // a uniform slope bound f on every azimuth adds kShadePerSlope lipschitz f to the ambient's
    const float floor = tolerance / (16.0f * kShadePerSlope * lipschitz);
    buildChangeLevels(cache.change, pyr, cache.receiverLevels);
    boundEnvironmentPerReceiver(cache.receiverLevels, cache.change, pyr, cache.azimuths, lipschitz, &refined, floor,
                                cache.receiverBound, geometryStride,
                                geometryStride > 0 ? &cache.receiverGeometry : nullptr);
    const auto largestIn = [&](const std::vector<float>& bound, int tx, int ty) {
        float largest = 0.0f;
        for (int Y = ty * kCacheTile; Y < std::min(pyr.nyr, (ty + 1) * kCacheTile); ++Y)
            for (int X = tx * kCacheTile; X < std::min(pyr.nxr, (tx + 1) * kCacheTile); ++X)
                largest = std::max(largest, bound[static_cast<std::size_t>(Y) * pyr.nxr + X]);
        return largest;
    };
    for (int ty = 0; ty < refined.tilesY; ++ty)
        for (int tx = 0; tx < refined.tilesX; ++tx) {
            const std::size_t t = static_cast<std::size_t>(ty) * refined.tilesX + tx;
            if (!refined.dirty[t]) continue;
            // a receiver's bounds hold wherever it was walked, whichever drift asked for it
            cache.envExcursion[t] = std::min(cache.envExcursion[t], largestIn(cache.receiverBound, tx, ty));
            if (geometryStride > 0)
                cache.geometryExcursion[t] =
                    std::min(cache.geometryExcursion[t], largestIn(cache.receiverGeometry, tx, ty));
        }
}

// The drifts' second path (gi/anchored_drift.h), its tiles: the cache tiles
// whose drift from the anchor passes the tolerance (their coarse or
// visibility-tile bounds, before any walk) while their drift from the last
// planned frame's heights does not, into cache.sinceLastTiles. False when
// there are none.
bool markSinceLastTiles(const std::vector<KeyLightRegion>& keys, float tolerance, VisibilityCache& cache) {
    const std::size_t tiles = cache.tiles.dirty.size();
    const float keyScale = keyShadePerFraction(keys);
    const auto open = [&](const AnchoredDrift& d, const std::vector<float>& e, float scale, std::size_t t) {
        return (d.fromAnchor[t] + e[t]) * scale > tolerance && d.sinceInputs[t] * scale <= tolerance;
    };
    cache.sinceLastTiles.assign(tiles, 0);
    bool any = false;
    for (std::size_t t = 0; t < tiles; ++t) {
        const bool o = open(cache.drift, cache.envExcursion, 1.0f, t) ||
                       open(cache.keyDrift, cache.keyExcursion, keyScale, t) ||
                       open(cache.geometryDrift, cache.geometryExcursion, 1.0f, t);
        cache.sinceLastTiles[t] = o ? 1 : 0;
        any = any || o;
    }
    return any;
}

// The second path's environment and geometry bounds of its tiles, from
// cache.lastChange: the coarse one (a slope bound over every direction per
// visibility tile, which holds along any azimuths), and per azimuth where
// the coarse one would take a tile's drift past kCoarseBoundShare of the
// tolerance (as the anchor's path does: the drift from the last frame's
// heights adds these bounds up frame after frame).
void environmentSinceLast(const HeightPyramid& pyr, const VisibilitySettings& vis, float lipschitz, float tolerance,
                          int geometryStride, VisibilityCache& cache) {
    boundSlopeChange(cache.lastChange, pyr, kVisibilityTile, cache.lastSlope);
    boundGradientChange(cache.lastChange, pyr, kVisibilityTile, cache.lastGrad);
    geometryBoundPerTile(cache.lastSlope, cache.lastGrad, lipschitz, cache.lastCoarse);
    markPerAzimuthTiles(cache.tiles, cache.lastCoarse, cache.drift.sinceInputs,
                        geometryStride > 0 ? &cache.geometryDrift.sinceInputs : nullptr, &cache.sinceLastTiles,
                        tolerance, cache.sinceLastVisibilityTiles);
    boundSlopeChangePerAzimuth(cache.lastChange, pyr, kVisibilityTile, vis.azimuths, cache.lastAzimuthBound,
                               cache.sinceLastVisibilityTiles);
    environmentAndGeometryBounds(cache.lastAzimuthBound, cache.lastGrad, cache.lastCoarse, vis.azimuths, lipschitz,
                                 geometryStride, cache.tileAzimuths, cache.lastEnv, cache.lastGeometry);
    keepCoarseBounds(cache.sinceLastVisibilityTiles, cache.lastCoarse, cache.lastEnv, cache.lastGeometry);
    const ReceiverTiles& ct = cache.tiles;
    for (int ty = 0; ty < ct.tilesY; ++ty)
        for (int tx = 0; tx < ct.tilesX; ++tx) {
            const std::size_t t = static_cast<std::size_t>(ty) * ct.tilesX + tx;
            if (!cache.sinceLastTiles[t]) continue;
            const std::size_t v = visibilityTileHolding(tx, ty, ct.nxr);
            cache.envSinceLast[t] = std::min(cache.lastCoarse[v], cache.lastEnv[v]);
            cache.geometrySinceLast[t] = std::min(cache.lastCoarse[v], cache.lastGeometry[v]);
        }
}

// The drifts' second path (gi/anchored_drift.h): per cache tile, the bounds
// of the change from the last planned frame's heights `before` to `after`
// (cache.lastChange, over the cells sinceBefore holds) into envSinceLast,
// keySinceLast and geometrySinceLast, for the tiles markSinceLastTiles
// marks; infinite elsewhere. Taken as the anchor's are, without receivers'
// walks: a change since the last frame lies at a new place, mostly far
// from the tiles a change that stayed recomputed. `differing` holds every
// cell where `after` differs from the anchor's heights.
void boundSinceLastFrame(ConstGridView before, ConstGridView after, const HeightPyramid& pyr,
                         const VisibilitySettings& vis, const std::vector<KeyLightRegion>& keys, float lipschitz,
                         float tolerance, int geometryStride, CellBox sinceBefore, CellBox differing,
                         VisibilityCache& cache) {
    const std::size_t tiles = cache.tiles.dirty.size();
    const float inf = std::numeric_limits<float>::infinity();
    cache.envSinceLast.assign(tiles, inf);
    cache.keySinceLast.assign(tiles, inf);
    cache.geometrySinceLast.assign(tiles, inf);
    // none when `after` is back at the anchor's heights (a change undone: the
    // anchor's path says all), or `before` (the last plan's) was at them:
    // the paths are one
    if (!markSinceLastTiles(keys, tolerance, cache) || differing.empty() || cache.anchorIsLastPlan) return;
    buildMaxChangePyramid(before, after, cache.lastChange, sinceBefore);
    environmentSinceLast(pyr, vis, lipschitz, tolerance, geometryStride, cache);
    boundGradientChange(cache.lastChange, pyr, kCacheTile, cache.lastCacheGrad);
    boundKeyFractions(pyr, keys, lipschitz, tolerance, cache.lastChange, cache.lastSlope, cache.lastCacheGrad,
                      cache.keyDrift.sinceInputs, &cache.sinceLastTiles, cache, cache.keySinceLast);
}

}  // namespace

void planVisibilityTiles(ConstGridView before, ConstGridView after, const HeightPyramid& pyr,
                         const VisibilitySettings& vis, const std::vector<KeyLightRegion>& keys, float tolerance,
                         VisibilityCache& cache, CellBox sinceBefore, int indirectAzimuths) {
    if (cache.tiles.nxr != pyr.nxr || cache.tiles.nyr != pyr.nyr || !cache.drift.fits(cache.tiles.dirty.size()) ||
        cache.anchorHeights.nx != after.nx || cache.anchorHeights.ny != after.ny)
        resetVisibilityCache(pyr, before, cache);
    // outside the cells that differ from the anchor's, |dh| is 0 (and the
    // anchor's rows the same as this frame's); they lie where the anchor
    // differs from `before` or `before` from `after`
    const CellBox mayDiffer = cache.anchorDiffers.joined(sinceBefore).cut(after.nx, after.ny);
    const CellBox differing = differingCellsIn(cache.anchorHeights.cview(), after, mayDiffer);
    buildMaxChangePyramid(cache.anchorHeights.cview(), after, cache.change, differing);
    // the indirect scan's azimuths, when they are every k-th of the environment's
    const bool subset = indirectAzimuths > 0 && vis.azimuths % indirectAzimuths == 0;
    const int geometryStride = subset ? vis.azimuths / indirectAzimuths : 0;
    // V depends on the heights through the maximum blocking slope and, below
    // it, the tangent plane's slope along the azimuth (moving by at most
    // sqrt2 times a gradient component's bound); shading reruns at the new
    // normals every frame, so only V's own change counts.
    const float lipschitz = blockingMaxLipschitz(vis.blockingMax);
    // the coarse bounds first: one slope bound over every direction per
    // visibility tile, and the gradient bounds
    parallelInvoke([&] { boundSlopeChange(cache.change, pyr, kVisibilityTile, cache.slopeBound); },
                   [&] {
                       boundGradientChange(cache.change, pyr, kVisibilityTile, cache.gradBound);
                       boundGradientChange(cache.change, pyr, kCacheTile, cache.cacheGradBound);
                   });
    geometryBoundPerTile(cache.slopeBound, cache.gradBound, lipschitz, cache.coarseBound);
    markPerAzimuthTiles(cache.tiles, cache.coarseBound, cache.drift.fromAnchor,
                        geometryStride > 0 ? &cache.geometryDrift.fromAnchor : nullptr, nullptr, tolerance,
                        cache.perAzimuth);
    // then the finer ones where the coarse ones would take more than their share of the tolerance
    parallelInvoke(
        [&] {
            boundSlopeChangePerAzimuth(cache.change, pyr, kVisibilityTile, vis.azimuths, cache.azimuthBound,
                                       cache.perAzimuth);
        },
        [&] {
            boundKeyFractions(pyr, keys, lipschitz, tolerance, cache.change, cache.slopeBound, cache.cacheGradBound,
                              cache.keyDrift.fromAnchor, nullptr, cache, cache.keyExcursion);
        });
    environmentAndGeometryBounds(cache.azimuthBound, cache.gradBound, cache.coarseBound, vis.azimuths, lipschitz,
                                 geometryStride, cache.tileAzimuths, cache.envBound, cache.geometryBound);
    keepCoarseBounds(cache.perAzimuth, cache.coarseBound, cache.envBound, cache.geometryBound);
    onCacheTiles(cache.envBound, cache.tiles, cache.envExcursion);
    onCacheTiles(cache.geometryBound, cache.tiles, cache.geometryExcursion);
    boundSinceLastFrame(before, after, pyr, vis, keys, lipschitz, tolerance, geometryStride, sinceBefore, differing,
                        cache);
    refinePerReceiver(pyr, vis, lipschitz, tolerance, geometryStride, cache);
    // one anchor for the three drifts: they vote together on moving it
    AnchorVotes votes;
    markAnchoredDrift(cache.envExcursion, cache.envSinceLast, {}, 1.0f, tolerance, cache.drift, cache.tiles.dirty,
                      votes);
    markAnchoredDrift(cache.keyExcursion, cache.keySinceLast, {}, keyShadePerFraction(keys), tolerance, cache.keyDrift,
                      cache.keyTiles.dirty, votes);
    markAnchoredDrift(cache.geometryExcursion, cache.geometrySinceLast, {}, 1.0f, tolerance, cache.geometryDrift,
                      cache.geometryTiles.dirty, votes);
    const bool reanchor = votes.reanchor();
    advanceAnchoredDrift(cache.envExcursion, cache.envSinceLast, cache.tiles.dirty, reanchor, cache.drift);
    advanceAnchoredDrift(cache.keyExcursion, cache.keySinceLast, cache.keyTiles.dirty, reanchor, cache.keyDrift);
    advanceAnchoredDrift(cache.geometryExcursion, cache.geometrySinceLast, cache.geometryTiles.dirty, reanchor,
                         cache.geometryDrift);
    // the anchor becomes `after`, which differs from `before` within
    // sinceBefore; else it differs from `after` (the next plan's `before`,
    // if this frame is recorded) within `differing`, and from `before`
    // within that and sinceBefore (where `after` differs from `before`):
    // the next plan compares only those cells, not the whole field again
    if (reanchor) copyGrid(after, cache.anchorHeights, differing.rows());
    cache.anchorDiffers = reanchor ? sinceBefore : differing.joined(sinceBefore);
    cache.anchorIsLastPlan = reanchor || differing.empty();
    const int all = static_cast<int>(cache.tiles.dirty.size());
    // the indirect light re-gathers the geometry's dirty tiles: both count
    countAfterPlan(std::min(cache.tiles.dirtyCount(), cache.geometryTiles.dirtyCount()), all, cache.skips);
}

}  // namespace terrain::gi
