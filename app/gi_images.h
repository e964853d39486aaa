#pragma once
// The images `terrain gi` writes: the shade map (.png sRGB after an
// exposure, or .exr / .tif linear), the ambient map (.npy, .exr or .tif) and
// the indirect light alone (.npy, .exr, .tif, or .png in false colour). A
// .tif is a float32 GeoTIFF carrying `geo` (the input's place and CRS when
// the heightmap was a GeoTIFF), so it overlays the input in a GIS.
#include <array>
#include <string>

#include "core/geotiff_io.h"
#include "core/grid.h"
#include "gi/horizon_angles.h"

namespace terrain::app {

/// Lower-case extension with its dot ("" when none).
std::string extensionOf(const std::string& file);

/// RGB shade: .exr and .tif (three bands) as is; .png times `exposure`,
/// clamped, sRGB-encoded.
void writeShade(const std::string& file, const std::array<Grid, 3>& rgb, float exposure, const GeoReference& geo);

/// The ambient map: .npy, .exr or .tif (one band).
void writeAmbient(const std::string& file, const Grid& ambient, const GeoReference& geo);

/// The indirect light: .npy (rows, columns, 3), .exr or .tif (three bands)
/// as is; .png as a
/// false-colour map of its luminance from 0 (black) to its 99th percentile
/// (white), through blue, magenta, orange and yellow, so that small
/// differences of a dim light show.
void writeIndirect(const std::string& file, const std::array<Grid, 3>& rgb, const GeoReference& geo);

/// The horizon angles (degrees), one plane per azimuth in ascending compass
/// bearing (clockwise from north; north from `geo`'s axes when it is
/// georeferenced, else row 0's side, as for a north-up raster): .npy float32
/// (azimuths, rows, columns); .exr one float32 channel per azimuth named
/// azDDD_FFF (the bearing's degrees and thousandths: no '.', which EXR
/// readers take for a layer separator, and names that sort by bearing); .tif
/// one band per azimuth described by its bearing in degrees.
void writeHorizons(const std::string& file, const gi::HorizonAngles& horizons, const GeoReference& geo);

/// Every map of a frame as float32 channels of one EXR (core/image_io.h):
/// `height` (m), `ambient`, `shade.R`, `shade.G`, `shade.B` and, when
/// computed, `indirect.R`, `indirect.G`, `indirect.B` (linear): an RGB map is
/// a layer of R, G, B channels, as OpenImageIO and Houdini name layers. The
/// cell size goes into the `terrain:cellSize` attribute.
void writeGiExr(const std::string& file, const Grid& heights, float cellSize, const std::array<Grid, 3>& shade,
                const Grid& ambient, const std::array<Grid, 3>* indirect);

}  // namespace terrain::app
