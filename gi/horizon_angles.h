#pragma once
// Horizon elevation angles per azimuth, as GIS tools report them: for each
// texel and azimuth, the elevation above the horizontal plane (degrees) of
// the highest terrain point along that azimuth, with its true sign: on a peak
// or a ridge every blocker may lie below the horizontal and the angle is
// negative. Neither the horizontal nor the texel's tangent plane is applied
// (the sky-view factors raise the angle to one or the other themselves:
// gi/sky_view.h, gi/ambient_horizon.h). A direction with no terrain point
// inside the domain at all (a border texel looking out) reports -90, the
// nadir: nothing bounds the view from below.
//
// The fast angles come from the environment scan's horizons
// (VisibilityField::maxSlope) along its azimuths; at sub-sampling each
// receiver's angle is interpolated bilinearly to the texels as the sky-view
// factor's horizons are (Fig. 7 of Nowrouzezahrai & Snyder 2009), the angle
// rather than its slope, and over the receivers that have terrain in the
// direction only: a border receiver looking out (-90) says nothing about the
// texels inside it, which have terrain before them. The exact
// angles come from the march of the bilinear field (referenceMaxSlope,
// gi/reference.h) along the same azimuths.
#include <vector>

#include "core/grid.h"
#include "gi/visibility.h"

namespace terrain::gi {

/// Horizon angles of a grid: one nx x ny plane per azimuth.
struct HorizonAngles {
    std::vector<double> azimuths;  // radians, from +x towards +y (the engine's axes)
    std::vector<Grid> degrees;     // per azimuth: elevation of the horizon (degrees, signed)
};

/// The environment scan's azimuths for m of them: 2 pi j / m, j = 0..m-1
/// (radians, from +x towards +y), as its folded wedge operator samples them.
std::vector<double> scanAzimuths(int m);

/// The angle (degrees) of a horizon slope; kNoBlocker (or below) gives -90.
double horizonDegrees(double slope);

/// The angles from the environment scan: `env` of the grid nx x ny at
/// `subsample`, `azimuths` its azimuths (radians, one per maxSlope plane).
/// InputError when the field is not of that grid or azimuth count.
void horizonAnglesFromScan(const VisibilityField& env, const std::vector<double>& azimuths, int subsample, int nx,
                           int ny, HorizonAngles& out);

/// At sub-sampling: raises each texel's angles to its own near field
/// (gi/near_field.h), which the receivers' scans, starting one receiver
/// spacing out, never sample. `heights` and `cellSize`: the field's.
void raiseHorizonAnglesToNearField(ConstGridView heights, float cellSize, int subsample, HorizonAngles& angles);

/// The exact angles of the bilinear field along `azimuths` (radians), at
/// every texel.
void referenceHorizonAngles(ConstGridView heights, float cellSize, const std::vector<double>& azimuths,
                            HorizonAngles& out);

/// The azimuth phi (radians, from +x towards +y) as a compass bearing:
/// degrees clockwise from north in [0, 360), for a map whose columns run
/// east when eastPerColumn > 0 (west otherwise) and whose rows run north when
/// northPerRow > 0 (south otherwise): the signs of a GeoTIFF's pixel width
/// and height. A north-up raster (row 0 the northern edge) has (+, -).
double compassAzimuthDegrees(double phi, double eastPerColumn, double northPerRow);

}  // namespace terrain::gi
