#pragma once
// Indirect light on the fast path (Sections 3-7; Eqs. 6-8, 12, 17-21).
//
// Each bounce filters the previous bounce's exit radiance into a pyramid,
// walks every receiver's casting sets (Eq. 17) against it and turns them into
// the bounce's exit radiance (gi/indirect_bounces.h). How the casting sets
// become light is the strategy, chosen from the settings and the BRDF:
//   LambertIndirect::BlockerRadiance, Lambert BRDF (the engine's default): the
//     exact clamped-cosine irradiance at the receivers, the blockers' mean
//     radiance times each texel's occlusion between them
//     (gi/indirect_blocker_radiance.h);
//   otherwise (LambertIndirect::ShKernel; GlossyIndirect::ScalarPyramid and
//     VectorPyramid): Eq. 12, U through the folded wedge operator, shaded in
//     SH (gi/indirect_sh_kernel.h); with VectorPyramid and a non-Lambert BRDF
//     the members send their SH exit-radiance vectors towards each receiver.
// The casting-set kernel of every strategy is gi/casting_set_scan.h.
#include "gi/indirect_inputs.h"
#include "gi/indirect_settings.h"
#include "gi/indirect_state.h"

namespace terrain::gi {

/// Indirect light of settings.bounces bounces over the frame's height pyramid
/// (state.indirect: their sum; state.total: direct + indirect). Throws
/// InputError when a setting is out of range, or for the vector pyramid
/// without a usable in.directShade.
void computeIndirect(const IndirectInputs& in, const IndirectSettings& settings, IndirectState& state);

/// The settings choose the glossy vector pyramid, which reads the direct
/// shading's incident SH field (ShadeMaps::keepIncident must be set on it).
bool readsIncidentSh(const IndirectSettings& settings, const ShadingSettings& shading);

/// The settings choose a strategy whose one-bounce result can be re-gathered
/// by receiver tiles over a cached one (IndirectInputs::only, with the bound
/// of gi/indirect_cache.h): LambertIndirect::BlockerRadiance, one bounce.
bool gathersByTiles(const IndirectSettings& settings, const ShadingSettings& shading);

}  // namespace terrain::gi
