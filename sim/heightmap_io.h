#pragma once
// Heightmaps by file extension: greyscale PNG (core/png_io.h), GeoTIFF
// (core/geotiff_io.h), float EXR (core/image_io.h) or OpenVDB (sim/vdb_io.h).
#include <string>

#include "core/geotiff_io.h"
#include "core/grid.h"

namespace terrain {

/// Fewest cells per side of a heightmap: slopes, normals and flow all need a
/// neighbour on each axis, so a 1-cell-wide field has no terrain to shade or
/// erode.
inline constexpr int kMinHeightmapSide = 2;

/// Reads a heightmap by extension: .png (with zScale/zOffset), .tif/.tiff
/// (heights in metres as stored, zScale and zOffset unused), .exr (metres as
/// stored: the channel `height`, else the file's only channel; its cell size
/// from a `terrain:cellSize` attribute when it has one, otherwise given as
/// for a PNG) or .vdb; for .tif and .vdb the cell size is taken from the
/// file when cellSizeOut is given,
/// and a GeoTIFF's georeferencing is returned through geoOut (left
/// unreferenced for the other formats). IoError when it
/// is smaller than kMinHeightmapSide per side or a height is NaN or Inf
/// (naming the first such cell). An 8-bit or lower-depth greyscale PNG is
/// read, with a one-line warning on stderr that it has only 256 levels; a
/// GeoTIFF with nodata cells with one saying how many were filled.
Grid readHeightmap(const std::string& file, float zScale, float zOffset, float* cellSizeOut = nullptr,
                   GeoReference* geoOut = nullptr);

}  // namespace terrain
