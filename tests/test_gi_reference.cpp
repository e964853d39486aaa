// gi/reference: the ground truth itself, and convergence of the fast path to it.
#include <cmath>
#include <functional>

#include <doctest/doctest.h>

#include "core/error.h"
#include "gi/frame.h"
#include "gi/reference.h"

using namespace terrain;
using namespace terrain::gi;

namespace {

Grid makeGrid(int nx, int ny, const std::function<float(int, int)>& f) {
    Grid g(nx, ny);
    for (int y = 0; y < ny; ++y)
        for (int x = 0; x < nx; ++x) g(x, y) = f(x, y);
    return g;
}

double rmseInterior(const Grid& a, const Grid& b, int border) {
    double s = 0.0;
    long n = 0;
    for (int y = border; y < a.ny - border; ++y)
        for (int x = border; x < a.nx - border; ++x) {
            const double d = static_cast<double>(a(x, y)) - b(x, y);
            s += d * d;
            ++n;
        }
    return std::sqrt(s / n);
}

}  // namespace

TEST_CASE("gi.reference: flat plane is exactly 1 and the pit matches r^2/(r^2+d^2)") {
    const Grid flat(20, 20, 7.0f);
    ReferenceResult rr;
    renderReference(flat.cview(), 3.0f, nullptr, nullptr, ReferenceSettings{}, rr);
    for (float v : rr.ambient.v) CHECK(v == doctest::Approx(1.0).epsilon(1e-6));
    // Pit radius 24 cells, depth = radius: the rim sits between texels, so the
    // horizon is atan(d / r') with r' in [r, r + 1 cell]: bound the value by both.
    const double r = 24.0, d = 24.0;
    const Grid pit = makeGrid(
        64, 64, [&](int x, int y) { return std::hypot(x - 32.0, y - 32.0) < r ? static_cast<float>(-d) : 0.0f; });
    renderReference(pit.cview(), 1.0f, nullptr, nullptr, ReferenceSettings{}, rr);
    const double v = rr.ambient(32, 32);
    MESSAGE("reference pit centre " << v << ", r^2/(r^2+d^2) = " << r * r / (r * r + d * d)
                                    << ", with r+1: " << (r + 1) * (r + 1) / ((r + 1) * (r + 1) + d * d));
    CHECK(v >= r * r / (r * r + d * d) - 1e-6);
    CHECK(v <= (r + 1) * (r + 1) / ((r + 1) * (r + 1) + d * d) + 1e-6);
}

TEST_CASE("gi.reference: SH lighting of the ground truth matches the ambient map under a uniform sky") {
    const Grid g = makeGrid(24, 20, [](int x, int y) { return 4.0f * std::sin(0.4f * x) * std::cos(0.3f * y); });
    const ShRgb sky = uniformSkyLight(1.0f);
    ReferenceResult rr;
    ReferenceSettings rs;
    rs.azimuths = 64;
    renderReference(g.cview(), 1.0f, &sky, nullptr, rs, rr);
    for (std::size_t i = 0; i < rr.ambient.size(); ++i)
        CHECK(rr.rgb[1].v[i] == doctest::Approx(rr.ambient.v[i]).epsilon(1e-5));
}

namespace {

SunSkySettings skyGradient(float zenith, float horizon, float ground) {
    SunSkySettings sky;
    for (int c = 0; c < 3; ++c) {
        sky.zenith[c] = zenith * (1.0f + 0.1f * c);
        sky.horizon[c] = horizon * (1.0f + 0.2f * c);
        sky.ground[c] = ground * (1.0f + 0.3f * c);
        sky.sun[c] = 0.0f;
    }
    return sky;
}

// (1 / pi) int_{N . w > 0} L(w) (N . w) dw by a dense Fibonacci sphere: an
// independent quadrature of the unoccluded gradient sky.
double unoccludedGradientShade(const SunSkySettings& sky, int ch, double nx, double ny, double nz) {
    const int K = 400000;
    double sum = 0.0;
    for (int k = 0; k < K; ++k) {
        const double z = 1.0 - (2.0 * k + 1.0) / K, r = std::sqrt(1.0 - z * z);
        const double phi = k * 2.399963229728653;
        const double cosine = nx * r * std::cos(phi) + ny * r * std::sin(phi) + nz * z;
        if (cosine <= 0.0) continue;
        const double L = z >= 0.0 ? sky.horizon[ch] + (sky.zenith[ch] - sky.horizon[ch]) * z : sky.ground[ch];
        sum += L * cosine;
    }
    return sum * 4.0 * kPi / K / kPi;
}

}  // namespace

TEST_CASE("gi.reference: the sky gradient's function integrated in closed form") {
    const SunSkySettings sky = skyGradient(0.4f, 0.9f, 0.15f);
    ReferenceResult rr;
    ReferenceSettings rs;
    rs.azimuths = 512;
    SUBCASE("flat ground: horizon + 2/3 (zenith - horizon) exactly") {
        const Grid flat(12, 10, 3.0f);
        renderReferenceSkyGradient(flat.cview(), 2.0f, sky, nullptr, rs, rr);
        for (int c = 0; c < 3; ++c)
            for (float v : rr.rgb[static_cast<std::size_t>(c)].v)
                CHECK(v ==
                      doctest::Approx(sky.horizon[c] + 2.0 / 3.0 * (sky.zenith[c] - sky.horizon[c])).epsilon(1e-6));
    }
    SUBCASE("a tilted plane sees the ground below the horizontal: equals a dense quadrature over the sphere") {
        const float slope = 0.7f;  // rises towards +x and, less, +y
        const Grid plane = makeGrid(33, 33, [&](int x, int y) { return slope * x + 0.3f * slope * y; });
        renderReferenceSkyGradient(plane.cview(), 1.0f, sky, nullptr, rs, rr);
        const double n = std::sqrt(1.0 + slope * slope + 0.09 * slope * slope);
        for (int c = 0; c < 3; ++c) {
            const double want = unoccludedGradientShade(sky, c, -slope / n, -0.3 * slope / n, 1.0 / n);
            CHECK(rr.rgb[static_cast<std::size_t>(c)](16, 16) == doctest::Approx(want).epsilon(2e-4));
        }
    }
    SUBCASE("a uniform gradient over bumps is the ambient map; albedo scales it") {
        const Grid g = makeGrid(24, 20, [](int x, int y) { return 4.0f * std::sin(0.4f * x) * std::cos(0.3f * y); });
        rs.azimuths = 64;
        SunSkySettings uniform = skyGradient(1.0f, 1.0f, 1.0f);
        for (int c = 0; c < 3; ++c) uniform.zenith[c] = uniform.horizon[c] = uniform.ground[c] = 1.0f;
        AlbedoMap albedo;
        albedo.channel[2] = Grid(24, 20, 0.5f);
        renderReferenceSkyGradient(g.cview(), 1.0f, uniform, &albedo, rs, rr);
        for (std::size_t i = 0; i < rr.ambient.size(); ++i) {
            CHECK(rr.rgb[0].v[i] == doctest::Approx(rr.ambient.v[i]).epsilon(1e-6));
            CHECK(rr.rgb[2].v[i] == doctest::Approx(0.5 * rr.ambient.v[i]).epsilon(1e-6));
        }
    }
    SUBCASE("a sun lobe is refused: the sun is a key light") {
        SunSkySettings withSun = sky;
        withSun.sun[0] = 1.0f;
        CHECK_THROWS_AS(renderReferenceSkyGradient(Grid(4, 4, 0.0f).cview(), 1.0f, withSun, nullptr, rs, rr),
                        InputError);
    }
}

TEST_CASE("gi.reference: the fast path converges to the ground truth as m, k_v and o_v grow") {
    // Small terrain with horizons of 10-40 degrees: hills plus a ridge.
    const Grid g = makeGrid(56, 56, [](int x, int y) {
        const double u = x / 6.0, v = y / 5.0;
        double h = std::sin(u) * std::cos(v) + 0.6 * std::sin(1.7 * u + 0.9 * v);
        h += 2.0 * std::exp(-std::pow((x - 34.0) / 3.0, 2.0));
        return static_cast<float>(6.0 * h);
    });
    const int border = 6;
    ReferenceResult rr;
    renderReference(g.cview(), 1.0f, nullptr, nullptr, ReferenceSettings{}, rr);
    struct Setting {
        int m, kv, ov;
    };
    const Setting sweep[] = {{8, 2, 0}, {16, 4, 1}, {32, 4, 2}, {64, 8, 4}, {128, 16, 6}};
    double previous = 1e9;
    for (const Setting& s : sweep) {
        GiSettings settings = paperGiSettings();
        settings.visibility.azimuths = s.m;
        settings.pyramid.levelsPerOctave = s.kv;
        settings.pyramid.levelOffset = s.ov;
        settings.visibility.blockingMax = BlockingMax::Samples;
        GiState st;
        runGiFrame(g.cview(), 1.0f, GiLighting{}, settings, st);
        const double e = rmseInterior(st.shade.ambient, rr.ambient, border);
        MESSAGE("m=" << s.m << " k_v=" << s.kv << " o_v=" << s.ov << ": ambient RMSE " << e);
        CHECK(e < previous);
        previous = e;
    }
    // the floor left is the order-4 SH truncation of visibility
    CHECK(previous < 0.02);
}
