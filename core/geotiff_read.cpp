// GeoTIFF heights through GDAL: band 1 in metres, the cell size and place
// from the geotransform, a projected CRS in metres required, nodata filled.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <limits>
#include <memory>
#include <vector>

#include <cpl_conv.h>
#include <gdal.h>
#include <ogr_srs_api.h>

#include "core/error.h"
#include "core/gdal_session.h"
#include "core/geotiff_io.h"
#include "core/nodata_fill.h"
#include "core/size_limits.h"

namespace terrain {
namespace {

// The largest strip or tile the reader lets GDAL allocate (all bands of a
// pixel-interleaved file together).
constexpr std::int64_t kMaxBlockBytes = std::int64_t{256} << 20;

struct DatasetCloser {
    void operator()(void* ds) const { GDALClose(static_cast<GDALDatasetH>(ds)); }
};
using Dataset = std::unique_ptr<void, DatasetCloser>;

// Only the TIFF driver, and no side-car files: the file alone is read.
Dataset openTiff(const std::string& file, const gdal::ErrorCapture& errors) {
    gdal::ensureRegistered();
    const char* const drivers[] = {"GTiff", nullptr};
    const char* const noSiblings[] = {nullptr};
    GDALDatasetH ds = GDALOpenEx(file.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, drivers, nullptr, noSiblings);
    if (!ds) throw IoError(file, "not a readable GeoTIFF: " + errors.message("GDAL cannot open it"));
    return Dataset(ds);
}

// Square, unrotated pixels: the engine's grid has one cell size.
double cellSizeOf(const std::string& file, const std::array<double, 6>& t) {
    for (double v : t)
        if (!std::isfinite(v)) throw IoError(file, "the geotransform holds a non-finite value");
    if (t[2] != 0.0 || t[4] != 0.0)
        throw IoError(file, "the geotransform is rotated; the engine needs a north-up grid (gdalwarp it first)");
    const double w = std::abs(t[1]), h = std::abs(t[5]);
    if (!(w > 0.0) || !(h > 0.0)) throw IoError(file, "the geotransform gives a pixel of zero size");
    if (std::abs(w - h) > 1e-6 * std::max(w, h))
        throw IoError(file, "pixels of " + std::to_string(w) + " x " + std::to_string(h) +
                                " m are not square; resample to square cells (gdalwarp -tr <size> <size>)");
    return w;
}

// A projected CRS whose linear unit is the metre; returns it as WKT.
std::string metricCrsWkt(const std::string& file, GDALDatasetH ds) {
    OGRSpatialReferenceH srs = GDALGetSpatialRef(ds);
    const std::string reproject = "; reproject it to a projected CRS in metres (gdalwarp -t_srs EPSG:<UTM zone>)";
    if (!srs)
        throw IoError(file, "has no coordinate reference system" + reproject + " or assign one (gdal_edit -a_srs)");
    if (OSRIsGeographic(srs)) throw IoError(file, "has a geographic CRS in degrees" + reproject);
    if (!OSRIsProjected(srs)) throw IoError(file, "has a CRS that is not projected" + reproject);
    char* unitName = nullptr;
    const double toMetres = OSRGetLinearUnits(srs, &unitName);
    if (toMetres != 1.0)
        throw IoError(file, "has a projected CRS in " + std::string(unitName ? unitName : "unknown units") +
                                ", not metres" + reproject);
    char* wkt = nullptr;
    if (OSRExportToWkt(srs, &wkt) != OGRERR_NONE || !wkt) {
        CPLFree(wkt);
        throw IoError(file, "its CRS cannot be written as WKT");
    }
    std::string text(wkt);
    CPLFree(wkt);
    return text;
}

// Whether a sample is the band's nodata value (compared in the band's own
// precision, as GDAL stores a float32 nodata as text).
struct NodataTest {
    bool has = false;
    double value = 0.0;
    bool asFloat = false;
    bool matches(double v) const {
        if (!has) return false;
        if (std::isnan(value)) return std::isnan(v);
        return asFloat ? static_cast<float>(v) == static_cast<float>(value) : v == value;
    }
};

// Band 1's samples row by row into g, masking the nodata cells.
void readBand(const std::string& file, GDALRasterBandH band, const NodataTest& nodata, Grid& g,
              std::vector<std::uint8_t>& masked, const gdal::ErrorCapture& errors) {
    std::vector<double> row(static_cast<std::size_t>(g.nx));
    for (int y = 0; y < g.ny; ++y) {
        if (GDALRasterIO(band, GF_Read, 0, y, g.nx, 1, row.data(), g.nx, 1, GDT_Float64, 0, 0) != CE_None)
            throw IoError(file, "cannot read row " + std::to_string(y) + ": " + errors.message("GDAL failed"));
        for (int x = 0; x < g.nx; ++x) {
            const std::size_t i = static_cast<std::size_t>(y) * g.nx + x;
            if (nodata.matches(row[x])) {
                masked[i] = 1;
                continue;
            }
            const float h = static_cast<float>(row[x]);
            if (!std::isfinite(row[x]) || !std::isfinite(h))
                throw IoError(file, "cell (" + std::to_string(x) + ", " + std::to_string(y) +
                                        ") has a non-finite height (not the band's nodata value)");
            g.v[i] = h;
        }
    }
}

// GDAL reads a whole block (a strip or a tile) at once, whatever its declared
// size: a small file can declare one tile of gigabytes. Legitimate files use
// tiles of 256 or 512 pixels or strips of a few rows.
void checkBlockSize(const std::string& file, GDALDatasetH ds, GDALRasterBandH band, GDALDataType type) {
    int bx = 0, by = 0;
    GDALGetBlockSize(band, &bx, &by);
    const std::int64_t bytes = static_cast<std::int64_t>(bx) * by * GDALGetDataTypeSizeBytes(type) *
                               std::max(1, GDALGetRasterCount(ds));  // pixel-interleaved bands share a block
    if (bx < 1 || by < 1 || bytes > kMaxBlockBytes)
        throw IoError(file, "declares blocks of " + std::to_string(bx) + " x " + std::to_string(by) +
                                " pixels; the engine reads blocks of up to " + std::to_string(kMaxBlockBytes >> 20) +
                                " MiB (rewrite it tiled: gdal_translate -co TILED=YES)");
}

}  // namespace

bool isGeoTiffPath(const std::string& file) {
    std::string ext = std::filesystem::path(file).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    return ext == ".tif" || ext == ".tiff";
}

GeoTiffHeights readGeoTiffHeights(const std::string& file) {
    gdal::ErrorCapture errors;
    Dataset ds = openTiff(file, errors);
    GDALDatasetH h = ds.get();
    checkDeclaredSize(file, GDALGetRasterXSize(h), GDALGetRasterYSize(h), "pixels");
    if (GDALGetRasterCount(h) < 1) throw IoError(file, "has no raster band");
    GDALRasterBandH band = GDALGetRasterBand(h, 1);
    const GDALDataType type = GDALGetRasterDataType(band);
    if (type == GDT_Unknown || GDALDataTypeIsComplex(type))
        throw IoError(file, "band 1 is not of a real number type (int16, uint16, int32, float32, float64...)");
    checkBlockSize(file, h, band, type);
    GeoTiffHeights out;
    if (GDALGetGeoTransform(h, out.geo.transform.data()) != CE_None)
        throw IoError(file, "has no geotransform: the cell size is unknown (use a PNG with --cell-size instead)");
    out.cellSize = cellSizeOf(file, out.geo.transform);
    out.geo.crsWkt = metricCrsWkt(file, h);
    NodataTest nodata;
    int hasNodata = 0;
    nodata.value = GDALGetRasterNoDataValue(band, &hasNodata);
    nodata.has = hasNodata != 0;
    nodata.asFloat = type == GDT_Float32;
    out.heights.resize(GDALGetRasterXSize(h), GDALGetRasterYSize(h));
    std::vector<std::uint8_t> masked(out.heights.v.size(), 0);
    readBand(file, band, nodata, out.heights, masked, errors);
    if (std::find(masked.begin(), masked.end(), 1) == masked.end()) return out;
    try {
        out.nodataFilled = fillNodata(out.heights, masked);
    } catch (const InputError&) {
        throw IoError(file, "every cell is nodata: there are no heights");
    }
    return out;
}

}  // namespace terrain
