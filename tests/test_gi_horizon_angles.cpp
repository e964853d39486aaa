// Horizon elevation angles (gi/horizon_angles.h) against closed forms: a
// tilted plane (every azimuth's horizon is the plane itself, negative
// downhill), a pit (the rim at 45 degrees from its centre), the border (no
// terrain: -90), and the compass bearings of the engine's azimuths.
#include <algorithm>
#include <cmath>

#include <doctest/doctest.h>

#include "core/error.h"
#include "gi/frame.h"
#include "gi/horizon_angles.h"
#include "gi/sh.h"
#include "gi/sky_view.h"
#include "tests/gi_test_terrain.h"

using namespace terrain;
using namespace terrain::gi;
using gi_test::gridOf;

namespace {

double degrees(double radians) { return radians * 180.0 / kPi; }

// The fast angles of `g` at `subsample` with the given scan settings.
HorizonAngles fastAngles(const Grid& g, float cell, GiSettings settings, int subsample) {
    settings.subsample = subsample;
    GiState st;
    runGiFrame(g.cview(), cell, GiLighting{}, settings, st);
    HorizonAngles h;
    horizonAnglesFromScan(st.envVisibility, st.envOperator.phi, subsample, g.nx, g.ny, h);
    return h;
}

}  // namespace

TEST_CASE("gi.horizon_angles: the scan's azimuths, and compass bearings clockwise from north") {
    const Grid flat(20, 20, 1.0f);
    GiState st;
    runGiFrame(flat.cview(), 1.0f, GiLighting{}, GiSettings{}, st);
    CHECK(scanAzimuths(GiSettings{}.visibility.azimuths) == st.envOperator.phi);
    CHECK_THROWS_AS(scanAzimuths(0), InputError);
    // north-up raster (row 0 north): +x east, +y south
    CHECK(compassAzimuthDegrees(0.0, 1.0, -1.0) == 90.0);
    CHECK(compassAzimuthDegrees(0.5 * kPi, 1.0, -1.0) == 180.0);
    CHECK(compassAzimuthDegrees(kPi, 1.0, -1.0) == 270.0);
    CHECK(compassAzimuthDegrees(1.5 * kPi, 1.0, -1.0) == 0.0);
    CHECK(compassAzimuthDegrees(0.25 * kPi, 1.0, -1.0) == 135.0);
    // rows running north (+y north)
    CHECK(compassAzimuthDegrees(0.5 * kPi, 1.0, 1.0) == 0.0);
    CHECK(compassAzimuthDegrees(0.25 * kPi, 1.0, 1.0) == 45.0);
    CHECK(horizonDegrees(kNoBlocker) == -90.0);
    CHECK(horizonDegrees(1.0) == doctest::Approx(45.0));
    CHECK(horizonDegrees(-1.0) == doctest::Approx(-45.0));
}

TEST_CASE("gi.horizon_angles: a tilted plane's horizon is the plane, signed: atan(a cos phi) at every azimuth") {
    const int n = 48;
    const float cell = 2.0f;
    const double a = 0.5;  // height gain per metre along +x
    const Grid plane = gridOf(n, n, [&](int x, int) { return static_cast<float>(a * cell * x); });
    const std::vector<double> phi = scanAzimuths(16);
    HorizonAngles exact;
    referenceHorizonAngles(plane.cview(), cell, phi, exact);
    REQUIRE(exact.degrees.size() == phi.size());
    for (std::size_t j = 0; j < phi.size(); ++j) {
        const double expected = degrees(std::atan(a * std::cos(phi[j])));
        CHECK(exact.degrees[j](24, 24) == doctest::Approx(expected).epsilon(1e-4));
        CHECK(exact.degrees[j](10, 30) == doctest::Approx(expected).epsilon(1e-4));
    }
    // the plain sky-view factor of that plane: the lune below it hidden, 1 - S / pi
    Grid svf;
    referenceSkyViewFactor(plane.cview(), cell, 256, svf);
    CHECK(svf(24, 24) == doctest::Approx(1.0 - std::atan(a) / kPi).epsilon(1e-3));
    // the east border looking east, the north border looking north: nothing there
    CHECK(exact.degrees[0](n - 1, 20) == -90.0f);
    CHECK(exact.degrees[12](20, 0) == -90.0f);
    for (int s : {1, 2}) {
        const HorizonAngles fast = fastAngles(plane, cell, GiSettings{}, s);
        REQUIRE(fast.degrees.size() == phi.size());
        CHECK(fast.azimuths == phi);
        // the pyramid's octaves are max-decimated (they keep every peak), so
        // its coarse samples stand above the plane: the fast horizon is raised,
        // most where the plane falls away
        double above = 0.0, below = 0.0;
        for (std::size_t j = 0; j < phi.size(); ++j) {
            REQUIRE(fast.degrees[j].nx == n);
            REQUIRE(fast.degrees[j].ny == n);
            for (int y = 12; y < 36; ++y)
                for (int x = 12; x < 36; ++x) {
                    const double e = fast.degrees[j](x, y) - exact.degrees[j](x, y);
                    above = std::max(above, e);
                    below = std::max(below, -e);
                }
        }
        MESSAGE(s << "x: tilted plane, fast - exact horizon within [" << -below << ", " << above << "] degrees");
        CHECK(above < 3.5);
        CHECK(below < 0.1);
        CHECK(fast.degrees[0](n - 1, 20) == -90.0f);
    }
}

TEST_CASE("gi.horizon_angles: from a pit's floor centre the rim stands at atan(d / r) at every azimuth") {
    const int n = 72;
    const double cell = 2.0, r = 16.0 * cell, d = r;
    const Grid pit = gridOf(
        n, n, [&](int x, int y) { return std::hypot(x - 36.0, y - 36.0) * cell < r ? static_cast<float>(-d) : 0.0f; });
    const std::vector<double> phi = scanAzimuths(64);
    HorizonAngles exact;
    referenceHorizonAngles(pit.cview(), static_cast<float>(cell), phi, exact);
    // the fast scan with levels fine enough to keep the rim's step (the default
    // pyramid blurs a vertical wall: gi.sky_view)
    GiSettings settings;
    settings.visibility.azimuths = 64;
    settings.pyramid.levelsPerOctave = 16;
    settings.pyramid.levelOffset = 6;
    const HorizonAngles fast = fastAngles(pit, static_cast<float>(cell), settings, 1);
    const double expected = degrees(std::atan(d / r));
    double worstExact = 0.0, worstFast = 0.0;
    for (std::size_t j = 0; j < phi.size(); ++j) {
        worstExact = std::max(worstExact, std::abs(exact.degrees[j](36, 36) - expected));
        worstFast = std::max(worstFast, std::abs(fast.degrees[j](36, 36) - expected));
    }
    MESSAGE("pit centre: largest |angle - 45| exact " << worstExact << ", fast " << worstFast << " degrees");
    // the discrete rim lies up to a cell beyond r
    CHECK(worstExact < 2.0);
    CHECK(worstFast < 2.5);
    // a plateau texel looking away from the pit: the flat plateau, 0 degrees
    CHECK(exact.degrees[0](60, 4) == 0.0f);
}

TEST_CASE("gi.horizon_angles: sub-sampled angles are the receivers' at their texels, interpolated between") {
    const Grid g = gridOf(40, 34, [](int x, int y) {
        return 6.0f * std::sin(0.37f * x) * std::cos(0.23f * y) + 3.0f * std::sin(0.11f * x + 0.71f * y);
    });
    GiSettings settings;
    settings.subsample = 2;
    GiState st;
    runGiFrame(g.cview(), 1.5f, GiLighting{}, settings, st);
    HorizonAngles h;
    horizonAnglesFromScan(st.envVisibility, st.envOperator.phi, 2, 40, 34, h);
    const int nxr = st.envVisibility.nxr, nyr = st.envVisibility.nyr;
    for (std::size_t j = 0; j < h.degrees.size(); ++j) {
        const float* slopes = st.envVisibility.maxSlope.data() + j * static_cast<std::size_t>(nxr) * nyr;
        auto receiver = [&](int X, int Y) {
            return static_cast<float>(horizonDegrees(slopes[static_cast<std::size_t>(Y) * nxr + X]));
        };
        CHECK(h.degrees[j](10, 8) == receiver(5, 4));
        CHECK(h.degrees[j](11, 8) == doctest::Approx(0.5f * (receiver(5, 4) + receiver(6, 4))).epsilon(1e-5));
    }
    // the east border's receivers see nothing eastwards (-90): the texel between the
    // last two receivers takes the inner one's angle, not a blend with -90
    const int last = nxr - 1;
    REQUIRE(horizonDegrees(st.envVisibility.maxSlope[static_cast<std::size_t>(4) * nxr + last]) == -90.0);
    REQUIRE(st.envVisibility.maxSlope[static_cast<std::size_t>(4) * nxr + last - 1] > kNoBlocker);
    CHECK(h.degrees[0](2 * last - 1, 8) ==
          static_cast<float>(horizonDegrees(st.envVisibility.maxSlope[static_cast<std::size_t>(4) * nxr + last - 1])));
    CHECK(h.degrees[0](2 * last, 8) == -90.0f);
    CHECK_THROWS_AS(horizonAnglesFromScan(st.envVisibility, st.envOperator.phi, 1, 40, 34, h), InputError);
    CHECK_THROWS_AS(horizonAnglesFromScan(st.envVisibility, scanAzimuths(8), 2, 40, 34, h), InputError);
}

TEST_CASE("gi.horizon_angles: at sub-sampling a texel between receivers takes its own near field") {
    // ridges on the even columns (the receivers at 2x), one-cell valleys on the
    // odd ones: across the ridges a valley texel sees a wall of slope 2
    const Grid g = gridOf(40, 34, [](int x, int) { return x % 2 == 0 ? 2.0f : 0.0f; });
    GiSettings settings;
    settings.subsample = 2;
    GiState st;
    runGiFrame(g.cview(), 1.0f, GiLighting{}, settings, st);
    HorizonAngles h;
    horizonAnglesFromScan(st.envVisibility, st.envOperator.phi, 2, 40, 34, h);
    const float interpolated = h.degrees[0](21, 16);  // azimuth 0: along +x, across the ridges
    raiseHorizonAnglesToNearField(g.cview(), 1.0f, 2, h);
    HorizonAngles exact;
    referenceHorizonAngles(g.cview(), 1.0f, h.azimuths, exact);
    MESSAGE("valley texel along +x: interpolated " << interpolated << ", with its near field " << h.degrees[0](21, 16)
                                                   << ", exact " << exact.degrees[0](21, 16));
    CHECK(interpolated < 1.0f);
    CHECK(h.degrees[0](21, 16) == doctest::Approx(exact.degrees[0](21, 16)).epsilon(1e-4));
    // a receiver on a ridge keeps its own angle
    CHECK(h.degrees[0](20, 16) == doctest::Approx(exact.degrees[0](20, 16)).epsilon(0.05));
}
