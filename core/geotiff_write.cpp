// Float maps as GeoTIFF through GDAL, atomically: GDAL writes a temporary
// beside the target, the close is checked, the file synced, then renamed.
#include <cmath>
#include <cstdio>

#include <fcntl.h>
#include <gdal.h>
#include <unistd.h>

#include "core/error.h"
#include "core/file_io.h"
#include "core/gdal_session.h"
#include "core/geotiff_io.h"

namespace terrain {
namespace {

// Removes the temporary unless the write reached the rename.
struct TemporaryGuard {
    std::string path;
    bool keep = false;
    ~TemporaryGuard() {
        if (!keep) std::remove(path.c_str());
    }
};

// GDAL closes without fsync; a write-back failure would otherwise show only
// after the rename.
void syncFile(const std::string& path, const std::string& target) {
    const int fd = ::open(path.c_str(), O_RDONLY);
    if (fd < 0) throw IoError(target, "cannot reopen the written temporary to sync it");
    const bool ok = ::fsync(fd) == 0;
    ::close(fd);
    if (!ok) throw IoError(target, "cannot sync the written file to disk");
}

// The bands and their place, while the dataset is open; false on a failure
// (its message is in the error capture).
bool fillDataset(GDALDatasetH ds, std::span<const Grid> bands, std::span<const std::string> names,
                 const GeoReference& geo) {
    if (geo.georeferenced()) {
        std::array<double, 6> t = geo.transform;
        if (GDALSetGeoTransform(ds, t.data()) != CE_None || GDALSetProjection(ds, geo.crsWkt.c_str()) != CE_None)
            return false;
    }
    for (std::size_t b = 0; b < bands.size(); ++b) {
        const Grid& g = bands[b];
        GDALRasterBandH band = GDALGetRasterBand(ds, static_cast<int>(b) + 1);
        if (b < names.size()) GDALSetDescription(band, names[b].c_str());
        if (GDALRasterIO(band, GF_Write, 0, 0, g.nx, g.ny, const_cast<float*>(g.v.data()), g.nx, g.ny, GDT_Float32, 0,
                         0) != CE_None)
            return false;
    }
    return true;
}

}  // namespace

GeoReference GeoReference::withCellSize(double cell) const {
    GeoReference r = *this;
    r.transform[1] = std::copysign(cell, transform[1]);
    r.transform[5] = std::copysign(cell, transform[5]);
    return r;
}

void writeGeoTiff(const std::string& file, std::span<const Grid> bands, const GeoReference& geo,
                  std::span<const std::string> names) {
    if (bands.empty()) throw IoError(file, "no band to write");
    if (!names.empty() && names.size() != bands.size()) throw IoError(file, "one name per band, or none");
    const Grid& g = bands[0];
    for (const Grid& b : bands)
        if (b.nx != g.nx || b.ny != g.ny) throw IoError(file, "bands of different sizes");
    gdal::ErrorCapture errors;  // first: registering the drivers may report too
    gdal::ensureRegistered();
    GDALDriverH driver = GDALGetDriverByName("GTiff");
    if (!driver) throw IoError(file, "GDAL has no GeoTIFF driver");
    TemporaryGuard tmp{temporaryNameFor(file)};
    // DEFLATE with the floating-point predictor: lossless and compact for smooth fields
    const char* const options[] = {"COMPRESS=DEFLATE", "PREDICTOR=3", "TILED=YES", nullptr};
    GDALDatasetH ds = GDALCreate(driver, tmp.path.c_str(), g.nx, g.ny, static_cast<int>(bands.size()), GDT_Float32,
                                 const_cast<char**>(options));
    if (!ds) throw IoError(file, "cannot create: " + errors.message("GDAL failed"));
    const bool filled = fillDataset(ds, bands, names, geo);
    GDALClose(ds);  // the data reach the file here; a failure shows as an error message
    if (!filled || errors.failed()) throw IoError(file, "cannot write: " + errors.message("GDAL failed"));
    syncFile(tmp.path, file);
    commitTemporary(tmp.path, file);
    tmp.keep = true;
}

}  // namespace terrain
