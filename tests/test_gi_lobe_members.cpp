// What the lobe gather's first-bounce members send (gi/glossy_lobe_members.h):
// the lobe-filtered light times the part of the lobe above the horizon.
#include <cmath>
#include <vector>

#include <doctest/doctest.h>

#include "gi/glossy_lobe_members.h"
#include "gi/phong_lobe_quadrature.h"

using namespace terrain;
using namespace terrain::gi;

namespace {

// Flat ground of n x n texels (1x) under a uniform sky of radiance 1, every
// receiver's horizon at slope `horizon` along every azimuth, no diffuse part.
struct FlatMembers {
    Grid gx, gy;
    VisibilityField env;
    LobeMembers m;
    FlatMembers(int n, float horizon, float S) : gx(n, n, 0.0f), gy(n, n, 0.0f) {
        env.nxr = env.nyr = n;
        env.maxSlope.assign(static_cast<std::size_t>(n) * n * 16, horizon);
        ShadingSettings shading;
        shading.brdf = Brdf::Phong;
        shading.phongExponent = S;
        prepareLobeMembers(gx.cview(), gy.cview(), env, 1, uniformSkyLight(1.0f), nullptr, shading, m);
        for (std::size_t k = 0; k < static_cast<std::size_t>(n) * n; ++k)
            for (int c = 0; c < 3; ++c) m.texels[k * LobeMembers::kRecord + LobeMembers::kDiffuse + c] = 0.0f;
    }
    // what the member at the centre sends towards `back`, whose reflection
    // about the flat ground's normal lies at elevation e (radians), azimuth 0
    float sendsWithReflectionAt(double e) const {
        const float back[3] = {static_cast<float>(-std::cos(e)), 0.0f, static_cast<float>(std::sin(e))};
        LobeMemberHits hits;
        hits.push(m, 8.3, 8.6, back);
        lobeMembersSend<simd::F4>(m, hits);
        return hits.sent[0][0];
    }
};

// The part of the Phong lobe of exponent S about elevation e (azimuth 0)
// above the horizontal plane, by a fine lobe quadrature.
double lobeAboveHorizontal(double e, double S) {
    const double r[3] = {std::cos(e), 0.0, std::sin(e)};
    double t[3], b[3];
    lobeFrame(r, t, b);
    const int n = 200;
    const LobeLayout layout = LobeLayout::uniform(n);
    double above = 0.0;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < 2 * n; ++j) {
            double w[3];
            lobeDirection(r, t, b, S, layout, i, j, w);
            above += w[2] > 0.0;
        }
    return above / (2.0 * n * n);
}

}  // namespace

TEST_CASE("gi.lobe_members: an open sky sends the filtered light, a horizon above the lobe nothing") {
    // a uniform sky filtered by any lobe is the sky itself (g_0 = 1)
    const FlatMembers open(17, -1.0e6f, 32.0f);
    CHECK(open.sendsWithReflectionAt(0.8) == doctest::Approx(1.0).epsilon(1e-4));
    // a horizon at 45 degrees: a lobe about 80 degrees clears it, one about
    // 10 degrees lies below it (its spread is 1 / sqrt(33) rad, 10 degrees)
    const FlatMembers walled(17, 1.0f, 32.0f);
    CHECK(walled.sendsWithReflectionAt(80.0 * kPi / 180.0) == doctest::Approx(1.0).epsilon(1e-3));
    CHECK(walled.sendsWithReflectionAt(10.0 * kPi / 180.0) < 1e-3);
    // and half of a lobe about the horizon itself
    CHECK(walled.sendsWithReflectionAt(0.25 * kPi) == doctest::Approx(0.5).epsilon(1e-3));
}

TEST_CASE("gi.lobe_members: the open fraction is the lobe's part above a horizontal horizon") {
    // The closed form treats the lobe as a 2D normal of variance 1 / (S + 1)
    // per axis; against a fine quadrature of the lobe itself it holds to
    // 0.01 from S = 8 on (measured: within 0.004).
    for (float S : {8.0f, 32.0f, 64.0f}) {
        const FlatMembers m(17, 0.0f, S);
        for (double deg : {-20.0, -8.0, -3.0, 0.0, 3.0, 8.0, 20.0}) {
            const double e = deg * kPi / 180.0;
            const double closed = m.sendsWithReflectionAt(e), exact = lobeAboveHorizontal(e, S);
            INFO("S = " << S << ", elevation " << deg << ": closed form " << closed << ", quadrature " << exact);
            CHECK(std::fabs(closed - exact) < 0.01);
        }
    }
}
