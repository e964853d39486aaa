// Hostile inputs: every numeric scene value is checked against its declared
// range as it is read (naming the key and its table), integers before they
// are narrowed, non-finite numbers nowhere accepted; scene files that set
// nothing are errors; and the last guards turn a non-finite result into an
// error instead of an output.
#include <climits>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>

#include <doctest/doctest.h>
#include <unistd.h>

#include "core/error.h"
#include "core/finite.h"
#include "core/parse.h"
#include "core/setting_range.h"
#include "sim/generators.h"
#include "sim/scene.h"
#include "sim/scene_ranges.h"

using namespace terrain;
namespace fs = std::filesystem;

namespace {

fs::path scratch() {
    const fs::path p = fs::temp_directory_path() / ("terrain_input_ranges_" + std::to_string(::getpid()));
    fs::create_directories(p);
    return p;
}

std::string write(const std::string& name, const std::string& text) {
    const fs::path p = scratch() / name;
    std::ofstream(p) << text;
    return p.string();
}

// The message loadSceneFile gives for a file holding `text` ("" when it loads).
std::string sceneError(const std::string& text) {
    try {
        loadSceneFile(write("scene.toml", text));
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

// Loading `text` fails with a message containing `part`.
void expectSceneError(const std::string& text, const std::string& part) {
    const std::string e = sceneError(text);
    CHECK_MESSAGE(e.find(part) != std::string::npos, "scene: ", text, "\nerror: ", e, "\nexpected: ", part);
}

}  // namespace

TEST_CASE("input ranges: a declared range names the value, its bounds and what it got") {
    const SettingRange<float> r{"rain", 0.0f, 0.5f, "Rain, m/s"};
    CHECK_NOTHROW(checkRange(r, 0.25f));
    CHECK_THROWS_WITH_AS(checkRange(r, 2.0f), "rain must be in [0, 0.5] (got 2)", InputError);
    CHECK_THROWS_WITH_AS(checkRange(r, 2.0f, "--rain"), "--rain must be in [0, 0.5] (got 2)", InputError);
    CHECK_THROWS_AS(checkRange(r, std::nanf("")), InputError);
    CHECK_THROWS_AS(checkRange(r, std::numeric_limits<float>::infinity()), InputError);
    const SettingRange<int> z{"azimuths", 3, 8, "Azimuths", true};
    CHECK_NOTHROW(checkRange(z, 0));
    CHECK_THROWS_WITH_AS(checkRange(z, -5), "azimuths must be 0 or [3, 8] (got -5)", InputError);
    // a 64-bit value is checked before it is narrowed: 2^32 + 32 is not 32
    CHECK_THROWS_AS(checkRange(widened(scene_ranges::kSize), std::int64_t{4294967328}), InputError);
    CHECK(describe(z) == "Azimuths, 0 or [3, 8]");
}

TEST_CASE("input ranges: third-party messages are cut to one bounded line") {
    CHECK(boundedLine("a\nb\r\nc\td\x01") == "a b  c d?");
    const std::string huge(100000, 'x');
    CHECK(boundedLine(huge).size() == kMaxErrorDetail);
    CHECK(boundedLine(huge, 10) == "xxxxxxx...");
}

TEST_CASE("input ranges: number lists reject what is not a finite number") {
    CHECK(parseNumberList("1,0.5,2", "--key").size() == 3);
    CHECK_THROWS_WITH_AS(parseNumberList("1,nan", "--key"), doctest::Contains("'nan' is not finite"), InputError);
    CHECK_THROWS_WITH_AS(parseNumberList("inf", "--sun"), doctest::Contains("--sun"), InputError);
    CHECK_THROWS_AS(parseNumberList("1e39", "--key"), InputError);
}

TEST_CASE("input ranges: the last guard finds a NaN or an infinity and says where") {
    Grid g(4, 3, 1.0f);
    CHECK(allFinite(std::span<const float>(g.v.data(), g.v.size())));
    CHECK_NOTHROW(requireFinite(g, "the ambient map"));
    g(2, 1) = std::numeric_limits<float>::infinity();
    CHECK_FALSE(allFinite(std::span<const float>(g.v.data(), g.v.size())));
    CHECK_THROWS_WITH_AS(requireFinite(g, "the ambient map"),
                         "the ambient map has a non-finite value (inf) at x=2, y=1", InputError);
    g(2, 1) = std::nanf("");
    CHECK_THROWS_WITH_AS(requireFinite(g, "map"), doctest::Contains("(nan)"), InputError);
}

TEST_CASE("input ranges: scene values outside their physical range are errors naming the key") {
    expectSceneError("base = \"erosion\"\n[hydraulic]\nrain_rate = 1e30\n",
                     "'hydraulic.rain_rate' must be in [0, 0.01] (got 1e+30)");
    expectSceneError("base = \"erosion\"\n[hydraulic]\ngravity = -9.81\n", "'hydraulic.gravity' must be in [0.1, 100]");
    expectSceneError("base = \"waves\"\n[waves]\ndry_depth = -1.0\n", "'waves.dry_depth'");
    expectSceneError("base = \"waves\"\n[waves]\ngravity = 0.0\n", "'waves.gravity'");
    expectSceneError("base = \"erosion\"\nsoil_depth = -5.0\n", "'soil_depth' must be in [0,");
    expectSceneError("base = \"erosion\"\ncell_size = 1e-38\n", "'cell_size'");
    expectSceneError("base = \"erosion\"\ndt = -1.0\n", "'dt'");
    expectSceneError("base = \"erosion\"\ndt = nan\n", "'dt' must be a finite number");
    expectSceneError("base = \"erosion\"\ndt = inf\n", "'dt' must be a finite number");
    expectSceneError("base = \"erosion\"\n[thermal]\ntalus_deg = 90.0\n", "'thermal.talus_deg'");
    expectSceneError("[terrain]\namplitude = 1e30\n", "'terrain.amplitude'");
    expectSceneError("[terrain]\nwavelength = 0.0\n", "'terrain.wavelength'");
    expectSceneError("[terrain]\nkind = \"dem\"\nfile = \"x.png\"\nz_scale = 1e30\n", "'terrain.z_scale'");
    expectSceneError("base = \"waves\"\n[waves.swell]\nperiod = 0.0\n", "'waves.swell.period'");
    expectSceneError("base = \"waves\"\n[[waves.drops]]\nheight = 1e30\n", "'waves.drops.height'");
    expectSceneError("[[lights.key]]\nrgb = [1e38, 1.0, 1.0]\n", "'lights.key.rgb'");
    expectSceneError("[lights]\nintensity = 1e30\n", "'lights.intensity'");
    expectSceneError("[[camera.key]]\nyaw = 1e30\n", "yaw");
    // a value inside its range loads (the files of scenes/ load in test_scene.cpp)
    CHECK(sceneError("base = \"erosion\"\n[hydraulic]\nrain_rate = 2e-4\n").empty());
    fs::remove_all(scratch());
}

TEST_CASE("input ranges: scene integers are checked before they are narrowed") {
    expectSceneError("base = \"erosion\"\nsize = 4294967328\n", "'size' must be in [1, 16384] (got 4294967328)");
    expectSceneError("base = \"erosion\"\nsize = [16, 4294967328]\n", "'size'");
    expectSceneError("[terrain]\noctaves = 4294967297\n", "'terrain.octaves'");
    expectSceneError("base = \"erosion\"\nchange_tile = 2147483647\n", "'change_tile'");
    expectSceneError("[lights.sun]\nday = 4294967468\n", "'lights.sun.day'");
    expectSceneError("base = \"erosion\"\nseed = -3\n", "'seed'");
    // a seed past 32 bits is kept whole, not truncated to 1
    const SceneSettings s = loadSceneFile(write("seed.toml", "base = \"erosion\"\nseed = 4294967297\n"));
    CHECK(s.seed == 4294967297ull);
    // [gi] refresh is kept as read, for the GI's range check when it applies it
    const SceneSettings g = loadSceneFile(write("gi.toml", "base = \"erosion\"\n[gi]\nrefresh = 4294967297\n"));
    REQUIRE(g.gi.refreshEvery);
    CHECK(*g.gi.refreshEvery == 4294967297);
    fs::remove_all(scratch());
}

TEST_CASE("input ranges: a float where an integer belongs is read only when it is one") {
    // beyond 64 bits: an error, not an undefined conversion (fuzz regressions
    // float-seed-beyond-int64, float-refresh-beyond-int64 under UBSan)
    expectSceneError("base = \"erosion\"\nseed = 3.33333e83\n", "'seed' must be an integer");
    expectSceneError("base = \"erosion\"\n[gi]\nrefresh = -4e300\n", "'gi.refresh' must be an integer");
    expectSceneError("base = \"erosion\"\nsize = 9.3e18\n", "'size'");
    expectSceneError("base = \"erosion\"\nseed = 2.5\n", "'seed' must be an integer");
    expectSceneError("base = \"erosion\"\nseed = nan\n", "'seed' must be an integer");
    // an integral float is the integer it spells
    const SceneSettings s = loadSceneFile(write("float-size.toml", "base = \"erosion\"\nsize = 64.0\nseed = 7.0\n"));
    CHECK(s.nx == 64);
    CHECK(s.seed == 7u);
    fs::remove_all(scratch());
}

TEST_CASE("input ranges: a scene file that is empty, a folder, or a dem without its file is an error") {
    expectSceneError("", "sets nothing");
    expectSceneError("# only a comment\n", "sets nothing");
    expectSceneError("size = 16\n[terrain]\nkind = \"dem\"\n", "'terrain.file' is missing");
    const fs::path dir = scratch() / "folder.toml";
    fs::create_directories(dir);
    CHECK_THROWS_WITH_AS(loadSceneFile(dir.string()), doctest::Contains("is not a file"), IoError);
    CHECK_THROWS_WITH_AS(resolveScene(dir.string(), SceneOverrides{}), doctest::Contains("is not a file"), IoError);
    fs::remove_all(scratch());
}

TEST_CASE("input ranges: the change-tracking tile and the generators check their ranges") {
    SceneSettings s = builtinScene("erosion", 16, 1);
    s.changeTile = INT_MAX;  // nx + tile - 1 would overflow an int
    CHECK_THROWS_WITH_AS(Simulation{s}, doctest::Contains("change-tracking tile size"), InputError);
    s.changeTile = scene_ranges::kChangeTile.hi;
    const Simulation big(s);
    CHECK(big.changes().tilesX == 1);
    CHECK(big.changes().tilesY == 1);
    Grid g;
    NoiseSettings n;
    n.gain = 4.0f;
    CHECK_THROWS_WITH_AS(generateNoise(g, 8, 8, 1.0f, 1, n), doctest::Contains("noise gain"), InputError);
    ShapeSettings sh;
    sh.radius = 0.0f;
    CHECK_THROWS_WITH_AS(generateShape(g, 8, 8, 1.0f, sh), doctest::Contains("shape radius"), InputError);
    CHECK_THROWS_WITH_AS(checkDimensions(8, 8, 1e-38f), doctest::Contains("cell size"), InputError);
}

TEST_CASE("input ranges: lights and camera keys are bounded so that the light stays finite") {
    LightSet l = builtinLights("erosion");
    CHECK_NOTHROW(validateLights(l));
    l.keys[0].rgb = {1e38f, 1.0f, 1.0f};
    CHECK_THROWS_WITH_AS(validateLights(l), doctest::Contains("key light 1 rgb must be in [0, 1e+06]"), InputError);
    l = builtinLights("erosion");
    l.environment.intensity = 1e30f;
    CHECK_THROWS_WITH_AS(validateLights(l), doctest::Contains("environment intensity"), InputError);
    CameraPath p;
    p.keys.push_back(CameraKey{});
    p.keys[0].yawDeg = std::nanf("");
    CHECK_THROWS_WITH_AS(validateCameraPath(p), doctest::Contains("yaw"), InputError);
    p.keys[0].yawDeg = 0.0f;
    p.keys[0].target[0] = 1e30f;
    CHECK_THROWS_WITH_AS(validateCameraPath(p), doctest::Contains("target"), InputError);
}
