// A frame's layers in every frame format (sim/frame_layers.h): float32 EXR
// channels and GeoTIFF bands come back bit for bit under their names, the
// OpenVDB frame carries the new grids, and a float EXR reads as a heightmap.
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include <doctest/doctest.h>
#include <gdal.h>
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include "core/error.h"
#include "core/geotiff_io.h"
#include "core/image_io.h"
#include "sim/frame_layers.h"
#include "sim/heightmap_io.h"
#include "sim/scene.h"
#include "sim/vdb_io.h"
#include "tests/scratch_files.h"

using namespace terrain;

namespace {

bool sameBits(const Grid& a, const Grid& b) {
    return a.nx == b.nx && a.ny == b.ny && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

// A flowing erosion scene's frame, with values a half float could not keep.
FrameLayers erodedFrame() {
    Simulation sim(builtinScene("erosion", 48, 4));
    for (int t = 0; t < 40; ++t) sim.tick();
    FrameLayers f = frameLayers(sim);
    Grid& h = f.layers[0].grid;
    h(0, 0) = 1234.5678f;
    h(1, 0) = -std::numeric_limits<float>::denorm_min();
    h(2, 0) = std::numeric_limits<float>::max();
    return f;
}

std::string readErrorOf(const std::string& file) {
    try {
        readHeightmap(file, 1.0f, 0.0f);
    } catch (const IoError& e) {
        return e.what();
    }
    return "";
}

}  // namespace

TEST_CASE("frame layers: the list names every layer of an eroding scene, in the documented order") {
    const FrameLayers f = erodedFrame();
    CHECK(f.names() == std::vector<std::string>{"height", "bedrock", "soil", "water", "sediment", "discharge",
                                                "velocity", "sediment_flux", "erosion", "deposition", "net_erosion",
                                                "wetness"});
    for (const FrameLayer& l : f.layers) CHECK(!l.unit.empty());
}

TEST_CASE("frame layers: EXR channels round trip bit for bit, with the cell size") {
    const auto dir = test::scratchDir("frame_exr");
    const FrameLayers f = erodedFrame();
    const std::string file = (dir / "frame.exr").string();
    writeExrChannels(file, f.names(), f.grids(), f.cellSize);
    const ExrChannels back = readExrChannels(file);
    CHECK(back.cellSize == f.cellSize);
    REQUIRE(back.names.size() == f.layers.size());
    for (std::size_t k = 0; k < back.names.size(); ++k) {
        CAPTURE(back.names[k]);
        const FrameLayer* layer = f.find(back.names[k]);
        REQUIRE(layer != nullptr);
        CHECK(sameBits(back.grids[k], layer->grid));
    }
    // one channel alone, by name
    const ExrChannels one = readExrChannels(file, "discharge");
    REQUIRE(one.grids.size() == 1);
    CHECK(sameBits(one.grids[0], f.find("discharge")->grid));
    CHECK(one.available.size() == f.layers.size());
    CHECK_THROWS_AS(writeExrChannels(file, {"a", "a"}, {f.grids()[0], f.grids()[1]}), IoError);
    std::filesystem::remove_all(dir);
}

TEST_CASE("frame layers: GeoTIFF bands round trip bit for bit, named by their descriptions") {
    const auto dir = test::scratchDir("frame_tif");
    FrameLayers f = erodedFrame();
    std::vector<Grid> bands;
    for (const FrameLayer& l : f.layers) bands.push_back(l.grid);
    const std::string file = (dir / "frame.tif").string();
    writeGeoTiff(file, bands, GeoReference{}, f.names());
    GDALAllRegister();
    GDALDatasetH ds = GDALOpen(file.c_str(), GA_ReadOnly);
    REQUIRE(ds != nullptr);
    REQUIRE(GDALGetRasterCount(ds) == static_cast<int>(bands.size()));
    for (std::size_t b = 0; b < bands.size(); ++b) {
        GDALRasterBandH band = GDALGetRasterBand(ds, static_cast<int>(b) + 1);
        CHECK(std::string(GDALGetDescription(band)) == f.layers[b].name);
        CHECK(GDALGetRasterDataType(band) == GDT_Float32);
        Grid back(bands[b].nx, bands[b].ny);
        REQUIRE(GDALRasterIO(band, GF_Read, 0, 0, back.nx, back.ny, back.data(), back.nx, back.ny, GDT_Float32, 0, 0) ==
                CE_None);
        CHECK(sameBits(back, bands[b]));
    }
    GDALClose(ds);
    CHECK_THROWS_AS(writeGeoTiff(file, bands, GeoReference{}, std::vector<std::string>{"one"}), IoError);
    std::filesystem::remove_all(dir);
}

TEST_CASE("frame layers: an OpenVDB frame holds every layer as a grid, and still reads as a terrain") {
    const auto dir = test::scratchDir("frame_vdb");
    const FrameLayers f = erodedFrame();
    const std::string file = (dir / "frame.vdb").string();
    writeVdbLayers(file, f);
    openvdb::initialize();
    openvdb::io::File in(file);
    in.open();
    for (const FrameLayer& l : f.layers) {
        CAPTURE(l.name);
        auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(in.readGrid(l.name));
        REQUIRE(grid);
        auto acc = grid->getConstAccessor();
        bool same = true;
        for (int y = 0; y < l.grid.ny; ++y)
            for (int x = 0; x < l.grid.nx; ++x) {
                const float v = acc.getValue(openvdb::Coord(x, y, 0));
                same = same && std::memcmp(&v, &l.grid.v[static_cast<std::size_t>(y) * l.grid.nx + x], sizeof v) == 0;
            }
        CHECK(same);
    }
    in.close();
    TerrainState s;
    readVdb(file, s, LayerSet{.water = true});
    CHECK(sameBits(s.bedrock, f.find("bedrock")->grid));
    CHECK(sameBits(s.water, f.find("water")->grid));
    std::filesystem::remove_all(dir);
}

TEST_CASE("frame layers: a float EXR is a heightmap: its height channel, or its only channel") {
    const auto dir = test::scratchDir("exr_heightmap");
    Grid h(5, 4), other(5, 4, 7.0f);
    for (std::size_t i = 0; i < h.size(); ++i) h.v[i] = 100.0f + 0.125f * static_cast<float>(i);
    const std::string frame = (dir / "frame.exr").string();
    writeExrChannels(frame, {"water", "height", "bedrock"}, {&other, &h, &other}, 12.5f);
    float cell = 0.0f;
    CHECK(sameBits(readHeightmap(frame, 1.0f, 0.0f, &cell), h));
    CHECK(cell == 12.5f);
    const std::string single = (dir / "y.exr").string();
    writeExrChannels(single, {"Y"}, {&h});
    cell = 0.0f;
    CHECK(sameBits(readHeightmap(single, 1.0f, 0.0f, &cell), h));
    CHECK(cell == 0.0f);  // no attribute: the cell size is given as for a PNG
    const std::string infinite = (dir / "inf.exr").string();
    writeExrChannels(infinite, {"height"}, {&h}, std::numeric_limits<float>::infinity());
    cell = 0.0f;
    CHECK(sameBits(readHeightmap(infinite, 1.0f, 0.0f, &cell), h));
    CHECK(cell == 0.0f);  // an infinite cell size counts as none
    const std::string two = (dir / "two.exr").string();
    writeExrChannels(two, {"R", "G"}, {&h, &other});
    CHECK(readErrorOf(two).find("no 'height' channel and more than one other (G, R)") != std::string::npos);
    std::filesystem::remove_all(dir);
}

TEST_CASE("frame layers: a truncated or damaged EXR heightmap gets one line naming the file") {
    const auto dir = test::scratchDir("exr_bad");
    Grid h(64, 64);
    for (std::size_t i = 0; i < h.size(); ++i) h.v[i] = std::sin(0.01f * static_cast<float>(i));
    const std::string good = (dir / "good.exr").string();
    writeExrChannels(good, {"height"}, {&h});
    const std::string bytes = test::readBytes(good);
    const std::string cut = (dir / "cut.exr").string();
    test::writeBytes(cut, bytes.substr(0, bytes.size() * 2 / 3));
    const std::string cutError = readErrorOf(cut);
    CHECK(cutError.find("cut.exr") != std::string::npos);
    CHECK(cutError.find("EXR") != std::string::npos);
    CHECK(cutError.find('\n') == std::string::npos);
    const std::string empty = (dir / "empty.exr").string();
    test::writeBytes(empty, "");
    CHECK(readErrorOf(empty).find("empty.exr") != std::string::npos);
    std::filesystem::remove_all(dir);
}

TEST_CASE("frame layers: an EXR declaring more pixels than its bytes can hold is refused before they are allocated") {
    const auto dir = test::scratchDir("exr_declared");
    Grid h(8, 8, 1.0f);
    const std::string small = (dir / "small.exr").string();
    writeExrChannels(small, {"height"}, {&h});
    std::string bytes = test::readBytes(small);
    // the data window's corners follow the attribute's name, type and size
    const std::string attribute("dataWindow\0box2i\0", 17);
    const std::size_t at = bytes.find(attribute);
    REQUIRE(at != std::string::npos);
    const std::int32_t corners[4] = {0, 0, 16383, 16383};
    bytes.replace(at + attribute.size() + 4, sizeof corners, reinterpret_cast<const char*>(corners), sizeof corners);
    bytes.append(9000, '\0');  // room for the offset table the header check asks of 16384 rows
    const std::string big = (dir / "big.exr").string();
    test::writeBytes(big, bytes);
    const std::string error = readErrorOf(big);
    CHECK(error.find("big.exr: 1 EXR channels of 16384 x 16384 pixels in") != std::string::npos);
    CHECK(error.find("more than the file can hold") != std::string::npos);
    std::filesystem::remove_all(dir);
}
