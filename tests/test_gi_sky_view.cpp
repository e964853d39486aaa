// The plain sky-view factor (gi/sky_view.h) against closed forms and its
// reference from the exact horizons.
#include <cmath>

#include <doctest/doctest.h>

#include "core/error.h"
#include "gi/frame.h"
#include "gi/sky_view.h"
#include "tests/gi_test_terrain.h"

using namespace terrain;
using namespace terrain::gi;
using gi_test::gridOf;

TEST_CASE("gi.sky_view: 1 on a flat plane and on a ridge top, 1 - sin(atan(d / r)) at a pit's floor centre") {
    const Grid flat(24, 20, 3.0f);
    GiState st;
    runGiFrame(flat.cview(), 2.0f, GiLighting{}, GiSettings{}, st);
    Grid svf;
    skyViewFactor(st, flat.cview(), svf);
    for (float v : svf.v) CHECK(v == 1.0f);
    // pit of radius r = 16 cells (cell 2 m), depth d = r: horizon 45 degrees
    const int n = 72;
    const double cell = 2.0, r = 16.0 * cell, d = r;
    const Grid pit = gridOf(
        n, n, [&](int x, int y) { return std::hypot(x - 36.0, y - 36.0) * cell < r ? static_cast<float>(-d) : 0.0f; });
    // the pyramid sampling the rim finely (the default's coarse levels blur a
    // vertical wall and lower the horizon: printed)
    for (int s : {1, 2}) {
        GiSettings settings;
        settings.subsample = s;
        settings.visibility.azimuths = 64;
        settings.pyramid.levelsPerOctave = 16;
        settings.pyramid.levelOffset = 6;
        runGiFrame(pit.cview(), static_cast<float>(cell), GiLighting{}, settings, st);
        skyViewFactor(st, pit.cview(), svf);
        const double expected = 1.0 - std::sin(std::atan(d / r));
        MESSAGE(s << "x: pit centre " << svf(36, 36) << ", 1 - sin 45 deg = " << expected);
        CHECK(std::abs(svf(36, 36) - expected) < 0.02);
    }
    runGiFrame(pit.cview(), static_cast<float>(cell), GiLighting{}, GiSettings{}, st);
    skyViewFactor(st, pit.cview(), svf);
    MESSAGE("default settings, 1x: pit centre " << svf(36, 36));
    Grid ref;
    referenceSkyViewFactor(pit.cview(), static_cast<float>(cell), 256, ref);
    MESSAGE("reference pit centre " << ref(36, 36));
    CHECK(std::abs(ref(36, 36) - (1.0 - std::sin(std::atan(d / r)))) < 0.02);
    // a texel on the plateau far from the pit sees the whole hemisphere
    CHECK(ref(2, 2) == 1.0f);
}

TEST_CASE("gi.sky_view: the fast factor follows the reference on rough terrain, at 1x and 2x") {
    const Grid g = gridOf(64, 64, [](int x, int y) {
        return 6.0f * std::sin(0.37f * x) * std::cos(0.23f * y) + 3.0f * std::sin(0.11f * x + 0.71f * y);
    });
    Grid ref;
    referenceSkyViewFactor(g.cview(), 1.5f, 256, ref);
    for (int s : {1, 2}) {
        GiSettings settings;
        settings.subsample = s;
        GiState st;
        runGiFrame(g.cview(), 1.5f, GiLighting{}, settings, st);
        Grid svf;
        skyViewFactor(st, g.cview(), svf);
        double sum = 0.0;
        int count = 0;
        for (int y = 6; y < 58; ++y)
            for (int x = 6; x < 58; ++x) {
                const double e = svf(x, y) - ref(x, y);
                sum += e * e;
                ++count;
                REQUIRE(svf(x, y) >= 0.0f);
                REQUIRE(svf(x, y) <= 1.0f);
            }
        const double rmse = std::sqrt(sum / count);
        MESSAGE(s << "x: sky-view factor RMSE against the reference " << rmse);
        // at 2x the texels between receivers take their own near field
        CHECK(rmse < (s == 1 ? 0.01 : 0.025));
    }
    GiState st;
    runGiFrame(g.cview(), 1.5f, GiLighting{}, GiSettings{}, st);
    Grid svf;
    CHECK_THROWS_AS(skyViewFactor(st, Grid(32, 64, 0.0f).cview(), svf), InputError);
}
