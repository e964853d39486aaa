#include "gi/indirect_cache.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "core/parallel.h"
#include "core/simd.h"
#include "gi/texel_runs.h"
#include "gi/visibility_cache.h"

namespace terrain::gi {

namespace {

// The cache describes a result of this grid, with the tiles and a radiance
// pyramid of the same receivers and steps.
bool cacheFits(const IndirectPlanInputs& in, const IndirectCache& cache) {
    const HeightPyramid& h = in.heights;
    if (!cache.valid || in.pyramid.fields.empty() || (cache.levelsRecorded && !cache.levels.fits(in.pyramid)))
        return false;
    const HeightPyramid& r = in.pyramid.fields[0];
    const Grid& last = cache.anchorSource[0];
    return r.nx == h.nx && r.ny == h.ny && r.nxr == h.nxr && r.nyr == h.nyr && r.steps.size() == h.steps.size() &&
           last.nx == h.nx && last.ny == h.ny && in.source[0].nx == h.nx && in.source[0].ny == h.ny &&
           cache.tiles.nxr == h.nxr && cache.tiles.nyr == h.nyr && cache.drift.fits(cache.tiles.dirty.size()) &&
           (!in.geometryTiles || (in.geometryTiles->nxr == h.nxr && in.geometryTiles->nyr == h.nyr &&
                                  in.geometryTiles->tileSize == kIndirectTile));
}

// The last pass kept the occlusions of this grid (sub-sampling).
bool hasOcclusions(const IndirectPlanInputs& in) {
    const BlockerRadianceState* b = in.blocker;
    const HeightPyramid& h = in.heights;
    const std::size_t planeR = static_cast<std::size_t>(h.nxr) * h.nyr;
    return b && b->occlusionValid && h.subsample > 1 && b->nx == h.nx && b->ny == h.ny && b->nxr == h.nxr &&
           b->nyr == h.nyr && b->azimuths == static_cast<int>(in.phi.size()) && b->occlusion.nx == h.nx &&
           b->occlusion.ny == h.ny && b->receiverOcclusionRunning.size() == in.phi.size() * planeR &&
           b->receiverGroupOcclusion.size() == static_cast<std::size_t>(kDistanceGroups) * planeR;
}

// A receiver's occlusion sum (unnormalised, over the azimuths) at or below
// this is rounding: its E_k and O_k come from two computations of the same
// clamped-cosine measures, whose ratio only bounds the shares when the
// measures are well above their rounding.
constexpr float kNoShareBelow = 1e-6f;

// The sample moves a row's receivers are weighed with: per azimuth j and
// distance group g, one value for every receiver (a tile's, D[j] and G[g])
// or one per receiver (planes of the receiver grid, D[j nxr nyr + Y nxr + X]
// and G likewise; boundSampleMovePerReceiver).
struct RowMoves {
    const float* D;
    const float* G;
    bool perReceiver;
};

// The largest rho_k of the receivers [x0, x1) of row Y (at most one tile's
// width): the smaller of two weighings of each one's occlusion
// (gi/indirect_cache.h), the azimuth bounds D_j by its shares per azimuth,
// sum_j (O_kj / O_k) D_j, and the distance groups' bounds G_g (over every
// azimuth) by its shares per group, sum_g (O_kg / O_k) G_g; its largest
// D_j for a receiver with (next to) no occlusion, and never more. Sums of m
// (or 8) positive float terms and a division, rounded up by 1e-5 plus one
// float epsilon per azimuth, above their rounding for any m; a positive
// term w D never rounds to 0 (at least the smallest float), so that
// tolerance 0 sees every change a member may carry. L receivers per vector
// (a run cut by the grid's edge copied into zero-padded lanes); lane-wise
// IEEE arithmetic, so the 4- and 8-wide builds give the same bits.
template <class V>
[[gnu::always_inline]] inline float rowShareBoundWith(const BlockerRadianceState& b, int Y, int x0, int x1,
                                                      const RowMoves& moves) {
    constexpr int L = simd::kLaneCount<V>, kLaneGroups = kIndirectTile / L;
    const std::size_t m = static_cast<std::size_t>(b.azimuths), plane = static_cast<std::size_t>(b.nxr) * b.nyr;
    const std::size_t at = static_cast<std::size_t>(Y) * b.nxr + static_cast<std::size_t>(x0);
    const int n = x1 - x0, laneGroups = (n + L - 1) / L;
    const V zero = simd::splat<V>(0.0f), denorm = simd::splat<V>(std::numeric_limits<float>::denorm_min());
    V azWeighed[kLaneGroups], azTotal[kLaneGroups], grWeighed[kLaneGroups], grTotal[kLaneGroups];
    V largest[kLaneGroups];
    for (int q = 0; q < laneGroups; ++q) azWeighed[q] = azTotal[q] = grWeighed[q] = grTotal[q] = largest[q] = zero;
    alignas(32) float lanes[kIndirectTile] = {};
    alignas(32) float moveLanes[kIndirectTile] = {};
    // a plane's run of the row (zero-padded when cut)
    const auto run = [&](const float* v, float* padded) {
        if (n % L == 0) return v;
        std::copy(v, v + n, padded);
        return static_cast<const float*>(padded);
    };
    const auto weighed = [&](const float* occlusion, const float* move, float d, V* sum, V* total, bool running) {
        const float* v = run(occlusion, lanes);
        const float* dv = moves.perReceiver ? run(move, moveLanes) : nullptr;
        for (int q = 0; q < laneGroups; ++q) {
            const V x = simd::load<V>(v + L * q);
            const V dq = dv ? simd::load<V>(dv + L * q) : simd::splat<V>(d);
            const V w = running ? x - total[q] : x;  // an azimuth's share: the running sum's step
            sum[q] += w > zero ? simd::vmax(w * dq, dq > zero ? denorm : zero) : zero;
            total[q] = running ? x : total[q] + x;
            if (running) largest[q] = simd::vmax(largest[q], dq);
        }
    };
    const auto moveAt = [&](const float* planes, std::size_t i) {
        return moves.perReceiver ? planes + i * plane + at : nullptr;
    };
    for (std::size_t j = 0; j < m; ++j)
        weighed(b.receiverOcclusionRunning.data() + j * plane + at, moveAt(moves.D, j),
                moves.perReceiver ? 0.0f : moves.D[j], azWeighed, azTotal, true);
    for (std::size_t g = 0; g < kDistanceGroups; ++g)
        weighed(b.receiverGroupOcclusion.data() + g * plane + at, moveAt(moves.G, g),
                moves.perReceiver ? 0.0f : moves.G[g], grWeighed, grTotal, false);
    // sum / total, positive when the sum is, or the largest D_j for (next to) no occlusion
    const V floor = simd::splat<V>(kNoShareBelow);
    const V up = simd::splat<V>(1.0f + 1e-5f + static_cast<float>(m) * std::numeric_limits<float>::epsilon());
    float bound = 0.0f;
    for (int q = 0; q < laneGroups; ++q) {
        const auto mean = [&](V sum, V total) {
            const V ratio = sum > zero ? simd::vmax(sum / total, denorm) : zero;
            return total > floor ? ratio : largest[q];
        };
        const V rho =
            simd::vmin(largest[q], simd::vmin(mean(azWeighed[q], azTotal[q]), mean(grWeighed[q], grTotal[q])) * up);
        for (int l = 0; l < L && L * q + l < n; ++l) bound = std::max(bound, rho[l]);
    }
    return bound;
}
float rowShareBoundSse(const BlockerRadianceState& b, int Y, int x0, int x1, const RowMoves& moves) {
    return rowShareBoundWith<simd::F4>(b, Y, x0, x1, moves);
}
[[gnu::target("avx2"), gnu::flatten]] float rowShareBoundAvx2(const BlockerRadianceState& b, int Y, int x0, int x1,
                                                              const RowMoves& moves) {
    return rowShareBoundWith<simd::F8>(b, Y, x0, x1, moves);
}

// Tile (tx, ty)'s share envelope (IndirectCache::shareEnvelope) from the
// last pass's occlusions: per azimuth and per distance group the largest
// share of a receiver's occlusion, rounded up a float.
void takeShareEnvelope(const BlockerRadianceState& b, int tx, int ty, float* envelope) {
    const std::size_t m = static_cast<std::size_t>(b.azimuths), plane = static_cast<std::size_t>(b.nxr) * b.nyr;
    const int x0 = tx * kIndirectTile, x1 = std::min(b.nxr, x0 + kIndirectTile);
    std::fill(envelope, envelope + m + kDistanceGroups, 0.0f);
    const auto raise = [](float& e, float part, float total) { e = std::max(e, part / total); };
    for (int Y = ty * kIndirectTile; Y < std::min(b.nyr, (ty + 1) * kIndirectTile); ++Y)
        for (int X = x0; X < x1; ++X) {
            const std::size_t at = static_cast<std::size_t>(Y) * b.nxr + static_cast<std::size_t>(X);
            const float total = b.receiverOcclusionRunning[(m - 1) * plane + at];
            float groups = 0.0f;
            for (std::size_t g = 0; g < kDistanceGroups; ++g) groups += b.receiverGroupOcclusion[g * plane + at];
            if (!(total > kNoShareBelow) || !(groups > kNoShareBelow)) {
                std::fill(envelope, envelope + m + kDistanceGroups, -1.0f);  // the receiver's bound is `largest`
                return;
            }
            float before = 0.0f;
            for (std::size_t j = 0; j < m; ++j) {
                const float running = b.receiverOcclusionRunning[j * plane + at];
                raise(envelope[j], std::max(running - before, 0.0f), total);
                before = running;
            }
            for (std::size_t g = 0; g < kDistanceGroups; ++g)
                raise(envelope[m + g], b.receiverGroupOcclusion[g * plane + at], groups);
        }
    // each largest share rounded up (the largest of the rounded-up shares)
    for (std::size_t i = 0; i < m + kDistanceGroups; ++i)
        envelope[i] = std::nextafter(envelope[i], std::numeric_limits<float>::infinity());
}

// A bound on every receiver's rho_k in a tile from its share envelope: a
// receiver's weighed sums are at most the envelope's (each share at most
// the envelope's, the moves D_j and G_g the tile's), so the smaller of the
// two envelope sums, rounded up as rowShareBound's, bounds the smaller of
// its two; at most `largest`.
float envelopeBound(const float* envelope, std::size_t m, const float* D, const float* G, float largest) {
    if (envelope[0] < 0.0f) return largest;
    const auto weighed = [](const float* share, const float* move, std::size_t n) {
        float sum = 0.0f;
        for (std::size_t i = 0; i < n; ++i)
            if (share[i] > 0.0f && move[i] > 0.0f)
                sum += std::max(share[i] * move[i], std::numeric_limits<float>::denorm_min());
        return sum;
    };
    const float up = 1.0f + 1e-5f + static_cast<float>(m + kDistanceGroups) * std::numeric_limits<float>::epsilon();
    return std::min(largest, std::min(weighed(envelope, D, m), weighed(envelope + m, G, kDistanceGroups)) * up);
}

// A tile whose bound from its share envelope is at most this fraction of the
// tolerance takes that bound, a little looser than weighing each receiver
// (sharedBounds): it keeps its light unless its drift from the anchor was
// already past the rest of the tolerance.
constexpr float kEnvelopeShareOfTolerance = 0.5f;

// Per tile: the radiance bound, the largest rho_k over its receivers (max_j
// D_tj without the last pass's occlusions, D and G those of the sample
// bounds' larger tile that holds it) times its occlusion factor; from the
// tile's share envelope where that is small enough. Tiles in parallel (each
// tile's value alone), each a chunk of its own at most: those weighed
// receiver by receiver cost far more than the rest.
void sharedBounds(const IndirectPlanInputs& in, IndirectCache& cache) {
    const HeightPyramid& h = in.heights;
    const int tilesX = tileCount(h.nxr, kIndirectTile), tilesY = tileCount(h.nyr, kIndirectTile);
    const std::size_t m = in.phi.size(), tiles = static_cast<std::size_t>(tilesX) * tilesY;
    const std::size_t perTile = m + kDistanceGroups;
    const bool shares = hasOcclusions(in);
    if (cache.shareEnvelope.size() != tiles * perTile || cache.shareEnvelopeStale.size() != tiles) {
        cache.shareEnvelope.assign(tiles * perTile, 0.0f);
        cache.shareEnvelopeStale.assign(tiles, 1);
    }
    const auto rowShareBound = simd::wideEnabled() ? rowShareBoundAvx2 : rowShareBoundSse;
    const auto tileBound = [&](int tx, int ty, const float* D, const float* G) {
        const float largest = *std::max_element(D, D + m);
        if (!shares) return largest;
        const std::size_t t = static_cast<std::size_t>(ty) * tilesX + tx;
        float* envelope = cache.shareEnvelope.data() + t * perTile;
        if (cache.shareEnvelopeStale[t]) {
            takeShareEnvelope(*in.blocker, tx, ty, envelope);
            cache.shareEnvelopeStale[t] = 0;
        }
        const float coarse = envelopeBound(envelope, m, D, G, largest);
        if (cache.occlusionFactor[t] * coarse <= in.tolerance * kEnvelopeShareOfTolerance) return coarse;
        float bound = 0.0f;
        const int x0 = tx * kIndirectTile, x1 = std::min(h.nxr, x0 + kIndirectTile);
        for (int Y = ty * kIndirectTile; Y < std::min(h.nyr, (ty + 1) * kIndirectTile); ++Y)
            bound = std::max(bound, rowShareBound(*in.blocker, Y, x0, x1, RowMoves{D, G, false}));
        return bound;
    };
    parallelFor(0, static_cast<int>(tiles), 1, [&](int t0, int t1) {
        for (int k = t0; k < t1; ++k) {
            const int tx = k % tilesX, ty = k / tilesX;
            const auto t = static_cast<std::size_t>(k);
            const std::size_t b = visibilityTileHolding(tx, ty, h.nxr);
            cache.radianceBound[t] =
                cache.occlusionFactor[t] *
                tileBound(tx, ty, cache.azimuthBound.data() + b * m, cache.groupBound.data() + b * kDistanceGroups);
        }
    });
}

// The largest of n >= 0 values (0 for none; the occlusions are >= 0), in
// eight independent maxima that the compiler keeps in vector lanes (a
// maximum is exact in any order).
float largestOf(const float* v, int n) {
    float lanes[8] = {};
    int i = 0;
    for (; i + 8 <= n; i += 8)
        for (int k = 0; k < 8; ++k) lanes[k] = std::max(lanes[k], v[i + k]);
    for (; i < n; ++i) lanes[0] = std::max(lanes[0], v[i]);
    return *std::max_element(lanes, lanes + 8);
}

// Per tile: min(1, the largest O / pi of the texels that read its
// receivers + the tolerance), or 1 without a texel occlusion (the
// occlusion factor of gi/indirect_cache.h). The largest O is kept per tile
// and taken again where the texels it reads meet the box of those whose
// occlusion was redone since.
void occlusionFactors(const IndirectPlanInputs& in, IndirectCache& cache) {
    const HeightPyramid& h = in.heights;
    const int tilesX = tileCount(h.nxr, kIndirectTile), tilesY = tileCount(h.nyr, kIndirectTile);
    const std::size_t tiles = static_cast<std::size_t>(tilesX) * tilesY;
    cache.occlusionFactor.assign(tiles, 1.0f);
    if (!hasOcclusions(in)) return;
    if (cache.largestOcclusion.size() != tiles) {
        cache.largestOcclusion.assign(tiles, 0.0f);
        cache.occlusionsRedone = CellBox{};
    }
    const CellBox redone = cache.occlusionsRedone.cut(h.nx, h.ny);
    const Grid* occ = &in.blocker->occlusion;
    std::vector<int> x0, x1, y0, y1;
    texelsReadingTiles(h.nx, h.subsample, h.nxr, kIndirectTile, x0, x1);
    texelsReadingTiles(h.ny, h.subsample, h.nyr, kIndirectTile, y0, y1);
    parallelFor(0, tilesY, 1, [&](int ty0, int ty1) {
        for (int ty = ty0; ty < ty1; ++ty)
            for (int tx = 0; tx < tilesX; ++tx) {
                const int a = x0[static_cast<std::size_t>(tx)], b = x1[static_cast<std::size_t>(tx)];
                const int c = y0[static_cast<std::size_t>(ty)], d = y1[static_cast<std::size_t>(ty)];
                float& largest = cache.largestOcclusion[static_cast<std::size_t>(ty) * tilesX + tx];
                if (a < redone.x1 && b >= redone.x0 && c < redone.y1 && d >= redone.y0) {
                    largest = 0.0f;
                    for (int y = c; y <= d; ++y)
                        largest = std::max(largest,
                                           largestOf(occ->data() + static_cast<std::size_t>(y) * h.nx + a, b - a + 1));
                }
                cache.occlusionFactor[static_cast<std::size_t>(ty) * tilesX + tx] =
                    std::min(1.0f, largest + in.tolerance);
            }
    });
    cache.occlusionsRedone = CellBox::none();
}

// Refines the radiance bound of the tiles it would re-gather (with their
// drift from the anchor) and the geometry does not re-gather anyway, unless
// their drift alone is past the tolerance: each
// takes the largest of its receivers' own bounds if smaller, their sample
// moves walked on their own (boundSampleMovePerReceiver) and weighed by
// their own shares (rowShareBound), times the tile's occlusion factor
// (without the occlusions: each receiver's largest move). Only where at
// most kRefineAtMost of the tiles are candidates (gi/plan_skips.h).
void refinePerReceiver(const IndirectPlanInputs& in, IndirectCache& cache) {
    const HeightPyramid& field = in.pyramid.fields[0];
    ReceiverTiles& refined = cache.refined;
    refined.reset(field.nxr, field.nyr, kIndirectTile, false);
    const std::size_t tiles = refined.dirty.size();
    const bool drifts = cache.drift.fits(tiles);  // else every result is at the anchor (a bound alone)
    std::size_t candidates = 0;
    for (std::size_t t = 0; t < tiles; ++t) {
        const bool forced = in.geometryTiles && in.geometryTiles->dirty[t];
        const float drift = drifts ? cache.drift.fromAnchor[t] : 0.0f;
        // a walk leaves a bound of at least 0: a drift past the tolerance re-gathers anyway
        refined.dirty[t] = !forced && drift + cache.radianceBound[t] > in.tolerance && drift <= in.tolerance ? 1 : 0;
        candidates += refined.dirty[t];
    }
    if (static_cast<double>(candidates) > kRefineAtMost * static_cast<double>(tiles))
        std::fill(refined.dirty.begin(), refined.dirty.end(), 0);
    if (refined.dirtyCount() == 0) return;
    buildChangeLevels(cache.change, field, cache.receiverLevels);
    boundSampleMovePerReceiver(cache.receiverLevels, field, in.phi, &refined, cache.receiverAzimuthMove,
                               cache.receiverGroupMove);
    const bool shares = hasOcclusions(in);
    const std::size_t m = in.phi.size(), plane = static_cast<std::size_t>(field.nxr) * field.nyr;
    const auto rowShareBound = simd::wideEnabled() ? rowShareBoundAvx2 : rowShareBoundSse;
    const RowMoves moves{cache.receiverAzimuthMove.data(), cache.receiverGroupMove.data(), true};
    // a receiver's largest move over the azimuths: its rho_k without shares
    const auto largestMove = [&](int Y, int x0, int x1) {
        float largest = 0.0f;
        for (std::size_t j = 0; j < m; ++j)
            for (int X = x0; X < x1; ++X)
                largest =
                    std::max(largest, cache.receiverAzimuthMove[j * plane + static_cast<std::size_t>(Y) * field.nxr +
                                                                static_cast<std::size_t>(X)]);
        return largest;
    };
    std::vector<int>& walked = cache.walkedTiles;
    walked.clear();
    for (std::size_t t = 0; t < tiles; ++t)
        if (refined.dirty[t]) walked.push_back(static_cast<int>(t));
    parallelForEach(walked, [&](int k) {
        const int tx = k % refined.tilesX, ty = k / refined.tilesX;
        const int x0 = tx * kIndirectTile, x1 = std::min(field.nxr, x0 + kIndirectTile);
        float bound = 0.0f;
        for (int Y = ty * kIndirectTile; Y < std::min(field.nyr, (ty + 1) * kIndirectTile); ++Y)
            bound = std::max(bound, shares ? rowShareBound(*in.blocker, Y, x0, x1, moves) : largestMove(Y, x0, x1));
        const auto t = static_cast<std::size_t>(k);
        cache.radianceBound[t] = std::min(cache.radianceBound[t], cache.occlusionFactor[t] * bound);
    });
}

}  // namespace

void boundRadianceChange(const IndirectPlanInputs& in, IndirectCache& cache) {
    const HeightPyramid& h = in.heights;
    const std::size_t tiles =
        static_cast<std::size_t>(tileCount(h.nxr, kIndirectTile)) * tileCount(h.nyr, kIndirectTile);
    const std::array<ConstGridView, 3> before{cache.anchorSource[0].cview(), cache.anchorSource[1].cview(),
                                              cache.anchorSource[2].cview()};
    const std::array<ConstGridView, 3> after{in.source[0].cview(), in.source[1].cview(), in.source[2].cview()};
    cache.anchorChanged = cache.anchorChanged.joined(in.sourceChanged);
    buildMaxChangePyramid(before, after, cache.change, cache.anchorChanged);
    cache.radianceBound.assign(tiles, 0.0f);
    if (maxChangeAll(cache.change) == 0.0f) return;
    // the levels differ from the anchor's within their reach of the texels
    // whose light differs (a box of the change pyramid's blocks, inside the
    // box of the texels reshaded since the anchor)
    buildLevelChanges(in.pyramid, changedCells(cache.change), cache.levels);
    boundSampleChangeFromLevels(cache.change, cache.levels, in.pyramid.fields[0], kVisibilityTile, in.phi,
                                cache.azimuthBound, cache.groupBound);
    occlusionFactors(in, cache);
    sharedBounds(in, cache);
    refinePerReceiver(in, cache);
}

bool startIndirectPlan(const IndirectPlanInputs& in, IndirectCache& cache) {
    const bool allGeometry =
        in.geometryTiles && in.geometryTiles->dirtyCount() == static_cast<int>(in.geometryTiles->dirty.size());
    if (!cacheFits(in, cache) || allGeometry) {
        cache.valid = false;
        return false;
    }
    if (skipsPlan(cache.skips)) return false;
    if (!cache.levelsRecorded) {
        recordAnchorLevels(in.pyramid, cache.levels);
        cache.levelsRecorded = true;
    }
    return true;
}

const ReceiverTiles* planIndirectTiles(const IndirectPlanInputs& in, IndirectCache& cache) {
    if (!cacheFits(in, cache)) {
        cache.valid = false;
        return nullptr;
    }
    boundRadianceChange(in, cache);
    // the geometry tiles are the indirect tiles (cacheFits)
    const std::span<const std::uint8_t> geometry =
        in.geometryTiles ? std::span<const std::uint8_t>(in.geometryTiles->dirty) : std::span<const std::uint8_t>{};
    if (planAnchoredDrift(cache.radianceBound, geometry, in.tolerance, cache.drift, cache.tiles.dirty)) {
        // L_0 equals the anchor's outside anchorChanged: copy its rows
        for (std::size_t c = 0; c < 3; ++c)
            copyGrid(in.source[c].cview(), cache.anchorSource[c], cache.anchorChanged.rows());
        recordAnchorLevels(in.pyramid, cache.levels, cache.anchorChanged);
        cache.anchorChanged = CellBox::none();
    }
    countAfterPlan(cache.tiles.dirtyCount(), static_cast<int>(cache.tiles.dirty.size()), cache.skips);
    return &cache.tiles;
}

void recordIndirectSource(const std::array<Grid, 3>& source, const RadiancePyramid& pyramid,
                          const HeightPyramid& heights, int azimuths, IndirectCache& cache) {
    cache.anchorSource = source;
    cache.levelsRecorded = !cache.levels.fits(pyramid);
    if (cache.levelsRecorded) {
        recordAnchorLevels(pyramid, cache.levels);
        buildLevelChanges(pyramid, CellBox::none(), cache.levels);
        // the receivers' walks (refinePerReceiver): their pyramid, of no change yet, and their planes
        const std::array<ConstGridView, 3> views{source[0].cview(), source[1].cview(), source[2].cview()};
        buildMaxChangePyramid(views, views, cache.change);
        buildChangeLevels(cache.change, pyramid.fields[0], cache.receiverLevels);
        const std::size_t planeR = static_cast<std::size_t>(heights.nxr) * heights.nyr;
        cache.receiverAzimuthMove.resize(static_cast<std::size_t>(azimuths) * planeR);
        cache.receiverGroupMove.resize(kDistanceGroups * planeR);
    }
    cache.anchorChanged = CellBox::none();
    cache.tiles.reset(heights.nxr, heights.nyr, kIndirectTile, false);
    cache.drift.reset(cache.tiles.dirty.size());
    cache.valid = true;
}

void noteOcclusionsRedone(const ReceiverTiles* redone, const TexelRuns* runs, IndirectCache& cache) {
    cache.occlusionsRedone = redone && runs ? cache.occlusionsRedone.joined(boundingBox(*runs)) : CellBox{};
    std::vector<std::uint8_t>& stale = cache.shareEnvelopeStale;
    if (!redone || redone->dirty.size() != stale.size()) {
        std::fill(stale.begin(), stale.end(), 1);
        return;
    }
    for (std::size_t t = 0; t < stale.size(); ++t) stale[t] = stale[t] || redone->dirty[t] ? 1 : 0;
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
    const ConstGridView last = in.lastHeights ? in.lastHeights->cview() : ConstGridView{};
    cache.texelRects.clear();
    appendTexelsToRedo(*in.gathered, in.sameGeometry ? nullptr : &last, in.heights, in.pyramid.subsample,
                       in.pyramid.subsample + 1, cache.texelRects, &cache.texels, in.heightsDiffer);
    texelRunsOfRects(cache.texelRects, in.heights.nx, in.heights.ny, cache.texelRuns);
    return &cache.texels;
}

}  // namespace terrain::gi
