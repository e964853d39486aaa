#pragma once
// Which receiver tiles must recompute their visibility after the heights
// changed (the frame's one place for it; the scans only take the tiles).
//
// Per tile of kCacheTile x kCacheTile receivers the cache keeps how
// far its cached V can have drifted since it was computed, from an anchor
// (gi/anchored_drift.h: the heights of an earlier frame): each frame with new
// heights takes the conservative bounds (gi/change_bound.h) of the change
// from the anchor's heights to its own (the move of the blocking slopes of
// each environment azimuth, and of the height gradients behind the tangent
// planes), turned into the largest change of the ambient map (unit sky)
// they allow, and adds how far the tile's V was from the anchor's. A tile is
// recomputed when that drift exceeds the tolerance; tolerance 0 recomputes
// every tile whose inputs may have changed at all, which reproduces a full
// recompute bit for bit. The drift bounds the accumulated change (triangle
// inequality), so slow changes over many frames are caught too, and a
// change that comes and goes is not counted again each time. A tile the
// anchor's drift would recompute is kept when its drift from the last
// frame's heights, plus the bound of the change since them, stays within
// the tolerance (the second path): a change that stays is then paid for
// once.
//
// Key lights sample their own azimuths, between the environment's, within
// their region of the sky: their tiles (keyTiles) keep a drift of their own
// in visible fraction, the largest over the lights of each one's bound
// (keyLightFractionBound: the slope bound over the light's azimuths,
// boundSlopeChangeOverRange, over its window's height, taken over each
// cache tile itself), and recompute when it, times the sum of the lights'
// largest channels this frame, exceeds the tolerance: the key lights' shade
// may then have drifted beyond it, in the shade units of the lights
// themselves, not of a unit sky (a shadow edge that moved across a texel is
// a change of the light's whole shade there), and a light made brighter
// since counts at its new brightness. A key light
// shaded through SH (the paper's settings) recomputes every tile whose bound
// is not 0, where its order-4 product has no such bound. The geometry
// tiles (geometryTiles) do the same with the environment's bound taken over
// the indirect scan's azimuths alone, where those are every k-th of the
// environment's (else with one slope bound over every direction): what the
// indirect light's casting sets may have moved (gi/indirect_cache.h).
// Each bound is first taken coarsely, with one slope bound over every
// direction per visibility tile, and per azimuth (or over a key light's
// azimuths) only where the coarse one would take a tile past
// kCoarseBoundShare of the tolerance.
#include <cstdint>
#include <span>
#include <vector>

#include "core/grid.h"
#include "gi/anchored_drift.h"
#include "gi/change_bound.h"
#include "gi/plan_skips.h"
#include "gi/pyramid.h"
#include "gi/receiver_azimuth_bound.h"
#include "gi/receiver_tiles.h"
#include "gi/visibility.h"

namespace terrain::gi {

/// Receivers per side of a visibility tile, over which the bounds are taken
/// (a multiple of ReceiverTiles::kTileAlign).
inline constexpr int kVisibilityTile = 32;

/// Receivers per side of the tiles whose V is kept or recomputed, each with
/// its own drift: a quarter of a visibility tile. A tile takes its
/// visibility tile's environment and geometry bounds, and where those would
/// recompute it, the largest of its receivers' own bounds
/// (gi/receiver_azimuth_bound.h) if smaller: the box bounds cost little per
/// tile and rule out most of the field, the receivers' bounds are precise
/// where a change lies near (a tile's bound charges each receiver with the
/// largest change within reach of any). The key lights' bounds are taken
/// over the cache tile itself.
inline constexpr int kCacheTile = 16;
static_assert(kVisibilityTile % kCacheTile == 0 && kCacheTile % ReceiverTiles::kTileAlign == 0,
              "cache tiles split visibility tiles into whole receiver groups");

/// The visibility tile (its row-major index over nxr receivers) holding
/// cache tile (tx, ty) (an indirect tile too: gi/indirect_cache.h).
inline std::size_t visibilityTileHolding(int tx, int ty, int nxr) {
    constexpr int kPer = kVisibilityTile / kCacheTile;
    return static_cast<std::size_t>(ty / kPer) * static_cast<std::size_t>(tileCount(nxr, kVisibilityTile)) +
           static_cast<std::size_t>(tx / kPer);
}

/// The share of the tolerance up to which a tile's drift may be counted with
/// its coarse bounds alone: one slope bound over every direction per
/// visibility tile (a few box queries per step) in place of one per azimuth
/// or over a key light's azimuths (a query per azimuth or sweep and step).
/// The coarse bound holds along every azimuth as the finer ones do, only
/// more loosely: it lets a tile's drift grow faster, by at most this share of
/// the tolerance from the anchor, while far from a local change most tiles
/// stay under it and the finer bounds cost most of the plan.
inline constexpr float kCoarseBoundShare = 0.25f;

/// What a key light's cached visibility answers for: the azimuths [phi0,
/// phi1] (radians) it reads and its window's sines (gi/lights.h,
/// keyLightExtent); with its largest channel this frame and whether it is
/// shaded with the exact cosine (else through SH).
struct KeyLightRegion {
    double phi0 = 0.0, phi1 = 0.0;
    float sinLow = -1.0f, sinHigh = 1.0f;
    float maxRgb = 1.0f;
    bool exactCosine = true;
};

struct VisibilityCache {
    Grid anchorHeights;            // the heights the drifts are measured from
    CellBox anchorDiffers;         // holds every cell where they may differ from the last plan's (all)
    bool anchorIsLastPlan = true;  // they are the last plan's (its `after`, or reset to them)
    MaxChangePyramid change;       // |dh| from the anchor to this frame
    // this frame's bounds per visibility tile (kVisibilityTile)
    std::vector<float> slopeBound, gradBound;    // all azimuths
    std::vector<float> coarseBound;              // the ambient-map bound from slopeBound (any azimuths)
    std::vector<std::uint8_t> perAzimuth;        // the tiles whose bounds are taken per azimuth too
    std::vector<float> azimuthBound;             // per tile and environment azimuth (tile-major; those tiles')
    std::vector<float> envBound, geometryBound;  // the ambient-map bound: every azimuth, the indirect scan's
    std::vector<float> tileAzimuths;             // scratch: one tile's per-azimuth slope bounds
    // this frame's bounds per cache tile (kCacheTile): the environment's and
    // the geometry's their visibility tile's, lowered to the cache tile's own
    // and its receivers' where those pass the tolerance; the key lights'
    // fraction bound its own
    std::vector<float> envExcursion, keyExcursion, geometryExcursion;
    std::vector<float> cacheGradBound;  // per cache tile: its own gradient bound
    // scratch: one key light's slopes per cache tile; the refined cache
    // tiles' own slope bounds per azimuth, environment and geometry bounds
    std::vector<float> rangeBound, cacheAzimuthBound, cacheEnvBound, cacheGeometryBound;
    std::vector<float> cacheSlope;        // scratch: each cache tile's visibility tile's slopeBound
    std::vector<std::uint8_t> overRange;  // scratch: the cache tiles a key light's range bound is taken for
    ChangeLevels receiverLevels;          // the |dh| pyramid of the receivers' bounds
    std::vector<double> azimuths;         // the environment's azimuths (radians) they are taken along
    std::vector<float> receiverBound;     // per receiver: the ambient-map bound (refined tiles only)
    std::vector<float> receiverGeometry;  // the same along the indirect scan's azimuths
    ReceiverTiles refined;                // scratch: the cache tiles refined this frame
    // the drifts' second path (gi/anchored_drift.h): |dh| from the last
    // planned frame's heights to this frame's, and per cache tile the
    // bounds of that change (infinite where not taken: the tiles that the
    // anchor's bounds keep, or whose drift from those heights is past the
    // tolerance already); per visibility tile, scratch
    MaxChangePyramid lastChange;
    std::vector<float> envSinceLast, keySinceLast, geometrySinceLast;
    std::vector<std::uint8_t> sinceLastTiles, sinceLastVisibilityTiles;
    std::vector<float> lastSlope, lastGrad, lastCoarse, lastCacheGrad, lastAzimuthBound, lastEnv, lastGeometry;
    AnchoredDrift drift, keyDrift;  // per cache tile: ambient-map (key: visible-fraction) change
    AnchoredDrift geometryDrift;    // per cache tile: the same along the indirect light's azimuths
    ReceiverTiles tiles;            // this frame's cache tiles to recompute (environment)
    ReceiverTiles keyTiles;         // the same for the key lights
    ReceiverTiles geometryTiles;    // cache tiles whose geometry moved beyond the tolerance
    PlanSkips skips;                // frames that recompute everything unplanned
};

/// A frame whose heights did not change but whose lights did: marks the key
/// tiles (cache.keyTiles, their drift reset to 0) whose drift, times this
/// frame's key-light brightness, exceeds the tolerance: a light made brighter
/// since counts at its new brightness. True when any tile is marked (false
/// too when the cache holds no drift of this grid).
bool planKeyBrightness(const std::vector<KeyLightRegion>& keys, float tolerance, VisibilityCache& cache);

/// Whether this frame's changed heights should be planned tile by tile
/// (false: recompute everything, resetVisibilityCache); counts the frames
/// without a plan down.
bool shouldPlanTiles(VisibilityCache& cache);

/// Forgets the drift: every tile's V is about to be computed from scratch,
/// from `heights` (the new anchor).
void resetVisibilityCache(const HeightPyramid& pyr, ConstGridView heights, VisibilityCache& cache);

/// Every receiver's environment V has just been computed from the last
/// planned heights: its drift is theirs (the key lights' and the geometry's
/// are kept, their results were not recomputed).
void forgetEnvironmentDrift(VisibilityCache& cache);

/// Per tile, the bound on the change of the environment's ambient map (unit
/// sky) that its per-azimuth slope bounds (`azimuthBound`, tile-major, before
/// the maximum rule's Lipschitz factor) and its gradient bound allow: what
/// planVisibilityTiles adds to an environment tile's drift. `scratch` holds
/// one tile's azimuths. With a stride k, over every k-th azimuth alone (from
/// the first; k divides `azimuths`): a geometry tile's, when the indirect
/// scan takes every k-th of the environment's azimuths.
void environmentBoundPerTile(std::span<const float> azimuthBound, std::span<const float> gradBound, int azimuths,
                             float lipschitz, std::vector<float>& scratch, std::vector<float>& out, int stride = 1);

/// The same from one slope bound per tile over every azimuth (`slopeBound`):
/// what planVisibilityTiles adds to a geometry tile's drift when the indirect
/// scan's azimuths are not every k-th of the environment's.
void geometryBoundPerTile(std::span<const float> slopeBound, std::span<const float> gradBound, float lipschitz,
                          std::vector<float>& out);

/// Bounds the change from the anchor's heights to the pyramid's heights
/// `after`, adds every tile's drift from the anchor, and marks the tiles
/// whose drift exceeds `tolerance`: cache.tiles for the environment's V
/// (`vis`: its azimuths and maximum rule), cache.keyTiles for the key lights'
/// (one region per light; none: no key tile), cache.geometryTiles along the
/// indirect scan's `indirectAzimuths` when those are every k-th of the
/// environment's (also refined per receiver), else over every direction (0:
/// not known). `before`: the last frame's heights, the anchor when the
/// cache starts afresh (no drift of this grid); `sinceBefore` holds every
/// cell where `after` differs from them (every cell by default). `pyr` is
/// the pyramid of `after`.
void planVisibilityTiles(ConstGridView before, ConstGridView after, const HeightPyramid& pyr,
                         const VisibilitySettings& vis, const std::vector<KeyLightRegion>& keys, float tolerance,
                         VisibilityCache& cache, CellBox sinceBefore = {}, int indirectAzimuths = 0);

}  // namespace terrain::gi
