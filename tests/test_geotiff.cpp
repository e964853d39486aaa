// GeoTIFF heightmaps through GDAL: values and georeferencing kept on a round
// trip, the cell size from the geotransform (the same light as a PNG given
// that cell size), nodata filled from the nearest valid cell, and every bad
// file (wrong CRS, rotated or non-square pixels, too large, corrupt,
// truncated) one bounded error line, never a crash.
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include <cpl_conv.h>
#include <doctest/doctest.h>
#include <gdal.h>
#include <ogr_srs_api.h>

#include "core/error.h"
#include "core/geotiff_io.h"
#include "core/nodata_fill.h"
#include "core/png_io.h"
#include "gi/frame.h"
#include "sim/heightmap_io.h"
#include "sim/scene.h"
#include "tests/scratch_files.h"

using namespace terrain;

namespace {

// UTM zone 32 north (metres), geographic WGS 84 (degrees), and a State
// Plane zone in US survey feet.
constexpr int kUtm32N = 32632;
constexpr int kWgs84 = 4326;
constexpr int kFeetStatePlane = 2227;

std::string wktOf(int epsg) {
    OGRSpatialReferenceH srs = OSRNewSpatialReference(nullptr);
    REQUIRE(OSRImportFromEPSG(srs, epsg) == OGRERR_NONE);
    char* wkt = nullptr;
    OSRExportToWkt(srs, &wkt);
    std::string text(wkt);
    CPLFree(wkt);
    OSRDestroySpatialReference(srs);
    return text;
}

// What a hand-made test file holds: its pixel type, georeferencing, nodata
// and layout, all written with GDAL's own writer (not the engine's).
struct TiffSpec {
    GDALDataType type = GDT_Float32;
    std::array<double, 6> transform{500000.0, 30.0, 0.0, 5000000.0, 0.0, -30.0};
    int epsg = kUtm32N;  // 0: no CRS
    bool hasTransform = true;
    bool hasNodata = false;
    double nodata = 0.0;
    std::vector<const char*> options;  // creation options (TILED, COMPRESS...)
};

void makeTiff(const std::string& path, int nx, int ny, const std::vector<double>& values, const TiffSpec& spec) {
    GDALAllRegister();
    std::vector<const char*> options = spec.options;
    options.push_back(nullptr);
    GDALDatasetH ds = GDALCreate(GDALGetDriverByName("GTiff"), path.c_str(), nx, ny, 1, spec.type,
                                 const_cast<char**>(options.data()));
    REQUIRE(ds != nullptr);
    if (spec.hasTransform) {
        std::array<double, 6> t = spec.transform;
        REQUIRE(GDALSetGeoTransform(ds, t.data()) == CE_None);
    }
    if (spec.epsg != 0) REQUIRE(GDALSetProjection(ds, wktOf(spec.epsg).c_str()) == CE_None);
    GDALRasterBandH band = GDALGetRasterBand(ds, 1);
    if (spec.hasNodata) REQUIRE(GDALSetRasterNoDataValue(band, spec.nodata) == CE_None);
    REQUIRE(GDALRasterIO(band, GF_Write, 0, 0, nx, ny, const_cast<double*>(values.data()), nx, ny, GDT_Float64, 0, 0) ==
            CE_None);
    GDALClose(ds);
}

// A smooth field with a ridge, heights in metres, x + y * nx ordering.
std::vector<double> ridge(int nx, int ny) {
    std::vector<double> v(static_cast<std::size_t>(nx) * ny);
    for (int y = 0; y < ny; ++y)
        for (int x = 0; x < nx; ++x)
            v[static_cast<std::size_t>(y) * nx + x] =
                1200.0 + 300.0 * std::sin(0.3 * x) * std::cos(0.2 * y) + 7.0 * x - 3.0 * y;
    return v;
}

std::string errorOf(const std::string& file) {
    try {
        readHeightmap(file, 1.0f, 0.0f);
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

bool sameBits(const Grid& a, const Grid& b) {
    return a.nx == b.nx && a.ny == b.ny && std::memcmp(a.v.data(), b.v.data(), a.v.size() * sizeof(float)) == 0;
}

// The GeoTIFF at `tif` reads as the same heights and cell size as the PNG's
// field, and a GI frame lights both bit for bit alike.
void requireLitAlike(const std::string& tif, const Grid& fromPng, double cell) {
    float tifCell = 0.0f;
    const Grid fromTif = readHeightmap(tif, 1.0f, 0.0f, &tifCell);
    REQUIRE(sameBits(fromTif, fromPng));
    REQUIRE(tifCell == static_cast<float>(cell));
    gi::GiState a, b;
    gi::runGiFrame(fromPng.cview(), static_cast<float>(cell), gi::GiLighting{}, gi::GiSettings{}, a);
    gi::runGiFrame(fromTif.cview(), tifCell, gi::GiLighting{}, gi::GiSettings{}, b);
    CHECK(sameBits(a.shade.ambient, b.shade.ambient));
}

}  // namespace

TEST_CASE("geotiff: every integer and float type reads as its heights, cell size and place") {
    const auto dir = test::scratchDir("geotiff_types");
    const int nx = 23, ny = 17;
    std::vector<double> v(static_cast<std::size_t>(nx) * ny);
    for (std::size_t i = 0; i < v.size(); ++i) v[i] = static_cast<double>((i * 37) % 1000) - 200.0;
    for (GDALDataType type : {GDT_Int16, GDT_UInt16, GDT_Int32, GDT_Float32, GDT_Float64}) {
        CAPTURE(GDALGetDataTypeName(type));
        std::vector<double> typed = v;
        if (type == GDT_UInt16)
            for (double& x : typed) x = std::abs(x);
        TiffSpec spec;
        spec.type = type;
        const std::string path = (dir / (std::string(GDALGetDataTypeName(type)) + ".tif")).string();
        makeTiff(path, nx, ny, typed, spec);
        float cell = 0.0f;
        GeoReference geo;
        const Grid g = readHeightmap(path, 1.0f, 0.0f, &cell, &geo);
        REQUIRE(g.nx == nx);
        REQUIRE(g.ny == ny);
        CHECK(cell == 30.0f);
        CHECK(geo.transform == spec.transform);
        CHECK(geo.georeferenced());
        for (std::size_t i = 0; i < typed.size(); ++i) REQUIRE(g.v[i] == static_cast<float>(typed[i]));
    }
    std::filesystem::remove_all(dir);
}

TEST_CASE("geotiff: tiled and compressed layouts read the same heights") {
    const auto dir = test::scratchDir("geotiff_layouts");
    const int nx = 70, ny = 45;
    const std::vector<double> v = ridge(nx, ny);
    TiffSpec plain;
    makeTiff((dir / "plain.tif").string(), nx, ny, v, plain);
    const Grid reference = readHeightmap((dir / "plain.tif").string(), 1.0f, 0.0f);
    const std::vector<std::vector<const char*>> layouts = {
        {"TILED=YES", "BLOCKXSIZE=16", "BLOCKYSIZE=16"},
        {"COMPRESS=LZW", "PREDICTOR=2"},
        {"COMPRESS=DEFLATE", "PREDICTOR=3", "TILED=YES", "BLOCKXSIZE=32", "BLOCKYSIZE=32"},
        {"COMPRESS=PACKBITS", "ENDIANNESS=BIG"},
        {"BIGTIFF=YES", "COMPRESS=ZSTD"},
    };
    for (std::size_t k = 0; k < layouts.size(); ++k) {
        CAPTURE(k);
        TiffSpec spec;
        spec.options = layouts[k];
        const std::string path = (dir / ("layout" + std::to_string(k) + ".tif")).string();
        makeTiff(path, nx, ny, v, spec);
        CHECK(sameBits(readHeightmap(path, 1.0f, 0.0f), reference));
    }
    std::filesystem::remove_all(dir);
}

TEST_CASE("geotiff: a written map reads back bit-exactly with its geotransform and CRS") {
    const auto dir = test::scratchDir("geotiff_round_trip");
    const int nx = 31, ny = 19;
    TiffSpec spec;
    spec.transform = {612345.5, 12.5, 0.0, 5087654.25, 0.0, -12.5};
    makeTiff((dir / "in.tif").string(), nx, ny, ridge(nx, ny), spec);
    GeoReference geo;
    Grid g = readHeightmap((dir / "in.tif").string(), 1.0f, 0.0f, nullptr, &geo);
    // values no decimal text could round-trip: the smallest subnormal, the largest float
    g.v[0] = std::numeric_limits<float>::denorm_min();
    g.v[1] = std::numeric_limits<float>::max();
    g.v[2] = -0.0f;
    const std::string out = (dir / "out.tiff").string();
    writeGeoTiff(out, std::span<const Grid>(&g, 1), geo);
    const GeoTiffHeights back = readGeoTiffHeights(out);
    CHECK(sameBits(back.heights, g));
    CHECK(back.geo.transform == geo.transform);
    CHECK(back.cellSize == 12.5);
    CHECK(back.geo.crsWkt == geo.crsWkt);
    // and the same bytes on a second write: no time stamp or other varying field
    const std::string again = (dir / "again.tiff").string();
    writeGeoTiff(again, std::span<const Grid>(&g, 1), geo);
    CHECK(test::readBytes(out) == test::readBytes(again));
    std::filesystem::remove_all(dir);
}

TEST_CASE("geotiff: three bands keep their order and values") {
    const auto dir = test::scratchDir("geotiff_rgb");
    std::array<Grid, 3> rgb;
    for (int c = 0; c < 3; ++c) {
        rgb[c].resize(9, 5);
        for (std::size_t i = 0; i < rgb[c].v.size(); ++i) rgb[c].v[i] = 0.1f * static_cast<float>(i) + c;
    }
    const std::string out = (dir / "rgb.tif").string();
    writeGeoTiff(out, rgb, GeoReference{});
    GDALAllRegister();
    GDALDatasetH ds = GDALOpen(out.c_str(), GA_ReadOnly);
    REQUIRE(ds != nullptr);
    REQUIRE(GDALGetRasterCount(ds) == 3);
    for (int c = 0; c < 3; ++c) {
        std::vector<float> band(rgb[c].v.size());
        REQUIRE(GDALRasterIO(GDALGetRasterBand(ds, c + 1), GF_Read, 0, 0, 9, 5, band.data(), 9, 5, GDT_Float32, 0, 0) ==
                CE_None);
        CHECK(std::memcmp(band.data(), rgb[c].v.data(), band.size() * sizeof(float)) == 0);
    }
    GDALClose(ds);
    std::filesystem::remove_all(dir);
}

TEST_CASE("geotiff: a failed write leaves the previous file as it was") {
    const auto dir = test::scratchDir("geotiff_failed_write");
    const std::string out = (dir / "map.tif").string();
    Grid g(8, 8, 1.0f);
    writeGeoTiff(out, std::span<const Grid>(&g, 1), GeoReference{});
    const std::string before = test::readBytes(out);
    std::array<Grid, 2> mismatched{Grid(8, 8, 2.0f), Grid(4, 4, 2.0f)};
    CHECK_THROWS_AS(writeGeoTiff(out, mismatched, GeoReference{}), IoError);
    GeoReference badCrs;
    badCrs.crsWkt = "not a CRS";
    CHECK_THROWS_AS(writeGeoTiff(out, std::span<const Grid>(&g, 1), badCrs), IoError);
    CHECK(test::readBytes(out) == before);
    std::size_t files = 0;
    for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir)) ++files;
    CHECK(files == 1);  // no temporary left behind
    std::filesystem::remove_all(dir);
}

TEST_CASE("geotiff: the same heights light the same as the PNG given the GeoTIFF's cell size") {
    const auto dir = test::scratchDir("geotiff_vs_png");
    const int nx = 48, ny = 40;
    const double cell = 25.0;
    Grid field(nx, ny);
    const std::vector<double> r = ridge(nx, ny);
    for (std::size_t i = 0; i < r.size(); ++i) field.v[i] = static_cast<float>(r[i]);
    const std::string png = (dir / "dem.png").string();
    writePngHeightmap(png, field, 0.05f, 800.0f);
    const Grid fromPng = readHeightmap(png, 0.05f, 800.0f);
    // the PNG's quantised heights, stored as a float32 GeoTIFF of that cell size
    std::vector<double> heights(fromPng.v.begin(), fromPng.v.end());
    TiffSpec spec;
    spec.transform = {300000.0, cell, 0.0, 5100000.0, 0.0, -cell};
    const std::string tif = (dir / "dem.tif").string();
    makeTiff(tif, nx, ny, heights, spec);
    requireLitAlike(tif, fromPng, cell);
    std::filesystem::remove_all(dir);
}

TEST_CASE("geotiff: the Mont Blanc DEM as a GeoTIFF lights the same as its PNG (when the data are here)") {
    const SceneSettings dem = builtinScene("dem", 64, 1);
    const std::string png = dem.terrain.demFile;
    if (!std::filesystem::exists(png)) {
        MESSAGE("skipped: the Mont Blanc DEM is not here (" << png << "; set TERRAIN_DATA)");
        return;
    }
    const Grid fromPng = readHeightmap(png, dem.terrain.demZScale, dem.terrain.demZOffset);
    const double cell = dem.terrain.demCellSize;
    GeoReference geo;
    geo.transform = {330000.0, cell, 0.0, 5090000.0, 0.0, -cell};
    geo.crsWkt = wktOf(kUtm32N);
    const auto dir = test::scratchDir("geotiff_montblanc");
    const std::string tif = (dir / "montblanc.tif").string();
    writeGeoTiff(tif, std::span<const Grid>(&fromPng, 1), geo);
    requireLitAlike(tif, fromPng, cell);
    std::filesystem::remove_all(dir);
}

TEST_CASE("geotiff: a scene's DEM takes the file's cell size, and its frames its place") {
    const auto dir = test::scratchDir("geotiff_scene");
    TiffSpec spec;
    makeTiff((dir / "dem.tif").string(), 20, 16, ridge(20, 16), spec);
    test::writeBytes(dir / "own.toml", "base = \"dem\"\n[terrain]\nfile = \"dem.tif\"\nresample = false\n");
    const Simulation own(loadSceneFile((dir / "own.toml").string()));
    CHECK(own.state().nx == 20);
    CHECK(own.state().cellSize == 30.0f);
    CHECK(own.geoReference().transform == spec.transform);
    CHECK(own.geoReference().crsWkt == wktOf(kUtm32N));
    // cell_size in the table overrides the file's; the place keeps its origin
    test::writeBytes(dir / "set.toml",
                     "base = \"dem\"\n[terrain]\nfile = \"dem.tif\"\nresample = false\ncell_size = 10.0\n");
    const Simulation set(loadSceneFile((dir / "set.toml").string()));
    CHECK(set.state().cellSize == 10.0f);
    const std::array<double, 6> expected{500000.0, 10.0, 0.0, 5000000.0, 0.0, -10.0};
    CHECK(set.geoReference().transform == expected);
    // a generated terrain has no place
    CHECK_FALSE(Simulation(builtinScene("erosion", 16, 1)).geoReference().georeferenced());
    std::filesystem::remove_all(dir);
}

TEST_CASE("geotiff: nodata cells take the nearest valid height and are counted") {
    const auto dir = test::scratchDir("geotiff_nodata");
    const int nx = 6, ny = 4;
    std::vector<double> v(static_cast<std::size_t>(nx) * ny);
    for (std::size_t i = 0; i < v.size(); ++i) v[i] = 100.0 + static_cast<double>(i);
    // a hole of three cells in row 1, and the far corner
    v[7] = v[8] = v[9] = -9999.0;
    v[23] = -9999.0;
    TiffSpec spec;
    spec.type = GDT_Int16;
    spec.hasNodata = true;
    spec.nodata = -9999.0;
    const std::string path = (dir / "holes.tif").string();
    makeTiff(path, nx, ny, v, spec);
    const GeoTiffHeights t = readGeoTiffHeights(path);
    CHECK(t.nodataFilled == 4);
    // every hole is one step from several valid cells; the tie goes to the
    // one first in row order: the cell above for row 1, for (5,3) too
    CHECK(t.heights.v[7] == 101.0f);
    CHECK(t.heights.v[8] == 102.0f);
    CHECK(t.heights.v[9] == 103.0f);
    CHECK(t.heights.v[23] == 117.0f);
    for (std::size_t i = 0; i < v.size(); ++i)
        if (v[i] != -9999.0) CHECK(t.heights.v[i] == static_cast<float>(v[i]));
    std::filesystem::remove_all(dir);
}

TEST_CASE("geotiff: a float32 NaN nodata is filled; a NaN that is not nodata is an error") {
    const auto dir = test::scratchDir("geotiff_nan");
    const double nan = std::numeric_limits<double>::quiet_NaN();
    std::vector<double> v = ridge(5, 5);
    v[12] = nan;
    TiffSpec spec;
    spec.hasNodata = true;
    spec.nodata = nan;
    makeTiff((dir / "nan_nodata.tif").string(), 5, 5, v, spec);
    const GeoTiffHeights t = readGeoTiffHeights((dir / "nan_nodata.tif").string());
    CHECK(t.nodataFilled == 1);
    CHECK(std::isfinite(t.heights.v[12]));
    makeTiff((dir / "nan.tif").string(), 5, 5, v, TiffSpec{});
    CHECK(errorOf((dir / "nan.tif").string()).find("cell (2, 2) has a non-finite height") != std::string::npos);
    std::vector<double> all(25, -32768.0);
    TiffSpec holes;
    holes.type = GDT_Int16;
    holes.hasNodata = true;
    holes.nodata = -32768.0;
    makeTiff((dir / "all.tif").string(), 5, 5, all, holes);
    CHECK(errorOf((dir / "all.tif").string()).find("every cell is nodata") != std::string::npos);
    std::filesystem::remove_all(dir);
}

TEST_CASE("fillNodata: nearest in steps, the same on every run, an error with nothing to fill from") {
    Grid g(5, 1);
    g.v = {1.0f, 0.0f, 0.0f, 0.0f, 5.0f};
    CHECK(fillNodata(g, {0, 1, 1, 1, 0}) == 3);
    CHECK(g.v[1] == 1.0f);
    CHECK(g.v[2] == 1.0f);  // a tie: the source queued first (row order) wins
    CHECK(g.v[3] == 5.0f);
    Grid none(2, 2);
    CHECK_THROWS_AS(fillNodata(none, {1, 1, 1, 1}), InputError);
}

TEST_CASE("geotiff: a CRS that is not projected in metres gets one line saying what to do") {
    const auto dir = test::scratchDir("geotiff_crs");
    const std::vector<double> v = ridge(8, 8);
    TiffSpec geographic;
    geographic.epsg = kWgs84;
    geographic.transform = {6.8, 0.0003, 0.0, 45.9, 0.0, -0.0003};
    makeTiff((dir / "wgs84.tif").string(), 8, 8, v, geographic);
    const std::string e = errorOf((dir / "wgs84.tif").string());
    CHECK(e.find("wgs84.tif") != std::string::npos);
    CHECK(e.find("geographic CRS in degrees") != std::string::npos);
    CHECK(e.find("gdalwarp") != std::string::npos);
    TiffSpec feet;
    feet.epsg = kFeetStatePlane;
    makeTiff((dir / "feet.tif").string(), 8, 8, v, feet);
    CHECK(errorOf((dir / "feet.tif").string()).find("not metres") != std::string::npos);
    TiffSpec noCrs;
    noCrs.epsg = 0;
    makeTiff((dir / "nocrs.tif").string(), 8, 8, v, noCrs);
    CHECK(errorOf((dir / "nocrs.tif").string()).find("no coordinate reference system") != std::string::npos);
    std::filesystem::remove_all(dir);
}

TEST_CASE("geotiff: rotated or non-square pixels are refused") {
    const auto dir = test::scratchDir("geotiff_transform");
    const std::vector<double> v = ridge(8, 8);
    TiffSpec rotated;
    rotated.transform = {500000.0, 30.0, 2.0, 5000000.0, 2.0, -30.0};
    makeTiff((dir / "rotated.tif").string(), 8, 8, v, rotated);
    CHECK(errorOf((dir / "rotated.tif").string()).find("rotated") != std::string::npos);
    TiffSpec oblong;
    oblong.transform = {500000.0, 30.0, 0.0, 5000000.0, 0.0, -20.0};
    makeTiff((dir / "oblong.tif").string(), 8, 8, v, oblong);
    CHECK(errorOf((dir / "oblong.tif").string()).find("not square") != std::string::npos);
    std::filesystem::remove_all(dir);
}

TEST_CASE("geotiff: a declared size over the limit is refused before any pixel is read") {
    const auto dir = test::scratchDir("geotiff_huge");
    GDALAllRegister();
    const std::string path = (dir / "huge.tif").string();
    // sparse: GDAL writes no strip, so the file is tiny whatever it declares
    const char* options[] = {"SPARSE_OK=TRUE", "COMPRESS=DEFLATE", "TILED=YES", nullptr};
    GDALDatasetH ds =
        GDALCreate(GDALGetDriverByName("GTiff"), path.c_str(), 20000, 16, 1, GDT_Float32, const_cast<char**>(options));
    REQUIRE(ds != nullptr);
    std::array<double, 6> t{0, 1, 0, 0, 0, -1};
    GDALSetGeoTransform(ds, t.data());
    GDALSetProjection(ds, wktOf(kUtm32N).c_str());
    GDALClose(ds);
    CHECK(std::filesystem::file_size(path) < 100000);
    const std::string e = errorOf(path);
    CHECK(e.find("20000") != std::string::npos);
    CHECK(e.find("16384") != std::string::npos);
    std::filesystem::remove_all(dir);
}

TEST_CASE("geotiff: a block (tile or strip) of gigabytes is refused before GDAL allocates it") {
    const auto dir = test::scratchDir("geotiff_big_block");
    TiffSpec spec;
    spec.type = GDT_Float64;
    spec.options = {"TILED=YES", "BLOCKXSIZE=8192", "BLOCKYSIZE=8192", "SPARSE_OK=TRUE", "COMPRESS=DEFLATE"};
    const std::string path = (dir / "big_block.tif").string();
    makeTiff(path, 32, 32, ridge(32, 32), spec);
    const std::string e = errorOf(path);
    CHECK(e.find("blocks of 8192 x 8192 pixels") != std::string::npos);
    // the same pixels in tiles of 256: read
    spec.options = {"TILED=YES", "BLOCKXSIZE=256", "BLOCKYSIZE=256"};
    makeTiff((dir / "small_block.tif").string(), 32, 32, ridge(32, 32), spec);
    CHECK(errorOf((dir / "small_block.tif").string()).empty());
    std::filesystem::remove_all(dir);
}

TEST_CASE("geotiff: truncated and corrupted files give one bounded line or a successful read") {
    const auto dir = test::scratchDir("geotiff_corrupt");
    TiffSpec spec;
    spec.options = {"COMPRESS=DEFLATE", "TILED=YES", "BLOCKXSIZE=16", "BLOCKYSIZE=16"};
    const std::string valid = (dir / "valid.tif").string();
    makeTiff(valid, 40, 24, ridge(40, 24), spec);
    const std::string bytes = test::readBytes(valid);
    const std::string probe = (dir / "probe.tif").string();
    int errors = 0, reads = 0;
    auto attempt = [&](const std::string& content) {
        test::writeBytes(probe, content);
        try {
            const Grid g = readHeightmap(probe, 1.0f, 0.0f);
            for (float h : g.v) REQUIRE(std::isfinite(h));
            ++reads;
        } catch (const Error& e) {
            const std::string m = e.what();
            REQUIRE(m.find('\n') == std::string::npos);
            REQUIRE(m.size() < 512);
            REQUIRE(m.rfind(probe, 0) == 0);
            ++errors;
        }
    };
    for (std::size_t cut = 0; cut < bytes.size(); cut += 1 + cut / 8) attempt(bytes.substr(0, cut));
    std::uint32_t state = 12345;
    for (int k = 0; k < 300; ++k) {
        std::string flipped = bytes;
        for (int f = 0; f < 1 + k % 4; ++f) {
            state = state * 1664525u + 1013904223u;
            flipped[state % flipped.size()] ^= static_cast<char>(1 + (state >> 24) % 255);
        }
        attempt(flipped);
    }
    CHECK(errors > 0);
    CHECK(reads > 0);
    std::filesystem::remove_all(dir);
}
