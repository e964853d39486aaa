// The engine's OpenVDB reader against OpenVDB itself: files OpenVDB writes
// in the engine's layout (any compression, inactive values, tiles, other
// transforms) read back exactly as OpenVDB reads them, and grids that are
// not a height field are rejected with one line.
#include <climits>
#include <cstring>
#include <filesystem>
#include <string>

#include <doctest/doctest.h>
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <unistd.h>

#include "core/error.h"
#include "sim/terrain.h"
#include "sim/vdb_io.h"
#include "tests/scratch_files.h"

using namespace terrain;
namespace fs = std::filesystem;
using openvdb::Coord;

namespace {

// A scratch folder, with OpenVDB's grid types registered for the test's own writes.
fs::path vdbScratchDir(const char* tag) {
    openvdb::initialize();
    return terrain::test::scratchDir(std::string("vdb_layout_") + tag);
}

void writeGrids(const fs::path& file, const openvdb::GridPtrVec& grids, std::uint32_t compression) {
    openvdb::io::File out(file.string());
    out.setCompression(compression);
    out.write(grids);
}

// What OpenVDB's reader gives at (x, y, 0) of a float grid.
Grid openvdbLayer(const fs::path& file, const std::string& name, int nx, int ny) {
    openvdb::io::File in(file.string());
    in.open(false);
    const auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(in.readGrid(name));
    in.close();
    Grid out(nx, ny);
    const auto acc = grid->getConstAccessor();
    for (int y = 0; y < ny; ++y)
        for (int x = 0; x < nx; ++x) out(x, y) = acc.getValue(Coord(x, y, 0));
    return out;
}

openvdb::math::Transform::Ptr cellTransform(bool translated) {
    auto t = openvdb::math::Transform::createLinearTransform(2.5);
    if (translated) t->postTranslate(openvdb::Vec3d(10.0, -4.0, 0.0));
    return t;
}

// Every cell of nx x ny active at z = 0: signs, -0 and denormals included.
openvdb::FloatGrid::Ptr denseLayer(const std::string& name, int nx, int ny, float scale) {
    auto g = openvdb::FloatGrid::create(0.0f);
    g->setName(name);
    auto acc = g->getAccessor();
    for (int y = 0; y < ny; ++y)
        for (int x = 0; x < nx; ++x) {
            const int i = y * nx + x;
            const float v =
                i % 11 == 0 ? -0.0f : (i % 13 == 0 ? 1e-40f : scale * static_cast<float>((i * 37) % 101 - 50));
            acc.setValueOn(Coord(x, y, 0), v);
        }
    return g;
}

// Some cells active, some inactive with other values, an inactive 128³
// tile, a background of its own, and values off the z = 0 layer.
openvdb::FloatGrid::Ptr sparseLayer(const std::string& name, int ny) {
    auto g = openvdb::FloatGrid::create(0.25f);
    g->setName(name);
    g->tree().fill(openvdb::CoordBBox(Coord(128, 0, 0), Coord(255, 127, 127)), -2.0f, false);
    auto acc = g->getAccessor();
    for (int y = 0; y < ny; ++y)
        for (int x = 0; x < 128; ++x) {
            if ((x + y) % 3 != 0) acc.setValueOn(Coord(x, y, 0), 0.01f * static_cast<float>(x - y));
            if (x % 5 == 0) acc.setValueOff(Coord(x, y, 0), y % 2 ? 7.0f : -0.25f);
        }
    acc.setValueOff(Coord(3, 3, -5), 9.0f);
    acc.setValueOff(Coord(-3, 2, 0), 4.0f);
    return g;
}

std::string readError(const fs::path& file) {
    TerrainState s;
    try {
        readVdb(file.string(), s, LayerSet{.water = true});
    } catch (const IoError& e) {
        return e.what();
    }
    return "no error";
}

}  // namespace

TEST_CASE("io.vdb: files OpenVDB writes in the engine's layout read back bit-identically") {
    const fs::path dir = vdbScratchDir("same");
    const int nx = 200, ny = 150;
    using namespace openvdb::io;
    const std::uint32_t compressions[] = {COMPRESS_NONE,
                                          COMPRESS_ZIP,
                                          COMPRESS_BLOSC,
                                          COMPRESS_ACTIVE_MASK,
                                          COMPRESS_ZIP | COMPRESS_ACTIVE_MASK,
                                          COMPRESS_BLOSC | COMPRESS_ACTIVE_MASK};
    for (int variant = 0; variant < 6; ++variant) {
        CAPTURE(variant);
        auto bedrock = denseLayer("bedrock", nx, ny, 1.5f), soil = denseLayer("soil", nx, ny, 0.001f);
        auto water = sparseLayer("water", ny);
        for (auto& g : {bedrock, soil, water}) g->setTransform(cellTransform(variant % 2 == 1));
        if (variant % 3 == 0) bedrock->insertMeta("terrain_nx", openvdb::Int32Metadata(nx));
        if (variant % 3 == 0) bedrock->insertMeta("terrain_ny", openvdb::Int32Metadata(ny));
        const fs::path file = dir / ("v" + std::to_string(variant) + ".vdb");
        writeGrids(file, {bedrock, soil, water}, compressions[variant]);
        TerrainState s;
        readVdb(file.string(), s, LayerSet{.water = true});
        REQUIRE((s.nx == nx && s.ny == ny));
        CHECK(s.cellSize == 2.5f);
        const Grid expectBedrock = openvdbLayer(file, "bedrock", nx, ny),
                   expectSoil = openvdbLayer(file, "soil", nx, ny);
        const Grid expectWater = openvdbLayer(file, "water", nx, ny);
        CHECK(std::memcmp(s.bedrock.data(), expectBedrock.data(), s.bedrock.size() * 4) == 0);
        CHECK(std::memcmp(s.soil.data(), expectSoil.data(), s.soil.size() * 4) == 0);
        CHECK(std::memcmp(s.water.data(), expectWater.data(), s.water.size() * 4) == 0);
        CHECK(s.water(150, 10) == -2.0f);   // the tile
        CHECK(s.water(150, 140) == 0.25f);  // the background
    }
    fs::remove_all(dir);
}

TEST_CASE("io.vdb: grids that are not a height field are rejected with one line") {
    const fs::path dir = vdbScratchDir("other");
    const fs::path file = dir / "f.vdb";
    auto check = [&](openvdb::GridBase::Ptr grid, const std::string& expected) {
        CAPTURE(expected);
        writeGrids(file, {grid}, openvdb::io::COMPRESS_BLOSC);
        const std::string error = readError(file);
        CHECK(error.find(expected) != std::string::npos);
        CHECK(error.size() <= file.string().size() + 2 + kMaxErrorDetail);
    };
    auto height = [] { return denseLayer("height", 8, 8, 1.0f); };
    auto g = height();
    g->tree().setValueOn(Coord(1, 1, 1), 3.0f);
    check(g, "active voxels off z = 0");
    g = height();
    g->tree().fill(openvdb::CoordBBox(Coord(8, 0, 0), Coord(15, 7, 7)), 1.0f, true);
    check(g, "active tile");
    g = height();
    g->setSaveFloatAsHalf(true);
    check(g, "16-bit floats");
    auto ints = openvdb::Int32Grid::create(0);
    ints->setName("height");
    ints->tree().setValueOn(Coord(0, 0, 0), 1);
    check(ints, "is a Tree_int32_5_4_3 grid, not a float grid");
    g = height();
    g->tree().setValueOff(Coord(3, 4, 0));
    check(g, "has 63 active voxels in its 8 x 8 box");
    g = openvdb::FloatGrid::create(0.0f);
    g->setName("height");
    g->tree().setValueOn(Coord(1, 1, 0), 1.0f);
    check(g, "does not start at voxel (0, 0)");
    g = height();
    g->tree().setValueOn(Coord(INT_MAX, 0, 0), 1.0f);
    check(g, "declares 2147483648 x 8 cells");
    g = height();
    g->insertMeta("terrain_nx", openvdb::Int32Metadata(16384));
    g->insertMeta("terrain_ny", openvdb::Int32Metadata(16384));
    check(g, "declares 16384 x 16384 cells but its active voxels span 8 x 8");
    g = height();
    g->setTransform(openvdb::math::Transform::createLinearTransform(
        openvdb::math::rotation<openvdb::Mat4d>(openvdb::math::Z_AXIS, 0.3)));
    check(g, "transform");
    g = height();
    g->setGridClass(openvdb::GRID_LEVEL_SET);
    check(g, "class 'level set'");
    fs::remove_all(dir);
}
