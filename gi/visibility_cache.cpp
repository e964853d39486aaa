#include "gi/visibility_cache.h"

#include <algorithm>
#include <cmath>

namespace terrain::gi {

void resetVisibilityCache(const HeightPyramid& pyr, VisibilityCache& cache) {
    cache.tiles.reset(pyr.nxr, pyr.nyr, kVisibilityTile, true);
    cache.drift.assign(cache.tiles.dirty.size(), 0.0f);
}

void planVisibilityTiles(ConstGridView before, ConstGridView after, const HeightPyramid& pyr, BlockingMax rule,
                         float tolerance, VisibilityCache& cache) {
    if (cache.tiles.nxr != pyr.nxr || cache.tiles.nyr != pyr.nyr || cache.drift.size() != cache.tiles.dirty.size())
        resetVisibilityCache(pyr, cache);
    buildMaxChangePyramid(before, after, cache.change);
    boundSlopeChange(cache.change, pyr, kVisibilityTile, cache.slopeBound);
    boundGradientChange(cache.change, pyr, kVisibilityTile, cache.gradBound);
    // V depends on the heights through the maximum blocking slope and, below
    // it, the tangent plane's slope along the azimuth (moving by at most
    // sqrt2 times a gradient component's bound); shading reruns at the new
    // normals every frame, so only V's own change counts.
    const float lipschitz = blockingMaxLipschitz(rule);
    for (std::size_t t = 0; t < cache.drift.size(); ++t) {
        const float slope = std::max(lipschitz * cache.slopeBound[t], std::sqrt(2.0f) * cache.gradBound[t]);
        cache.drift[t] += shadeChangePerSlope(1.0f) * slope;
        const bool recompute = cache.drift[t] > tolerance;
        cache.tiles.dirty[t] = recompute ? 1 : 0;
        if (recompute) cache.drift[t] = 0.0f;
    }
}

}  // namespace terrain::gi
