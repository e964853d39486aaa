#pragma once
// Which receiver tiles must re-gather their indirect light (the frame's one
// place for it; the Lambert scan only takes the tiles, IndirectInputs::only).
// Its tiles (kIndirectTile receivers a side) are a quarter of the
// visibility's: the sample bounds below are per visibility tile, but each
// receiver's weighing is its own, so the smaller tiles keep the light of
// receivers that a larger one's worst receiver would re-gather.
//
// One bounce of LambertIndirect::BlockerRadiance gathers, at each receiver,
// the direct light L_0 of its casting sets. Its result can move for two
// reasons, and a tile re-gathers when either says so:
//  - the blockers' radiance: per tile, how far the change of L_0 since the
//    anchor (gi/anchored_drift.h: the L_0 of an earlier pass, kept while it
//    pays, with its radiance pyramid's levels) moved the samples the tile's
//    scan reads, the largest per indirect azimuth and per distance group,
//    taken from this frame's pyramid and the anchor's
//    (gi/radiance_sample_change.h), weighed and scaled as below, plus how far the tile's
//    cached result was from the anchor's, bounds its drift (triangle
//    inequality); beyond the tolerance, the tile re-gathers. A change that
//    comes and goes (a pit dropped and filled) costs nothing once it is gone.
//
//    Weights and scale (sub-sampling): a texel's light is O(x) times its
//    receivers' interpolated mean blocker radiance sum w_k E_k / sum w_k O_k
//    (gi/blocker_radiance.h), and a receiver's E_k sums the samples' radiance
//    over its casting sets, whose clamped-cosine measures along azimuth j
//    add up to O_kj, its occlusion along j (O_k = sum_j O_kj). So E_k moves
//    by at most sum_j O_kj D_j (D_j: the largest sample move along j), the
//    mean blocker radiance by at most rho_k = sum_j (O_kj / O_k) D_j <= max_j
//    D_j, and the texel's light by at most O(x) max_k rho_k, O(x) = O / pi
//    <= 1. The same holds per distance group of the steps (gi/pyramid.h):
//    the segments of group g's members, over every azimuth, measure O_kg
//    (the scan sums them, BlockerRadianceState::receiverGroupOcclusion;
//    sum_g O_kg = O_k), and with G_g the largest sample move of group g's
//    steps along any azimuth, rho_k <= sum_g (O_kg / O_k) G_g; the smaller of
//    the two weighings is taken. Per tile the bound is the largest rho_k of
//    its receivers (D_j and G_g those of the visibility tile holding it)
//    times the largest O(x) of the texels that read them. A
//    far change (a pit, a crater) moves the coarse, far samples of every
//    tile: it then counts by the share of the sky the far members of its
//    azimuths cover, not the whole occlusion along them. The occlusions are the
//    last pass's; the geometry may have moved since by no more than the
//    tolerance (else the tile re-gathers), so the factor is that largest
//    O(x) plus the tolerance, at most 1. Without sub-sampling (every texel a
//    receiver, no texel occlusion kept) the bound is max_j D_j.
//    Refined per receiver: where that bound would re-gather a tile that the
//    geometry does not, D_kj and G_kg of each receiver's own samples
//    (gi/receiver_azimuth_bound.h, walked over the pyramid of |L_0 - L_0 at
//    the anchor|) weighed by its own shares replace the larger tile's, if
//    smaller: beside a local change, a tile's receivers see it along a few
//    azimuths and at a few distances of their own, where the larger tile's
//    bounds charge each with the nearest and largest move of any.
//  - the geometry within reach: the tiles whose geometry drifted beyond the
//    tolerance this frame (VisibilityCache::geometryTiles, the visibility
//    cache's tiles, which are these: the bound over every azimuth, or along
//    the environment's when the indirect scan takes those, so it covers the
//    indirect azimuths): their casting sets have drifted beyond the
//    tolerance in the ambient map's units.
// Tolerance 0 re-gathers every tile where either bound is not 0, which gives
// the full recompute bit for bit. More than one bounce, or another strategy:
// every receiver (no per-bounce cache).
//
// The texel passes after the scan (gi/blocker_radiance.h: each texel's
// occlusion below its receivers' horizons and near field, and its light
// from its receivers' E and O) redo only the texel tiles whose inputs can
// differ from the last pass's, bit for bit (planIndirectTexels). A texel
// belongs to the tile of its lower receiver and reads that receiver and the
// next one along each axis, so its tile is redone when
//  - one of those receivers was re-gathered (its tile, or the tile after it
//    along x, y or both), or
//  - a height changed within s + 1 cells of the tile's texels (the near
//    samples reach s cells, the gradients one more, and the receivers' own
//    gradients lie among them), or
//  - the albedo changed (every texel).
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "core/grid.h"
#include "gi/anchored_drift.h"
#include "gi/blocker_radiance.h"
#include "gi/change_bound.h"
#include "gi/plan_skips.h"
#include "gi/pyramid.h"
#include "gi/radiance_pyramid.h"
#include "gi/radiance_sample_change.h"
#include "gi/receiver_azimuth_bound.h"
#include "gi/receiver_tiles.h"
#include "gi/shading.h"
#include "gi/texel_runs.h"
#include "gi/visibility_cache.h"

namespace terrain::gi {

/// Receivers per side of an indirect tile: a divisor of kVisibilityTile (the
/// sample bounds and the geometry tiles are per visibility tile) and a
/// multiple of ReceiverTiles::kTileAlign.
inline constexpr int kIndirectTile = 16;
static_assert(kVisibilityTile % kIndirectTile == 0 && kIndirectTile % ReceiverTiles::kTileAlign == 0,
              "indirect tiles split visibility tiles into whole receiver groups");
static_assert(kIndirectTile == kCacheTile, "the visibility cache's geometry tiles are the indirect tiles");

struct IndirectCache {
    bool valid = false;                // the fields below describe the cached indirect result
    std::array<Grid, 3> anchorSource;  // L_0 at the anchor (gi/anchored_drift.h)
    CellBox anchorChanged;             // holds every texel where L_0 may differ from anchorSource (every one)
    // this frame: max over the channels of |L_0 - anchorSource| (no block
    // sums: the sample bounds read maxima alone)
    MaxChangePyramid change{.withSums = false};
    RadianceLevelChange levels;          // the anchor's radiance pyramid levels, this frame's change of each
    bool levelsRecorded = false;         // `levels` hold the anchor's (else the last pass's pyramid is the anchor's)
    std::vector<float> azimuthBound;     // per tile and indirect azimuth (tile-major)
    std::vector<float> groupBound;       // per tile and distance group (gi/pyramid.h), over every azimuth
    AnchoredDrift drift;                 // per tile: how far its result was from the anchor's
    std::vector<float> occlusionFactor;  // per tile: this frame's factor of the radiance bound
    // per tile: the largest O / pi of the texels that read its receivers,
    // taken again only where the texel passes redid an occlusion since
    // (occlusionsRedone: a box of texels, every one by default)
    std::vector<float> largestOcclusion;
    CellBox occlusionsRedone;
    std::vector<float> radianceBound;  // per tile: this frame's bound from the anchor (boundRadianceChange)
    // the receivers' own sample moves (refined tiles only): the |L_0 -
    // anchor| pyramid they are walked on, per azimuth and per distance group
    ChangeLevels receiverLevels;
    std::vector<float> receiverAzimuthMove, receiverGroupMove;
    ReceiverTiles refined;         // scratch: the tiles refined this frame
    std::vector<int> walkedTiles;  // scratch: their indices
    // per tile: the largest share of a receiver's occlusion along each
    // azimuth, then in each distance group (azimuths + kDistanceGroups
    // floats, rounded up), or all -1 when some receiver has (next to) no
    // occlusion; of the occlusions of the last pass that redid the tile's
    // (shareEnvelopeStale: not yet taken since)
    std::vector<float> shareEnvelope;
    std::vector<std::uint8_t> shareEnvelopeStale;
    ReceiverTiles tiles;                // this frame's tiles to re-gather
    ReceiverTiles texels;               // this frame's tiles whose receivers' occlusion the texel passes redo
    TexelRuns texelRuns;                // and the texels they redo
    std::vector<TexelRect> texelRects;  // their scratch
    std::uint64_t geometryVersion = 0;  // GiState::geometryVersion of the last pass
    PlanSkips skips;                    // frames that re-gather everything unplanned
    bool hadAlbedo = false;             // the last pass's albedo channels (empty: 1)
    std::array<Grid, 3> lastAlbedo;
};

/// What the frame knows when it plans the indirect tiles.
struct IndirectPlanInputs {
    const std::array<Grid, 3>& source;   // this frame's L_0 (full resolution)
    const HeightPyramid& heights;        // this frame's height pyramid
    const RadiancePyramid& pyramid;      // the RGB radiance pyramid of `source` (the scan's steps)
    const ReceiverTiles* geometryTiles;  // tiles whose geometry drifted beyond the tolerance; null: none
    std::span<const double> phi;         // the indirect scan's azimuths (FoldedWedgeOperator::phi)
    float tolerance;
    // the last pass's occlusions (sub-sampling, blocker radiance: the
    // occlusion factor and the azimuths' shares); null: neither
    const BlockerRadianceState* blocker = nullptr;
    // holds every texel of `source` that may differ from the last pass's
    // (which planned or recorded it); every texel by default
    CellBox sourceChanged = {};
};

/// This frame's bound per tile (cache.radianceBound, shade units; 0 where L_0
/// did not change) on how far the change of L_0 from cache.anchorSource to
/// in.source moves the indirect light of every texel that reads one of the
/// tile's receivers, the geometry being the last pass's: the largest sample
/// move over the tile's azimuths weighed by each receiver's shares of its
/// occlusion, times the occlusion factor (above). The samples' moves come
/// from in.pyramid against cache.levels (recordAnchorLevels of the anchor's
/// pyramid).
void boundRadianceChange(const IndirectPlanInputs& in, IndirectCache& cache);

/// Whether this frame plans its indirect tiles, asked before the frame builds
/// its radiance pyramid (in.pyramid is still the last pass's): a valid cache
/// of this grid, some geometry tile within the tolerance, and no frame left
/// of a run without plans (counted down here; gi/plan_skips.h: after a plan
/// that found most tiles dirty, frames re-gather everything without
/// computing the bound, whose cost would only be added to a full pass).
/// When it plans and the anchor's levels are not recorded yet, the last
/// pass's pyramid is the anchor's: its levels are copied now (a pass that
/// is not followed by a plan costs no copy). False: every receiver
/// re-gathers (an unfit cache is dropped: the drifts start again at 0).
bool startIndirectPlan(const IndirectPlanInputs& in, IndirectCache& cache);

/// The tiles to re-gather (cache.tiles), after startIndirectPlan said so and
/// with in.pyramid this frame's; null when every receiver must be.
const ReceiverTiles* planIndirectTiles(const IndirectPlanInputs& in, IndirectCache& cache);

/// After an indirect pass over `source` (its RGB radiance pyramid `pyramid`,
/// on the receiver grid of `heights`, with the scan's `azimuths`) that
/// gathered every receiver: `source` is the anchor the next frames compare
/// with, the drifts start again at 0. The pyramid's levels are copied by the
/// next plan, if any; only the first pass on a grid copies them at once,
/// with their (zero) change, and sizes the receivers' walks (their pyramid
/// and planes), so that the cache's memory is taken then and not in the
/// middle of a run. (A planned pass moved the anchor, if at all, in
/// planIndirectTiles.)
void recordIndirectSource(const std::array<Grid, 3>& source, const RadiancePyramid& pyramid,
                          const HeightPyramid& heights, int azimuths, IndirectCache& cache);

/// After an indirect pass whose texel passes redid the receivers'
/// occlusions in the tiles `redone` (cache.texels) and the texels'
/// occlusions at `runs` (cache.texelRuns; both null: every one): their share
/// envelopes and largest occlusions are taken again by the next plan.
void noteOcclusionsRedone(const ReceiverTiles* redone, const TexelRuns* runs, IndirectCache& cache);

/// What the frame knows of the texels' inputs since the last pass.
struct IndirectTexelInputs {
    const ReceiverTiles* gathered;  // this pass's receiver tiles (null: every receiver)
    bool sameGeometry;              // heights and gradients are the last pass's
    const Grid* lastHeights;        // else the last pass's heights (null: not known)
    ConstGridView heights;          // and this pass's
    const AlbedoMap* albedo;        // this pass's (null: 1)
    const HeightPyramid& pyramid;   // this pass's grid
    CellBox heightsDiffer = {};     // holds every height where lastHeights and heights may differ
};

/// The texel passes' extent, or null for every texel: every receiver
/// gathered, the height change not known, or a new albedo (recorded for the
/// next pass). cache.texels (on the layout of cache.tiles): the gathered
/// tiles and those within s + 1 cells of a changed height (the near
/// samples reach s cells, the gradients one more), whose receivers' own
/// occlusion may have changed; cache.texelRuns: the texels that read a
/// gathered receiver and those of the tiles near a changed height
/// (appendTexelsToRedo).
const ReceiverTiles* planIndirectTexels(const IndirectTexelInputs& in, IndirectCache& cache);

/// Forgets the cache: the next pass gathers every receiver.
inline void invalidateIndirectCache(IndirectCache& cache) { cache.valid = false; }

}  // namespace terrain::gi
