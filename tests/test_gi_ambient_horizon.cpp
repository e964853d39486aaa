// The exact per-azimuth ambient (gi/ambient_horizon.h) against closed forms
// and the ground truth of gi/reference.
#include <cmath>

#include <doctest/doctest.h>

#include "core/error.h"
#include "core/parallel.h"
#include "gi/frame.h"
#include "gi/reference.h"
#include "tests/gi_test_terrain.h"

using namespace terrain;
using namespace terrain::gi;
using gi_test::gridOf;

namespace {

double rmseInterior(const Grid& a, const Grid& b, int border, double* bias = nullptr) {
    double s = 0.0, sb = 0.0;
    int n = 0;
    for (int y = border; y < a.ny - border; ++y)
        for (int x = border; x < a.nx - border; ++x) {
            const double d = static_cast<double>(a(x, y)) - b(x, y);
            s += d * d;
            sb += d;
            ++n;
        }
    if (bias) *bias = sb / n;
    return std::sqrt(s / n);
}

double worstInterior(const Grid& g, float value, int border) {
    double w = 0.0;
    for (int y = border; y < g.ny - border; ++y)
        for (int x = border; x < g.nx - border; ++x) w = std::max(w, std::abs(static_cast<double>(g(x, y)) - value));
    return w;
}

}  // namespace

TEST_CASE("gi.ambient_horizon: a tilted plane sees its whole upper hemisphere: ambient 1 at 1x, 2x and 4x") {
    // No horizon rises above the tangent plane, so the visible sky is the
    // hemisphere about N and the normal-weighted sky-view factor is 1; what is
    // left is the midpoint rule over 16 azimuths of a smooth function of phi
    // and the max-decimated pyramid levels, which on a slope sit a little
    // above the plane (GiSettings{}: peak blend 1).
    for (float slope : {0.0f, 0.3f, 1.5f}) {
        const Grid g = gridOf(48, 40, [&](int x, int y) { return slope * (0.8f * x - 0.6f * y); });
        for (int s : {1, 2, 4}) {
            GiSettings settings;
            settings.subsample = s;
            GiState st;
            runGiFrame(g.cview(), 2.0f, GiLighting{}, settings, st);
            const double worst = worstInterior(st.shade.ambient, 1.0f, 0);
            MESSAGE("slope " << slope << ", " << s << "x: largest |ambient - 1| " << worst);
            CHECK(worst < (slope == 0.0f ? 1e-6 : 2.5e-3 * slope));
        }
    }
}

TEST_CASE("gi.ambient_horizon: the pit floor centre is the mean of cos^2 of the horizon, near r^2 / (r^2 + d^2)") {
    // Pit of radius r = 16 cells (cell 2 m), depth d, receiver at the centre
    // on flat floor: ambient = (1 / 2 pi) int cos^2 h(phi) dphi exactly, with
    // no SH term. Against the reference march's horizons (256 azimuths) the
    // only difference is where the pyramid's steps land beyond the rim.
    const int n = 72;
    const double cell = 2.0, r = 16.0 * cell;
    for (double d : {0.5 * r, r, 2.0 * r}) {
        const Grid g = gridOf(n, n, [&](int x, int y) {
            return std::hypot(x - 36.0, y - 36.0) * cell < r ? static_cast<float>(-d) : 0.0f;
        });
        GiSettings settings;
        settings.visibility.azimuths = 64;
        settings.pyramid.levelsPerOctave = 16;
        settings.pyramid.levelOffset = 6;
        GiState st;
        runGiFrame(g.cview(), static_cast<float>(cell), GiLighting{}, settings, st);
        double fromReference = 0.0;
        for (int a = 0; a < 256; ++a) {
            const double phi = 2.0 * kPi * (a + 0.5) / 256.0;
            const double t =
                referenceMaxSlope(g.cview(), static_cast<float>(cell), 36, 36, std::cos(phi), std::sin(phi), 0.0);
            fromReference += 1.0 / (1.0 + t * t) / 256.0;
        }
        const double fast = st.shade.ambient(36, 36), exact = r * r / (r * r + d * d);
        MESSAGE("pit d/r = " << d / r << ": fast " << fast << ", from the reference horizons " << fromReference
                             << ", r^2/(r^2+d^2) " << exact);
        CHECK(std::abs(fast - fromReference) < 0.006);
        CHECK(std::abs(fast - exact) < 0.02);
    }
}

TEST_CASE("gi.ambient_horizon: on rough terrain it is closer to the ground truth than the SH product") {
    const Grid g = gridOf(64, 64, [](int x, int y) {
        return 6.0f * std::sin(0.37f * x) * std::cos(0.23f * y) + 3.0f * std::sin(0.11f * x + 0.71f * y) +
               0.05f * static_cast<float>(x * y % 7);
    });
    const float cell = 1.5f;
    ReferenceResult ref;
    renderReference(g.cview(), cell, nullptr, nullptr, ReferenceSettings{}, ref);
    const int border = 6;
    for (int s : {1, 2}) {
        GiSettings horizons, sh;
        horizons.subsample = sh.subsample = s;
        sh.ambient = AmbientMethod::ShProduct;
        GiState a, b;
        runGiFrame(g.cview(), cell, GiLighting{}, horizons, a);
        runGiFrame(g.cview(), cell, GiLighting{}, sh, b);
        double biasH = 0.0, biasS = 0.0;
        const double eH = rmseInterior(a.shade.ambient, ref.ambient, border, &biasH);
        const double eS = rmseInterior(b.shade.ambient, ref.ambient, border, &biasS);
        MESSAGE(s << "x: RMSE horizons " << eH << " (bias " << biasH << "), SH product " << eS << " (bias " << biasS
                  << ")");
        CHECK(eH < eS);
        CHECK(eH < (s == 1 ? 0.007 : 0.014));
        // a uniform unit sky is all constant part: its Lambert shade is the exact ambient, bit for bit
        for (const Grid& channel : a.shade.rgb) CHECK(gi_test::sameBits(channel.v, a.shade.ambient.v));
    }
}

TEST_CASE("gi.ambient_horizon: at sub-sampling a texel between receivers sees its own near field") {
    // ridges on the even columns (the receivers at 2x), one-cell valleys on
    // the odd ones: the receivers see open sky across the ridges, a valley
    // texel a wall of slope 2 one cell away on either side
    const Grid g = gridOf(48, 48, [](int x, int) { return x % 2 == 0 ? 2.0f : 0.0f; });
    ReferenceResult ref;
    ReferenceSettings rs;
    rs.border = 8;
    renderReference(g.cview(), 1.0f, nullptr, nullptr, rs, ref);
    GiSettings settings;
    settings.subsample = 2;
    GiState st;
    runGiFrame(g.cview(), 1.0f, GiLighting{}, settings, st);
    for (int x : {23, 25}) {
        const double fast = st.shade.ambient(x, 24), exact = ref.ambient(x, 24);
        MESSAGE("valley texel " << x << ": 2x " << fast << ", reference " << exact);
        CHECK(exact < 0.5);
        CHECK(fast == doctest::Approx(exact).epsilon(0.05));
    }
}

TEST_CASE("gi.ambient_horizon: a state reused for a field of another size gives what a fresh state gives") {
    // the SH shading must not write the exact ambient's map (once of another size)
    const Grid small = gridOf(24, 20, [](int x, int y) { return 0.3f * x - 0.2f * y; });
    const Grid large = gi_test::bumpy(72, 60);
    for (int s : {1, 2}) {
        GiSettings settings;
        settings.subsample = s;
        GiState reused, fresh;
        runGiFrame(small.cview(), 2.0f, GiLighting{}, settings, reused);
        runGiFrame(large.cview(), 2.0f, gi_test::sunSkyAndKey(), settings, reused);
        runGiFrame(large.cview(), 2.0f, gi_test::sunSkyAndKey(), settings, fresh);
        CHECK(gi_test::sameOutputs(reused, fresh));
    }
}

TEST_CASE("gi.ambient_horizon: horizons of another grid or azimuth count are refused") {
    const Grid g = gridOf(16, 16, [](int x, int y) { return 0.1f * x * y; });
    GiState st;
    runGiFrame(g.cview(), 1.0f, GiLighting{}, GiSettings{}, st);
    AmbientInputs in{.gradX = st.gradX.cview(),
                     .gradY = st.gradY.cview(),
                     .subsample = 2,
                     .env = &st.envVisibility,
                     .cosSin = st.envCosSin};
    Grid out;
    AmbientScratch scratch;
    CHECK_THROWS_AS(ambientFromHorizons(in, {out}, scratch), InputError);
    in.subsample = 1;
    in.cosSin = std::span<const float>(st.envCosSin).first(4);
    CHECK_THROWS_AS(ambientFromHorizons(in, {out}, scratch), InputError);
}

namespace {

// The analytic sky as a function and as its SH projection, as engine::LightRig gives them.
GiLighting gradientSky(float scale) {
    SunSkySettings f;
    GiLighting light;
    SkyGradient g;
    for (std::size_t c = 0; c < 3; ++c) {
        g.zenith[c] = f.zenith[c] = scale * (0.15f + 0.1f * c);
        g.horizon[c] = f.horizon[c] = scale * (0.3f + 0.05f * c);
        g.ground[c] = f.ground[c] = scale * 0.08f;
        f.sun[c] = 0.0f;
    }
    light.environment = sunSkyLight(f);
    light.gradient = g;
    return light;
}

double relativeRmse(const std::array<Grid, 3>& a, const std::array<Grid, 3>& b, int border) {
    double se = 0.0, sr = 0.0;
    for (std::size_t c = 0; c < 3; ++c)
        for (int y = border; y < a[c].ny - border; ++y)
            for (int x = border; x < a[c].nx - border; ++x) {
                const double d = static_cast<double>(a[c](x, y)) - b[c](x, y);
                se += d * d;
                sr += static_cast<double>(b[c](x, y)) * b[c](x, y);
            }
    return std::sqrt(se / sr);
}

}  // namespace

TEST_CASE("gi.ambient_horizon: the analytic sky lit by its own function above the horizons, not its SH") {
    const GiLighting light = gradientSky(1.0f);
    SunSkySettings f;
    for (std::size_t c = 0; c < 3; ++c) {
        f.zenith[c] = light.gradient->zenith[c];
        f.horizon[c] = light.gradient->horizon[c];
        f.ground[c] = light.gradient->ground[c];
        f.sun[c] = 0.0f;
    }
    SUBCASE("flat ground: horizon + 2/3 (zenith - horizon)") {
        GiState st;
        runGiFrame(Grid(24, 20, 1.0f).cview(), 1.0f, light, GiSettings{}, st);
        for (std::size_t c = 0; c < 3; ++c)
            for (float v : st.shade.rgb[c].v)
                CHECK(v == doctest::Approx(f.horizon[c] + 2.0 / 3.0 * (f.zenith[c] - f.horizon[c])).epsilon(1e-5));
    }
    SUBCASE("rough terrain: closer to the sky function's reference than through SH, at 1x and 2x") {
        const Grid g = gi_test::bumpy(64, 64);
        ReferenceResult ref;
        ReferenceSettings rs;
        rs.border = 6;
        renderReferenceSkyGradient(g.cview(), 2.0f, f, nullptr, rs, ref);
        GiLighting shOnly = light;
        shOnly.gradient.reset();
        for (int s : {1, 2}) {
            GiSettings settings;
            settings.subsample = s;
            GiState exact, sh;
            runGiFrame(g.cview(), 2.0f, light, settings, exact);
            runGiFrame(g.cview(), 2.0f, shOnly, settings, sh);
            const double eExact = relativeRmse(exact.shade.rgb, ref.rgb, 6);
            const double eSh = relativeRmse(sh.shade.rgb, ref.rgb, 6);
            const double eAmbient = relativeRmse({exact.shade.ambient, exact.shade.ambient, exact.shade.ambient},
                                                 {ref.ambient, ref.ambient, ref.ambient}, 6);
            MESSAGE(s << "x: sky shade relative RMSE, its function " << eExact << ", its SH " << eSh << "; ambient "
                      << eAmbient);
            CHECK(eExact < eSh);
            // what is left is the horizons' error, which the ambient shows alone
            CHECK(eExact < 1.1 * eAmbient + 0.002);
        }
    }
    SUBCASE("the same bits for any thread count, and a relit frame equals a fresh one") {
        const Grid g = gi_test::bumpy(40, 36);
        GiSettings settings;
        settings.subsample = 2;
        GiState one, three;
        withThreads(1, [&] { return runGiFrame(g.cview(), 2.0f, light, settings, one), 0; });
        withThreads(3, [&] { return runGiFrame(g.cview(), 2.0f, light, settings, three), 0; });
        CHECK(gi_test::sameOutputs(one, three));
        GiState relit;
        runGiFrame(g.cview(), 2.0f, GiLighting{}, settings, relit);  // no sky parts yet
        CHECK(gi_test::incrementalMatchesFull(g, 2.0f, gradientSky(0.5f), settings, relit));
        CHECK(gi_test::incrementalMatchesFull(g, 2.0f, gradientSky(1.5f), settings, relit));
    }
}
