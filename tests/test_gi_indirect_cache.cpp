// gi/indirect_cache: the indirect light re-gathers the receiver tiles whose
// sources or geometry drifted beyond the tolerance, bit for bit a full
// recompute at tolerance 0, and the radiance bound it adds up holds.
#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include <doctest/doctest.h>

#include "core/parallel.h"
#include "gi/change_bound.h"
#include "gi/frame.h"
#include "gi/visibility_cache.h"
#include "sim/scene.h"
#include "tests/gi_test_terrain.h"

using namespace terrain;
using namespace terrain::gi;
using gi_test::bumpy;
using gi_test::incrementalMatchesFull;
using gi_test::sameOutputs;
using gi_test::sunSkyAndKey;
using gi_test::withBounces;

namespace {

constexpr float kCell = 2.0f;

// Largest |a - b| over every channel of two RGB maps.
double largestDifference(const std::array<Grid, 3>& a, const std::array<Grid, 3>& b) {
    double worst = 0.0;
    for (std::size_t c = 0; c < 3; ++c)
        for (std::size_t i = 0; i < a[c].v.size(); ++i)
            worst = std::max(worst, std::fabs(static_cast<double>(a[c].v[i]) - b[c].v[i]));
    return worst;
}

}  // namespace

TEST_CASE("gi.indirect_cache: one-bounce incremental frames equal full recomputes, for any thread count") {
    Simulation sim(resolveScene("erosion", 48, 3));
    GiLighting light = sunSkyAndKey();
    for (int s : {1, 2}) {
        GiSettings settings = withBounces(GiSettings{}, s, 1);
        settings.tolerance = 0.0f;  // exact: bit for bit the full frames
        REQUIRE(gathersByTiles(settings.indirect, settings.shading));
        std::vector<GiState> states(4);
        const int threads[] = {1, 2, 3, 8};
        Grid h;
        for (int f = 0; f < 6; ++f) {
            // frames 2 and 4 repeat the last surface; the light moves on frame 3, brightens on frame 4
            if (f != 2 && f != 4)
                for (int t = 0; t < 20; ++t) sim.tick();
            if (f == 3) light.keys[0].elevationDeg += 2.0f;
            if (f == 4) light.keys[0].rgb[1] *= 1.5f;
            sim.state().groundHeight(h);
            for (std::size_t i = 0; i < states.size(); ++i)
                withThreads(threads[i], [&] { CHECK(incrementalMatchesFull(h, kCell, light, settings, states[i])); });
            for (std::size_t i = 1; i < states.size(); ++i) CHECK(sameOutputs(states[i], states[0]));
            CHECK(states[0].indirectUpdated == (f != 2));
        }
    }
}

TEST_CASE("gi.indirect_cache: the radiance bound holds for local, global and edge changes of the sources") {
    const Grid h = bumpy(160, 128);
    for (int s : {1, 2, 4}) {
        const GiSettings settings = withBounces(GiSettings{}, s, 1);
        GiState st;
        runGiFrame(h.cview(), kCell, sunSkyAndKey(), settings, st);
        const FoldedWedgeOperator op = foldFullCircle(settings.indirect.azimuths, settings.visibility.interp);
        const auto gather = [&](const std::array<Grid, 3>& source, IndirectState& out) {
            const IndirectInputs in{.heights = st.pyramid,
                                    .gradX = st.gradX.cview(),
                                    .gradY = st.gradY.cview(),
                                    .op = op,
                                    .envVisibility = st.envVisibility,
                                    .direct = source,
                                    .directShade = nullptr,
                                    .albedo = nullptr,
                                    .shading = settings.shading};
            computeIndirect(in, settings.indirect, out);
        };
        const std::array<Grid, 3> base = st.shade.rgb;
        IndirectState before;
        gather(base, before);
        std::mt19937 rng(11 + s);
        std::uniform_real_distribution<float> u(-1.0f, 1.0f);
        const int nx = h.nx, ny = h.ny;
        // a bright patch, noise everywhere, a shadow edge moving across the field
        const auto bump = [&](int x, int y, int) { return std::hypot(x - 40.0f, y - 90.0f) < 6.0f ? 0.8f : 0.0f; };
        const auto noise = [&](int, int, int) { return 0.02f * u(rng); };
        const auto edge = [&](int x, int y, int c) { return (x + y / 3) % 37 == 0 ? (c == 0 ? -0.5f : 0.3f) : 0.0f; };
        for (const auto& [name, change] : std::vector<std::pair<const char*, std::function<float(int, int, int)>>>{
                 {"patch", bump}, {"noise", noise}, {"edges", edge}}) {
            CAPTURE(s);
            const std::string caseName = name;
            CAPTURE(caseName);
            std::array<Grid, 3> after = base;
            Grid dL(nx, ny);
            for (int y = 0; y < ny; ++y)
                for (int x = 0; x < nx; ++x)
                    for (int c = 0; c < 3; ++c) {
                        Grid& g = after[static_cast<std::size_t>(c)];
                        g(x, y) = std::max(0.0f, g(x, y) + change(x, y, c));
                        dL(x, y) = std::max(dL(x, y), std::fabs(g(x, y) - base[static_cast<std::size_t>(c)](x, y)));
                    }
            IndirectState later;
            gather(after, later);
            MaxChangePyramid changePyramid;
            buildMaxChangePyramid(dL.cview(), changePyramid);
            std::vector<float> bound;
            boundSampleChangePerAzimuth(changePyramid, later.radiance.fields[0], kVisibilityTile, op.azimuths, bound);
            const int m = op.azimuths, tilesX = tileCount(st.pyramid.nxr, kVisibilityTile);
            const auto tileBound = [&](int X, int Y) {
                const std::size_t t = static_cast<std::size_t>(Y / kVisibilityTile) * tilesX + X / kVisibilityTile;
                return *std::max_element(bound.begin() + static_cast<std::ptrdiff_t>(t * m),
                                         bound.begin() + static_cast<std::ptrdiff_t>((t + 1) * m));
            };
            // every texel's exit radiance (white albedo) moves by at most the
            // largest bound of the receivers it reads
            double worstRatio = 0.0, excess = 0.0;
            for (int y = 0; y < ny; ++y)
                for (int x = 0; x < nx; ++x) {
                    const int X0 = std::min(x / s, st.pyramid.nxr - 1), Y0 = std::min(y / s, st.pyramid.nyr - 1);
                    const int X1 = std::min(X0 + 1, st.pyramid.nxr - 1), Y1 = std::min(Y0 + 1, st.pyramid.nyr - 1);
                    const float b =
                        std::max({tileBound(X0, Y0), tileBound(X1, Y0), tileBound(X0, Y1), tileBound(X1, Y1)});
                    for (std::size_t c = 0; c < 3; ++c) {
                        const double d =
                            std::fabs(static_cast<double>(later.indirect[c](x, y)) - before.indirect[c](x, y));
                        excess = std::max(excess, d - (b * (1.0 + 1e-5) + 1e-6));
                        if (b > 0.0f) worstRatio = std::max(worstRatio, d / b);
                    }
                }
            CHECK(excess <= 0.0);
            const float smallest = *std::min_element(bound.begin(), bound.end());
            MESSAGE(s << "x, " << name << ": largest change / bound " << worstRatio << "; bounds from " << smallest
                      << " to " << maxChangeAll(changePyramid));
            // a local patch: tiles far from it are charged less than its full change
            if (caseName == "patch") CHECK(smallest < maxChangeAll(changePyramid));
        }
    }
}

TEST_CASE("gi.indirect_cache: small source changes accumulate until they pass the tolerance") {
    const Grid h = bumpy(96, 96);
    GiLighting light;  // uniform unit sky plus a key light that brightens a little each frame
    KeyLight key;
    key.azimuthDeg = 60.0f;
    key.elevationDeg = 35.0f;
    light.keys.push_back(key);
    GiSettings settings = withBounces(GiSettings{}, 2, 1);
    settings.tolerance = 0.01f;
    GiState inc;
    runGiFrame(h.cview(), kCell, light, settings, inc);
    int regathered = 0, kept = 0;
    for (int f = 0; f < 12; ++f) {
        light.keys[0].rgb[0] *= 1.002f;  // the direct light changes by a few thousandths
        runGiFrame(h.cview(), kCell, light, settings, inc);
        CHECK(inc.receiversRecomputed == 0.0);  // static geometry: the environment's V is cached
        (inc.indirectRecomputed > 0.0 ? regathered : kept) += 1;
        GiSettings off = settings;
        off.incremental = false;
        GiState full;
        runGiFrame(h.cview(), kCell, light, off, full);
        // the direct light is exact; the indirect light within the tolerance
        CHECK(largestDifference(inc.shade.rgb, full.shade.rgb) == 0.0);
        CHECK(largestDifference(inc.indirect.indirect, full.indirect.indirect) <= settings.tolerance);
    }
    MESSAGE("indirect light re-gathered on " << regathered << " of 12 frames");
    CHECK(kept > 0);
    CHECK(regathered > 0);
}

TEST_CASE("gi.indirect_cache: with a local height change the indirect light stays within the tolerance") {
    const Grid h = bumpy(256, 256);
    GiLighting light;  // uniform unit sky: shade units are the ambient map's
    Grid crater = h;
    for (int y = 120; y < 136; ++y)
        for (int x = 120; x < 136; ++x) crater(x, y) -= 6.0f;
    GiSettings settings = withBounces(GiSettings{}, 2, 1);
    settings.tolerance = 0.02f;
    GiState inc;
    runGiFrame(h.cview(), 10.0f, light, settings, inc);
    runGiFrame(crater.cview(), 10.0f, light, settings, inc);
    GiSettings off = settings;
    off.incremental = false;
    GiState full;
    runGiFrame(crater.cview(), 10.0f, light, off, full);
    const double direct = largestDifference(inc.shade.rgb, full.shade.rgb);
    const double indirect = largestDifference(inc.indirect.indirect, full.indirect.indirect);
    MESSAGE("crater, tolerance " << settings.tolerance << ": V recomputed at " << 100.0 * inc.receiversRecomputed
                                 << " % of the receivers, indirect light at " << 100.0 * inc.indirectRecomputed
                                 << " %; largest difference from the full frame: direct " << direct << ", indirect "
                                 << indirect);
    CHECK(inc.receiversRecomputed < 1.0);
    CHECK(direct <= settings.tolerance);
    CHECK(indirect <= settings.tolerance);
}
