#pragma once
// GeoTIFF heightmaps and maps through GDAL: one band of heights in metres
// read with its georeferencing, float maps written with it, so an output
// overlays its input in a GIS.
#include <array>
#include <cstdint>
#include <span>
#include <string>

#include "core/grid.h"

namespace terrain {

/// Where a grid lies on the Earth: GDAL's affine geotransform (origin x,
/// pixel width, row rotation, origin y, column rotation, pixel height) and
/// the coordinate reference system as WKT. Empty WKT: not georeferenced.
struct GeoReference {
    std::array<double, 6> transform{0.0, 1.0, 0.0, 0.0, 0.0, 1.0};
    std::string crsWkt;

    bool georeferenced() const { return !crsWkt.empty(); }
    /// The same origin and axis directions with square pixels of `cell`
    /// metres: a grid resampled over the same place, or given another cell
    /// size by the user.
    GeoReference withCellSize(double cell) const;
};

/// A GeoTIFF's heights and what the reader found.
struct GeoTiffHeights {
    Grid heights;         // band 1, metres, row 0 first in the file
    double cellSize = 0;  // metres, from the geotransform
    GeoReference geo;
    std::int64_t nodataFilled = 0;  // cells that held the nodata value
};

/// Whether `file` names a GeoTIFF by its extension (.tif or .tiff, any case).
bool isGeoTiffPath(const std::string& file);

/// Reads band 1 of a GeoTIFF as heights in metres. IoError (one bounded
/// line naming the file) when the file is not a readable TIFF, declares a
/// side over kMaxGridSide (checked before any pixel is read), has no
/// projected CRS in metres, a rotated geotransform or non-square pixels, a
/// complex band, only nodata cells or a NaN or infinite height outside the
/// nodata value. Nodata cells take the height of the nearest valid cell
/// (core/nodata_fill.h).
GeoTiffHeights readGeoTiffHeights(const std::string& file);

/// Writes each grid as a float32 band (one for a height or ambient map,
/// three for an RGB map, in order), DEFLATE-compressed, to `file`
/// atomically (a temporary beside it, renamed after a checked close and a
/// sync): with `geo`'s transform and CRS when it is georeferenced, and each
/// band's description set to its name when names are given (one per band).
/// The bands must share one size. IoError on any failure, the target left
/// as it was.
void writeGeoTiff(const std::string& file, std::span<const Grid> bands, const GeoReference& geo,
                  std::span<const std::string> names = {});

}  // namespace terrain
