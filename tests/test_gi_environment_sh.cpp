// gi/frame: the environment's SH visibility V is computed only when the frame
// reads it. The exact ambient and the analytic sky read the horizons alone,
// so a uniform or analytic sky skips V; the outputs are those of a frame that
// computes it, bit for bit, and a lighting that later reads V gets it.
#include <cstring>

#include <doctest/doctest.h>

#include "core/error.h"
#include "gi/frame.h"
#include "tests/gi_test_terrain.h"

using namespace terrain;
using namespace terrain::gi;
using gi_test::bumpy;
using gi_test::incrementalMatchesFull;
using gi_test::sameBits;
using gi_test::sameOutputs;
using gi_test::sunSkyAndKey;
using gi_test::withBounces;

namespace {

// The analytic sky (its function and its SH projection) and a key light.
GiLighting analyticSkyAndKey() {
    SunSkySettings f;
    GiLighting light = sunSkyAndKey();
    SkyGradient g;
    for (std::size_t c = 0; c < 3; ++c) {
        g.zenith[c] = f.zenith[c] = 0.15f + 0.1f * c;
        g.horizon[c] = f.horizon[c] = 0.3f + 0.05f * c;
        g.ground[c] = f.ground[c] = 0.08f;
        f.sun[c] = 0.0f;
    }
    light.environment = sunSkyLight(f);
    light.gradient = g;
    return light;
}

GiSettings wholeFrames(int subsample, int bounces) {
    GiSettings s = withBounces(GiSettings{}, subsample, bounces);
    s.incremental = false;
    return s;
}

}  // namespace

TEST_CASE("gi.environment_sh: a uniform or analytic sky computes no V and shades as a frame with V, bit for bit") {
    const Grid h = bumpy(45, 38);
    for (int lighting = 0; lighting < 2; ++lighting)
        for (int s : {1, 2})
            for (int bounces : {0, 1}) {
                INFO("lighting " << lighting << ", subsample " << s << ", bounces " << bounces);
                const GiLighting light = lighting == 0 ? GiLighting{} : analyticSkyAndKey();
                GiSettings settings = wholeFrames(s, bounces);
                GiState without, with;
                runGiFrame(h.cview(), 2.0f, light, settings, without);
                CHECK(without.envVisibility.planes == 0);
                CHECK(without.envVisibility.sh.empty());
                settings.minEnvironmentShRows = kShCount;
                runGiFrame(h.cview(), 2.0f, light, settings, with);
                CHECK(with.envVisibility.planes == kShCount);
                CHECK(sameBits(without.envVisibility.maxSlope, with.envVisibility.maxSlope));
                CHECK(sameOutputs(without, with));
            }
}

TEST_CASE("gi.environment_sh: an environment with SH variation, the SH ambient or a glossy BRDF read V") {
    const Grid h = bumpy(40, 33);
    GiSettings settings = wholeFrames(2, 0);
    GiState st;
    runGiFrame(h.cview(), 2.0f, sunSkyAndKey(), settings, st);  // sunSkyLight: SH beyond band 0
    CHECK(st.envVisibility.planes == kShCount);
    GiSettings shAmbient = settings;
    shAmbient.ambient = AmbientMethod::ShProduct;
    runGiFrame(h.cview(), 2.0f, GiLighting{}, shAmbient, st);
    CHECK(st.envVisibility.planes == kShCount);
    GiSettings phong = settings;
    phong.shading.brdf = Brdf::Phong;
    runGiFrame(h.cview(), 2.0f, GiLighting{}, phong, st);  // the uniform sky through the Phong lobe
    CHECK(st.envVisibility.planes == kShCount);
}

TEST_CASE("gi.environment_sh: a lighting that newly reads V on the same geometry gets it, as a full frame would") {
    const Grid h = bumpy(48, 40);
    for (int s : {1, 2}) {
        INFO("subsample " << s);
        GiSettings settings = withBounces(GiSettings{}, s, 1);  // incremental frames
        GiState st;
        CHECK(incrementalMatchesFull(h, 2.0f, GiLighting{}, settings, st));
        CHECK(st.envVisibility.planes == 0);
        CHECK(incrementalMatchesFull(h, 2.0f, sunSkyAndKey(), settings, st));
        CHECK(st.envVisibility.planes == kShCount);
        CHECK(incrementalMatchesFull(h, 2.0f, analyticSkyAndKey(), settings, st));
        // the same heights, once more: no work, the same outputs
        CHECK(incrementalMatchesFull(h, 2.0f, analyticSkyAndKey(), settings, st));
        CHECK(st.receiversRecomputed == 0.0);
    }
}

TEST_CASE("gi.environment_sh: V_00 alone on request, the bits of the full V's first plane; bad requests rejected") {
    const Grid h = bumpy(41, 35);
    GiSettings settings = wholeFrames(2, 0);
    settings.minEnvironmentShRows = 1;
    GiState one, all;
    runGiFrame(h.cview(), 2.0f, GiLighting{}, settings, one);
    settings.minEnvironmentShRows = kShCount;
    runGiFrame(h.cview(), 2.0f, GiLighting{}, settings, all);
    REQUIRE(one.envVisibility.planes == 1);
    const std::size_t plane = static_cast<std::size_t>(one.envVisibility.nxr) * one.envVisibility.nyr;
    REQUIRE(one.envVisibility.sh.size() == plane);
    CHECK(std::memcmp(one.envVisibility.sh.data(), all.envVisibility.sh.data(), plane * sizeof(float)) == 0);
    CHECK(sameOutputs(one, all));
    for (int bad : {-1, 2, 9, 17}) {
        settings.minEnvironmentShRows = bad;
        CHECK_THROWS_AS(runGiFrame(h.cview(), 2.0f, GiLighting{}, settings, one), InputError);
    }
}

TEST_CASE("gi.environment_sh: reshading with a lighting that reads V after a frame without it is an input error") {
    const Grid h = bumpy(36, 30);
    const GiSettings settings = wholeFrames(1, 0);
    GiState st;
    runGiFrame(h.cview(), 2.0f, GiLighting{}, settings, st);
    REQUIRE(st.envVisibility.planes == 0);
    GiLighting brighter;  // a uniform sky still: lit from the ambient map alone
    for (ShVector& c : brighter.environment.c) c[0] *= 2.0;
    CHECK_NOTHROW(shadeDirect(brighter, settings, nullptr, st));
    CHECK_THROWS_AS(shadeDirect(sunSkyAndKey(), settings, nullptr, st), InputError);
}
