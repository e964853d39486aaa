#pragma once
// A key light shaded with the exact cosine (GiSettings::keyLightExactCosine):
// albedo RGB f max(0, N . l) added to the shade, f the visible fraction of
// the light's region (V_key's band-0 coefficient times sqrt(4 pi) over the
// region's solid angle), bilinear from the receiver grid like the SH vectors
// (Nowrouzezahrai & Snyder 2009, Fig. 7), instead of V_key dotted with the
// order-4 SH clamped cosine, whose band-2 truncation is off for a small light.
#include <array>
#include <cstdint>
#include <vector>

#include "core/grid.h"
#include "gi/lights.h"
#include "gi/shading.h"
#include "gi/texel_runs.h"
#include "gi/visibility.h"

namespace terrain::gi {

/// Adds the key light's shade to `out` (the gradients' size) at every texel
/// of the runs (gi/texel_runs.h; null: every texel).
/// `v`: the light's visibility (its V_00 plane) on the receiver grid of
/// sub-sampling s. Each texel's value depends on its own inputs alone.
void addKeyLightExactCosine(const KeyLight& light, const VisibilityField& v, int s, ConstGridView gradX,
                            ConstGridView gradY, const AlbedoMap* albedo, std::array<Grid, 3>& out,
                            const TexelRuns* runs = nullptr);

}  // namespace terrain::gi
