// gi/blocker_radiance: texel occlusion O / pi against analytic horizons, the
// shading relation E(x) = O(x) sum w E_k / sum w O_k, and determinism. The
// receivers' horizons (farSlope) come from the indirect scan in a frame; here
// the tests fill them.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <functional>
#include <vector>

#include <doctest/doctest.h>

#include "core/parallel.h"
#include "core/simd.h"
#include "gi/blocker_radiance.h"
#include "gi/frame.h"
#include "gi/visibility.h"
#include "tests/gi_test_terrain.h"

using namespace terrain;
using namespace terrain::gi;
using gi_test::gridOf;
using gi_test::sameBits;

namespace {

// A blocker-radiance state set up as a frame would, with the horizons left to the test.
struct Setup {
    HeightPyramid pyr;
    Grid gx, gy;
    std::vector<double> phi;
    BlockerRadianceState st;
};

// zeroGradient: receivers and texels taken horizontal (the analytic pit);
// otherwise the frame's central differences.
void prepare(const Grid& h, float cell, int s, int m, bool zeroGradient, Setup& b) {
    buildHeightPyramid(h.cview(), cell, s, paperGiSettings().pyramid, b.pyr);
    if (zeroGradient) {
        b.gx = Grid(h.nx, h.ny, 0.0f);
        b.gy = Grid(h.nx, h.ny, 0.0f);
    } else {
        computeGradient(h.cview(), cell, b.gx, b.gy);
    }
    b.phi.resize(static_cast<std::size_t>(m));
    for (int j = 0; j < m; ++j) b.phi[static_cast<std::size_t>(j)] = 2.0 * kPi * (j + 0.5) / m;
    prepareBlockerRadiance(b.pyr, m, b.st);
}

// Fills the receivers' horizons (tan of the elevation) with slope(j, X, Y).
void fillFar(Setup& b, const std::function<float(int, int, int)>& slope) {
    const BlockerRadianceState& st = b.st;
    REQUIRE(b.st.farSlope.size() == static_cast<std::size_t>(st.azimuths) * st.nxr * st.nyr);
    for (int j = 0; j < st.azimuths; ++j)
        for (int Y = 0; Y < st.nyr; ++Y)
            for (int X = 0; X < st.nxr; ++X)
                b.st.farSlope[(static_cast<std::size_t>(j) * st.nyr + Y) * st.nxr + X] = slope(j, X, Y);
}

float farAt(const Setup& b, int j, int X, int Y) {
    return b.st.farSlope[(static_cast<std::size_t>(j) * b.st.nyr + Y) * b.st.nxr + X];
}

// Bilinear interpolation of per-receiver values v(X, Y) at full-resolution texel (x, y).
double lerpReceivers(const Setup& b, int x, int y, const std::function<double(int, int)>& v) {
    const int s = b.st.subsample;
    const int X0 = std::min(x / s, b.st.nxr - 1), Y0 = std::min(y / s, b.st.nyr - 1);
    const int X1 = std::min(X0 + 1, b.st.nxr - 1), Y1 = std::min(Y0 + 1, b.st.nyr - 1);
    const double fx = (x - s * X0) / static_cast<double>(s), fy = (y - s * Y0) / static_cast<double>(s);
    return (1.0 - fy) * ((1.0 - fx) * v(X0, Y0) + fx * v(X1, Y0)) + fy * ((1.0 - fx) * v(X0, Y1) + fx * v(X1, Y1));
}

double sin2OfSlope(double t) { return t * t / (1.0 + t * t); }

Grid bumpy(int nx, int ny) {
    return gridOf(nx, ny, [](int x, int y) {
        return static_cast<float>(6.0 * std::sin(0.31 * x) * std::cos(0.23 * y) + 2.0 * std::sin(0.9 * x + 0.5 * y));
    });
}

// A deterministic horizon pattern in [0.05, 0.85] (tan of the elevation).
float patternSlope(int j, int X, int Y) {
    return 0.05f + 0.8f * static_cast<float>((j * 7 + X * 13 + Y * 29) % 17) / 16.0f;
}

AlbedoMap patternAlbedo(int nx, int ny) {
    AlbedoMap a;
    a.channel[0] = gridOf(nx, ny, [](int x, int y) { return 0.2f + 0.05f * static_cast<float>((x + 3 * y) % 11); });
    a.channel[1] = Grid(nx, ny, 0.5f);
    // channel 2 left empty: albedo 1
    return a;
}

double albedoAt(const AlbedoMap& a, std::size_t ch, int x, int y) {
    return a.channel[ch].empty() ? 1.0 : a.channel[ch](x, y);
}

}  // namespace

TEST_CASE(
    "gi.blocker: a flat or tilted plane with no blocker above it has occlusion exactly 0 and gets exactly no light") {
    const int nx = 45, ny = 38, m = 8;
    const Grid flat(nx, ny, 57.5f);
    const Grid tilted = gridOf(
        nx, ny, [](int x, int y) { return 100.0f + 0.3f * static_cast<float>(x) - 0.2f * static_cast<float>(y); });
    for (int s : {2, 4})
        for (int shape = 0; shape < 2; ++shape)
            for (float far : {kNoBlocker, 0.0f}) {
                if (shape == 1 && far == 0.0f) continue;  // a horizon at 0 is above a tilted plane's downhill side
                Setup b;
                prepare(shape == 0 ? flat : tilted, 1.5f, s, m, false, b);
                fillFar(b, [&](int, int, int) { return far; });
                computeTexelOcclusion(b.pyr, b.gx.cview(), b.gy.cview(), b.phi, nullptr, nullptr, b.st);
                for (std::vector<float>& e : b.st.receiverShade) std::fill(e.begin(), e.end(), 0.75f);
                std::array<Grid, 3> rgb;
                const AlbedoMap a = patternAlbedo(nx, ny);
                shadeBlockerRadiance(b.st, &a, nullptr, nullptr, rgb);
                INFO("s " << s << (shape == 0 ? " flat" : " tilted") << ", far horizon " << far);
                CHECK(std::count(b.st.occlusion.v.begin(), b.st.occlusion.v.end(), 0.0f) ==
                      static_cast<long>(b.st.occlusion.size()));
                CHECK(std::count(b.st.receiverOcclusion.begin(), b.st.receiverOcclusion.end(), 0.0f) ==
                      static_cast<long>(b.st.receiverOcclusion.size()));
                for (const Grid& g : rgb)
                    CHECK(std::count(g.v.begin(), g.v.end(), 0.0f) == static_cast<long>(g.size()));
            }
}

TEST_CASE(
    "gi.blocker: circular pit: O / pi at the centre is sin^2(atan(d / r)), and every floor texel matches its "
    "receivers' horizons") {
    // Pit of radius r = 12 cells (cell 2 m), depth d, receivers horizontal; the
    // far horizons are the exact wall slopes d / D, D the distance to the rim
    // along the azimuth. O / pi = (1/m) sum_j sin^2 h_j: the cosine-weighted
    // fraction of the hemisphere below elevation h is sin^2 h, so at the
    // centre (h = atan(d / r) in every azimuth) O / pi = d^2 / (r^2 + d^2).
    // Between receivers the horizon is the bilinear interpolation of theirs
    // (tan, per azimuth). The floor texels checked lie far enough from the rim
    // that the near samples (up to s cells, bilinear taps one more) read the
    // floor only. Tolerance 2e-6: float rounding of a sum of m = 24 terms below 1 (measured below 3e-7).
    const int n = 64, c = 32, m = 24;
    const double cell = 2.0, rCells = 12.0, r = rCells * cell;
    for (double d : {0.5 * r, r, 2.0 * r})
        for (int s : {2, 4}) {
            const Grid h = gridOf(
                n, n, [&](int x, int y) { return std::hypot(x - c, y - c) < rCells ? static_cast<float>(-d) : 0.0f; });
            Setup b;
            prepare(h, static_cast<float>(cell), s, m, true, b);
            auto wallSlope = [&](int j, double px, double py) {  // px, py: metres from the centre
                const double ux = std::cos(b.phi[static_cast<std::size_t>(j)]),
                             uy = std::sin(b.phi[static_cast<std::size_t>(j)]);
                const double pu = px * ux + py * uy, pp = px * px + py * py;
                if (pp >= r * r) return static_cast<double>(kNoBlocker);
                return d / (-pu + std::sqrt(r * r - pp + pu * pu));
            };
            fillFar(b, [&](int j, int X, int Y) {
                return static_cast<float>(wallSlope(j, (s * X - c) * cell, (s * Y - c) * cell));
            });
            computeTexelOcclusion(b.pyr, b.gx.cview(), b.gy.cview(), b.phi, nullptr, nullptr, b.st);
            INFO("d / r = " << d / r << ", s " << s);
            const double exact = d * d / (r * r + d * d);
            CHECK(std::fabs(b.st.occlusion(c, c) - exact) < 2e-6);
            CHECK(std::fabs(b.st.receiverOcclusion[static_cast<std::size_t>(c / s) * b.st.nxr + c / s] - exact) < 2e-6);
            double worstTexel = 0.0, worstReceiver = 0.0;
            int texels = 0;
            for (int y = 0; y < n; ++y)
                for (int x = 0; x < n; ++x) {
                    if (std::hypot(x - c, y - c) > rCells - 1.5 * (s + 1) - 0.5) continue;
                    double sum = 0.0;
                    for (int j = 0; j < m; ++j)
                        sum += sin2OfSlope(lerpReceivers(b, x, y, [&](int X, int Y) { return farAt(b, j, X, Y); }));
                    worstTexel = std::max(worstTexel, std::fabs(b.st.occlusion(x, y) - sum / m));
                    ++texels;
                    if (x % s == 0 && y % s == 0) {  // a receiver: against the exact horizons
                        double exactSum = 0.0;
                        for (int j = 0; j < m; ++j)
                            exactSum += sin2OfSlope(wallSlope(j, (x - c) * cell, (y - c) * cell));
                        worstReceiver = std::max(worstReceiver, std::fabs(b.st.occlusion(x, y) - exactSum / m));
                    }
                }
            CHECK(texels > 40);
            CHECK(worstTexel < 2e-6);
            CHECK(worstReceiver < 2e-6);
        }
}

TEST_CASE("gi.blocker: shading gives O(x) sum w E_k / sum w O_k; E_k = c O_k gives c O(x) times the albedo") {
    // E(x) = albedo O(x) sum_k w_k E_k / sum_k w_k O_k (w: bilinear weights of
    // the receivers). With E_k = c O_k the ratio is c wherever the receivers see
    // a blocker, so every texel gets albedo c O(x) up to rounding (a few ulp of
    // a quotient of two interpolations: tolerance 2e-6 relative).
    const int nx = 45, ny = 38, m = 8;
    const Grid h = bumpy(nx, ny);
    const AlbedoMap a = patternAlbedo(nx, ny);
    const float k[3] = {0.3f, 0.55f, 0.8f};
    for (int s : {2, 4}) {
        Setup b;
        prepare(h, 1.0f, s, m, false, b);
        fillFar(b, patternSlope);
        computeTexelOcclusion(b.pyr, b.gx.cview(), b.gy.cview(), b.phi, nullptr, nullptr, b.st);
        INFO("s " << s);
        // every receiver sees a blocker: along phi or phi + pi its own plane is not above 0.05
        for (float o : b.st.receiverOcclusion) REQUIRE(o > 0.0f);
        // proportional: E_k = c O_k
        for (std::size_t ch = 0; ch < 3; ++ch)
            for (std::size_t i = 0; i < b.st.receiverOcclusion.size(); ++i)
                b.st.receiverShade[ch][i] = k[ch] * b.st.receiverOcclusion[i];
        std::array<Grid, 3> rgb;
        shadeBlockerRadiance(b.st, &a, nullptr, nullptr, rgb);
        double worst = 0.0;
        int positive = 0;
        for (std::size_t ch = 0; ch < 3; ++ch)
            for (int y = 0; y < ny; ++y)
                for (int x = 0; x < nx; ++x) {
                    const double want = albedoAt(a, ch, x, y) * k[ch] * b.st.occlusion(x, y);
                    worst = std::max(worst, std::fabs(rgb[ch](x, y) - want) / (want + 1e-12));
                    positive += want > 0.0;
                }
        CHECK(positive > nx * ny);  // most texels lit: the check is not of zeros
        CHECK(worst < 2e-6);
        // any E_k: the quotient of the interpolations, computed here in double
        for (std::size_t ch = 0; ch < 3; ++ch)
            for (int Y = 0; Y < b.st.nyr; ++Y)
                for (int X = 0; X < b.st.nxr; ++X)
                    b.st.receiverShade[ch][static_cast<std::size_t>(Y) * b.st.nxr + X] =
                        0.1f + 0.02f * static_cast<float>((X * 5 + Y * 3 + static_cast<int>(ch)) % 9);
        shadeBlockerRadiance(b.st, &a, nullptr, nullptr, rgb);
        worst = 0.0;
        auto receivers = [&](const std::vector<float>& v) {
            return
                [&v, &b](int X, int Y) { return static_cast<double>(v[static_cast<std::size_t>(Y) * b.st.nxr + X]); };
        };
        for (std::size_t ch = 0; ch < 3; ++ch)
            for (int y = 0; y < ny; ++y)
                for (int x = 0; x < nx; ++x) {
                    const double num = lerpReceivers(b, x, y, receivers(b.st.receiverShade[ch]));
                    const double den = lerpReceivers(b, x, y, receivers(b.st.receiverOcclusion));
                    const double want = albedoAt(a, ch, x, y) * b.st.occlusion(x, y) * num / den;
                    worst = std::max(worst, std::fabs(rgb[ch](x, y) - want) / (want + 1e-12));
                }
        CHECK(worst < 2e-6);
    }
}

TEST_CASE("gi.blocker: at 1x every texel is a receiver and gets albedo E / pi exactly") {
    const int nx = 45, ny = 38;
    const Grid h = bumpy(nx, ny);
    const AlbedoMap a = patternAlbedo(nx, ny);
    Setup b;
    prepare(h, 1.0f, 1, 8, false, b);
    for (std::size_t ch = 0; ch < 3; ++ch)
        for (std::size_t i = 0; i < b.st.receiverShade[ch].size(); ++i)
            b.st.receiverShade[ch][i] = 0.01f * static_cast<float>(i % 37 + ch);
    std::array<Grid, 3> rgb;
    shadeBlockerRadiance(b.st, &a, nullptr, nullptr, rgb);
    long off = 0;
    for (std::size_t ch = 0; ch < 3; ++ch)
        for (int y = 0; y < ny; ++y)
            for (int x = 0; x < nx; ++x) {
                const std::size_t i = static_cast<std::size_t>(y) * nx + x;
                off += rgb[ch].v[i] != static_cast<float>(albedoAt(a, ch, x, y)) * b.st.receiverShade[ch][i];
            }
    CHECK(off == 0);
}

TEST_CASE(
    "gi.blocker: occlusion and shading are bit-identical for 1, 2 and 3 threads and for the SSE2 and AVX2 kernels") {
    const int nx = 61, ny = 70, m = 8;
    const Grid h = bumpy(nx, ny);
    const AlbedoMap a = patternAlbedo(nx, ny);
    for (int s : {2, 4}) {
        struct Out {
            Grid occlusion;
            std::vector<float> receiverOcclusion;
            std::array<Grid, 3> rgb;
        };
        auto run = [&] {
            Setup b;
            prepare(h, 1.25f, s, m, false, b);
            fillFar(b, patternSlope);
            computeTexelOcclusion(b.pyr, b.gx.cview(), b.gy.cview(), b.phi, nullptr, nullptr, b.st);
            for (std::size_t ch = 0; ch < 3; ++ch)
                for (std::size_t i = 0; i < b.st.receiverOcclusion.size(); ++i)
                    b.st.receiverShade[ch][i] = (0.2f + 0.1f * static_cast<float>(ch + i % 5)) *  // E_k ~ O_k
                                                b.st.receiverOcclusion[i];
            Out o;
            shadeBlockerRadiance(b.st, &a, nullptr, nullptr, o.rgb);
            o.occlusion = b.st.occlusion;
            o.receiverOcclusion = b.st.receiverOcclusion;
            return o;
        };
        const Out one = withThreads(1, run);
        auto same = [&](const Out& o) {
            bool ok = sameBits(o.occlusion.v, one.occlusion.v) && sameBits(o.receiverOcclusion, one.receiverOcclusion);
            for (std::size_t ch = 0; ch < 3; ++ch) ok = ok && sameBits(o.rgb[ch].v, one.rgb[ch].v);
            return ok;
        };
        for (int t : {2, 3}) CHECK_MESSAGE(same(withThreads(t, run)), "s " << s << ", " << t << " threads");
        // the other lane width
        const bool was = simd::wideEnabled();
        if (simd::setWideEnabled(!was) != was) CHECK_MESSAGE(same(withThreads(2, run)), "s " << s << ", wide " << !was);
        simd::setWideEnabled(was);
    }
}
