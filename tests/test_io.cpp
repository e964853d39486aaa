#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>

#include <doctest/doctest.h>
#include <unistd.h>

#include "core/error.h"
#include "core/png_io.h"
#include "sim/generators.h"
#include "sim/heightmap_io.h"
#include "sim/terrain.h"
#include "sim/vdb_io.h"
#include "tests/scratch_files.h"

using namespace terrain;
namespace fs = std::filesystem;
using terrain::test::readBytes;
using terrain::test::scratchDir;
using terrain::test::writeBytes;

namespace {}  // namespace

TEST_CASE("sim.io: 16-bit PNG round trip is exact to the 16-bit step") {
    const fs::path dir = scratchDir("io");
    Grid h;
    generateNoise(h, 67, 45, 10.0f, 3, NoiseSettings{});
    float scale = 0.0f, offset = 0.0f;
    pngRangeFor(h, scale, offset);
    const std::string file = (dir / "h.png").string();
    writePngHeightmap(file, h, scale, offset);
    const Grid back = readPngHeightmap(file, scale, offset);
    REQUIRE(back.nx == 67);
    REQUIRE(back.ny == 45);
    double worst = 0.0;
    for (std::size_t i = 0; i < h.size(); ++i) worst = std::max(worst, std::fabs(double(back.v[i]) - h.v[i]));
    CHECK(worst <= 0.5 * scale * (1.0 + 1e-4) + 1e-3f * std::fabs(offset) * 1e-3);
    // and exact on the quantised values: a second trip changes nothing
    writePngHeightmap(file, back, scale, offset);
    const Grid again = readPngHeightmap(file, scale, offset);
    CHECK(again.v == back.v);
    // orientation: row 0 of the image is y = 0
    Grid ramp(3, 2);
    ramp(2, 0) = 65535.0f;
    writePngHeightmap(file, ramp, 1.0f, 0.0f);
    const Grid r = readPngHeightmap(file, 1.0f, 0.0f);
    CHECK(r(2, 0) == 65535.0f);
    CHECK(r(2, 1) == 0.0f);
    fs::remove_all(dir);
}

TEST_CASE("sim.io: the real DEM loads with its height mapping") {
    const std::string file = std::string(TERRAIN_SOURCE_DIR) + "/../shared/data/alps-montblanc.png";
    if (!fs::exists(file)) {
        MESSAGE("shared/data not present; skipped");
        return;
    }
    const Grid g = readPngHeightmap(file, (4810.0f - 454.0f) / 65535.0f, 454.0f);
    CHECK(g.nx == 647);
    CHECK(g.ny == 647);
    const auto [lo, hi] = std::minmax_element(g.v.begin(), g.v.end());
    CHECK(*lo >= 453.9f);
    CHECK(*hi <= 4810.1f);
    CHECK(*hi > 4500.0f);  // Mont Blanc is 4808 m
}

TEST_CASE("sim.io: corrupt, truncated and wrong-typed PNGs are rejected with the file name") {
    const fs::path dir = scratchDir("io");
    Grid h(20, 10, 5.0f);
    const std::string good = (dir / "good.png").string();
    writePngHeightmap(good, h, 1.0f, 0.0f);
    const std::string bytes = readBytes(good);
    const fs::path truncated = dir / "truncated.png";
    writeBytes(truncated, bytes.substr(0, bytes.size() / 2));
    CHECK_THROWS_WITH_AS(readPngHeightmap(truncated.string()), doctest::Contains("truncated.png"), IoError);
    std::string corrupt = bytes;
    for (std::size_t i = 40; i < corrupt.size() - 20; i += 7) corrupt[i] = static_cast<char>(corrupt[i] ^ 0x5a);
    writeBytes(dir / "corrupt.png", corrupt);
    CHECK_THROWS_AS(readPngHeightmap((dir / "corrupt.png").string()), IoError);
    writeBytes(dir / "text.png", "this is not a png at all");
    CHECK_THROWS_WITH_AS(readPngHeightmap((dir / "text.png").string()), doctest::Contains("not a PNG"), IoError);
    CHECK_THROWS_WITH_AS(readPngHeightmap((dir / "missing.png").string()), doctest::Contains("missing.png"), IoError);
    std::vector<std::uint8_t> rgb(4 * 3 * 3, 100);
    writePngRgb((dir / "colour.png").string(), 4, 3, rgb);
    CHECK_THROWS_WITH_AS(readPngHeightmap((dir / "colour.png").string()), doctest::Contains("greyscale"), IoError);
    fs::remove_all(dir);
}

TEST_CASE("sim.io: VDB round trip is bit-exact for every layer") {
    const fs::path dir = scratchDir("io");
    TerrainState s;
    s.allocate(37, 23, 2.5f, LayerSet{.water = true, .sediment = true});
    Grid h;
    generateNoise(h, 37, 23, 2.5f, 11, NoiseSettings{});
    s.bedrock.v = h.v;
    for (std::size_t i = 0; i < s.soil.size(); ++i) {
        s.soil.v[i] = 0.001f * static_cast<float>(i % 13);
        s.water.v[i] = (i % 5 == 0) ? 0.0f : 1.0f / static_cast<float>(i + 1);
        s.suspended.v[i] = 1e-7f * static_cast<float>(i);
    }
    s.bedrock(3, 4) = -1234.5678f;  // negative heights
    s.bedrock(0, 0) = 0.0f;         // equals the background value
    const std::string file = (dir / "frame.vdb").string();
    writeVdb(file, s);
    TerrainState r;
    readVdb(file, r, LayerSet{.water = true, .sediment = true});
    CHECK(r.nx == 37);
    CHECK(r.ny == 23);
    CHECK(r.cellSize == 2.5f);
    CHECK(std::memcmp(r.bedrock.data(), s.bedrock.data(), s.bedrock.size() * 4) == 0);
    CHECK(std::memcmp(r.soil.data(), s.soil.data(), s.soil.size() * 4) == 0);
    CHECK(std::memcmp(r.water.data(), s.water.data(), s.water.size() * 4) == 0);
    CHECK(std::memcmp(r.suspended.data(), s.suspended.data(), s.suspended.size() * 4) == 0);
    // and through the generic heightmap reader: bedrock + soil
    float cell = 0.0f;
    const Grid g = readHeightmap(file, 1.0f, 0.0f, &cell);
    CHECK(cell == 2.5f);
    CHECK(g(5, 6) == s.bedrock(5, 6) + s.soil(5, 6));
    fs::remove_all(dir);
}

TEST_CASE("sim.io: corrupt or truncated VDB files and NaN heights are rejected") {
    const fs::path dir = scratchDir("io");
    TerrainState s;
    s.allocate(16, 16, 1.0f, {});
    s.bedrock(4, 4) = 7.0f;
    const std::string good = (dir / "good.vdb").string();
    writeVdb(good, s);
    const std::string bytes = readBytes(good);
    writeBytes(dir / "truncated.vdb", bytes.substr(0, bytes.size() / 2));
    TerrainState r;
    CHECK_THROWS_WITH_AS(readVdb((dir / "truncated.vdb").string(), r, {}), doctest::Contains("truncated.vdb"), IoError);
    writeBytes(dir / "garbage.vdb", std::string(300, 'x'));
    CHECK_THROWS_AS(readVdb((dir / "garbage.vdb").string(), r, {}), IoError);
    CHECK_THROWS_AS(readVdb((dir / "missing.vdb").string(), r, {}), IoError);
    s.bedrock(2, 3) = std::numeric_limits<float>::quiet_NaN();
    writeVdb((dir / "nan.vdb").string(), s);
    CHECK_THROWS_WITH_AS(readVdb((dir / "nan.vdb").string(), r, {}), doctest::Contains("non-finite"), IoError);
    s.bedrock(2, 3) = std::numeric_limits<float>::infinity();
    writeVdb((dir / "inf.vdb").string(), s);
    CHECK_THROWS_AS(readVdb((dir / "inf.vdb").string(), r, {}), IoError);
    fs::remove_all(dir);
}

TEST_CASE("sim.io: a failed write leaves the previous file in place") {
    const fs::path dir = scratchDir("io");
    Grid h(8, 8, 3.0f);
    const std::string file = (dir / "keep.png").string();
    writePngHeightmap(file, h, 1.0f, 0.0f);
    const std::string before = readBytes(file);
    Grid bad(8, 8, std::numeric_limits<float>::quiet_NaN());
    CHECK_THROWS_AS(writePngHeightmap(file, bad, 1.0f, 0.0f), InputError);
    CHECK(readBytes(file) == before);
    // no temporary files left behind
    int files = 0;
    for (auto& e : fs::directory_iterator(dir)) files += e.is_regular_file() ? 1 : 0;
    CHECK(files == 1);
    CHECK_THROWS_AS(writePngHeightmap((dir / "no/such/dir/x.png").string(), h, 1.0f, 0.0f), IoError);
    fs::remove_all(dir);
}
