// Scene lights: the sun stands where astronomy puts it and reddens as it
// sets, the analytic sky's SH mixes exactly, an image environment projects
// like gi/'s, scene files and bad values, and a moving sun re-lights the
// frames while static lights leave a static scene alone.
#include <cmath>
#include <filesystem>
#include <fstream>

#include <doctest/doctest.h>

#include "core/error.h"
#include "core/image_io.h"
#include "engine/light_rig.h"
#include "engine/pipeline.h"
#include "sim/scene.h"
#include "tests/scratch_files.h"

using namespace terrain;
using namespace terrain::engine;

namespace {

double angleBetween(double a, double b) { return std::fabs(std::remainder(a - b, 360.0)); }

}  // namespace

TEST_CASE("lights: the sun's position follows latitude, day and hour") {
    SunSpec s;
    s.latitudeDeg = 45.8f;
    s.dayOfYear = 172;  // June solstice: declination +23.44
    SunPosition noon = sunPosition(s, 12.0);
    CHECK(noon.elevationDeg == doctest::Approx(90.0 - 45.8 + 23.44).epsilon(2e-3));
    CHECK(angleBetween(noon.azimuthDeg, 90.0) < 0.01);  // due south: +y with north at -y
    // symmetric about noon, the morning sun in the east (grid +x side)
    const SunPosition morning = sunPosition(s, 9.0), afternoon = sunPosition(s, 15.0);
    CHECK(morning.elevationDeg == doctest::Approx(afternoon.elevationDeg).epsilon(1e-5));
    CHECK(std::cos(morning.azimuthDeg * 0.017453292519943295) > 0.3);
    CHECK(std::cos(afternoon.azimuthDeg * 0.017453292519943295) < -0.3);
    // at the equator near an equinox, sunrise at 6 h in the east
    s.latitudeDeg = 0.0f;
    s.dayOfYear = 80;
    const SunPosition rise = sunPosition(s, 6.0);
    CHECK(std::fabs(rise.elevationDeg) < 0.5);
    CHECK(angleBetween(rise.azimuthDeg, 0.0) < 1.0);
    // turning the grid turns the sun with it
    s.northAzimuthDeg = 0.0f;
    CHECK(angleBetween(sunPosition(s, 6.0).azimuthDeg, 90.0) < 1.0);
}

TEST_CASE("lights: sunlight dims and reddens towards the horizon") {
    const auto high = sunTransmittance(60.0f), low = sunTransmittance(5.0f);
    for (std::size_t c = 0; c < 3; ++c) {
        CHECK(high[c] > low[c]);
        CHECK(high[c] < 1.0f);
    }
    CHECK(high[0] > high[2]);                           // blue scatters most
    CHECK(low[0] / low[2] > 2.0f * high[0] / high[2]);  // and more so along a long path
    const auto below = sunTransmittance(-10.0f);
    CHECK(below[0] + below[1] + below[2] == 0.0f);
}

TEST_CASE("lights: the analytic sky mixes its SH basis exactly as gi/ projects it") {
    LightSet set;
    set.environment.kind = EnvironmentSpec::Kind::SunSky;
    set.environment.zenith = {0.2f, 0.3f, 0.6f};
    set.environment.horizon = {0.5f, 0.55f, 0.6f};
    set.environment.ground = {0.1f, 0.08f, 0.05f};
    const SceneLights l = LightRig(set).at(0);
    gi::SunSkySettings g;
    for (int c = 0; c < 3; ++c) {
        g.zenith[c] = set.environment.zenith[static_cast<std::size_t>(c)];
        g.horizon[c] = set.environment.horizon[static_cast<std::size_t>(c)];
        g.ground[c] = set.environment.ground[static_cast<std::size_t>(c)];
        g.sun[c] = 0.0f;
    }
    const gi::ShRgb want = gi::sunSkyLight(g);
    for (std::size_t c = 0; c < 3; ++c)
        for (std::size_t i = 0; i < want.c[c].size(); ++i)
            CHECK(std::fabs(l.sky.c[c][i] - want.c[c][i]) <= 1e-6 * (1.0 + std::fabs(want.c[c][i])));
    CHECK(l.skyKind == SkyKind::Gradient);
    CHECK(l.keys.empty());
}

TEST_CASE("lights: the sun is the first key light, moves each frame and sets") {
    LightSet set = builtinLights("erosion");
    set.sun.enabled = true;
    set.sun.hour = 16.0f;
    set.sun.hoursPerFrame = 1.0f;
    const LightRig rig(set);
    const SceneLights at16 = rig.at(0), at18 = rig.at(2), at23 = rig.at(7);
    REQUIRE(at16.keys.size() == 2);
    CHECK(at16.keys[1].azimuthDeg == set.keys[0].azimuthDeg);  // the fixed key follows the sun
    CHECK(at18.keys[0].elevationDeg < at16.keys[0].elevationDeg);
    CHECK(at18.keys[0].rgb[2] / at18.keys[0].rgb[0] < at16.keys[0].rgb[2] / at16.keys[0].rgb[0]);
    // the horizon reddens as the sun sets
    LightSet sky = set;
    sky.environment.kind = EnvironmentSpec::Kind::SunSky;
    const LightRig skyRig(sky);
    const SceneLights noon = skyRig.at(-4), dusk = skyRig.at(3);  // 12 h and 19 h
    CHECK(dusk.horizon[0] / dusk.horizon[2] > 1.5f * noon.horizon[0] / noon.horizon[2]);
    CHECK(noon.horizon[2] == doctest::Approx(sky.environment.horizon[2] * sunState(sky.sun, -4).daylight));
    // at night: no sun, a faint sky
    REQUIRE(at23.keys.size() == 1);
    CHECK(at23.sky.c[0][0] < 0.05 * at16.sky.c[0][0]);
}

TEST_CASE("lights: an image environment projects as gi/ does, scaled by its intensity") {
    const std::filesystem::path dir = terrain::test::scratchDir("lights");
    Grid r(32, 16), g(32, 16), b(32, 16);
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 32; ++x) {
            r(x, y) = y < 8 ? 1.0f : 0.25f;  // a bright upper hemisphere
            g(x, y) = 0.5f;
            b(x, y) = 0.25f;
        }
    const std::string file = (dir / "sky.exr").string();
    writeExr(file, {&r, &g, &b});
    LightSet set;
    set.environment.kind = EnvironmentSpec::Kind::Image;
    set.environment.file = file;
    set.environment.intensity = 2.0f;
    const SceneLights l = LightRig(set).at(0);
    int w = 0, h = 0;
    const std::vector<float> pixels = readEquirect(file, w, h);
    const gi::ShRgb want = gi::projectEquirect(pixels, w, h);
    for (std::size_t c = 0; c < 3; ++c)
        for (std::size_t i = 0; i < want.c[c].size(); ++i)
            CHECK(l.sky.c[c][i] == doctest::Approx(2.0 * want.c[c][i]).epsilon(1e-9));
    REQUIRE(l.image);
    CHECK(l.image->width == 32);
    CHECK(l.imageScale == 2.0f);
    set.environment.file = (dir / "missing.exr").string();
    CHECK_THROWS_AS(LightRig{set}, IoError);
    std::filesystem::remove_all(dir);
}

TEST_CASE("lights: scene files set the lights and reject bad ones") {
    const std::filesystem::path dir = terrain::test::scratchDir("lights");
    auto write = [&](const char* name, const char* text) {
        std::ofstream(dir / name) << text;
        return (dir / name).string();
    };
    const SceneSettings s = loadSceneFile(write("lit.toml", R"(
base = "dem"
[lights]
environment = "uniform"
intensity = 0.5
[[lights.key]]
azimuth = 10.0
elevation = 20.0
radius = 2.0
rgb = [1.0, 0.5, 0.25]
[[lights.key]]
azimuth = 200.0
elevation = 40.0
[lights.sun]
hour = 8.5
hours_per_frame = 0.25
latitude = 40.0
day = 100
)"));
    CHECK(s.lights.environment.kind == EnvironmentSpec::Kind::Uniform);
    CHECK(s.lights.environment.intensity == 0.5f);
    REQUIRE(s.lights.keys.size() == 2);
    CHECK(s.lights.keys[0].rgb[1] == 0.5f);
    CHECK(s.lights.keys[1].azimuthDeg == 200.0f);
    CHECK(s.lights.sun.enabled);
    CHECK(s.lights.sun.dayOfYear == 100);
    CHECK(s.lights.sun.hoursPerFrame == 0.25f);
    const SceneSettings img = loadSceneFile(write("img.toml", "[lights]\nenvironment = \"skies/noon.hdr\"\n"));
    CHECK(img.lights.environment.kind == EnvironmentSpec::Kind::Image);
    CHECK(img.lights.environment.file == (dir / "skies/noon.hdr").string());
    CHECK_THROWS_WITH_AS(loadSceneFile(write("b1.toml", "[lights]\nenvironment = \"sky.png\"\n")),
                         doctest::Contains("lights.environment"), IoError);
    CHECK_THROWS_WITH_AS(loadSceneFile(write("b2.toml", "[[lights.key]]\nelevation = 95.0\n")),
                         doctest::Contains("elevation"), IoError);
    CHECK_THROWS_WITH_AS(loadSceneFile(write("b3.toml", "[lights.sun]\nday = 400\n")), doctest::Contains("day"),
                         IoError);
    CHECK_THROWS_WITH_AS(loadSceneFile(write("b4.toml", "[lights]\nintensity = -1.0\n")),
                         doctest::Contains("intensity"), IoError);
    CHECK_THROWS_WITH_AS(loadSceneFile(write("b5.toml", "[lights.sun]\nhours = 3.0\n")),
                         doctest::Contains("lights.sun.hours"), IoError);
    std::filesystem::remove_all(dir);
}

TEST_CASE("lights: a moving sun re-lights a static scene; static lights leave it alone") {
    SceneSettings scene = builtinScene("erosion", 64, 1);
    scene.hydraulic = scene.thermal = false;  // a static scene
    PipelineSettings ps;
    ps.lighting = LightingMode::Global;
    FramePipeline fixed(scene, ps);
    scene.lights.sun.enabled = true;
    scene.lights.sun.hour = 9.0f;
    scene.lights.sun.hoursPerFrame = 0.5f;
    FramePipeline moving(scene, ps);
    for (int f = 0; f < 3; ++f) {
        for (FramePipeline* p : {&fixed, &moving}) {
            p->advance();
            p->light();
        }
        if (f == 0) continue;
        CHECK_FALSE(fixed.giState().directUpdated);  // nothing moved: no GI work
        CHECK(moving.giState().directUpdated);
        CHECK(moving.lights().keys[0].elevationDeg > 0.0f);
    }
    CHECK(moving.frameIndex() == 2);
}
