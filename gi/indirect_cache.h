#pragma once
// Which receiver tiles must re-gather their indirect light (the frame's one
// place for it; the Lambert scan only takes the tiles, IndirectInputs::only).
//
// One bounce of LambertIndirect::BlockerRadiance gathers, at each receiver,
// the direct light L_0 of its casting sets. Its result can move for two
// reasons, and a tile re-gathers when either says so:
//  - the blockers' radiance: each frame adds, per tile, the bound of
//    gi/change_bound.h on how far the frame's change of L_0 moves the
//    samples the tile's scan reads (boundSampleChangePerAzimuth, the largest
//    over the indirect azimuths: the gathered irradiance and the mean blocker
//    radiance move by at most that much, in shade units). The sum of these
//    bounds since the tile's cached result was computed bounds its drift
//    (triangle inequality); beyond the tolerance, the tile re-gathers.
//  - the geometry within reach: the tiles whose geometry drifted beyond the
//    tolerance this frame (VisibilityCache::geometryTiles, the bound over
//    every azimuth, so it covers the indirect azimuths): their casting sets
//    have drifted beyond the tolerance in the ambient map's units.
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
#include <vector>

#include "core/grid.h"
#include "gi/change_bound.h"
#include "gi/pyramid.h"
#include "gi/radiance_pyramid.h"
#include "gi/receiver_tiles.h"
#include "gi/shading.h"

namespace terrain::gi {

struct IndirectCache {
    bool valid = false;                 // the fields below describe the cached indirect result
    std::array<Grid, 3> lastSource;     // L_0 the last indirect pass read
    MaxChangePyramid change;            // this frame: max over the channels of |L_0 - lastSource|
    std::vector<float> azimuthBound;    // per tile and indirect azimuth (tile-major)
    std::vector<float> drift;           // per tile: bound of the radiance change since its result was gathered
    ReceiverTiles tiles;                // this frame's tiles to re-gather
    ReceiverTiles texels;               // this frame's texel tiles to redo
    std::uint64_t geometryVersion = 0;  // GiState::geometryVersion of the last pass
    bool hadAlbedo = false;             // the last pass's albedo channels (empty: 1)
    std::array<Grid, 3> lastAlbedo;
};

/// What the frame knows when it plans the indirect tiles.
struct IndirectPlanInputs {
    const std::array<Grid, 3>& source;   // this frame's L_0 (full resolution)
    const HeightPyramid& heights;        // this frame's height pyramid
    const RadiancePyramid& lastPyramid;  // the last indirect pass's radiance pyramid (its steps)
    const ReceiverTiles* geometryTiles;  // tiles whose geometry drifted beyond the tolerance; null: none
    int azimuths;                        // of the indirect scan
    float tolerance;
};

/// The tiles to re-gather (cache.tiles), or null when every receiver must be
/// (no valid cache of this grid: the drifts start again at 0).
const ReceiverTiles* planIndirectTiles(const IndirectPlanInputs& in, IndirectCache& cache);

/// After an indirect pass over `source` (on the receiver grid of `heights`):
/// it is what the next frame compares with; `all` when the pass gathered
/// every receiver (the tiles and drifts start again at 0).
void recordIndirectSource(const std::array<Grid, 3>& source, const HeightPyramid& heights, bool all,
                          IndirectCache& cache);

/// What the frame knows of the texels' inputs since the last pass.
struct IndirectTexelInputs {
    const ReceiverTiles* gathered;  // this pass's receiver tiles (null: every receiver)
    bool sameGeometry;              // heights and gradients are the last pass's
    const Grid* lastHeights;        // else the last pass's heights (null: not known)
    ConstGridView heights;          // and this pass's
    const AlbedoMap* albedo;        // this pass's (null: 1)
    const HeightPyramid& pyramid;   // this pass's grid
};

/// The texel tiles to redo (cache.texels, on the layout of cache.tiles), or
/// null for every texel: every receiver gathered, the height change not
/// known, or a new albedo (recorded for the next pass).
const ReceiverTiles* planIndirectTexels(const IndirectTexelInputs& in, IndirectCache& cache);

/// Forgets the cache: the next pass gathers every receiver.
inline void invalidateIndirectCache(IndirectCache& cache) { cache.valid = false; }

}  // namespace terrain::gi
