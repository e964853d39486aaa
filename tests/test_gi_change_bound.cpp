// gi/change_bound: bounds on how much the visibility scan and the ambient
// light can change when the heights change. Box maxima against brute force,
// the reach of pyramid samples against single-cell changes, the SH constants
// against quadrature, and the tile bounds against the engine's own frames
// before and after perturbations of a terrain.
#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <span>
#include <sstream>
#include <vector>

#include <doctest/doctest.h>

#include "core/error.h"
#include "gi/change_bound.h"
#include "gi/frame.h"
#include "gi/nlp.h"
#include "gi/sh.h"
#include "gi/visibility_cache.h"
#include "tests/gi_test_terrain.h"

using namespace terrain;
using namespace terrain::gi;
using gi_test::gridOf;

namespace {

constexpr float kCell = 2.0f;  // metres

float bruteMax(const Grid& g, int x0, int y0, int x1, int y1) {
    float m = 0.0f;
    for (int y = std::max(y0, 0); y <= std::min(y1, g.ny - 1); ++y)
        for (int x = std::max(x0, 0); x <= std::min(x1, g.nx - 1); ++x) m = std::max(m, std::fabs(g(x, y)));
    return m;
}

// Rolling hills, a cliff along a wavy line (high side x > cliffEdge) and a
// little noise, heights in metres.
float cliffEdge(int nx, int y) {
    return 0.62f * static_cast<float>(nx) + 4.0f * std::sin(0.2f * static_cast<float>(y));
}

Grid baseTerrain(int nx, int ny) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> noise(-0.25f, 0.25f);
    return gridOf(nx, ny, [&](int x, int y) {
        const float fx = static_cast<float>(x), fy = static_cast<float>(y);
        const float hills =
            14.0f * std::sin(0.13f * fx) * std::cos(0.11f * fy) + 5.0f * std::sin(0.37f * fx + 0.29f * fy);
        return hills + (fx > cliffEdge(nx, y) ? 10.0f : 0.0f) + noise(rng);
    });
}

enum class Change { Bump, Noise, CliffCollapse, Spike, EdgeSpikes };
const char* nameOf(Change c) {
    switch (c) {
        case Change::Bump:
            return "bump";
        case Change::Noise:
            return "noise";
        case Change::CliffCollapse:
            return "cliff collapse";
        case Change::Spike:
            return "spike";
        case Change::EdgeSpikes:
            return "edge spikes";
    }
    return "";
}

// (a) a local Gaussian bump (cut at 4 sigma), (b) low-amplitude noise
// everywhere, (c) the cliff's edge lowered and its foot raised over a stretch
// of rows, (d) one texel raised, (e) texels on the last column and row raised
// (where the grid's edge cuts the octaves' blocks, whose cells weigh more).
Grid perturbed(const Grid& base, Change c, unsigned seed) {
    Grid g = base;
    const int nx = g.nx, ny = g.ny;
    std::mt19937 rng(seed);
    if (c == Change::Bump) {
        const float cx = 0.35f * nx, cy = 0.45f * ny, sigma = 3.0f;
        for (int y = 0; y < ny; ++y)
            for (int x = 0; x < nx; ++x) {
                const float r2 = (x - cx) * (x - cx) + (y - cy) * (y - cy);
                if (r2 < 16.0f * sigma * sigma) g(x, y) += 3.0f * std::exp(-r2 / (2.0f * sigma * sigma));
            }
    } else if (c == Change::Noise) {
        std::uniform_real_distribution<float> u(-0.02f, 0.02f);
        for (float& v : g.v) v += u(rng);
    } else if (c == Change::CliffCollapse) {
        for (int y = static_cast<int>(0.3f * ny); y < static_cast<int>(0.6f * ny); ++y)
            for (int x = 0; x < nx; ++x) {
                const float d = static_cast<float>(x) - cliffEdge(nx, y);
                if (d > 0.0f && d <= 3.0f)
                    g(x, y) -= 6.0f * (1.0f - d / 4.0f);
                else if (d <= 0.0f && d > -5.0f)
                    g(x, y) += 3.0f * (1.0f + d / 5.0f);
            }
    } else if (c == Change::Spike) {
        g(static_cast<int>(0.7f * nx), static_cast<int>(0.25f * ny)) += 8.0f;
    } else {
        g(nx - 1, ny - 1) += 8.0f;
        g(nx - 1, ny / 3) -= 5.0f;
        g(nx / 4, ny - 1) += 6.0f;
    }
    return g;
}

float maxAbs(const Grid& g) {
    float m = 0.0f;
    for (float v : g.v) m = std::max(m, std::fabs(v));
    return m;
}

double median(std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    return v[v.size() / 2];
}

// What one before / after comparison found.
struct Comparison {
    int slopeOver = 0, ambientOver = 0;           // receivers past bound + allowance
    int azimuthOver = 0, azimuthAmbientOver = 0;  // the same for the per-azimuth bounds (per receiver and azimuth)
    int azimuthAboveTile = 0;                     // per-azimuth bounds above the tile's bound over all azimuths
    double worstAzimuth = 0.0, worstAzimuthAmbient = 0.0;
    std::vector<double> tileAzimuthAmbientLoose;   // per tile: per-azimuth ambient bound / largest change
    double worstSlope = 0.0, worstAmbient = 0.0;   // largest change / bound
    std::vector<double> slopeLoose, ambientLoose;  // per receiver: bound / change where the change is clearly non-zero
    std::vector<double> tileSlopeLoose, tileAmbientLoose;  // per tile: bound / largest change in the tile
};

// Per tile: the bound and the largest change of its receivers.
struct TileChange {
    double slopeBound = 0.0, ambientBound = 0.0, azimuthAmbientBound = 0.0, slope = 0.0, ambient = 0.0;
};

void addTileLooseness(const std::vector<TileChange>& tiles, Comparison& c) {
    for (const TileChange& t : tiles) {
        if (t.slope > 1e-3) c.tileSlopeLoose.push_back(t.slopeBound / t.slope);
        if (t.ambient > 1e-4) c.tileAmbientLoose.push_back(t.ambientBound / t.ambient);
        if (t.ambient > 1e-4) c.tileAzimuthAmbientLoose.push_back(t.azimuthAmbientBound / t.ambient);
    }
}

// Frames a (heights h0) and b (h1): every receiver's maximum blocking slope
// at every azimuth and its ambient texel against its tile's bounds.
Comparison compareFrames(const GiState& a, const GiState& b, const Grid& h0, const Grid& h1, int T, float lipschitz) {
    MaxChangePyramid dh;
    buildMaxChangePyramid(h0.cview(), h1.cview(), dh);
    std::vector<float> slopeBound, gradBound;
    boundSlopeChange(dh, a.pyramid, T, slopeBound);
    boundGradientChange(dh, a.pyramid, T, gradBound);
    const HeightPyramid& p = a.pyramid;
    const int nxr = p.nxr, nyr = p.nyr, s = p.subsample, tilesX = tileCount(nxr, T);
    const int m = static_cast<int>(a.envVisibility.maxSlope.size() / (static_cast<std::size_t>(nxr) * nyr));
    std::vector<float> azimuthBound;
    boundSlopeChangePerAzimuth(dh, a.pyramid, T, m, azimuthBound);
    std::vector<float> perAzimuth(static_cast<std::size_t>(m));
    // Float rounding: a level sample is some dozen float operations deep,
    // each off by half an ulp of a height at most, and the slope divides by
    // the step (>= 1 cell); before and after round independently.
    const double hMax = std::max(maxAbs(h0), maxAbs(h1));
    const double heightUlps = 64.0 * FLT_EPSILON * hMax / kCell;
    Comparison c;
    std::vector<TileChange> tiles(slopeBound.size());
    for (int Y = 0; Y < nyr; ++Y)
        for (int X = 0; X < nxr; ++X) {
            const std::size_t t = static_cast<std::size_t>(Y / T) * tilesX + static_cast<std::size_t>(X / T);
            const double sb = lipschitz * slopeBound[t];
            double change = 0.0, allowance = 0.0;
            for (int j = 0; j < m; ++j) {
                const std::size_t i = (static_cast<std::size_t>(j) * nyr + Y) * nxr + X;
                const double s0 = a.envVisibility.maxSlope[i], s1 = b.envVisibility.maxSlope[i];
                const double cj = std::fabs(s1 - s0);
                const double aj = heightUlps + 4.0 * FLT_EPSILON * std::max(std::fabs(s0), std::fabs(s1));
                change = std::max(change, cj);
                allowance = std::max(allowance, aj);
                const float bj = azimuthBound[t * static_cast<std::size_t>(m) + static_cast<std::size_t>(j)];
                perAzimuth[static_cast<std::size_t>(j)] = lipschitz * bj;
                c.azimuthOver += cj > lipschitz * bj + aj;
                c.azimuthAboveTile += bj > slopeBound[t];
                if (bj > 0.0f) c.worstAzimuth = std::max(c.worstAzimuth, cj / (lipschitz * bj));
            }
            c.slopeOver += change > sb + allowance;
            if (sb > 0.0) c.worstSlope = std::max(c.worstSlope, change / sb);
            if (change > 1e-3) c.slopeLoose.push_back(sb / change);
            const double ab = ambientChangeBound(static_cast<float>(sb), gradBound[t], 1.0f, true);
            const double ambChange = std::fabs(b.shade.ambient(s * X, s * Y) - a.shade.ambient(s * X, s * Y));
            c.ambientOver += ambChange > ab + 1e-5;  // a few ulp of values about 1
            const double azb = ambientChangeBoundPerAzimuth(perAzimuth.data(), m, gradBound[t], 1.0f, true);
            c.azimuthAmbientOver += ambChange > azb + 1e-5;
            if (azb > 0.0) c.worstAzimuthAmbient = std::max(c.worstAzimuthAmbient, ambChange / azb);
            if (ab > 0.0) c.worstAmbient = std::max(c.worstAmbient, ambChange / ab);
            if (ambChange > 1e-4) c.ambientLoose.push_back(ab / ambChange);
            tiles[t] = {sb, ab, std::max(tiles[t].azimuthAmbientBound, azb), std::max(tiles[t].slope, change),
                        std::max(tiles[t].ambient, ambChange)};
        }
    addTileLooseness(tiles, c);
    return c;
}

void runFrame(const Grid& h, const GiSettings& settings, GiState& st) {
    runGiFrame(h.cview(), kCell, GiLighting{}, settings, st);
}

struct Config {
    int nx, ny, subsample, tile;
    bool paper;  // paperGiSettings (Eq. 16's maximum, mean pyramid, receiver tangent planes) instead of GiSettings{}
};

}  // namespace

TEST_CASE("gi.change_bound: |b - a| rounded up in float arithmetic is the exact difference rounded up") {
    // exponents within 28 of each other: the difference of two floats is then
    // exact in double (24 + 28 bits), and rounding it up is the reference
    const auto reference = [](float a, float b) {
        const double v = std::fabs(static_cast<double>(b) - static_cast<double>(a));
        float f = static_cast<float>(v);
        if (static_cast<double>(f) < v) f = std::nextafter(f, std::numeric_limits<float>::infinity());
        return f;
    };
    std::mt19937 rng(11);
    std::uniform_int_distribution<int> exponent(-14, 14);
    const auto randomFloat = [&](int e) {
        const float m = 1.0f + static_cast<float>(rng() % (1u << 23)) * 0x1p-23f;
        return (rng() % 2 ? m : -m) * std::ldexp(1.0f, e);
    };
    int inexact = 0;
    for (int i = 0; i < 200000; ++i) {
        const float a = randomFloat(exponent(rng));
        // a near neighbour half of the time (exact float differences), any float the rest
        const float b = i % 2 ? a + randomFloat(std::max(-14, exponent(rng) / 2 - 8)) : randomFloat(exponent(rng));
        const float got = absDifferenceUp(a, b);
        REQUIRE(got == reference(a, b));
        const simd::F4 lanes = absDifferenceUp(simd::splat<simd::F4>(a), simd::F4{b, a, b, 0.0f});
        CHECK((lanes[0] == got && lanes[1] == 0.0f && lanes[2] == got));
        CHECK(absDifferenceUp(b, a) == got);
        inexact += static_cast<double>(got) != std::fabs(static_cast<double>(b) - static_cast<double>(a));
    }
    CHECK(inexact > 10000);  // both kinds were met
    CHECK(absDifferenceUp(3.0f, 3.0f) == 0.0f);
    CHECK(absDifferenceUp(0.0f, std::numeric_limits<float>::denorm_min()) == std::numeric_limits<float>::denorm_min());
    // far apart the double difference is rounded itself; the float one still bounds it
    const float big = 0x1.eae2b4p+28f, tiny = -0x1.221ba4p-28f;
    CHECK(absDifferenceUp(tiny, big) > big);
}

TEST_CASE(
    "gi.change_bound: box maxima equal the brute-force maximum, the covering blocks bound it from a slightly larger "
    "box, "
    "box sums bound the brute-force sum") {
    std::mt19937 rng(7);
    MaxChangePyramid p;
    for (int trial = 0; trial < 30; ++trial) {
        const int nx = 1 + static_cast<int>(rng() % 90), ny = 1 + static_cast<int>(rng() % 90);
        std::uniform_real_distribution<float> u(-1.0f, 1.0f);
        // sparse changes half of the time: most blocks zero, as after a local edit
        const bool sparse = trial % 2 == 1;
        const Grid dh = gridOf(nx, ny, [&](int, int) { return sparse && rng() % 16 != 0 ? 0.0f : u(rng); });
        buildMaxChangePyramid(dh.cview(), p);
        for (int q = 0; q < 200; ++q) {
            const int x0 = static_cast<int>(rng() % (nx + 10)) - 5, y0 = static_cast<int>(rng() % (ny + 10)) - 5;
            const int x1 = x0 + static_cast<int>(rng() % (q % 2 ? 6 : nx + 5));
            const int y1 = y0 + static_cast<int>(rng() % (q % 2 ? 6 : ny + 5));
            const float exact = bruteMax(dh, x0, y0, x1, y1);
            CHECK(maxChangeInBox(p, x0, y0, x1, y1) == exact);
            // the covering blocks: at least the box's maximum, at most that of
            // the box grown by a third of its longer side (clamped to the grid)
            const int grow =
                (std::max(std::min(x1, nx - 1) - std::max(x0, 0), std::min(y1, ny - 1) - std::max(y0, 0)) + 1) / 3 + 1;
            const float covering = maxChangeCoveringBox(p, x0, y0, x1, y1);
            CHECK(covering >= exact);
            CHECK(covering <= bruteMax(dh, x0 - grow, y0 - grow, x1 + grow, y1 + grow));
            CHECK(maxChangeCoveringBox(p, x0, y0, x1, y1, 2.0f) == 2.0f);  // |dh| <= 1 here
            double sum = 0.0;
            for (int y = std::max(y0, 0); y <= std::min(y1, ny - 1); ++y)
                for (int x = std::max(x0, 0); x <= std::min(x1, nx - 1); ++x) sum += std::fabs(dh(x, y));
            CHECK(sumChangeInBox(p, x0, y0, x1, y1) >= sum * (1.0 - 1e-12));
        }
        CHECK(sumChangeInBox(p, 0, 0, nx - 1, ny - 1) <= [&] {
            double all = 0.0;
            for (float v : dh.v) all += std::fabs(v);
            return all * (1.0 + 1e-6) + 1e-30;
        }());
        // boxes on the block edges of level k (cut by the grid's edge) are exact
        for (int k = 0; k < static_cast<int>(p.levels.size()); ++k) {
            const int b = 1 << k, bx = static_cast<int>(rng() % static_cast<unsigned>(p.levels[k].nx));
            const int by = static_cast<int>(rng() % static_cast<unsigned>(p.levels[k].ny));
            const int cx = 1 + static_cast<int>(rng() % 4), cy = 1 + static_cast<int>(rng() % 4);
            const int x0 = bx * b, y0 = by * b, x1 = (bx + cx) * b - 1, y1 = (by + cy) * b - 1;
            CHECK(maxChangeInBox(p, x0, y0, x1, y1) == bruteMax(dh, x0, y0, x1, y1));
        }
        CHECK(maxChangeAll(p) == bruteMax(dh, 0, 0, nx - 1, ny - 1));
    }
    // a rebuild of the same size reuses every buffer
    const Grid a = gridOf(37, 21, [](int x, int y) { return static_cast<float>(x - y); });
    buildMaxChangePyramid(a.cview(), p);
    std::vector<const float*> before;
    for (const Grid& g : p.levels) before.push_back(g.data());
    buildMaxChangePyramid(a.cview(), gridOf(37, 21, [](int x, int) { return static_cast<float>(x); }).cview(), p);
    for (std::size_t k = 0; k < p.levels.size(); ++k) CHECK(p.levels[k].data() == before[k]);
    CHECK(maxChangeAll(p) == 20.0f);
}

TEST_CASE("gi.change_bound: a height change moves pyramid levels only within the reach, by at most its size") {
    const int nx = 150, ny = 101;
    const Grid base = baseTerrain(nx, ny);
    for (int s : {1, 2, 4})
        for (float blend : {0.0f, 0.5f}) {
            PyramidSettings ps;
            ps.peakBlend = blend;
            ps.levelOffset = 1;  // more level steps on a small grid
            HeightPyramid p0, p1;
            buildHeightPyramid(base.cview(), kCell, s, ps, p0);
            const std::vector<float> reach = stepReachCells(p0);
            double tightest = 0.0;
            for (const int cx : {0, 37, nx - 1}) {
                const int cy = cx == 37 ? 52 : cx % ny;
                Grid h = base;
                h(cx, cy) += 4.0f;
                buildHeightPyramid(h.cview(), kCell, s, ps, p1);
                for (std::size_t i = 0; i < p0.steps.size(); ++i) {
                    const int level = p0.steps[i].level;
                    if (level < 0) continue;
                    const double r = reach[i] - s;  // the level texel's own reach
                    const PaddedField &a = p0.levels[static_cast<std::size_t>(level)],
                                      &b = p1.levels[static_cast<std::size_t>(level)];
                    int far = -1;
                    float worst = 0.0f;
                    for (int Y = 0; Y < p0.nyr; ++Y)
                        for (int X = 0; X < p0.nxr; ++X) {
                            const float d = std::fabs(b.row(Y)[X] - a.row(Y)[X]);
                            if (d == 0.0f) continue;
                            far = std::max(far, std::max(std::abs(s * X - cx), std::abs(s * Y - cy)));
                            worst = std::max(worst, d);
                        }
                    CHECK(far <= r);
                    CHECK(worst <= 4.0f * heightFilterLipschitz(p0) * (1.0f + 1e-5f));
                    tightest = std::max(tightest, far / r);
                }
            }
            MESSAGE("s=" << s << " peak blend " << blend << ": farthest changed level texel / its reach " << tightest);
        }
}

TEST_CASE("gi.change_bound: away from the image edges a mean level weighs one cell by at most (2/3)^2 4^-o") {
    // the B-spline's largest tap is 2/3 per axis; a cell lies in one texel of
    // the mean octave o, with weight 4^-o, and the level blend and the
    // bilinear read are convex: a change of one cell by 1 moves every texel
    // of a level whose finer octave is o by at most (2/3)^2 4^-o, where no
    // clamped tap lands on the cell's texel
    const int nx = 300, ny = 260, cx = 150, cy = 131;
    const Grid base = baseTerrain(nx, ny);
    for (int s : {1, 2}) {
        PyramidSettings ps;
        ps.peakBlend = 0.0f;  // the mean octaves alone
        HeightPyramid p0, p1;
        buildHeightPyramid(base.cview(), kCell, s, ps, p0);
        Grid h = base;
        h(cx, cy) += 1.0f;
        buildHeightPyramid(h.cview(), kCell, s, ps, p1);
        const int kv = std::max(1, ps.levelsPerOctave);
        double tightest = 0.0;
        int checked = 0;
        for (std::size_t l = 0; l < p0.levels.size(); ++l) {
            const int o = std::min(static_cast<int>(l) / kv, p0.octaves - 1);
            // the cell's texel is neither the first nor the last of octaves o and o + 1
            const int block = 1 << (o + 1);
            if (o < 1 || cx < block || cy < block || nx - cx <= 2 * block || ny - cy <= 2 * block) continue;
            const double bound = 4.0 / 9.0 * std::ldexp(1.0, -2 * o);
            float worst = 0.0f;
            for (int Y = 0; Y < p0.nyr; ++Y)
                for (int X = 0; X < p0.nxr; ++X)
                    worst = std::max(worst, std::fabs(p1.levels[l].row(Y)[X] - p0.levels[l].row(Y)[X]));
            CHECK(worst <= bound * (1.0 + 1e-4) + 1e-6);
            tightest = std::max(tightest, worst / bound);
            ++checked;
        }
        CHECK(checked >= 2);
        MESSAGE("s=" << s << ": " << checked << " levels, largest move / (2/3)^2 4^-o " << tightest);
    }
}

TEST_CASE("gi.change_bound: SH constants cover the engine's horizon kernel") {
    // k(t) = sum_l z_l sqrt((2l + 1) / (4 pi)) P_l(t) / pi: lam(N) . V is the integral of W k(N . w)
    const double* zh = lambertZonal();
    const double kPiD = 3.14159265358979323846;
    const double k0 = zh[0] * std::sqrt(1.0 / (4.0 * kPiD)) / kPiD, k1 = zh[1] * std::sqrt(3.0 / (4.0 * kPiD)) / kPiD;
    const double k2 = zh[2] * std::sqrt(5.0 / (4.0 * kPiD)) / kPiD;
    auto k = [&](double t) { return k0 + k1 * t + k2 * 0.5 * (3.0 * t * t - 1.0); };
    // max |g|: g(u) = sum_l NLP_l(u) integral over z of NLP_l(z) k(N . w(z, phi)), midpoint rule in z
    const int nz = 800;
    double maxG = 0.0;
    for (int it = 0; it < 90; ++it)
        for (int ip = 0; ip <= 60; ++ip) {
            const double tilt = it * kPiD / 180.0, phi = ip * kPiD / 60.0;
            double proj[kNlpCount] = {};
            for (int iz = 0; iz < nz; ++iz) {
                const double z = -1.0 + (iz + 0.5) * 2.0 / nz, r = std::sqrt(1.0 - z * z);
                double nlp[kNlpCount];
                nlpEvaluate(z, nlp);
                const double kv = k(std::sin(tilt) * r * std::cos(phi) + std::cos(tilt) * z) * 2.0 / nz;
                for (int l = 0; l < kNlpCount; ++l) proj[l] += nlp[l] * kv;
            }
            for (int iu = 0; iu <= 100; ++iu) {
                double nlp[kNlpCount];
                nlpEvaluate(-1.0 + iu * 0.02, nlp);
                double g = 0.0;
                for (int l = 0; l < kNlpCount; ++l) g += nlp[l] * proj[l];
                maxG = std::max(maxG, std::fabs(g));
            }
        }
    // the range of W: order-4 Legendre approximations of "visible above s"
    double wLo = 1.0, wHi = 0.0;
    for (int is = 0; is <= 400; ++is) {
        double v[kNlpCount];
        nlpVisibleAbove(-1.0 + is * 0.005, v);
        for (int iz = 0; iz <= 400; ++iz) {
            double nlp[kNlpCount];
            nlpEvaluate(-1.0 + iz * 0.005, nlp);
            const double w = v[0] * nlp[0] + v[1] * nlp[1] + v[2] * nlp[2] + v[3] * nlp[3];
            wLo = std::min(wLo, w);
            wHi = std::max(wHi, w);
        }
    }
    // integral over the sphere of |x| |k1 + 2 k2' m z| (k2' = 1.5 k2, k's t^2 coefficient), m = 0 and 1
    double d[2] = {};
    for (int m = 0; m < 2; ++m)
        for (int iz = 0; iz < 20000; ++iz) {
            const double z = -1.0 + (iz + 0.5) * 2.0 / 20000;
            d[m] += 4.0 * std::sqrt(1.0 - z * z) * std::fabs(k1 + 3.0 * k2 * m * z) * 2.0 / 20000;
        }
    const double perSlope = 2.0 * kPiD * maxG, perNormal = 0.5 * (wHi - wLo) * std::max(d[0], d[1]);
    MESSAGE("per slope: 2 pi max|g| = " << perSlope << " (constant " << kShadePerSlope << ", exact integral "
                                        << kShadePerSlopeExact << "); per normal: " << perNormal << " (constant "
                                        << kShadePerNormal << "); W in [" << wLo << ", " << wHi << "]");
    CHECK(perSlope <= kShadePerSlope);
    CHECK(perNormal <= kShadePerNormal);
}

TEST_CASE("gi.change_bound: tile bounds hold for the engine's slopes and ambient light") {
    const Config configs[] = {{97, 70, 1, 8, false},
                              {120, 83, 2, 8, false},
                              {150, 118, 4, 4, false},
                              {80, 96, 1, 6, true},
                              {61, 47, 2, 1, false}};
    double worstSlope = 0.0, worstAmbient = 0.0, worstAzimuth = 0.0, worstAzimuthAmbient = 0.0;
    for (const Config& cfg : configs) {
        const GiSettings settings = gi_test::fullDirectFrames(cfg.paper, cfg.subsample);
        const float lipschitz = blockingMaxLipschitz(settings.visibility.blockingMax);
        const Grid base = baseTerrain(cfg.nx, cfg.ny);
        GiState before, after;
        runFrame(base, settings, before);
        for (Change change : {Change::Bump, Change::Noise, Change::CliffCollapse, Change::Spike, Change::EdgeSpikes}) {
            const Grid h = perturbed(base, change, 5u + static_cast<unsigned>(change));
            runFrame(h, settings, after);
            const Comparison c = compareFrames(before, after, base, h, cfg.tile, lipschitz);
            std::ostringstream label;
            label << cfg.nx << " x " << cfg.ny << " s=" << cfg.subsample << " tiles of " << cfg.tile
                  << (cfg.paper ? " (paper settings)" : "") << ", " << nameOf(change);
            INFO(label.str());
            CHECK(c.slopeOver == 0);
            CHECK(c.ambientOver == 0);
            CHECK(c.azimuthOver == 0);
            CHECK(c.azimuthAmbientOver == 0);
            CHECK(c.azimuthAboveTile == 0);
            worstSlope = std::max(worstSlope, c.worstSlope);
            worstAmbient = std::max(worstAmbient, c.worstAmbient);
            worstAzimuth = std::max(worstAzimuth, c.worstAzimuth);
            worstAzimuthAmbient = std::max(worstAzimuthAmbient, c.worstAzimuthAmbient);
            if (change == Change::Bump)
                MESSAGE(label.str() << ": median bound / change per receiver " << median(c.slopeLoose) << " (slopes), "
                                    << median(c.ambientLoose) << " (ambient); per tile (largest change) "
                                    << median(c.tileSlopeLoose) << " (slopes, " << c.tileSlopeLoose.size()
                                    << " tiles), " << median(c.tileAmbientLoose) << " (ambient, "
                                    << c.tileAmbientLoose.size() << "), per azimuth "
                                    << median(c.tileAzimuthAmbientLoose) << " (ambient)");
        }
    }
    MESSAGE("worst change / bound: slopes " << worstSlope << ", ambient " << worstAmbient << "; per azimuth: slopes "
                                            << worstAzimuth << ", ambient " << worstAzimuthAmbient);
}

TEST_CASE("gi.change_bound: no change gives zero bounds, a distant change a small positive one") {
    const Grid h = baseTerrain(90, 70);
    HeightPyramid pyr;
    buildHeightPyramid(h.cview(), kCell, 1, PyramidSettings{}, pyr);
    MaxChangePyramid dh;
    buildMaxChangePyramid(h.cview(), h.cview(), dh);
    std::vector<float> slope, grad;
    boundSlopeChange(dh, pyr, 8, slope);
    boundGradientChange(dh, pyr, 8, grad);
    REQUIRE(slope.size() == static_cast<std::size_t>(tileCount(90, 8) * tileCount(70, 8)));
    CHECK(std::all_of(slope.begin(), slope.end(), [](float v) { return v == 0.0f; }));
    CHECK(std::all_of(grad.begin(), grad.end(), [](float v) { return v == 0.0f; }));
    CHECK(ambientChangeBound(0.0f, 0.0f, 1.0f, true) == 0.0f);

    Grid g = h;
    g(2, 3) += 5.0f;
    buildMaxChangePyramid(h.cview(), g.cview(), dh);
    boundSlopeChange(dh, pyr, 8, slope);
    boundGradientChange(dh, pyr, 8, grad);
    const float near = slope.front(), far = slope.back();
    MESSAGE("spike in the first tile: bound there " << near << ", in the farthest tile " << far);
    CHECK(far > 0.0f);
    CHECK(far < near / 10.0f);
    CHECK(grad.front() > 0.0f);
    CHECK(grad.back() == 0.0f);
    CHECK(boundOfTile(dh, pyr, 8, tileCount(90, 8) - 1, tileCount(70, 8) - 1) == far);
    // per azimuth: the farthest tile sees the spike only along the azimuths that point back at it
    std::vector<float> perAzimuth;
    boundSlopeChangePerAzimuth(dh, pyr, 8, 16, perAzimuth);
    REQUIRE(perAzimuth.size() == slope.size() * 16);
    const float* farAz = perAzimuth.data() + (slope.size() - 1) * 16;
    CHECK(*std::max_element(farAz, farAz + 16) <= far);
    CHECK(farAz[10] > 0.0f);  // phi = 225 degrees, towards the origin
    CHECK(farAz[2] == 0.0f);  // phi = 45 degrees, away from it
    CHECK(azimuthBoundOfTile(dh, pyr, 8, tileCount(90, 8) - 1, tileCount(70, 8) - 1, 1.25 * 3.14159265358979) ==
          farAz[10]);
    // of flagged tiles alone: theirs bit for bit, the others' 0
    std::vector<std::uint8_t> only(slope.size(), 0);
    only.front() = only.back() = 1;
    std::vector<float> flagged;
    boundSlopeChangePerAzimuth(dh, pyr, 8, 16, flagged, only);
    REQUIRE(flagged.size() == perAzimuth.size());
    for (std::size_t i = 0; i < flagged.size(); ++i) {
        CAPTURE(i);
        CHECK(flagged[i] == (only[i / 16] ? perAzimuth[i] : 0.0f));
    }
    CHECK_THROWS_AS(boundSlopeChangePerAzimuth(dh, pyr, 8, 16, flagged, std::vector<std::uint8_t>(3, 1)), InputError);
    buildMaxChangePyramid(h.cview(), h.cview(), dh);
    boundSlopeChangePerAzimuth(dh, pyr, 8, 16, perAzimuth);
    CHECK(std::all_of(perAzimuth.begin(), perAzimuth.end(), [](float v) { return v == 0.0f; }));
    CHECK(ambientChangeBoundPerAzimuth(perAzimuth.data(), 16, 0.0f, 1.0f, true) == 0.0f);
    CHECK_THROWS_AS(boundSlopeChangePerAzimuth(dh, pyr, 8, 0, perAzimuth), InputError);

    CHECK_THROWS_AS(boundSlopeChange(dh, pyr, 0, slope), InputError);
    MaxChangePyramid small;
    buildMaxChangePyramid(gridOf(10, 10, [](int, int) { return 1.0f; }).cview(), small);
    CHECK_THROWS_AS(boundGradientChange(small, pyr, 8, grad), InputError);
}

TEST_CASE("gi.change_bound: azimuth-range bounds hold for a key light's slopes and stay below the tile's") {
    // key lights of several regions: across the +x axis (a wrapped range), a
    // large one facing -y, a small one
    const float azimuths[] = {2.0f, 250.0f, 130.0f};
    const float radii[] = {12.0f, 40.0f, 3.0f};
    const Config configs[] = {{97, 70, 1, 8, false}, {120, 83, 2, 8, false}, {80, 96, 1, 6, true}};
    double worst = 0.0, worstFraction = 0.0;
    int smallerTiles = 0;
    for (const Config& cfg : configs)
        for (int k = 0; k < 3; ++k) {
            const GiSettings settings = gi_test::fullDirectFrames(cfg.paper, cfg.subsample);
            GiLighting light;
            KeyLight key;
            key.azimuthDeg = azimuths[k];
            key.elevationDeg = 20.0f;
            key.radiusDeg = radii[k];
            light.keys.push_back(key);
            const KeyLightExtent ext = keyLightExtent(key);
            const float lipschitz = blockingMaxLipschitz(settings.visibility.blockingMax);
            const Grid base = baseTerrain(cfg.nx, cfg.ny);
            GiState before, after;
            runGiFrame(base.cview(), kCell, light, settings, before);
            for (Change change :
                 {Change::Bump, Change::Noise, Change::CliffCollapse, Change::Spike, Change::EdgeSpikes}) {
                const Grid h = perturbed(base, change, 9u + static_cast<unsigned>(change));
                runGiFrame(h.cview(), kCell, light, settings, after);
                MaxChangePyramid dh;
                buildMaxChangePyramid(base.cview(), h.cview(), dh);
                std::vector<float> range, all;
                boundSlopeChangeOverRange(dh, before.pyramid, cfg.tile, ext.phiStart, ext.phiEnd, range);
                boundSlopeChange(dh, before.pyramid, cfg.tile, all);
                INFO(cfg.nx << " x " << cfg.ny << " s=" << cfg.subsample << ", key at " << azimuths[k] << ", "
                            << nameOf(change));
                const HeightPyramid& p = before.pyramid;
                const int nxr = p.nxr, nyr = p.nyr, tilesX = tileCount(nxr, cfg.tile);
                const VisibilityField &va = before.keyVisibility[0], &vb = after.keyVisibility[0];
                const int m = static_cast<int>(va.maxSlope.size() / (static_cast<std::size_t>(nxr) * nyr));
                REQUIRE(m == settings.keyLightAzimuths);
                const double heightUlps = 64.0 * FLT_EPSILON * std::max(maxAbs(base), maxAbs(h)) / kCell;
                int over = 0;
                for (int Y = 0; Y < nyr; ++Y)
                    for (int X = 0; X < nxr; ++X) {
                        const std::size_t t =
                            static_cast<std::size_t>(Y / cfg.tile) * tilesX + static_cast<std::size_t>(X / cfg.tile);
                        const double b = lipschitz * range[t];
                        for (int j = 0; j < m; ++j) {
                            const std::size_t i = (static_cast<std::size_t>(j) * nyr + Y) * nxr + X;
                            const double s0 = va.maxSlope[i], s1 = vb.maxSlope[i];
                            const double allowance =
                                heightUlps + 4.0 * FLT_EPSILON * std::max(std::fabs(s0), std::fabs(s1));
                            over += std::fabs(s1 - s0) > b + allowance;
                            if (b > 0.0) worst = std::max(worst, std::fabs(s1 - s0) / b);
                        }
                    }
                CHECK(over == 0);
                // the light's visible fraction f (its shade at rgb 1, before the
                // cosine) at every receiver against keyLightFractionBound
                std::vector<float> grad;
                boundGradientChange(dh, p, cfg.tile, grad);
                const double toFrac = std::sqrt(4.0 * 3.14159265358979) /
                                      ((ext.phiEnd - ext.phiStart) * (static_cast<double>(ext.sinHigh) - ext.sinLow));
                int fractionOver = 0;
                for (int Y = 0; Y < nyr; ++Y)
                    for (int X = 0; X < nxr; ++X) {
                        const std::size_t t =
                            static_cast<std::size_t>(Y / cfg.tile) * tilesX + static_cast<std::size_t>(X / cfg.tile);
                        const std::size_t i = static_cast<std::size_t>(Y) * nxr + X;
                        const double f0 = std::clamp(va.plane(0)[i] * toFrac, 0.0, 1.0);
                        const double f1 = std::clamp(vb.plane(0)[i] * toFrac, 0.0, 1.0);
                        const double b = keyLightFractionBound(lipschitz * range[t], grad[t], ext.sinLow, ext.sinHigh);
                        fractionOver += std::fabs(f1 - f0) > b + 1e-5;
                        if (b > 0.0 && b < 1.0) worstFraction = std::max(worstFraction, std::fabs(f1 - f0) / b);
                    }
                CHECK(fractionOver == 0);
                for (std::size_t t = 0; t < range.size(); ++t) {
                    CHECK(range[t] <= all[t]);
                    smallerTiles += range[t] < all[t];
                }
                CHECK(rangeBoundOfTile(dh, p, cfg.tile, 1, 1, ext.phiStart, ext.phiEnd) == range[tilesX + 1]);
                // with flags, the flagged tiles' bounds alone (every other tile here), the others 0
                std::vector<std::uint8_t> only(range.size());
                for (std::size_t t = 0; t < only.size(); ++t) only[t] = t % 2 == 0 ? 1 : 0;
                std::vector<float> flagged;
                boundSlopeChangeOverRange(dh, p, cfg.tile, ext.phiStart, ext.phiEnd, flagged, only);
                REQUIRE(flagged.size() == range.size());
                for (std::size_t t = 0; t < range.size(); ++t) CHECK(flagged[t] == (only[t] ? range[t] : 0.0f));
            }
        }
    MESSAGE("key-light slopes: worst change / range bound "
            << worst << "; " << smallerTiles << " tile bounds below the bound over every azimuth"
            << "; visible fraction: worst change / fraction bound " << worstFraction);
    CHECK(smallerTiles > 0);
    CHECK(worstFraction > 0.01);  // the bound is met by changes of its own order somewhere
    // the fraction bound: the slope bound over the window's height, at most the whole light
    CHECK(keyLightFractionBound(0.0f, 0.0f, 0.4f, 0.5f) == 0.0f);
    CHECK(keyLightFractionBound(0.01f, 0.0f, 0.4f, 0.5f) == doctest::Approx(0.1));
    CHECK(keyLightFractionBound(0.0f, 0.01f, 0.4f, 0.5f) == doctest::Approx(0.1 * std::sqrt(2.0)));
    CHECK(keyLightFractionBound(1.0f, 0.0f, 0.4f, 0.5f) == 1.0f);
    MaxChangePyramid dh;
    const Grid flat = baseTerrain(40, 40);
    buildMaxChangePyramid(flat.cview(), flat.cview(), dh);
    GiState st;
    runGiFrame(flat.cview(), kCell, GiLighting{}, GiSettings{}, st);
    std::vector<float> range;
    CHECK_THROWS_AS(boundSlopeChangeOverRange(dh, st.pyramid, 8, 1.0, 0.5, range), InputError);
    const std::vector<std::uint8_t> tooFew(1, 1);  // one flag for several tiles
    CHECK_THROWS_AS(boundSlopeChangeOverRange(dh, st.pyramid, 8, 0.5, 1.0, range, tooFew), InputError);
}

TEST_CASE("gi.change_bound: a change pyramid redone over the box of differing cells is a whole build's") {
    // the anchor's field against fields that differ from it in a box; the
    // pyramid of the last one is reused with the box alone (the cells the
    // last build found changed are redone too: a change that moved away)
    const int nx = 150, ny = 101;
    const Grid anchor = gi_test::bumpy(nx, ny);
    const auto withPatch = [&](CellBox box, float by) {
        Grid g = anchor;
        for (int y = box.y0; y < box.y1; ++y)
            for (int x = box.x0; x < box.x1; ++x) g(x, y) += by * static_cast<float>(1 + (x * 7 + y) % 5);
        return g;
    };
    const auto same = [](const MaxChangePyramid& a, const MaxChangePyramid& b) {
        bool ok = a.levels.size() == b.levels.size() && a.changed.x0 == b.changed.x0 && a.changed.y0 == b.changed.y0 &&
                  a.changed.x1 == b.changed.x1 && a.changed.y1 == b.changed.y1;
        for (std::size_t k = 0; ok && k < a.levels.size(); ++k)
            ok = gi_test::sameBits(a.levels[k].v, b.levels[k].v) && gi_test::sameBits(a.sums[k].v, b.sums[k].v);
        return ok;
    };
    const std::vector<CellBox> boxes{{10, 10, 20, 15}, {140, 90, 150, 101}, {0, 0, 1, 1},
                                     {60, 0, 61, 101}, {70, 40, 90, 60},    {0, 0, 150, 101}};
    MaxChangePyramid reused;
    buildMaxChangePyramid(anchor.cview(), anchor.cview(), reused);
    CHECK(maxChangeAll(reused) == 0.0f);
    for (std::size_t i = 0; i < boxes.size(); ++i) {
        CAPTURE(i);
        const Grid now = withPatch(boxes[i], 0.25f);
        buildMaxChangePyramid(anchor.cview(), now.cview(), reused, boxes[i]);
        MaxChangePyramid whole;
        buildMaxChangePyramid(anchor.cview(), now.cview(), whole);
        CHECK(same(reused, whole));
        CHECK(maxChangeAll(whole) > 0.0f);
    }
    // back to the anchor's field: the last box alone, and every cell is 0 again
    buildMaxChangePyramid(anchor.cview(), anchor.cview(), reused, CellBox{0, 0, 0, 0});
    CHECK(maxChangeAll(reused) == 0.0f);
    // a box that misses the change leaves it out: the box is what is redone
    const Grid moved = withPatch(boxes[4], 0.25f);
    buildMaxChangePyramid(anchor.cview(), moved.cview(), reused, boxes[0]);
    CHECK(maxChangeAll(reused) == 0.0f);
}

TEST_CASE("gi.change_bound: a tile's bound over every k-th azimuth is the ambient bound of those azimuths alone") {
    constexpr int kAzimuths = 16, kTiles = 3;
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(0.0f, 0.2f);
    std::vector<float> perAzimuth(kTiles * kAzimuths), grad(kTiles);
    for (float& v : perAzimuth) v = u(rng);
    for (float& v : grad) v = u(rng) / 4.0f;
    const float lipschitz = 1.25f;
    std::vector<float> scratch, all, every2nd, every4th;
    environmentBoundPerTile(perAzimuth, grad, kAzimuths, lipschitz, scratch, all);
    environmentBoundPerTile(perAzimuth, grad, kAzimuths, lipschitz, scratch, every2nd, 2);
    environmentBoundPerTile(perAzimuth, grad, kAzimuths, lipschitz, scratch, every4th, 4);
    REQUIRE(every2nd.size() == kTiles);
    for (int t = 0; t < kTiles; ++t) {
        CAPTURE(t);
        std::vector<float> taken;
        for (int j = 0; j < kAzimuths; j += 2) taken.push_back(lipschitz * perAzimuth[t * kAzimuths + j]);
        CHECK(every2nd[t] == ambientChangeBoundPerAzimuth(taken.data(), kAzimuths / 2, grad[t], 1.0f, false));
        CHECK(all[t] > 0.0f);
        CHECK(every4th[t] > 0.0f);
    }
    CHECK_THROWS_AS(environmentBoundPerTile(perAzimuth, grad, kAzimuths, lipschitz, scratch, all, 3), InputError);
    CHECK_THROWS_AS(environmentBoundPerTile(perAzimuth, grad, kAzimuths, lipschitz, scratch, all, 0), InputError);
}
