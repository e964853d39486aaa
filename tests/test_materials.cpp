// Scene materials: the rules put each material where it belongs, the maps
// are deterministic, scene files set them and reject bad values, and the
// albedo reaches the GI (a red floor tints the light it bounces onto a white
// wall, in proportion to its albedo).
#include <cmath>
#include <filesystem>
#include <fstream>

#include <doctest/doctest.h>

#include "core/error.h"
#include "core/parallel.h"
#include "engine/material_maps.h"
#include "engine/pipeline.h"
#include "sim/scene.h"

using namespace terrain;
using namespace terrain::engine;

namespace {

void checkAlbedo(const Material& got, const Material& want, float eps = 1e-5f) {
    for (std::size_t c = 0; c < 3; ++c) CHECK(got.albedo[c] == doctest::Approx(want.albedo[c]).epsilon(eps));
}

// A floor of red soil (x < half) under a bare white wall rising at 60 deg to
// a plateau; no simulators. Returns the pipeline after one lit frame.
std::unique_ptr<FramePipeline> litWall(const std::array<float, 3>& floorAlbedo) {
    SceneSettings scene = builtinScene("erosion", 64, 1);
    scene.hydraulic = scene.thermal = false;
    scene.soilDepth = 0.0f;
    scene.materials = MaterialSet{};
    scene.materials.bedrock.albedo = {0.9f, 0.9f, 0.9f};
    scene.materials.soil.material.albedo = floorAlbedo;
    PipelineSettings ps;
    ps.lighting = LightingMode::Global;
    ps.verticalExaggeration = 1.0f;
    ps.gi.subsample = 1;
    scene.lights.keys.at(0).azimuthDeg = 180.0f;  // from -x: lights the floor and the wall's face
    scene.lights.keys.at(0).elevationDeg = 35.0f;
    auto p = std::make_unique<FramePipeline>(scene, ps);
    TerrainState& st = p->simulation().state();
    for (int y = 0; y < st.ny; ++y)
        for (int x = 0; x < st.nx; ++x) {
            const float rise = std::max(0.0f, static_cast<float>(x - 32) * st.cellSize * std::sqrt(3.0f));
            st.bedrock(x, y) = std::min(rise, 200.0f);
            st.soil(x, y) = x < 32 ? 1.0f : 0.0f;
        }
    p->terrainReplaced();
    p->advance();
    p->light();
    return p;
}

// Mean indirect light (RGB) over the wall's face, away from the grid's edges.
std::array<double, 3> wallIndirect(const FramePipeline& p) {
    const auto& ind = p.giState().indirect.indirect;
    std::array<double, 3> sum{};
    int n = 0;
    for (int y = 16; y < 48; ++y)
        for (int x = 34; x < 42; ++x, ++n)
            for (std::size_t c = 0; c < 3; ++c) sum[c] += ind[c](x, y);
    for (double& s : sum) s /= n;
    return sum;
}

}  // namespace

TEST_CASE("materials: each rule puts its material where it belongs") {
    const MaterialSet m = builtinMaterials("dem");
    REQUIRE(m.vegetation.enabled);
    REQUIRE(m.snow.enabled);
    // bare granite on steep ground at any altitude
    checkAlbedo(materialAt(m, 1000.0f, 70.0f, 0.0f, 0.0f), m.bedrock);
    checkAlbedo(materialAt(m, 3600.0f, 70.0f, 0.0f, 0.0f), m.bedrock);
    // meadows low and gentle, snow high and gentle, rock in between
    checkAlbedo(materialAt(m, 1000.0f, 10.0f, 0.0f, 0.0f), m.vegetation.material);
    checkAlbedo(materialAt(m, 3600.0f, 10.0f, 0.0f, 0.0f), m.snow.material);
    checkAlbedo(materialAt(m, 2750.0f, 10.0f, 0.0f, 0.0f), m.bedrock);
    // soil hides the rock once it is cover_depth thick
    MaterialSet bare = m;
    bare.vegetation.enabled = bare.snow.enabled = false;
    checkAlbedo(materialAt(bare, 1000.0f, 10.0f, bare.soil.coverDepth, 0.0f), bare.soil.material);
    // soaked ground is darker by wet.darkening; deep water shows its own body
    const Material wet = materialAt(bare, 1000.0f, 10.0f, 0.0f, bare.wet.depth);
    const float bedWeight = std::exp(-2.0f * bare.wet.depth / bare.water.clarity);
    for (std::size_t c = 0; c < 3; ++c)
        CHECK(wet.albedo[c] == doctest::Approx(bedWeight * bare.wet.darkening * bare.bedrock.albedo[c] +
                                               (1.0f - bedWeight) * bare.water.material.albedo[c])
                                   .epsilon(1e-5));
    checkAlbedo(materialAt(bare, 1000.0f, 10.0f, 0.0f, 100.0f), bare.water.material, 1e-4f);
    // foam on shallow water whose depth changes fast (the swash zone), none
    // on a film of the same depth that keeps its depth
    MaterialSet beach = builtinMaterials("waves");
    REQUIRE(beach.foam.enabled);
    const Material front = materialAt(beach, 0.0f, 5.0f, 0.0f, 0.1f, 0.2f);
    checkAlbedo(front, beach.foam.material);
    const Material film = materialAt(beach, 0.0f, 5.0f, 0.0f, 0.1f, 0.0f);
    beach.foam.enabled = false;
    checkAlbedo(film, materialAt(beach, 0.0f, 5.0f, 0.0f, 0.1f, 0.2f));
    // exponents blend geometrically: half soil is the geometric mean
    bare.soil.coverDepth = 1.0f;
    const float half = materialAt(bare, 0.0f, 0.0f, 0.5f, 0.0f).phongExponent;
    CHECK(half == doctest::Approx(std::sqrt(bare.bedrock.phongExponent * bare.soil.material.phongExponent)));
}

TEST_CASE("materials: the maps are identical for any thread count") {
    SceneSettings scene = builtinScene("erosion", 96, 2);
    Simulation sim(scene);
    for (int t = 0; t < 200; ++t) sim.tick();  // water and moved soil
    MaterialMaps one;
    withThreads(1, [&] { deriveMaterialMaps(sim.state(), scene.materials, one); });
    for (int threads : {2, 3, 8}) {
        MaterialMaps many;
        withThreads(threads, [&] { deriveMaterialMaps(sim.state(), scene.materials, many); });
        for (std::size_t c = 0; c < 3; ++c) CHECK(many.albedo.channel[c].v == one.albedo.channel[c].v);
        CHECK(many.exponent.v == one.exponent.v);
    }
}

TEST_CASE("materials: bad values are one clear error") {
    MaterialSet m = builtinMaterials("erosion");
    CHECK_NOTHROW(validateMaterials(m));
    m.soil.material.albedo[1] = 1.5f;
    CHECK_THROWS_WITH_AS(validateMaterials(m), doctest::Contains("soil.albedo"), InputError);
    m = builtinMaterials("erosion");
    m.vegetation.minAltitude = 500.0f;
    m.vegetation.maxAltitude = 100.0f;
    CHECK_THROWS_WITH_AS(validateMaterials(m), doctest::Contains("vegetation"), InputError);
    m = builtinMaterials("erosion");
    m.water.clarity = 0.0f;
    CHECK_THROWS_WITH_AS(validateMaterials(m), doctest::Contains("water.clarity"), InputError);
    m = builtinMaterials("erosion");
    m.snow.material.phongExponent = 0.5f;
    CHECK_THROWS_WITH_AS(validateMaterials(m), doctest::Contains("snow.exponent"), InputError);
}

TEST_CASE("materials: scene files declare materials and reject bad ones") {
    const std::filesystem::path dir = std::filesystem::temp_directory_path() / "terrain_test_materials";
    std::filesystem::create_directories(dir);
    auto write = [&](const char* name, const char* text) {
        std::ofstream(dir / name) << text;
        return (dir / name).string();
    };
    const SceneSettings s = loadSceneFile(write("red.toml", R"(
base = "erosion"
[materials.soil]
albedo = [0.5, 0.1, 0.05]
exponent = 3.0
cover_depth = 0.2
[materials.snow]
enabled = false
[materials.water]
clarity = 4.0
)"));
    CHECK(s.materials.soil.material.albedo[0] == 0.5f);
    CHECK(s.materials.soil.material.phongExponent == 3.0f);
    CHECK(s.materials.soil.coverDepth == 0.2f);
    CHECK_FALSE(s.materials.snow.enabled);
    CHECK(s.materials.vegetation.enabled);  // kept from the base scene
    CHECK(s.materials.water.clarity == 4.0f);
    CHECK_THROWS_WITH_AS(loadSceneFile(write("bad1.toml", "[materials.soil]\nalbedo = [0.5, 0.1]\n")),
                         doctest::Contains("materials.soil.albedo"), IoError);
    CHECK_THROWS_WITH_AS(loadSceneFile(write("bad2.toml", "[materials.soil]\nalbedo = [0.5, 2.0, 0.1]\n")),
                         doctest::Contains("soil.albedo"), IoError);
    CHECK_THROWS_WITH_AS(loadSceneFile(write("bad3.toml", "[materials.rock]\nalbedo = [0.5, 0.5, 0.5]\n")),
                         doctest::Contains("materials.rock"), IoError);
    std::filesystem::remove_all(dir);
}

TEST_CASE("materials: the albedo reaches the GI: a red floor tints a white wall, in proportion") {
    const auto red = litWall({0.6f, 0.1f, 0.1f});
    const std::array<double, 3> onWall = wallIndirect(*red);
    CHECK(onWall[0] > 0.0);
    CHECK(onWall[0] > 3.0 * onWall[1]);  // the bounce carries the floor's colour
    // halving the floor's albedo halves what it bounces onto the wall
    const auto dim = litWall({0.3f, 0.05f, 0.05f});
    const std::array<double, 3> dimmer = wallIndirect(*dim);
    for (std::size_t c = 0; c < 3; ++c) CHECK(dimmer[c] / onWall[c] == doctest::Approx(0.5).epsilon(1e-3));
    // what the renderer uploads as base colour is the GI's albedo map
    const FrameData& f = red->frame();
    const MaterialMaps& maps = red->materialMaps();
    REQUIRE(f.albedo.size() == 4 * maps.exponent.v.size());
    bool same = true;
    for (std::size_t i = 0; i < maps.exponent.v.size(); ++i) {
        for (std::size_t c = 0; c < 3; ++c) same = same && f.albedo[4 * i + c] == maps.albedo.channel[c].v[i];
        same = same && f.albedo[4 * i + 3] == maps.exponent.v[i];
    }
    CHECK(same);
    CHECK(maps.albedo.channel[0](10, 32) == doctest::Approx(0.6f));  // the floor
    CHECK(maps.albedo.channel[1](40, 32) == doctest::Approx(0.9f));  // the wall
}
