#pragma once
// What the indirect light reads of a frame (gi/indirect.h): the bundle every
// strategy gets, filled once by the caller (gi/frame.cpp).
#include <array>

#include "core/grid.h"
#include "gi/pyramid.h"
#include "gi/shading.h"
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
};

}  // namespace terrain::gi
