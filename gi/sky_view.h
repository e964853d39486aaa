#pragma once
// The sky-view factor as GIS tools define it (Zaksek, Ostir & Kokalj 2011,
// "Sky-view factor as a relief visualization technique", Eq. 1): the fraction
// of the upper hemisphere's solid angle that the terrain leaves open, with
// the horizontal plane as reference,
//
//   SVF = 1 - (1 / m) sum_j sin(gamma_j),  gamma_j = max(0, horizon elevation
//   along azimuth j),
//
// the solid angle above elevation gamma over an azimuthal wedge being
// (1 - sin gamma) dphi. This is the plain factor of SAGA, GRASS r.skyview and
// the Relief Visualization Toolbox; the normal-weighted one (cosine-weighted
// visible sky at each texel's own normal / pi) is the engine's ambient map
// (gi/ambient_horizon.h).
#include "core/grid.h"
#include "gi/frame.h"

namespace terrain::gi {

/// The plain sky-view factor from the last frame's environment scan
/// (st.envVisibility's horizons along st.envCosSin's azimuths), at full
/// resolution; `heights`: that frame's. At sub-sampling each receiver's
/// horizon slope, raised to 0, is interpolated bilinearly to the texels (Fig.
/// 7 of Nowrouzezahrai & Snyder 2009) and raised to the texel's own near
/// field (gi/near_field.h). Throws InputError when the state holds no frame of
/// these heights.
void skyViewFactor(const GiState& st, ConstGridView heights, Grid& out);

/// The same from the exact horizons of the bilinear field (referenceMaxSlope,
/// gi/reference.h) along `azimuths` evenly spaced azimuths (phi = 2 pi (j +
/// 1/2) / azimuths): the ground truth the fast one is measured against.
void referenceSkyViewFactor(ConstGridView heights, float cellSize, int azimuths, Grid& out);

}  // namespace terrain::gi
