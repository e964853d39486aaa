#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include <doctest/doctest.h>
#include <unistd.h>

#include "core/error.h"
#include "core/parallel.h"
#include "sim/scene.h"

using namespace terrain;
namespace fs = std::filesystem;

namespace {
std::string runHashes(SceneSettings s, int ticks, int every) {
    Simulation sim(s);
    std::string out;
    for (int t = 1; t <= ticks; ++t) {
        sim.tick();
        if (t % every == 0) out += std::to_string(t) + ":" + hashHex(hashState(sim.state())) + "\n";
    }
    return out;
}
fs::path scratch() {
    fs::path p = fs::temp_directory_path() / ("terrain_scene_test_" + std::to_string(::getpid()));
    fs::create_directories(p);
    return p;
}
void writeText(const fs::path& p, const std::string& t) { std::ofstream(p) << t; }
}  // namespace

TEST_CASE("sim.scene: built-in scenes build on power-of-two and other sizes") {
    for (const char* name : {"erosion", "waves"}) {
        for (int n : {1, 2, 67, 128}) {
            SceneSettings s = builtinScene(name, n, 5);
            Simulation sim(s);
            CHECK(sim.state().nx == n);
            CHECK(sim.dt() > 0.0f);
            for (int t = 0; t < 3; ++t) sim.tick();
            CHECK_NOTHROW(checkFinite(sim.state()));
        }
    }
    for (const char* name : {"erosion", "waves"}) {  // non-square, non-power-of-two
        SceneSettings s = builtinScene(name, 200, 5);
        s.ny = 300;
        Simulation sim(s);
        CHECK(sim.state().nx == 200);
        CHECK(sim.state().ny == 300);
        for (int t = 0; t < 3; ++t) sim.tick();
        CHECK_NOTHROW(checkFinite(sim.state()));
    }
    SceneSettings w = builtinScene("waves", 64, 1);
    Simulation sim(w);
    // the water surface starts flat at the scene's level wherever there is water
    const TerrainState& st = sim.state();
    int wet = 0, dry = 0;
    for (int y = 0; y < st.ny; ++y)
        for (int x = 0; x < st.nx; ++x) {
            if (st.water(x, y) > 0.0f) {
                ++wet;
                CHECK(std::fabs(st.ground(x, y) + st.water(x, y) - w.waterLevel) < 1e-4f);
            } else {
                ++dry;
            }
        }
    CHECK(wet > 0);
    CHECK(dry > 0);  // a coast: islands and beach stick out
    CHECK_THROWS_AS(builtinScene("volcano", 64, 1), InputError);
}

TEST_CASE("sim.scene: the dem scene loads the Mont Blanc DEM at true scale") {
    SceneSettings s = builtinScene("dem", 128, 1);
    if (!fs::exists(s.terrain.demFile)) {
        MESSAGE("shared/data not present; skipped");
        return;
    }
    Simulation sim(s);
    CHECK(sim.state().nx == 128);
    CHECK(sim.state().cellSize == doctest::Approx(60000.0 / 128.0).epsilon(1e-4));
    float hi = -1e9f;
    for (float v : sim.state().bedrock.v) hi = std::max(hi, v);
    CHECK(hi > 4000.0f);
    CHECK(hi < 4811.0f);
}

TEST_CASE("sim.scene: simulated frames are bit-identical for 1, 2, 3 and 8 threads and across runs") {
    for (const char* name : {"erosion", "waves"}) {
        SceneSettings s = builtinScene(name, 1, 9);
        s.nx = 67;
        s.ny = 45;
        const std::string ref = withThreads(1, [&] { return runHashes(s, 30, 10); });
        CHECK(ref.size() > 0);
        for (int t : {2, 3, 8}) CHECK_MESSAGE(withThreads(t, [&] { return runHashes(s, 30, 10); }) == ref, name, t);
        CHECK(runHashes(s, 30, 10) == ref);
        // and the state really evolves
        SceneSettings s2 = s;
        Simulation a(s2);
        const auto h0 = hashState(a.state());
        a.tick();
        CHECK(hashState(a.state()) != h0);
    }
}

TEST_CASE("sim.scene: golden hashes of the built-in scenes") {
    // tests/golden/sim_hashes.txt: "<scene> <size> <ticks> <seed> <hash>" per line.
    // Re-bless after an intended change: TERRAIN_BLESS=1 build/terrain_tests -tc='sim.scene: golden*'
    const std::string file = std::string(TERRAIN_SOURCE_DIR) + "/tests/golden/sim_hashes.txt";
    struct Entry {
        std::string scene;
        int size, ticks, seed;
    };
    const Entry entries[] = {{"erosion", 96, 50, 1}, {"waves", 96, 50, 1}};
    std::map<std::string, std::string> golden;
    {
        std::ifstream in(file);
        std::string scene, hash;
        int size, ticks, seed;
        while (in >> scene >> size >> ticks >> seed >> hash)
            golden[scene + " " + std::to_string(size) + " " + std::to_string(ticks) + " " + std::to_string(seed)] =
                hash;
    }
    const char* bless = std::getenv("TERRAIN_BLESS");
    std::ostringstream blessed;
    for (const Entry& e : entries) {
        SceneSettings s = builtinScene(e.scene, e.size, static_cast<std::uint64_t>(e.seed));
        Simulation sim(s);
        for (int t = 0; t < e.ticks; ++t) sim.tick();
        const std::string key =
            e.scene + " " + std::to_string(e.size) + " " + std::to_string(e.ticks) + " " + std::to_string(e.seed);
        const std::string h = hashHex(hashState(sim.state()));
        blessed << key << " " << h << "\n";
        if (!bless) {
            REQUIRE_MESSAGE(golden.count(key), "no golden hash for ", key, " (bless with TERRAIN_BLESS=1)");
            CHECK_MESSAGE(golden[key] == h, key, ": the simulation changed; if intended, re-bless (README)");
        }
    }
    if (bless) {
        std::ofstream(file) << blessed.str();
        MESSAGE("golden hashes re-blessed in ", file);
    }
}

TEST_CASE("sim.scene: change tracking reports the tiles that changed and the largest change") {
    SceneSettings s;
    s.name = "spike";
    s.nx = 100;
    s.ny = 70;
    s.cellSize = 1.0f;
    s.terrain.kind = TerrainSource::Kind::Shape;
    s.terrain.shape.shape = Shape::Spike;
    s.terrain.shape.height = 50.0f;
    s.thermal = true;
    s.changeTile = 16;
    Simulation sim(s);
    sim.tick();  // thermal turns the over-steep bedrock into soil in place: the ground has not moved yet
    CHECK(sim.changes().dirtyCount == 0);
    CHECK(sim.changes().maxGroundChange == 0.0f);
    sim.tick();  // now the soil slides off the spike
    const ChangeReport& c = sim.changes();
    CHECK(c.tilesX == 7);
    CHECK(c.tilesY == 5);
    CHECK(c.dirtyCount >= 1);
    CHECK(c.dirtyCount <= 4);  // only around the spike at (50, 35)
    CHECK(c.dirty[static_cast<std::size_t>(35 / 16) * 7 + 50 / 16] == 1);
    CHECK(c.dirty[0] == 0);
    CHECK(c.maxGroundChange > 0.0f);
    CHECK(c.maxGroundChange <= 50.0f);
    CHECK(c.maxWaterChange == 0.0f);
}

TEST_CASE("sim.scene: a requested step above the CFL limit is clamped") {
    SceneSettings s = builtinScene("waves", 64, 1);
    Simulation free(s);
    s.dt = 1000.0f;
    Simulation clamped(s);
    CHECK(clamped.dtClamped());
    CHECK(clamped.dt() == clamped.dtLimit());
    CHECK(clamped.dt() == free.dt());
    s.dt = free.dt() * 0.5f;
    Simulation small(s);
    CHECK_FALSE(small.dtClamped());
    CHECK(small.dt() == free.dt() * 0.5f);
    // the default step is below the CFL limit at every supported size
    for (int n : {64, 256, 1024}) {
        Simulation w(builtinScene("waves", n, 1));
        const float c = std::sqrt(9.81f * 10.0f);  // deepest water ~ 9 m in the bay
        CHECK(w.dt() * c / w.state().cellSize <= 1.0f);
    }
}

TEST_CASE("sim.scene: TOML scene files set everything and reject mistakes") {
    const fs::path dir = scratch();
    writeText(dir / "bay.toml", R"(
name = "bay"
base = "waves"
size = [80, 60]
cell_size = 2.0
seed = 4
[terrain]
kind = "shape"
shape = "bump"
base = -5.0
height = 8.0
radius = 20.0
[waves]
friction = 0.01
[waves.swell]
edge = "+y"
amplitude = 0.5
period = 4.0
[[waves.drops]]
time = 1.0
x = 40.0
y = 30.0
)");
    SceneSettings s = loadSceneFile((dir / "bay.toml").string());
    CHECK(s.name == "bay");
    CHECK(s.nx == 80);
    CHECK(s.ny == 60);
    CHECK(s.cellSize == 2.0f);
    CHECK(s.seed == 4);
    CHECK(s.waves);
    CHECK_FALSE(s.hydraulic);
    CHECK(s.terrain.kind == TerrainSource::Kind::Shape);
    CHECK(s.terrain.shape.shape == Shape::GaussianBump);
    CHECK(s.waveSettings.swell.edge == 3);
    CHECK(s.waveSettings.swell.amplitude == 0.5f);
    REQUIRE(s.waveSettings.drops.size() == 1);
    CHECK(s.waveSettings.drops[0].x == 40.0f);
    Simulation sim(s);
    sim.tick();
    CHECK(sim.state().nx == 80);

    writeText(dir / "typo.toml", "base = \"erosion\"\n[hydraulic]\nrain_rat = 1.0\n");
    CHECK_THROWS_WITH_AS(loadSceneFile((dir / "typo.toml").string()), doctest::Contains("hydraulic.rain_rat"), IoError);
    writeText(dir / "syntax.toml", "size = [1, \n");
    CHECK_THROWS_WITH_AS(loadSceneFile((dir / "syntax.toml").string()), doctest::Contains("line"), IoError);
    writeText(dir / "type.toml", "size = \"big\"\n");
    CHECK_THROWS_WITH_AS(loadSceneFile((dir / "type.toml").string()), doctest::Contains("size"), IoError);
    writeText(dir / "absurd.toml", "size = 100000\n");
    CHECK_THROWS_AS(loadSceneFile((dir / "absurd.toml").string()), IoError);
    CHECK_THROWS_AS(loadSceneFile((dir / "missing.toml").string()), IoError);
    fs::remove_all(dir);
}

TEST_CASE("sim.scene: every example scene file in scenes/ loads and runs") {
    int count = 0;
    for (const auto& e : fs::directory_iterator(std::string(TERRAIN_SOURCE_DIR) + "/scenes")) {
        if (e.path().extension() != ".toml") continue;
        CAPTURE(e.path().string());
        SceneSettings s = resolveScene(e.path().string(), 48, 1);
        if (s.terrain.kind == TerrainSource::Kind::Dem && !fs::exists(s.terrain.demFile)) {
            MESSAGE("DEM not present; skipped ", e.path().string());
            continue;
        }
        Simulation sim(s);
        CHECK(sim.state().nx == 48);
        for (int t = 0; t < 3; ++t) sim.tick();
        CHECK_NOTHROW(checkFinite(sim.state()));
        ++count;
    }
    CHECK(count >= 2);
}

TEST_CASE("sim.scene: a scene file's size, seed and dt apply unless the command line gives its own") {
    const fs::path dir = scratch();
    writeText(dir / "rect.toml", "base = \"erosion\"\nsize = [30, 20]\ncell_size = 5.0\nseed = 4\ndt = 0.25\n");
    const std::string file = (dir / "rect.toml").string();
    // nothing given: the file's values, none replaced by a command-line default
    const SceneSettings own = resolveScene(file, SceneOverrides{});
    CHECK(own.nx == 30);
    CHECK(own.ny == 20);
    CHECK(own.cellSize == 5.0f);
    CHECK(own.seed == 4);
    CHECK(own.dt == 0.25f);
    // each one given wins, the rest stay the file's
    const SceneSettings sized = resolveScene(file, SceneOverrides{.size = 60});
    CHECK(sized.nx == 60);
    CHECK(sized.ny == 60);
    CHECK(sized.cellSize == doctest::Approx(2.5));  // the extent is kept
    CHECK(sized.seed == 4);
    CHECK(sized.dt == 0.25f);
    const SceneSettings seeded = resolveScene(file, SceneOverrides{.seed = 5, .dt = 0.5f});
    CHECK(seeded.nx == 30);
    CHECK(seeded.seed == 5);
    CHECK(seeded.dt == 0.5f);
    // and the file's seed reaches the terrain: seeds 4 and 5 differ
    CHECK(hashState(Simulation(own).state()) != hashState(Simulation(seeded).state()));
    // a built-in's defaults: 256 cells, seed 1
    const SceneSettings builtin = resolveScene("waves", SceneOverrides{});
    CHECK(builtin.nx == 256);
    CHECK(builtin.seed == 1);
    CHECK(resolveScene("waves", SceneOverrides{.size = 32, .seed = 7}).nx == 32);
    // the example scene keeps its 128 cells of 1 m
    const SceneSettings pit = resolveScene(std::string(TERRAIN_SOURCE_DIR) + "/scenes/pit-lake.toml", SceneOverrides{});
    CHECK(pit.nx == 128);
    CHECK(pit.cellSize == 1.0f);
    fs::remove_all(dir);
}
