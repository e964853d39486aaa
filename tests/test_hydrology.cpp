// Hydrology maps (sim/hydrology.h): discharge against the model's own water
// balance, erosion and deposition against the ground's change, wetness, and
// the same bytes for any thread count.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include <doctest/doctest.h>

#include "core/parallel.h"
#include "sim/frame_layers.h"
#include "sim/hydrology.h"
#include "sim/scene.h"

using namespace terrain;

namespace {

constexpr int kSide = 64;

std::vector<double> groundOf(const TerrainState& s) {
    std::vector<double> g(s.bedrock.size());
    for (std::size_t i = 0; i < g.size(); ++i) g[i] = static_cast<double>(s.bedrock.v[i] + s.soil.v[i]);
    return g;
}

}  // namespace

TEST_CASE("hydrology: every cell's water change is dt times its net face discharge, plus rain, minus evaporation") {
    Simulation sim(builtinScene("erosion", kSide, 3));
    for (int t = 0; t < 150; ++t) sim.tick();  // a flowing network, not the first film of rain
    const TerrainState& s = sim.state();
    const Grid before = s.water;
    sim.tick();
    const HydraulicSettings& h = sim.settings().hydraulicSettings;
    const double dt = sim.dt();
    const double area = static_cast<double>(s.cellSize) * s.cellSize;
    // the model's own coefficients (sim/hydraulic.cpp)
    const double rain = static_cast<double>(std::max(0.0f, h.rainRate) * sim.dt());
    const double keep = std::clamp(1.0f - h.evaporation * sim.dt(), 0.0f, 1.0f);
    double worst = 0.0, largestFlow = 0.0;
    Grid discharge, velocity;
    dischargeMap(s, discharge);
    velocityMap(s, velocity);
    for (int y = 0; y < s.ny; ++y)
        for (int x = 0; x < s.nx; ++x) {
            const FaceFlows f = cellFaceFlows(s, x, y);
            const double net = (static_cast<double>(f.west) - f.east) + (static_cast<double>(f.north) - f.south);
            const double d1 = static_cast<double>(before(x, y)) + rain;
            const double d2 = d1 + dt * net / area;
            const double expected = d2 * keep;
            // rounding of the model's float sums: a few ulps of the volumes it adds
            const double scale =
                d1 + dt / area * (std::fabs(f.west) + std::fabs(f.east) + std::fabs(f.north) + std::fabs(f.south));
            const double residual = std::fabs(static_cast<double>(s.water(x, y)) - expected) / scale;
            worst = std::max(worst, residual);
            largestFlow = std::max(largestFlow, static_cast<double>(discharge(x, y)));
            // discharge is the volume flow the model's velocity carries through the mean wet section
            const double qx = 0.5 * (static_cast<double>(f.west) + f.east);
            const double qy = 0.5 * (static_cast<double>(f.north) + f.south);
            CHECK(discharge(x, y) == doctest::Approx(std::hypot(qx, qy)).epsilon(1e-6));
            const double dbar = 0.5 * (d1 + d2);
            if (dbar > 1e-3)
                CHECK(velocity(x, y) * s.cellSize * dbar ==
                      doctest::Approx(discharge(x, y)).epsilon(1e-4).scale(1e-9 * s.cellSize));
        }
    MESSAGE("largest relative water-balance residual " << worst << ", largest discharge " << largestFlow << " m^3/s");
    CHECK(largestFlow > 1e-3);  // the check saw real flow
    CHECK(worst < 8.0 * std::numeric_limits<float>::epsilon());
}

TEST_CASE("hydrology: erosion minus deposition is the ground's change over 200 ticks of the erosion scene") {
    Simulation sim(builtinScene("erosion", kSide, 5));
    const std::vector<double> start = groundOf(sim.state());
    for (int t = 0; t < 200; ++t) sim.tick();
    const std::vector<double> now = groundOf(sim.state());
    const HydrologyAccumulator& h = sim.hydrology();
    REQUIRE(h.tracksGround());
    CHECK(h.ticks() == 200);
    double worst = 0.0, moved = 0.0, eroded = 0.0, deposited = 0.0;
    for (std::size_t i = 0; i < now.size(); ++i) {
        CHECK(h.erosion()[i] >= 0.0);
        CHECK(h.deposition()[i] >= 0.0);
        worst = std::max(worst, std::fabs((h.erosion()[i] - h.deposition()[i]) - (start[i] - now[i])));
        moved = std::max(moved, std::fabs(start[i] - now[i]));
        eroded += h.erosion()[i];
        deposited += h.deposition()[i];
    }
    MESSAGE("largest |erosion - deposition - (g0 - g)| " << worst << " m; largest ground change " << moved
                                                         << " m; total erosion " << eroded << " m, deposition "
                                                         << deposited << " m");
    CHECK(moved > 1e-3);  // the scene eroded something
    CHECK(eroded > 0.0);
    CHECK(deposited > 0.0);
    // the sums are of exact float differences: only double rounding remains
    CHECK(worst < 1e-9);
    // the float maps are those sums, rounded once
    Grid net;
    h.netErosionMap(net);
    for (std::size_t i = 0; i < now.size(); ++i)
        CHECK(net.v[i] == static_cast<float>(h.erosion()[i] - h.deposition()[i]));
}

TEST_CASE("hydrology: wetness is a fraction, 1 under the sea, and only a scene with water tracks it") {
    Simulation sim(builtinScene("waves", kSide, 1));
    const Grid startWater = sim.state().water;
    for (int t = 0; t < 100; ++t) sim.tick();
    const HydrologyAccumulator& h = sim.hydrology();
    REQUIRE(h.tracksWater());
    CHECK_FALSE(h.tracksGround());  // waves move no ground
    Grid wet;
    h.wetnessMap(wet);
    int deep = 0, dry = 0;
    for (std::size_t i = 0; i < wet.size(); ++i) {
        CHECK(wet.v[i] >= 0.0f);
        CHECK(wet.v[i] <= 1.0f);
        if (startWater.v[i] > 2.0f) {
            CHECK(wet.v[i] == 1.0f);
            ++deep;
        }
        if (startWater.v[i] == 0.0f && wet.v[i] == 0.0f) ++dry;
    }
    CHECK(deep > 100);
    CHECK(dry > 0);  // the islands and the beach stay dry: wetness is not 1 everywhere

    SceneSettings dryScene = builtinScene("erosion", kSide, 1);
    dryScene.hydraulic = false;  // thermal alone: ground maps, no water
    Simulation thermal(dryScene);
    thermal.tick();
    CHECK(thermal.hydrology().tracksGround());
    CHECK_FALSE(thermal.hydrology().tracksWater());
    CHECK(frameLayers(thermal).find("wetness") == nullptr);
    CHECK(frameLayers(thermal).find("discharge") == nullptr);
}

TEST_CASE("hydrology: the frame layers are the same bytes for 1, 2, 3 and 8 threads") {
    for (const char* scene : {"erosion", "waves"}) {
        CAPTURE(scene);
        const auto run = [&] {
            Simulation sim(builtinScene(scene, kSide, 9));
            for (int t = 0; t < 60; ++t) sim.tick();
            std::vector<float> bytes;
            for (const FrameLayer& l : frameLayers(sim).layers)
                bytes.insert(bytes.end(), l.grid.v.begin(), l.grid.v.end());
            return bytes;
        };
        const std::vector<float> one = withThreads(1, run);
        for (int threads : {2, 3, 8}) {
            CAPTURE(threads);
            const std::vector<float> other = withThreads(threads, run);
            REQUIRE(other.size() == one.size());
            CHECK(std::memcmp(other.data(), one.data(), one.size() * sizeof(float)) == 0);
        }
    }
}
