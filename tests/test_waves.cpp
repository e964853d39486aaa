// Shallow-water waves (sim/waves.h) against analytic cases:
// lake at rest, wave speed sqrt(g H), Ritter's dam break, the first seiche
// mode, mass conservation, hard cases, determinism across thread counts,
// swell and drops.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <doctest/doctest.h>

#include "core/parallel.h"
#include "sim/terrain.h"
#include "sim/waves.h"

using namespace terrain;

namespace {

constexpr double kPi = 3.14159265358979323846;

// --- small local terrain helpers (independent of sim/generators.h) ----------

TerrainState makeWaterState(int nx, int ny, float dx) {
    TerrainState s;
    s.allocate(nx, ny, dx, LayerSet{.water = true, .faceVelocity = true});
    return s;
}

// Deterministic value in [0, 1) per (x, y, seed): splitmix64 of the key.
float hash01(int x, int y, std::uint64_t seed) {
    std::uint64_t z = seed * 0x9e3779b97f4a7c15ull + static_cast<std::uint64_t>(x) * 0xbf58476d1ce4e5b9ull +
                      static_cast<std::uint64_t>(y) * 0x94d049bb133111ebull;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    return static_cast<float>(z >> 40) / static_cast<float>(1ull << 24);
}

void setGround(TerrainState& s, const std::function<float(int, int)>& f) {
    for (int y = 0; y < s.ny; ++y)
        for (int x = 0; x < s.nx; ++x) s.bedrock(x, y) = f(x, y);
}

// Still water up to `level` wherever the ground is below it.
void fillToLevel(TerrainState& s, float level) {
    for (int y = 0; y < s.ny; ++y)
        for (int x = 0; x < s.nx; ++x) s.water(x, y) = std::max(0.0f, level - s.ground(x, y));
}

double totalWater(const TerrainState& s) {
    double sum = 0.0;
    for (float h : s.water.v) sum += h;
    return sum;
}

float maxAbs(const Grid& g) {
    float m = 0.0f;
    for (float v : g.v) m = std::max(m, std::fabs(v));
    return m;
}

bool allFinite(const TerrainState& s) {
    for (const Grid* g : {&s.water, &s.faceU, &s.faceV})
        for (float v : g->v)
            if (!std::isfinite(v)) return false;
    return true;
}

float minValue(const Grid& g) {
    float m = 0.0f;
    for (float v : g.v) m = std::min(m, v);
    return m;
}

// One tick at the default stable step; the test owns the clock, as a scene does.
float tickAdaptive(TerrainState& s, const WaveSettings& ws, WaveScratch& scratch) {
    const float dt = waveMaxDt(s, ws);
    waveStep(s, ws, dt, scratch);
    s.time += dt;
    s.tick += 1;
    return dt;
}

// Surface elevation of row-averaged 1-D strips.
std::vector<double> stripSurface(const TerrainState& s) {
    std::vector<double> eta(static_cast<std::size_t>(s.nx), 0.0);
    for (int x = 0; x < s.nx; ++x) {
        double e = 0.0;
        for (int y = 0; y < s.ny; ++y) e += s.water(x, y) + s.ground(x, y);
        eta[static_cast<std::size_t>(x)] = e / s.ny;
    }
    return eta;
}

// Least-squares slope of y over x.
double fitSlope(const std::vector<double>& xs, const std::vector<double>& ys) {
    const double n = static_cast<double>(xs.size());
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (std::size_t i = 0; i < xs.size(); ++i) {
        sx += xs[i];
        sy += ys[i];
        sxx += xs[i] * xs[i];
        sxy += xs[i] * ys[i];
    }
    return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

// Sub-cell position (in cells) of the maximum of v over [lo, hi): parabola
// through the largest sample and its two neighbours.
double peakPosition(const std::vector<double>& v, int lo, int hi) {
    int best = lo;
    for (int i = lo; i < hi; ++i)
        if (v[static_cast<std::size_t>(i)] > v[static_cast<std::size_t>(best)]) best = i;
    if (best <= 0 || best + 1 >= static_cast<int>(v.size())) return best;
    const double a = v[static_cast<std::size_t>(best - 1)], b = v[static_cast<std::size_t>(best)],
                 c = v[static_cast<std::size_t>(best + 1)];
    const double den = a - 2.0 * b + c;
    return best + (den != 0.0 ? 0.5 * (a - c) / den : 0.0);
}

}  // namespace

TEST_CASE("sim.waves: lake at rest on a rough, partly dry bottom stays at rest") {
    // A rough bottom (random texels from -2 m to +0.9 m, so part of it is dry
    // land sticking out of the surface at 0.3713 m) plus a cliff island and a
    // smooth island; still water. 10^4 ticks at the default step.
    // The same lake at 0 m and lifted to a 1000 m mountain lake (eta rounds
    // at a coarser ulp there).
    const int n = 64;
    for (float lift : {0.0f, 1000.0f}) {
        TerrainState s = makeWaterState(n, n, 1.0f);
        setGround(s, [lift](int x, int y) {
            float b = -2.0f + 2.9f * hash01(x, y, 7);
            const float dx1 = static_cast<float>(x - 20), dy1 = static_cast<float>(y - 30);
            if (dx1 * dx1 + dy1 * dy1 < 36.0f) b = 3.0f;  // cliff island
            const float dx2 = static_cast<float>(x - 45), dy2 = static_cast<float>(y - 40);
            b += 2.5f * std::exp(-(dx2 * dx2 + dy2 * dy2) / 50.0f);  // smooth island
            return b + lift;
        });
        // A level that is not a round number, so h = level - b rounds and the
        // surface eta = h + b is only equal up to float rounding (at 0 m it would
        // be exact and the test too easy).
        fillToLevel(s, lift + 0.3713f);
        int dry = 0;
        for (float h : s.water.v) dry += h == 0.0f;
        REQUIRE(dry > n * n / 10);  // really partly dry
        REQUIRE(dry < n * n / 2);
        std::vector<float> eta0(s.water.v.size());
        float maxDepth = 0.0f;
        for (std::size_t i = 0; i < eta0.size(); ++i) {
            eta0[i] = s.water.v[i] + s.bedrock.v[i];
            maxDepth = std::max(maxDepth, s.water.v[i]);
        }
        WaveSettings ws;
        WaveScratch scratch;
        for (int t = 0; t < 10000; ++t) tickAdaptive(s, ws, scratch);
        const float maxVel = std::max(maxAbs(s.faceU), maxAbs(s.faceV));
        float maxMove = 0.0f;  // surface movement over wet cells, relative to the deepest water
        for (std::size_t i = 0; i < eta0.size(); ++i)
            if (s.water.v[i] > 0.0f || eta0[i] != s.bedrock.v[i])  // wet now or before
                maxMove = std::max(maxMove, std::fabs(s.water.v[i] + s.bedrock.v[i] - eta0[i]));
        MESSAGE("rest lake at " << lift << " m: max |velocity| " << maxVel << " m/s, max surface move "
                                << maxMove / maxDepth << " of the max depth " << maxDepth << " m");
        CHECK(maxVel <= 1e-5f);
        CHECK(maxMove / maxDepth <= 1e-5f);
        CHECK(allFinite(s));
    }
}

TEST_CASE("sim.waves: a small bump spreads at sqrt(g H)") {
    // 1-D strip, 1600 x 4 cells of 1 m. A Gaussian bump at 600 m (sigma 8 m,
    // amplitude 1e-3 H) splits into two pulses of speed c = sqrt(g H).
    // Measurement: the sub-cell peak (parabola through the largest sample) of
    // the surface right of the start, i.e. of the right-going pulse (the
    // left-going one, reflected at the west wall, stays 1200 m behind),
    // recorded every tick once the pulses have separated (travelled > 100 m)
    // until 800 m; speed = least-squares slope of position over time.
    for (float H : {1.0f, 10.0f}) {
        const int nx = 1600;
        TerrainState s = makeWaterState(nx, 4, 1.0f);
        setGround(s, [&](int, int) { return -H; });
        fillToLevel(s, 0.0f);
        const float x0 = 600.0f, sigma = 8.0f, amp = 1e-3f * H;
        for (int y = 0; y < s.ny; ++y)
            for (int x = 0; x < nx; ++x) {
                const float r = static_cast<float>(x) - x0;
                s.water(x, y) += amp * std::exp(-r * r / (2.0f * sigma * sigma));
            }
        WaveSettings ws;
        WaveScratch scratch;
        const double c = std::sqrt(9.81 * H);
        std::vector<double> ts, xs;
        while (s.time * c < 800.0) {
            tickAdaptive(s, ws, scratch);
            if (s.time * c < 100.0) continue;
            const std::vector<double> eta = stripSurface(s);
            ts.push_back(s.time);
            xs.push_back(peakPosition(eta, static_cast<int>(x0), nx) * s.cellSize);
        }
        const double speed = fitSlope(ts, xs);
        const double err = speed / c - 1.0;
        MESSAGE("H = " << H << " m: measured " << speed << " m/s, sqrt(gH) = " << c << " m/s, error " << err * 100
                       << " %");
        CHECK(std::fabs(err) < 0.02);
        CHECK(allFinite(s));
    }
}

TEST_CASE("sim.waves: dam break on a dry flat bed follows Ritter's solution") {
    // Flat dry bed, h_l = 1 m left of the dam (between cells 399 and 400,
    // x_d = 399.5 m), dry to the right, 1 m cells, closed far walls. Ritter:
    // h = 4/(9g) (sqrt(g h_l) - xi/(2t))^2 for -c0 t <= xi <= 2 c0 t, xi = x - x_d.
    // Front: the last cell deeper than theta = 1e-2 h_l. Ritter's own depth
    // reaches theta at xi = (2 - 3 sqrt(theta)) c0 t (0.85 of 2 c0 t), so the
    // numerical front is compared with that point, the error expressed as a
    // fraction of the full run-out 2 c0 t. (This first-order scheme's very tip
    // lags: at theta = 1e-3 the front is ~13 % short of 2 c0 t where Ritter
    // is 4.7 % short; the MESSAGE prints both.) L1 error: mean |h - h_Ritter|
    // over the wave region [x_d - c0 t, x_d + 2 c0 t], divided by h_l.
    const int nx = 1200, x0 = 400;
    const float hl = 1.0f;
    TerrainState s = makeWaterState(nx, 4, 1.0f);
    for (int y = 0; y < s.ny; ++y)
        for (int x = 0; x < x0; ++x) s.water(x, y) = hl;
    WaveSettings ws;
    WaveScratch scratch;
    const double g = 9.81, c0 = std::sqrt(g * hl), xd = x0 - 0.5;
    auto frontAt = [&](const std::vector<double>& h, double theta) {
        int front = 0;
        for (int x = 0; x < nx; ++x)
            if (h[static_cast<std::size_t>(x)] > theta * hl) front = x;
        return front - xd;
    };
    for (double tCheck : {40.0, 100.0}) {
        while (s.time < tCheck) {
            const float dt = std::min<float>(waveMaxDt(s, ws), static_cast<float>(tCheck - s.time) + 1e-6f);
            waveStep(s, ws, dt, scratch);
            s.time += dt;
        }
        const double t = s.time;
        const std::vector<double> h = stripSurface(s);  // ground is 0: surface = depth
        const double runOut = 2.0 * c0 * t;
        for (double theta : {1e-2, 1e-3, 1e-4}) {
            const double ritter = (2.0 - 3.0 * std::sqrt(theta)) * c0 * t;
            MESSAGE("t = " << t << " s, theta = " << theta << " h_l: front " << frontAt(h, theta) << " m, Ritter "
                           << ritter << " m, 2 c0 t = " << runOut << " m: error vs Ritter "
                           << (frontAt(h, theta) - ritter) / runOut * 100 << " %, vs 2 c0 t "
                           << (frontAt(h, theta) / runOut - 1.0) * 100 << " %");
        }
        const double theta = 1e-2;
        const double frontErr = (frontAt(h, theta) - (2.0 - 3.0 * std::sqrt(theta)) * c0 * t) / runOut;
        double l1 = 0.0;
        int cells = 0;
        for (int x = 0; x < nx; ++x) {
            const double xi = x - xd;
            if (xi < -c0 * t || xi > 2.0 * c0 * t) continue;
            const double a = c0 - xi / (2.0 * t);
            const double ritter = 4.0 / (9.0 * g) * a * a;
            l1 += std::fabs(h[static_cast<std::size_t>(x)] - ritter);
            ++cells;
        }
        l1 /= cells * static_cast<double>(hl);
        MESSAGE("t = " << t << " s: L1 depth error " << l1 * 100 << " % of h_l over " << cells << " cells");
        CHECK(std::fabs(frontErr) <= 0.05);
        CHECK(l1 <= 0.05);
    }
    CHECK(allFinite(s));
}

TEST_CASE("sim.waves: first seiche period of a closed basin is 2L / sqrt(g H)") {
    // Closed basin L = 100 m (100 cells between the walls), H = 2 m, initial
    // surface A cos(pi x / L) with A = 1e-3 H (x from the west wall to each cell
    // centre). The surface at the west-end cell crosses zero every half period:
    // crossing times by linear interpolation, period = 2 x least-squares slope
    // of crossing time over crossing index, over ~6 periods.
    const int nx = 100;
    const float H = 2.0f, L = 100.0f;
    TerrainState s = makeWaterState(nx, 3, 1.0f);
    setGround(s, [&](int, int) { return -H; });
    fillToLevel(s, 0.0f);
    const float amp = 1e-3f * H;
    for (int y = 0; y < s.ny; ++y)
        for (int x = 0; x < nx; ++x) s.water(x, y) += amp * static_cast<float>(std::cos(kPi * (x + 0.5) / L));
    const double T = 2.0 * L / std::sqrt(9.81 * H);
    WaveSettings ws;
    WaveScratch scratch;
    std::vector<double> crossings, idx;
    double prevEta = amp, prevT = 0.0;
    while (s.time < 6.2 * T) {
        tickAdaptive(s, ws, scratch);
        const double eta = s.water(0, 1) - H;
        if ((eta > 0.0) != (prevEta > 0.0)) {
            crossings.push_back(prevT + (s.time - prevT) * prevEta / (prevEta - eta));
            idx.push_back(static_cast<double>(idx.size()));
        }
        prevEta = eta;
        prevT = s.time;
    }
    REQUIRE(crossings.size() >= 10);
    const double period = 2.0 * fitSlope(idx, crossings);
    const double err = period / T - 1.0;
    MESSAGE("seiche: measured period " << period << " s, 2L/sqrt(gH) = " << T << " s, error " << err * 100 << " %");
    CHECK(std::fabs(err) < 0.01);
}

TEST_CASE("sim.waves: water mass is conserved with closed boundaries") {
    // Rough, partly dry basin with a tilted surface and a bump: waves run up
    // and down the shores for 1000 ticks.
    TerrainState s = makeWaterState(96, 80, 2.0f);
    setGround(s, [](int x, int y) {
        return -3.0f + 0.06f * static_cast<float>(x) + 1.5f * hash01(x, y, 3) +
               2.0f * std::sin(0.2f * static_cast<float>(y));
    });
    for (int y = 0; y < s.ny; ++y)
        for (int x = 0; x < s.nx; ++x) {
            const float level = 0.5f - 0.01f * static_cast<float>(x) +
                                0.8f * std::exp(-(std::pow(x - 30.0f, 2.0f) + std::pow(y - 40.0f, 2.0f)) / 40.0f);
            s.water(x, y) = std::max(0.0f, level - s.ground(x, y));
        }
    const double m0 = totalWater(s);
    WaveSettings ws;
    WaveScratch scratch;
    for (int t = 0; t < 1000; ++t) tickAdaptive(s, ws, scratch);
    const double rel = std::fabs(totalWater(s) - m0) / m0;
    MESSAGE("mass: relative change " << rel << " after 1000 ticks, max |u| " << maxAbs(s.faceU) << " m/s");
    CHECK(rel <= 1e-5);
    CHECK(minValue(s.water) >= 0.0f);
    CHECK(allFinite(s));
}

TEST_CASE("sim.waves: hard cases stay finite") {
    struct Case {
        const char* name;
        int nx, ny;
        std::function<void(TerrainState&, WaveSettings&)> setup;
    };
    auto drop = [](float x, float y, float r, float h) {
        WaveDrop d;
        d.time = 0.0;
        d.x = x;
        d.y = y;
        d.radius = r;
        d.height = h;
        return d;
    };
    const std::vector<Case> cases = {
        {"1000 m vertical cliff under water", 40, 30,
         [&](TerrainState& s, WaveSettings& ws) {
             setGround(s, [](int x, int) { return x < 20 ? -1000.0f : 0.0f; });
             fillToLevel(s, 5.0f);
             ws.drops.push_back(drop(20.0f, 15.0f, 3.0f, 2.0f));
         }},
        {"one-texel spike", 33, 33,
         [&](TerrainState& s, WaveSettings& ws) {
             setGround(s, [](int x, int y) { return (x == 16 && y == 16) ? 500.0f : 0.0f; });
             fillToLevel(s, 1.0f);
             s.water(16, 16) = 3.0f;  // water on the spike top falls off it
             ws.drops.push_back(drop(10.0f, 16.0f, 2.0f, 0.5f));
         }},
        {"flat dry plane", 17, 9, [&](TerrainState&, WaveSettings&) {}},
        {"flat plane under water", 17, 9, [&](TerrainState& s, WaveSettings&) { fillToLevel(s, 1.0f); }},
        {"heights of 1e5 m", 40, 30,
         [&](TerrainState& s, WaveSettings& ws) {
             setGround(s, [](int x, int y) { return 1.0e5f + 3.0f * hash01(x, y, 1); });
             fillToLevel(s, 1.0e5f + 2.0f);
             ws.drops.push_back(drop(20.0f, 15.0f, 3.0f, 1.0f));
         }},
        {"negative heights", 40, 30,
         [&](TerrainState& s, WaveSettings& ws) {
             setGround(s, [](int x, int y) { return -5000.0f + 10.0f * hash01(x, y, 2) + 0.5f * x; });
             fillToLevel(s, -4985.0f);
             ws.drops.push_back(drop(20.0f, 15.0f, 3.0f, 1.0f));
         }},
        {"1000 m water column beside dry land", 40, 30,
         [&](TerrainState& s, WaveSettings&) {
             for (int y = 10; y < 20; ++y)
                 for (int x = 5; x < 15; ++x) s.water(x, y) = 1000.0f;
         }},
        {"1x1 grid", 1, 1,
         [&](TerrainState& s, WaveSettings& ws) {
             s.water(0, 0) = 2.0f;
             ws.drops.push_back(drop(0.0f, 0.0f, 1.0f, 1.0f));
         }},
        {"2x2 grid", 2, 2,
         [&](TerrainState& s, WaveSettings& ws) {
             s.water(0, 0) = 5.0f;
             s.bedrock(1, 1) = 10.0f;
             ws.drops.push_back(drop(1.0f, 0.0f, 1.0f, 1.0f));
             ws.swell.enabled = true;
             ws.swell.seaLevel = 2.0f;
         }},
        {"1 x 7 strip with a swell", 1, 7,
         [&](TerrainState& s, WaveSettings& ws) {
             fillToLevel(s, 1.0f);
             ws.swell.enabled = true;
             ws.swell.edge = 3;
             ws.swell.seaLevel = 1.0f;
             ws.swell.period = 2.0f;
         }},
    };
    for (const Case& c : cases) {
        TerrainState s = makeWaterState(c.nx, c.ny, 1.0f);
        WaveSettings ws;
        c.setup(s, ws);
        const double m0 = totalWater(s);
        WaveScratch scratch;
        float dtMin = 1e30f, dtMax = 0.0f;
        for (int t = 0; t < 400; ++t) {
            const float dt = tickAdaptive(s, ws, scratch);
            dtMin = std::min(dtMin, dt);
            dtMax = std::max(dtMax, dt);
        }
        INFO(c.name);
        MESSAGE(std::string(c.name) << ": dt " << dtMin << " .. " << dtMax << " s, max |u| "
                                    << std::max(maxAbs(s.faceU), maxAbs(s.faceV)) << " m/s, water " << m0 << " -> "
                                    << totalWater(s));
        CHECK(allFinite(s));
        CHECK(minValue(s.water) >= 0.0f);
        CHECK(std::isfinite(dtMin));
        CHECK(dtMin > 0.0f);
    }
}

TEST_CASE("sim.waves: a step far above the CFL limit is sub-stepped, not blown up") {
    TerrainState s = makeWaterState(50, 20, 1.0f);
    for (int y = 0; y < s.ny; ++y)
        for (int x = 0; x < 25; ++x) s.water(x, y) = 20.0f;
    WaveSettings ws;
    WaveScratch scratch;
    const double m0 = totalWater(s);
    const float dt = 10.0f * waveMaxDt(s, ws);
    for (int t = 0; t < 50; ++t) {
        waveStep(s, ws, dt, scratch);
        s.time += dt;
    }
    CHECK(scratch.lastSubsteps > 1);
    CHECK(allFinite(s));
    CHECK(std::fabs(totalWater(s) - m0) / m0 <= 1e-5);
}

TEST_CASE("sim.waves: bit-identical results for 1, 2, 3 and 8 threads") {
    // Non-power-of-two grids with a drop and a swell. 307 x 211 spans several
    // row chunks of parallelForRows (16384 cells each), so the threads really
    // split the work; 67 x 45 is a single chunk.
    for (const auto& size : {std::pair{307, 211}, std::pair{67, 45}}) {
        const int nx = size.first, ny = size.second;  // plain locals: INFO and the lambda capture them
        auto run = [nx, ny] {
            TerrainState s = makeWaterState(nx, ny, 1.5f);
            setGround(s, [](int x, int y) { return -4.0f + 0.05f * static_cast<float>(x) + 2.0f * hash01(x, y, 11); });
            fillToLevel(s, 0.0f);
            WaveSettings ws;
            ws.friction = 0.02f;
            ws.swell.enabled = true;
            ws.swell.edge = 2;
            ws.swell.amplitude = 0.2f;
            ws.swell.period = 5.0f;
            WaveDrop d;
            d.time = 1.0;
            d.x = 0.4f * nx * 1.5f;
            d.y = 0.6f * ny * 1.5f;
            d.radius = 4.0f;
            d.height = 0.8f;
            ws.drops.push_back(d);
            WaveScratch scratch;
            std::vector<std::uint64_t> hashes;
            for (int t = 0; t < 60; ++t) {
                tickAdaptive(s, ws, scratch);
                if (t % 20 == 19) hashes.push_back(hashState(s));
            }
            return hashes;
        };
        const auto h1 = withThreads(1, run);
        CHECK(h1.front() != h1.back());  // the state really evolves
        for (int threads : {2, 3, 8}) {
            INFO(nx << "x" << ny << ", threads " << threads);
            CHECK(withThreads(threads, run) == h1);
        }
    }
}

TEST_CASE("sim.waves: swell enters, propagates and stays bounded") {
    // Flat 5 m deep channel, 240 x 24 cells of 2 m, swell through each edge in
    // turn (amplitude 0.1 m, period 8 s: wavelength ~56 m), closed elsewhere,
    // so the far wall reflects and the swell edge must let the reflection out.
    // 12 periods. Interior: cells more than a wavelength from the swell edge.
    for (int edge = 0; edge < 4; ++edge) {
        const bool alongX = edge < 2;
        const int nx = alongX ? 240 : 24, ny = alongX ? 24 : 240;
        TerrainState s = makeWaterState(nx, ny, 2.0f);
        setGround(s, [](int, int) { return -5.0f; });
        fillToLevel(s, 0.0f);
        WaveSettings ws;
        ws.swell.enabled = true;
        ws.swell.edge = edge;
        ws.swell.amplitude = 0.1f;
        ws.swell.period = 8.0f;
        WaveScratch scratch;
        double energy = 0.0;  // mean eta^2 over the interior during the last 4 periods
        int samples = 0;
        float maxEta = 0.0f;
        while (s.time < 12.0 * ws.swell.period) {
            tickAdaptive(s, ws, scratch);
            if (s.time < 8.0 * ws.swell.period) continue;
            for (int y = 0; y < ny; ++y)
                for (int x = 0; x < nx; ++x) {
                    const int dist = edge == 0 ? x : edge == 1 ? nx - 1 - x : edge == 2 ? y : ny - 1 - y;
                    const float eta = s.water(x, y) - 5.0f;
                    maxEta = std::max(maxEta, std::fabs(eta));
                    if (dist * 2.0f < 60.0f) continue;
                    energy += static_cast<double>(eta) * eta;
                    ++samples;
                }
        }
        const double rms = std::sqrt(energy / samples);
        MESSAGE("swell edge " << edge << ": interior rms eta " << rms << " m (a progressive wave of 0.1 m: "
                              << 0.1 / std::sqrt(2.0) << "), max |eta| " << maxEta << " m");
        CHECK(allFinite(s));
        CHECK(rms > 0.05);      // the wave is in the interior
        CHECK(maxEta < 0.35f);  // standing wave against the far wall: <= 2 A, plus a margin; no blow-up
    }
}

TEST_CASE("sim.waves: an open (Flather) edge lets an outgoing pulse leave") {
    // 1-D strip, 5 m deep, swell edge 0 with zero amplitude is a pure
    // radiation boundary. A bump's left half leaves through it at once, the
    // right half after reflecting from the far wall. Energy left afterwards
    // (potential + kinetic, relative to the start) measures the reflection.
    const int nx = 400;
    const float H = 5.0f;
    TerrainState s = makeWaterState(nx, 4, 1.0f);
    setGround(s, [&](int, int) { return -H; });
    fillToLevel(s, 0.0f);
    for (int y = 0; y < s.ny; ++y)
        for (int x = 0; x < nx; ++x) s.water(x, y) += 0.01f * std::exp(-std::pow((x - 200.0f) / 10.0f, 2.0f));
    auto energy = [&] {
        double e = 0.0;
        for (int y = 0; y < s.ny; ++y)
            for (int x = 0; x < nx; ++x) {
                const double eta = s.water(x, y) - H;
                const double u = 0.5 * (s.faceU(x, y) + s.faceU(x + 1, y));
                e += 0.5 * 9.81 * eta * eta + 0.5 * H * u * u;
            }
        return e;
    };
    const double e0 = energy();
    WaveSettings ws;
    ws.swell.enabled = true;
    ws.swell.edge = 0;
    ws.swell.amplitude = 0.0f;
    WaveScratch scratch;
    const double c = std::sqrt(9.81 * H);
    while (s.time < 1.3 * (200.0 + nx) / c) tickAdaptive(s, ws, scratch);
    const double left = energy() / e0;
    MESSAGE("open edge: energy left after the pulses passed out: " << left * 100 << " %");
    CHECK(left < 0.02);
}

TEST_CASE("sim.waves: a drop adds its volume and makes a ring wave") {
    // Flat 2 m deep pool, 128 x 128 cells of 1 m, one drop (sigma 3 m, 0.2 m)
    // in the centre at t = 0.5 s. Added volume = height 2 pi sigma^2; after
    // 6 s the ring's crest sits near c t from the centre, the same in x and y.
    const int n = 128;
    TerrainState s = makeWaterState(n, n, 1.0f);
    setGround(s, [](int, int) { return -2.0f; });
    fillToLevel(s, 0.0f);
    WaveSettings ws;
    WaveDrop d;
    d.time = 0.5;
    d.x = 64.0f;
    d.y = 64.0f;
    d.radius = 3.0f;
    d.height = 0.2f;
    ws.drops.push_back(d);
    WaveScratch scratch;
    const double m0 = totalWater(s);
    while (s.time < 0.5) tickAdaptive(s, ws, scratch);
    const double added = totalWater(s) - m0;
    const double expected = d.height * 2.0 * kPi * d.radius * d.radius;
    MESSAGE("drop volume " << added << " m^3, expected " << expected);
    CHECK(std::fabs(added / expected - 1.0) < 0.01);
    while (s.time < 6.5) tickAdaptive(s, ws, scratch);
    std::vector<double> rowX(n), colY(n);
    for (int i = 0; i < n; ++i) {
        rowX[static_cast<std::size_t>(i)] = s.water(i, 64) - 2.0;
        colY[static_cast<std::size_t>(i)] = s.water(64, i) - 2.0;
    }
    const double rx = peakPosition(rowX, 66, n) - 64.0;
    const double ry = peakPosition(colY, 66, n) - 64.0;
    const double ct = std::sqrt(9.81 * 2.0) * (s.time - 0.5);
    MESSAGE("ring crest at " << rx << " m (x) and " << ry << " m (y), c t = " << ct << " m");
    CHECK(std::fabs(rx / ct - 1.0) < 0.15);
    CHECK(std::fabs(rx - ry) < 1e-3);
    CHECK(allFinite(s));
}
