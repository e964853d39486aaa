// Fuzz target: GeoTIFF heightmaps (core/geotiff_io readGeoTiffHeights)
// through GDAL's TIFF driver, with the engine's checks around it.
#include <cmath>

#include "core/geotiff_io.h"
#include "fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    static terrain::fuzz::InputFile file(".tif");
    const std::string& path = file.write(data, size);
    terrain::fuzz::expectSuccessOrError([&] {
        const terrain::GeoTiffHeights t = terrain::readGeoTiffHeights(path);
        const terrain::Grid& g = t.heights;
        terrain::fuzz::require(g.nx > 0 && g.ny > 0 && g.v.size() == static_cast<std::size_t>(g.nx) * g.ny,
                               "the grid's size matches its samples");
        terrain::fuzz::require(t.cellSize > 0.0 && std::isfinite(t.cellSize), "the cell size is positive");
        terrain::fuzz::require(t.geo.georeferenced(), "a read GeoTIFF has a CRS");
        terrain::fuzz::require(t.nodataFilled >= 0 && t.nodataFilled < static_cast<std::int64_t>(g.v.size()),
                               "some cell was valid");
        for (float v : g.v) terrain::fuzz::require(std::isfinite(v), "heights are finite");
    });
    return 0;
}
