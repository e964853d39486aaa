#pragma once
// What the indirect light reads of a frame (gi/indirect.h): the bundle every
// strategy gets, filled once by the caller (gi/frame.cpp).
#include <array>

#include "core/grid.h"
#include "gi/lights.h"
#include "gi/pyramid.h"
#include "gi/receiver_tiles.h"
#include "gi/shading.h"
#include "gi/texel_runs.h"
#include "gi/visibility.h"
#include "gi/wedge.h"

namespace terrain::gi {

struct IndirectInputs {
    const HeightPyramid& heights;   // the frame's height pyramid (receiver grid, steps)
    ConstGridView gradX, gradY;     // full-resolution height gradients
    const FoldedWedgeOperator& op;  // folded wedge operator of the indirect azimuths (IndirectSettings::azimuths)
    const VisibilityField& envVisibility;  // environment visibility (the shading's ambient map)
    const std::array<Grid, 3>& direct;     // bounce 0's exit radiance (full resolution, albedo applied)
    // The direct shading `direct` came from (its rgb is `direct`; its
    // incident SH vectors): required by GlossyIndirect::VectorPyramid with a
    // non-Lambert BRDF (InputError without it), unused otherwise (may be null).
    const ShadeMaps* directShade;
    const AlbedoMap* albedo;  // null: 1
    const ShadingSettings& shading;
    // Receiver tiles (change-driven GI, gi/receiver_tiles.h); null: every
    // receiver. The Lambert strategies' scans then recompute the receivers of
    // the dirty tiles only (BlockerRadiance: E and the horizons; ShKernel: U),
    // bit-identical to a full scan, and leave the others' values in the state
    // as they are: the caller's cache, which must hold a result of this
    // receiver grid and these settings (InputError when the sizes differ).
    // The state holds the outputs of one bounce, the one scanned last: a
    // clean receiver keeps the previous call's last bounce at bounce 1 and
    // this call's bounce b - 1 at bounce b, so the tiles give a consistent
    // result with one bounce; more bounces need a cache per bounce, which the
    // state does not keep (gathersByTiles, gi/indirect.h).
    // GlossyIndirect::VectorPyramid ignores the tiles (every receiver).
    const ReceiverTiles* only = nullptr;
    // BlockerRadiance, one bounce: the tiles whose receivers' occlusion the
    // texel passes redo, and the texels whose occlusion and light they redo
    // (gi/blocker_radiance.h); null: every texel. The others keep the
    // state's values: the caller's cache (gi/indirect_cache.h).
    const ReceiverTiles* texels = nullptr;
    const TexelRuns* texelRuns = nullptr;
    // The heights, gradients and settings are those of the state's last
    // call: BlockerRadiance keeps the texel occlusion it computed then
    // (a pure function of them), where it holds one of this grid.
    bool sameGeometry = false;
    // The texels of `direct` that may differ from the state's last call's
    // (every texel by default): after a call whose last pyramid was bounce
    // 0's, the RGB pyramid of bounce 0 redoes only what reads them, bit for
    // bit a full build (buildRadiancePyramid).
    CellBox directChanged;
    // The state's RGB pyramid is already that of `direct` (the caller built
    // it, IndirectState::radianceOfDirect set): bounce 1 keeps it.
    bool radianceCurrent = false;
    // The lights' SH radiance the direct shading filtered, unoccluded: what
    // the lobe gather's first-bounce members reflect above their horizons
    // (GlossyLobeMembers::Windowed; null: they send E).
    const ShRgb* memberLight = nullptr;
};

}  // namespace terrain::gi
