#include <algorithm>
#include <cmath>
#include <string>

#include <doctest/doctest.h>

#include "core/parallel.h"
#include "gi/reference_gi.h"
#include "tests/gi_test_terrain.h"

using namespace terrain;
using namespace terrain::gi;

namespace {
// A circular pit of radius r cells and depth d metres, 1 m cells.
Grid pit(int n, float r, float d) {
    Grid g(n, n);
    const float c = 0.5f * static_cast<float>(n - 1);
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const float dx = static_cast<float>(x) - c, dy = static_cast<float>(y) - c;
            g(x, y) = dx * dx + dy * dy <= r * r ? -d : 0.0f;
        }
    return g;
}
using gi_test::valley;
std::array<Grid, 3> constant(int nx, int ny, float v) {
    std::array<Grid, 3> g;
    for (auto& c : g) c.resize(nx, ny, v);
    return g;
}
}  // namespace

TEST_CASE("gi.reference_gi: gathering a uniform unit exit radiance gives 1 - ambient") {
    // Irradiance from terrain of radiance 1 is pi times the normal-weighted
    // solid angle the terrain covers: pi (1 - ambient). The exact ambient of
    // gi/reference (dense azimuths, exact elevation integrals) is an
    // independent computation of the same geometry.
    for (int shape = 0; shape < 2; ++shape) {
        const Grid h = shape == 0 ? pit(41, 10.0f, 10.0f) : valley(41, 41, 1.0f);
        ReferenceSettings rs;
        rs.azimuths = 512;
        ReferenceResult exact;
        renderReference(h.view(), 1.0f, nullptr, nullptr, rs, exact);
        ReferenceGiSettings gs;
        gs.directions = 8192;
        gs.marchStep = 0.25f;
        std::array<Grid, 3> next;
        gatherReferenceBounce(h.view(), 1.0f, constant(41, 41, 1.0f), nullptr, gs, next);
        double sumErr = 0.0, maxErr = 0.0;
        int n = 0;
        for (int y = 8; y < 33; ++y)
            for (int x = 8; x < 33; ++x) {
                const double expect = 1.0 - exact.ambient(x, y);
                const double err = std::fabs(next[0](x, y) - expect);
                sumErr += err;
                maxErr = std::max(maxErr, err);
                ++n;
                CHECK(next[0](x, y) == next[1](x, y));
            }
        MESSAGE(std::string(shape == 0 ? "pit" : "valley")
                << ": mean |gathered - (1 - ambient)| " << sumErr / n << ", max " << maxErr);
        CHECK(sumErr / n < 0.01);
        CHECK(maxErr < 0.05);
        if (shape == 0)
            CHECK(next[0](20, 20) == doctest::Approx(0.5).epsilon(0.03));  // floor centre: 1 - r^2/(r^2+d^2)
    }
}

TEST_CASE("gi.reference_gi: a flat plane gets no indirect light for any bounce count") {
    const Grid h(24, 17, 123.0f);
    for (int b : {1, 2, 3}) {
        ReferenceGiSettings s;
        s.directions = 512;
        s.bounces = b;
        s.azimuths = 64;
        ReferenceGiResult r;
        renderReferenceGi(h.view(), 2.0f, uniformSkyLight(1.0f), nullptr, s, r);
        for (int c = 0; c < 3; ++c)
            for (float v : r.indirect[c].v) CHECK(v == 0.0f);
        CHECK(r.direct[0](12, 8) == doctest::Approx(1.0).epsilon(1e-3));
    }
}

TEST_CASE("gi.reference_gi: bounces lose energy and stay below the closed-cavity bound") {
    const Grid h = valley(33, 9, 1.5f);
    const float albedo = 0.6f;
    AlbedoMap a;
    for (auto& c : a.channel) c.resize(33, 9, albedo);
    ReferenceGiSettings s;
    s.directions = 2048;
    s.azimuths = 128;
    s.bounces = 3;
    ReferenceGiResult r3;
    renderReferenceGi(h.view(), 1.0f, uniformSkyLight(1.0f), &a, s, r3);
    s.bounces = 1;
    ReferenceGiResult r1;
    renderReferenceGi(h.view(), 1.0f, uniformSkyLight(1.0f), &a, s, r1);
    s.bounces = 2;
    ReferenceGiResult r2;
    renderReferenceGi(h.view(), 1.0f, uniformSkyLight(1.0f), &a, s, r2);
    float directMax = 0.0f;
    for (float v : r3.direct[0].v) directMax = std::max(directMax, v);
    const int x = 16, y = 4;  // the valley floor
    const float b1 = r1.indirect[0](x, y);
    const float b2 = r2.indirect[0](x, y) - b1;
    const float b3 = r3.indirect[0](x, y) - r2.indirect[0](x, y);
    MESSAGE("valley floor: direct " << r3.direct[0](x, y) << ", bounce 1 " << b1 << ", bounce 2 " << b2 << ", bounce 3 "
                                    << b3);
    CHECK(b1 > 0.05f);
    CHECK(b2 > 0.0f);
    CHECK(b2 < b1);
    CHECK(b3 < b2);
    for (std::size_t i = 0; i < r3.indirect[0].v.size(); ++i) {
        CHECK(r3.indirect[0].v[i] >= 0.0f);
        CHECK(r3.indirect[0].v[i] <= directMax * albedo / (1.0f - albedo));
    }
}

TEST_CASE("gi.reference_gi: a red wall bleeds red onto a white floor") {
    // A steep red wall (rising 3 m per cell from x = 20 to 12 m) beside a
    // white floor; the wall's albedo starts one cell early so the bilinear
    // faces the floor sees are red throughout.
    Grid h(40, 12, 0.0f);
    AlbedoMap a;
    for (auto& c : a.channel) c.resize(40, 12, 0.8f);
    for (int y = 0; y < 12; ++y)
        for (int x = 19; x < 40; ++x) {
            h(x, y) = std::min(12.0f, 3.0f * static_cast<float>(x - 19));
            a.channel[1](x, y) = 0.05f;
            a.channel[2](x, y) = 0.05f;
        }
    ReferenceGiSettings s;
    s.directions = 2048;
    s.azimuths = 128;
    ReferenceGiResult r;
    renderReferenceGi(h.view(), 1.0f, uniformSkyLight(1.0f), &a, s, r);
    const float red = r.indirect[0](15, 6), green = r.indirect[1](15, 6), blue = r.indirect[2](15, 6);
    MESSAGE("floor next to the red wall: indirect rgb " << red << " " << green << " " << blue);
    CHECK(red > 0.02f);
    CHECK(red > 5.0f * green);
    CHECK(green == doctest::Approx(blue).epsilon(1e-4));
}

TEST_CASE("gi.reference_gi: bit-identical for 1, 2, 3 and 8 threads") {
    const Grid h = pit(23, 6.0f, 5.0f);
    ReferenceGiSettings s;
    s.directions = 256;
    s.azimuths = 32;
    s.bounces = 2;
    auto run = [&] {
        ReferenceGiResult r;
        renderReferenceGi(h.view(), 1.0f, uniformSkyLight(1.0f), nullptr, s, r);
        return r.total[0].v;
    };
    const auto ref = withThreads(1, run);
    for (int t : {2, 3, 8}) CHECK(withThreads(t, run) == ref);
}

TEST_CASE("gi.reference.keycap: exact cap on a flat plane and in a shadowed pit") {
    using namespace terrain;
    using namespace terrain::gi;
    // flat plane: int_cap (N . d) = pi sin^2(r) (N . l), radiance RGB / sin^2 r -> albedo RGB sin(el)
    Grid h(33, 33, 5.0f);
    KeyLight k;
    k.azimuthDeg = 30.0f;
    k.elevationDeg = 40.0f;
    k.radiusDeg = 6.0f;
    k.rgb[0] = 1.0f;
    k.rgb[1] = 0.5f;
    k.rgb[2] = 2.0f;
    std::array<Grid, 3> rgb;
    addReferenceKeyLight(h.cview(), 1.0f, k, nullptr, 64, rgb);
    const double expect = std::sin(40.0 * kPi / 180.0);
    for (int c = 0; c < 3; ++c) CHECK(rgb[c](16, 16) == doctest::Approx(k.rgb[c] * expect).epsilon(2e-3));
    // a 10 m wall towards the light: 10 cells away it rises 45 deg (cap fully hidden),
    // 40 cells away 14 deg (below the cap's lowest 15 deg: fully lit)
    Grid w(64, 64, 0.0f);
    for (int y = 0; y < 64; ++y)
        for (int x = 40; x < 64; ++x) w(x, y) = 10.0f;
    KeyLight e;
    e.azimuthDeg = 0.0f;
    e.elevationDeg = 20.0f;
    e.radiusDeg = 5.0f;
    std::array<Grid, 3> sh;
    addReferenceKeyLight(w.cview(), 1.0f, e, nullptr, 32, sh);
    CHECK(sh[0](30, 32) == 0.0f);
    CHECK(sh[0](0, 32) == doctest::Approx(std::sin(20.0 * kPi / 180.0)).epsilon(2e-3));
}
