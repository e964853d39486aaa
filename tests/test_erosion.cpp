// Hydraulic and thermal erosion: conservation, convergence, hard cases,
// determinism and symmetry. Terrains come from small local generators (sine
// hills, cones, hash-based value noise) so these tests depend on nothing but
// the two stages under test.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <doctest/doctest.h>

#include "core/parallel.h"
#include "sim/hydraulic.h"
#include "sim/terrain.h"
#include "sim/thermal.h"

using namespace terrain;

namespace {

// --- terrains ---------------------------------------------------------------

TerrainState makeState(int nx, int ny, float cell) {
    TerrainState s;
    s.allocate(nx, ny, cell, LayerSet{.water = true, .sediment = true, .pipes = true});
    return s;
}

// Integer hash of (x, y, seed) to [0, 1).
float hash01(int x, int y, std::uint32_t seed) {
    std::uint32_t h =
        static_cast<std::uint32_t>(x) * 0x8da6b343u ^ static_cast<std::uint32_t>(y) * 0xd8163841u ^ seed * 0xcb1ab31fu;
    h ^= h >> 15;
    h *= 0x2c1b3c6du;
    h ^= h >> 12;
    h *= 0x297a2d39u;
    h ^= h >> 15;
    return static_cast<float>(h >> 8) * (1.0f / 16777216.0f);
}

// Smooth value noise in [0, 1).
float valueNoise(float x, float y, std::uint32_t seed) {
    const float fx0 = std::floor(x), fy0 = std::floor(y);
    const int x0 = static_cast<int>(fx0), y0 = static_cast<int>(fy0);
    float tx = x - fx0, ty = y - fy0;
    tx = tx * tx * (3.0f - 2.0f * tx);
    ty = ty * ty * (3.0f - 2.0f * ty);
    const float a = hash01(x0, y0, seed), b = hash01(x0 + 1, y0, seed);
    const float c = hash01(x0, y0 + 1, seed), d = hash01(x0 + 1, y0 + 1, seed);
    return (a + (b - a) * tx) + ((c + (d - c) * tx) - (a + (b - a) * tx)) * ty;
}

// fBm in about [0, 1): five octaves, base wavelength `scale` cells.
float fbm(int x, int y, float scale, std::uint32_t seed) {
    float sum = 0.0f, amp = 0.5f, freq = 1.0f / scale;
    for (int o = 0; o < 5; ++o) {
        sum += amp * valueNoise(static_cast<float>(x) * freq, static_cast<float>(y) * freq, seed + 17u * o);
        amp *= 0.5f;
        freq *= 2.0f;
    }
    return sum / 0.97f;
}

// Rough mountains: bedrock = base + amp * (fBm + sine ridges), soil 0.5..1.5 m.
void roughTerrain(TerrainState& s, float base, float amp, std::uint32_t seed) {
    for (int y = 0; y < s.ny; ++y) {
        for (int x = 0; x < s.nx; ++x) {
            const float ridges = 0.15f * std::sin(0.45f * x) * std::sin(0.31f * y + 1.0f);
            s.bedrock(x, y) = base + amp * (fbm(x, y, 12.0f, seed) + ridges);
            s.soil(x, y) = 0.5f + hash01(x, y, seed + 99u);
        }
    }
}

void cone(TerrainState& s, float height, float radiusCells) {
    const float cx = 0.5f * (s.nx - 1), cy = 0.5f * (s.ny - 1);
    for (int y = 0; y < s.ny; ++y)
        for (int x = 0; x < s.nx; ++x) {
            const float r = std::hypot(x - cx, y - cy);
            s.bedrock(x, y) = height * std::max(0.0f, 1.0f - r / radiusCells);
        }
}

// --- measurements -----------------------------------------------------------

struct Totals {
    double material = 0.0;  // sum of bedrock + soil + suspended, m (per cell area)
    double water = 0.0;     // sum of water depth, m
    double minBed = 0.0;    // lowest bedrock, m
};

Totals totals(const TerrainState& s) {
    Totals t;
    t.minBed = s.bedrock.v.empty() ? 0.0 : s.bedrock.v[0];
    for (std::size_t i = 0; i < s.bedrock.size(); ++i) {
        t.material += static_cast<double>(s.bedrock.v[i]) + static_cast<double>(s.soil.v[i]);
        if (!s.suspended.empty()) t.material += static_cast<double>(s.suspended.v[i]);
        if (!s.water.empty()) t.water += static_cast<double>(s.water.v[i]);
        t.minBed = std::min(t.minBed, static_cast<double>(s.bedrock.v[i]));
    }
    return t;
}

// Material volume above the initial lowest bedrock point: the physically
// meaningful amount of material (a constant offset of every height adds
// nothing to move), and a much stricter base than sum(|height|).
double materialAboveBase(const Totals& t, const TerrainState& s) {
    return t.material - t.minBed * static_cast<double>(s.bedrock.size());
}

bool allFinite(const TerrainState& s, std::string& where) {
    const std::pair<const char*, const Grid*> layers[] = {
        {"bedrock", &s.bedrock}, {"soil", &s.soil},   {"water", &s.water}, {"suspended", &s.suspended},
        {"fluxL", &s.fluxL},     {"fluxR", &s.fluxR}, {"fluxT", &s.fluxT}, {"fluxB", &s.fluxB},
        {"velX", &s.velX},       {"velY", &s.velY}};
    for (const auto& [name, g] : layers)
        for (float v : g->v)
            if (!std::isfinite(v)) {
                where = name;
                return false;
            }
    return true;
}

float minOf(const Grid& g) { return g.v.empty() ? 0.0f : *std::min_element(g.v.begin(), g.v.end()); }

struct Sim {
    HydraulicSettings hydraulic;
    ThermalSettings thermal;
    HydraulicScratch hs;
    ThermalScratch ts;
    bool runHydraulic = true;
    bool runThermal = true;

    void tick(TerrainState& s, float dt) {
        if (runHydraulic) hydraulicStep(s, hydraulic, dt, hs);
        if (runThermal) thermalStep(s, thermal, dt, ts);
    }
};

}  // namespace

// ---------------------------------------------------------------------------
// Conservation
// ---------------------------------------------------------------------------

TEST_CASE("sim.hydraulic: closed basin conserves material and water over 1000 ticks") {
    // 67 x 45 (not a power of two), rough 0..50 m bedrock, 1 m of water plus
    // a 5 m deep pond in one corner so that water really runs; no rain, no
    // evaporation, closed boundary. Material is measured above the lowest
    // bedrock point (see materialAboveBase), water against the total water.
    for (const float cell : {1.0f, 25.0f}) {
        CAPTURE(cell);
        TerrainState s = makeState(67, 45, cell);
        roughTerrain(s, 0.0f, 50.0f, 7u);
        for (int y = 0; y < s.ny; ++y)
            for (int x = 0; x < s.nx; ++x) s.water(x, y) = 1.0f + (x < 15 && y < 12 ? 5.0f : 0.0f);
        const TerrainState start = s;

        Sim sim;
        sim.runThermal = false;
        sim.hydraulic.rainRate = 0.0f;
        sim.hydraulic.evaporation = 0.0f;
        const float dt = hydraulicMaxDt(s, sim.hydraulic);
        const Totals t0 = totals(s);
        float maxSuspended = 0.0f;
        for (int t = 0; t < 1000; ++t) {
            sim.tick(s, dt);
            if (t % 50 == 0)
                maxSuspended = std::max(maxSuspended, *std::max_element(s.suspended.v.begin(), s.suspended.v.end()));
        }
        const Totals t1 = totals(s);

        // Erosion and deposition really happened.
        double soilChange = 0.0, bedChange = 0.0;
        for (std::size_t i = 0; i < s.soil.size(); ++i) {
            soilChange += std::fabs(static_cast<double>(s.soil.v[i]) - start.soil.v[i]);
            bedChange += std::fabs(static_cast<double>(s.bedrock.v[i]) - start.bedrock.v[i]);
        }
        soilChange /= static_cast<double>(s.soil.size());
        CHECK(soilChange > 0.01);  // mean |change of soil| above 1 cm
        CHECK(maxSuspended > 0.01f);

        const double materialErr = std::fabs(t1.material - t0.material) / materialAboveBase(t0, start);
        const double waterErr = std::fabs(t1.water - t0.water) / t0.water;
        MESSAGE("cell " << cell << " m: mean |dsoil| " << soilChange << " m, mean |dbedrock| "
                        << bedChange / static_cast<double>(s.soil.size()) << " m, max suspended " << maxSuspended
                        << " m; relative error material " << materialErr << ", water " << waterErr);
        CHECK(materialErr <= 1e-5);
        CHECK(waterErr <= 1e-5);
        CHECK(minOf(s.water) >= 0.0f);
        CHECK(minOf(s.soil) >= 0.0f);
        CHECK(minOf(s.suspended) >= 0.0f);
    }
}

TEST_CASE("sim.hydraulic: hydraulic + thermal together conserve material under rain and evaporation") {
    // Rain and evaporation change the water only; with a closed boundary
    // bedrock + soil + suspended sediment must stay constant.
    TerrainState s = makeState(53, 71, 2.0f);
    roughTerrain(s, 0.0f, 50.0f, 11u);
    Sim sim;
    sim.hydraulic.rainRate *= 20.0f;
    const float dt = hydraulicMaxDt(s, sim.hydraulic);
    const Totals t0 = totals(s);
    for (int t = 0; t < 1000; ++t) sim.tick(s, dt);
    const Totals t1 = totals(s);
    const double err = std::fabs(t1.material - t0.material) / materialAboveBase(t0, s);
    MESSAGE("relative material error " << err << ", water now " << t1.water << " m*cells");
    CHECK(t1.water > 0.0);
    CHECK(err <= 1e-5);
}

// ---------------------------------------------------------------------------
// Thermal erosion
// ---------------------------------------------------------------------------

TEST_CASE("sim.thermal: relaxes every slope to the talus angle and conserves material") {
    ThermalSettings settings;
    const float tanTalus = std::tan(settings.talusAngleDeg * 3.14159265f / 180.0f);
    const float dt = 10.0f;  // rate * dt above the per-step cap: fastest relaxation

    struct Case {
        const char* name;
        std::function<void(TerrainState&)> make;
        float cell;
    };
    const Case cases[] = {
        {"bedrock cone, slope 3", [](TerrainState& s) { cone(s, 60.0f, 20.0f); }, 1.0f},
        {"one-texel spike", [](TerrainState& s) { s.bedrock(30, 20) = 40.0f; }, 1.0f},
        {"soil cone on flat rock",
         [](TerrainState& s) {
             cone(s, 30.0f, 15.0f);
             std::swap(s.bedrock.v, s.soil.v);
         },
         1.0f},
        {"rough noise, 10 m cells", [](TerrainState& s) { roughTerrain(s, 0.0f, 50.0f, 3u); }, 10.0f},
        // On a 1000 m plateau one float step is 6e-5 m, still well below the
        // 1e-3 slope tolerance at 1 m cells (at 1e4 m it would be 1e-3).
        {"rough noise on a 1000 m plateau", [](TerrainState& s) { roughTerrain(s, 1000.0f, 50.0f, 5u); }, 1.0f},
    };
    for (const Case& c : cases) {
        const std::string name = c.name;
        CAPTURE(name);
        TerrainState s = makeState(61, 43, c.cell);
        c.make(s);
        const Totals t0 = totals(s);
        const float slope0 = maxGroundSlope(s);
        ThermalScratch scratch;
        int steps = 0;
        while (maxGroundSlope(s) > tanTalus + 1e-3f && steps < 20000) {
            for (int k = 0; k < 20; ++k) thermalStep(s, settings, dt, scratch);
            steps += 20;
        }
        const Totals t1 = totals(s);
        const float slope1 = maxGroundSlope(s);
        const double err = std::fabs(t1.material - t0.material) / materialAboveBase(t0, s);
        MESSAGE(name << ": max slope " << slope0 << " -> " << slope1 << " (tan talus " << tanTalus << ") after "
                     << steps << " steps, relative material error " << err);
        CHECK(slope0 > tanTalus + 0.1f);
        CHECK(slope1 <= tanTalus + 1e-3f);
        CHECK(err <= 1e-5);
        CHECK(minOf(s.soil) >= 0.0f);
    }
}

TEST_CASE("sim.thermal: without erodeBedrock only soil moves") {
    ThermalSettings settings;
    settings.erodeBedrock = false;
    TerrainState s = makeState(41, 37, 1.0f);
    cone(s, 40.0f, 12.0f);  // steep bedrock
    for (float& v : s.soil.v) v = 0.3f;
    const TerrainState start = s;
    ThermalScratch scratch;
    for (int k = 0; k < 500; ++k) thermalStep(s, settings, 1.0f, scratch);
    CHECK(s.bedrock.v == start.bedrock.v);
    const double err = std::fabs(totals(s).material - totals(start).material) / materialAboveBase(totals(start), start);
    CHECK(err <= 1e-5);
    CHECK(minOf(s.soil) >= 0.0f);
    // The soil slid off the flanks: the summit is bare.
    CHECK(s.soil(20, 18) < 0.3f);
}

// ---------------------------------------------------------------------------
// Erosion does something sensible
// ---------------------------------------------------------------------------

TEST_CASE("sim.hydraulic: rain erodes the slopes and deposits in the valleys") {
    // A noisy cone mountain (slope ~1) in a closed 80 x 72 domain under a
    // heavy rain (10x the default: 0.7 m/h, so that 3000 steps of 0.11 s see
    // 7 cm of rain) with default evaporation, hydraulic erosion only.
    TerrainState s = makeState(80, 72, 1.0f);
    cone(s, 36.0f, 36.0f);
    for (int y = 0; y < s.ny; ++y)
        for (int x = 0; x < s.nx; ++x) {
            s.bedrock(x, y) += 3.0f * fbm(x, y, 6.0f, 23u);
            s.soil(x, y) = 2.0f;
        }
    const TerrainState start = s;
    Sim sim;
    sim.runThermal = false;
    sim.hydraulic.rainRate *= 10.0f;
    const float dt = hydraulicMaxDt(s, sim.hydraulic);
    for (int t = 0; t < 3000; ++t) sim.tick(s, dt);

    // Upper flanks (initial ground in the top quarter, off the very summit)
    // and the foot of the mountain (lowest quarter).
    std::vector<float> g0(start.bedrock.size());
    for (std::size_t i = 0; i < g0.size(); ++i) g0[i] = start.bedrock.v[i] + start.soil.v[i];
    std::vector<float> sorted = g0;
    std::sort(sorted.begin(), sorted.end());
    const float q25 = sorted[sorted.size() / 4], q75 = sorted[3 * sorted.size() / 4];
    double highChange = 0.0, lowSoilChange = 0.0;
    int nHigh = 0, nLow = 0;
    for (std::size_t i = 0; i < g0.size(); ++i) {
        const double g1 = static_cast<double>(s.bedrock.v[i]) + s.soil.v[i];
        if (g0[i] >= q75) {
            highChange += g1 - g0[i];
            ++nHigh;
        }
        if (g0[i] <= q25) {
            lowSoilChange += static_cast<double>(s.soil.v[i]) + s.suspended.v[i] - start.soil.v[i];
            ++nLow;
        }
    }
    highChange /= nHigh;
    lowSoilChange /= nLow;
    const double err = std::fabs(totals(s).material - totals(start).material) / materialAboveBase(totals(start), start);
    MESSAGE("mean ground change, top quarter: " << highChange << " m; mean soil + suspended gain, bottom quarter: "
                                                << lowSoilChange << " m; relative material error " << err);
    CHECK(highChange < -0.01);    // the high ground lost material
    CHECK(lowSoilChange > 0.01);  // the low ground gained sediment
    CHECK(err <= 1e-5);
}

// ---------------------------------------------------------------------------
// Hard cases
// ---------------------------------------------------------------------------

TEST_CASE("sim.hydraulic: hard cases stay finite") {
    struct Case {
        const char* name;
        int nx, ny;
        float cell;
        float rainScale;
        std::function<void(TerrainState&)> make;
    };
    const Case cases[] = {
        {"1000 m vertical cliff", 40, 30, 1.0f, 1.0f,
         [](TerrainState& s) {
             for (int y = 0; y < s.ny; ++y)
                 for (int x = 0; x < s.nx; ++x) {
                     s.bedrock(x, y) = x < 20 ? 1000.0f : 0.0f;
                     s.water(x, y) = x < 20 ? 2.0f : 0.0f;
                 }
         }},
        {"one-texel spike", 33, 31, 1.0f, 1.0f, [](TerrainState& s) { s.bedrock(16, 15) = 1000.0f; }},
        {"flat plane", 32, 32, 1.0f, 1.0f, [](TerrainState&) {}},
        {"heights of 1e5 m", 37, 29, 1.0f, 1.0f, [](TerrainState& s) { roughTerrain(s, 1.0e5f, 50.0f, 1u); }},
        {"negative heights", 37, 29, 1.0f, 1.0f, [](TerrainState& s) { roughTerrain(s, -2000.0f, 50.0f, 2u); }},
        {"heavy rain (100x)", 37, 29, 1.0f, 100.0f, [](TerrainState& s) { roughTerrain(s, 0.0f, 50.0f, 4u); }},
        {"heavy rain, 100 m cells", 37, 29, 100.0f, 100.0f,
         [](TerrainState& s) { roughTerrain(s, 0.0f, 2000.0f, 4u); }},
        {"10 cm cells", 37, 29, 0.1f, 1.0f, [](TerrainState& s) { roughTerrain(s, 0.0f, 5.0f, 6u); }},
        {"1000 m deep water", 37, 29, 1.0f, 1.0f,
         [](TerrainState& s) {
             roughTerrain(s, 0.0f, 50.0f, 8u);
             for (float& w : s.water.v) w = 1000.0f;
         }},
        {"1 x 1", 1, 1, 1.0f, 100.0f, [](TerrainState& s) { s.bedrock(0, 0) = 5.0f; }},
        {"2 x 2", 2, 2, 1.0f, 100.0f,
         [](TerrainState& s) {
             s.bedrock(0, 0) = 100.0f;
             s.water(1, 1) = 3.0f;
         }},
        {"1 x 9 strip", 1, 9, 1.0f, 100.0f, [](TerrainState& s) { s.bedrock(0, 4) = 50.0f; }},
        {"9 x 1 strip", 9, 1, 1.0f, 100.0f, [](TerrainState& s) { s.bedrock(4, 0) = 50.0f; }},
    };
    for (const Case& c : cases) {
        for (const bool closed : {true, false}) {
            const std::string name = c.name;
            CAPTURE(name);
            CAPTURE(closed);
            TerrainState s = makeState(c.nx, c.ny, c.cell);
            c.make(s);
            Sim sim;
            sim.hydraulic.rainRate *= c.rainScale;
            sim.hydraulic.closedBoundary = closed;
            const float dt = hydraulicMaxDt(s, sim.hydraulic);
            REQUIRE(std::isfinite(dt));
            REQUIRE(dt > 0.0f);
            std::string where;
            bool finite = true;
            for (int t = 0; t < 300 && finite; ++t) {
                sim.tick(s, dt);
                finite = allFinite(s, where);
            }
            CHECK_MESSAGE(finite, "non-finite value in " << where);
            CHECK(minOf(s.water) >= 0.0f);
            CHECK(minOf(s.soil) >= 0.0f);
            CHECK(minOf(s.suspended) >= 0.0f);
            CHECK(std::isfinite(maxGroundSlope(s)));
        }
    }
}

// ---------------------------------------------------------------------------
// Determinism and symmetry
// ---------------------------------------------------------------------------

TEST_CASE("sim.hydraulic: erosion is bit-identical for 1, 2, 3 and 8 threads and across runs") {
    // 203 x 331: not a power of two, and tall enough that parallelForRows
    // cuts it into several chunks.
    auto run = [] {
        TerrainState s = makeState(203, 331, 1.5f);
        roughTerrain(s, 0.0f, 50.0f, 42u);
        Sim sim;
        sim.hydraulic.rainRate *= 50.0f;
        const float dt = hydraulicMaxDt(s, sim.hydraulic);
        std::vector<std::uint64_t> hashes;
        for (int t = 1; t <= 60; ++t) {
            sim.tick(s, dt);
            if (t % 20 == 0) hashes.push_back(hashState(s));
        }
        return hashes;
    };
    const auto ref = withThreads(1, run);
    REQUIRE(ref.size() == 3);
    CHECK(ref[0] != ref[2]);  // the state does change
    for (int threads : {2, 3, 8}) {
        CAPTURE(threads);
        CHECK(withThreads(threads, run) == ref);
    }
    CHECK(withThreads(1, run) == ref);
}

namespace {
TerrainState mirrorX(const TerrainState& s) {
    TerrainState m = s;
    for (int y = 0; y < s.ny; ++y)
        for (int x = 0; x < s.nx; ++x) {
            const int mx = s.nx - 1 - x;
            m.bedrock(mx, y) = s.bedrock(x, y);
            m.soil(mx, y) = s.soil(x, y);
            m.water(mx, y) = s.water(x, y);
            m.suspended(mx, y) = s.suspended(x, y);
            m.fluxL(mx, y) = s.fluxR(x, y);
            m.fluxR(mx, y) = s.fluxL(x, y);
            m.fluxT(mx, y) = s.fluxT(x, y);
            m.fluxB(mx, y) = s.fluxB(x, y);
            m.velX(mx, y) = 0.0f - s.velX(x, y);
            m.velY(mx, y) = s.velY(x, y);
        }
    return m;
}
TerrainState mirrorY(const TerrainState& s) {
    TerrainState m = s;
    for (int y = 0; y < s.ny; ++y)
        for (int x = 0; x < s.nx; ++x) {
            const int my = s.ny - 1 - y;
            m.bedrock(x, my) = s.bedrock(x, y);
            m.soil(x, my) = s.soil(x, y);
            m.water(x, my) = s.water(x, y);
            m.suspended(x, my) = s.suspended(x, y);
            m.fluxL(x, my) = s.fluxL(x, y);
            m.fluxR(x, my) = s.fluxR(x, y);
            m.fluxT(x, my) = s.fluxB(x, y);
            m.fluxB(x, my) = s.fluxT(x, y);
            m.velX(x, my) = s.velX(x, y);
            m.velY(x, my) = 0.0f - s.velY(x, y);
        }
    return m;
}
}  // namespace

TEST_CASE("sim.hydraulic: a mirrored terrain evolves bit-for-bit mirrored (SIMD, scalar and edge paths agree)") {
    // The kernels treat the two directions of an axis symmetrically and every
    // sum they form is commutative in mirrored pairs, so mirroring commutes
    // with a step exactly. Mirroring moves cells between SIMD lanes, the
    // scalar tail and the edge path (37 columns: 35 interior = 8 x 4 + 3), so
    // this checks those paths against each other bit for bit.
    TerrainState a = makeState(37, 29, 1.0f);
    roughTerrain(a, 0.0f, 40.0f, 5u);
    for (int y = 0; y < a.ny; ++y)
        for (int x = 0; x < a.nx; ++x) a.water(x, y) = x < 9 ? 3.0f : 0.2f;
    TerrainState bx = mirrorX(a), by = mirrorY(a);
    Sim simA, simX, simY;
    for (Sim* sim : {&simA, &simX, &simY}) sim->hydraulic.rainRate *= 50.0f;
    const float dt = hydraulicMaxDt(a, simA.hydraulic);
    for (int t = 0; t < 200; ++t) {
        simA.tick(a, dt);
        simX.tick(bx, dt);
        simY.tick(by, dt);
    }
    // Compared with float ==, which takes -0 == +0: a dry cell's velocity is
    // (+-flux) * 0, whose sign of zero legitimately flips under a mirror.
    auto sameLayers = [](const TerrainState& p, const TerrainState& q) {
        const Grid TerrainState::*layers[] = {&TerrainState::bedrock,   &TerrainState::soil,  &TerrainState::water,
                                              &TerrainState::suspended, &TerrainState::fluxL, &TerrainState::fluxR,
                                              &TerrainState::fluxT,     &TerrainState::fluxB, &TerrainState::velX,
                                              &TerrainState::velY};
        int differing = 0;
        for (auto layer : layers) differing += (p.*layer).v == (q.*layer).v ? 0 : 1;
        return differing;
    };
    CHECK(sameLayers(bx, mirrorX(a)) == 0);
    CHECK(sameLayers(by, mirrorY(a)) == 0);
    CHECK(a.soil.v != bx.soil.v);  // the terrain is not symmetric itself
}
