// gi/frame_change: incremental frames rerun a stage only when its inputs
// changed, and give bit for bit what a full recompute gives.
#include <algorithm>
#include <cmath>
#include <vector>

#include <doctest/doctest.h>

#include "core/parallel.h"
#include "gi/frame.h"
#include "sim/scene.h"
#include "tests/gi_test_terrain.h"

using namespace terrain;
using namespace terrain::gi;
using gi_test::bumpy;
using gi_test::incrementalMatchesFull;
using gi_test::sameOutputs;
using gi_test::sunSkyAndKey;
using gi_test::withBounces;

TEST_CASE("gi.frame_change: a static scene does no GI work after the first frame") {
    const Grid h = bumpy(64, 48);
    const GiLighting light = sunSkyAndKey();
    for (int s : {1, 2, 4}) {
        const GiSettings settings = withBounces(GiSettings{}, s, 1);
        GiState st;
        runGiFrame(h.cview(), 2.0f, light, settings, st);
        CHECK(st.receiversRecomputed == 1.0);
        GiState first = st;
        for (int f = 0; f < 3; ++f) {
            runGiFrame(h.cview(), 2.0f, light, settings, st);
            CHECK_FALSE(st.directUpdated);
            CHECK_FALSE(st.indirectUpdated);
            CHECK(st.receiversRecomputed == 0.0);
            CHECK(st.indirectRecomputed == 0.0);
            CHECK(sameOutputs(st, first));
        }
        // switched off, the same frame recomputes everything, with the same result
        GiSettings off = settings;
        off.incremental = false;
        runGiFrame(h.cview(), 2.0f, light, off, st);
        CHECK((st.directUpdated && st.indirectUpdated));
        CHECK(sameOutputs(st, first));
    }
}

TEST_CASE("gi.frame_change: a moving sun on static geometry reruns its visibility and the shading only") {
    const Grid h = bumpy(64, 48);
    GiLighting light = sunSkyAndKey();
    GiSettings settings = withBounces(GiSettings{}, 2, 1);
    settings.tolerance = 0.0f;  // exact: bit for bit the full frames
    GiState st;
    runGiFrame(h.cview(), 2.0f, light, settings, st);
    for (int f = 0; f < 4; ++f) {
        light.keys[0].azimuthDeg += 1.0f;  // 1 degree per frame
        CHECK(incrementalMatchesFull(h, 2.0f, light, settings, st));
        CHECK(st.receiversRecomputed == 0.0);
        CHECK(st.timings.visibility == 0.0);  // the environment's V is cached: not even timed
        CHECK(st.keyVisibilitiesRecomputed == 1);
        CHECK(st.indirectUpdated);
    }
    // a changed environment (brighter sky): shading and bounces only
    light.environment = sunSkyLight();
    for (auto& c : light.environment.c)
        for (double& v : c) v *= 1.5;
    CHECK(incrementalMatchesFull(h, 2.0f, light, settings, st));
    CHECK(st.receiversRecomputed == 0.0);
    CHECK(st.keyVisibilitiesRecomputed == 0);
    // a brighter key light of the same size and direction: no visibility at all
    light.keys[0].rgb[0] = 2.0f;
    CHECK(incrementalMatchesFull(h, 2.0f, light, settings, st));
    CHECK(st.timings.visibility == 0.0);
    CHECK(st.keyVisibilitiesRecomputed == 0);
}

TEST_CASE("gi.frame_change: incremental frames of an eroding terrain equal full recomputes, for any thread count") {
    SceneSettings scene = resolveScene("erosion", 48, 3);
    GiLighting light = sunSkyAndKey();
    GiSettings settings = withBounces(GiSettings{}, 2, 2);
    settings.tolerance = 0.0f;  // exact: bit for bit the full frames
    std::vector<GiState> states(4);
    const int threads[] = {1, 2, 3, 8};
    Simulation sim(scene);
    Grid h;
    for (int f = 0; f < 6; ++f) {
        // frames 2 and 4 repeat the last surface; the light moves on frame 3
        if (f != 2 && f != 4)
            for (int t = 0; t < 20; ++t) sim.tick();
        if (f == 3) light.keys[0].elevationDeg += 2.0f;
        sim.state().groundHeight(h);
        for (std::size_t i = 0; i < states.size(); ++i)
            withThreads(threads[i], [&] { CHECK(incrementalMatchesFull(h, 2.0f, light, settings, states[i])); });
        for (std::size_t i = 1; i < states.size(); ++i) CHECK(sameOutputs(states[i], states[0]));
        CHECK(states[0].directUpdated == (f != 2 && f != 4));
    }
}

namespace {

// Largest |a - b| of the ambient map per visibility tile (texels of its receivers).
std::vector<double> tileAmbientChange(const GiState& a, const GiState& b, int s) {
    const Grid &ga = a.shade.ambient, &gb = b.shade.ambient;
    const int tilesX = tileCount(a.pyramid.nxr, kVisibilityTile);
    std::vector<double> out(static_cast<std::size_t>(tilesX) * tileCount(a.pyramid.nyr, kVisibilityTile), 0.0);
    for (int y = 0; y < ga.ny; ++y)
        for (int x = 0; x < ga.nx; ++x) {
            const int tx = std::min(x / s, a.pyramid.nxr - 1) / kVisibilityTile;
            const int ty = std::min(y / s, a.pyramid.nyr - 1) / kVisibilityTile;
            double& t = out[static_cast<std::size_t>(ty) * tilesX + tx];
            t = std::max(t, std::fabs(static_cast<double>(gb(x, y)) - ga(x, y)));
        }
    return out;
}

double medianOf(std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    return v[v.size() / 2];
}

}  // namespace

TEST_CASE("gi.frame_change: a crater recomputes the tiles within its reach, within the tolerance of a full frame") {
    const Grid h = bumpy(256, 256);
    GiLighting light;  // uniform unit sky: the shade is the ambient map the tolerance speaks of
    Grid crater = h;
    for (int y = 120; y < 136; ++y)
        for (int x = 120; x < 136; ++x) crater(x, y) -= 6.0f;  // 16 x 16 cells, 6 m deep
    const int s = 1;  // at 2x this field has 4 x 4 tiles, all within reach of the coarse levels
    for (float tolerance : {1e-2f, 5e-2f}) {
        GiSettings settings = withBounces(GiSettings{}, s, 0);
        settings.tolerance = tolerance;
        GiState inc;
        runGiFrame(h.cview(), 10.0f, light, settings, inc);
        const GiState first = inc;
        runGiFrame(crater.cview(), 10.0f, light, settings, inc);
        GiSettings off = settings;
        off.incremental = false;
        GiState full;
        runGiFrame(crater.cview(), 10.0f, light, off, full);
        INFO("tolerance " << tolerance << ", receivers recomputed " << inc.receiversRecomputed);
        MESSAGE("crater at " << s << "x, tolerance " << tolerance << ": " << 100.0 * inc.receiversRecomputed
                             << " % of the receivers recomputed");
        CHECK(inc.receiversRecomputed > 0.0);
        CHECK(inc.receiversRecomputed < (tolerance < 0.02f ? 0.35 : 0.1));
        double worst = 0.0;
        for (std::size_t i = 0; i < full.shade.ambient.v.size(); ++i)
            worst = std::max(worst, std::fabs(static_cast<double>(inc.shade.ambient.v[i]) - full.shade.ambient.v[i]));
        MESSAGE("largest ambient difference from the full frame " << worst);
        CHECK(worst <= settings.tolerance);
        // the crater's own tile is among the recomputed ones: its floor sees the walls
        const int r = 128 / s / inc.visibilityCache.tiles.tileSize;
        CHECK(inc.visibilityCache.tiles.isDirty(r, r));
        // per receiver the bound keeps more than the visibility tiles' alone would
        const VisibilityCache& vc = inc.visibilityCache;
        double coarse = 0.0;
        for (float b : vc.envBound) coarse += b > tolerance ? 1.0 : 0.0;
        coarse /= static_cast<double>(vc.envBound.size());
        MESSAGE("visibility tiles' bounds alone: " << 100.0 * coarse << " % of the receivers");
        CHECK(inc.receiversRecomputed < coarse);
        if (tolerance > 0.02f) continue;
        // looseness: each tile's one-frame bound (its drift before any reset: the
        // key lights' full-circle form, the environment's per azimuth) over the
        // largest change of its ambient texels between the two full frames
        const std::vector<double> change = tileAmbientChange(first, full, s);
        const VisibilityCache& cache = inc.visibilityCache;
        const float lipschitz = blockingMaxLipschitz(settings.visibility.blockingMax);
        const int m = settings.visibility.azimuths;
        std::vector<double> fullCircle, perAzimuth;
        std::vector<float> az(static_cast<std::size_t>(m));
        for (std::size_t t = 0; t < change.size(); ++t) {
            // the tiles whose bounds were taken per azimuth (the others' coarse bound was enough)
            if (change[t] <= 1e-7 || !cache.perAzimuth[t]) continue;
            for (int j = 0; j < m; ++j)
                az[static_cast<std::size_t>(j)] = lipschitz * cache.azimuthBound[t * m + static_cast<std::size_t>(j)];
            const double g = std::sqrt(2.0) * cache.gradBound[t];
            fullCircle.push_back(kShadePerSlope * std::max<double>(lipschitz * cache.slopeBound[t], g) / change[t]);
            perAzimuth.push_back(ambientChangeBoundPerAzimuth(az.data(), m, cache.gradBound[t], 1.0f, false) /
                                 change[t]);
        }
        MESSAGE("median bound / largest ambient change per tile (" << perAzimuth.size() << " tiles): full circle "
                                                                   << medianOf(fullCircle) << ", per azimuth "
                                                                   << medianOf(perAzimuth));
    }
}

TEST_CASE("gi.frame_change: a plan takes per-azimuth bounds only where the coarse ones pass their share") {
    // a crater in a field of 8 x 8 visibility tiles at 2x, sun and sky and a
    // key light: the tiles near it need the finer bounds, the far ones not
    const Grid h = bumpy(512, 512);
    Grid crater = h;
    for (int y = 248; y < 264; ++y)
        for (int x = 248; x < 264; ++x) crater(x, y) -= 6.0f;
    GiSettings settings = withBounces(GiSettings{}, 2, 0);
    settings.tolerance = 0.05f;
    const float share = kCoarseBoundShare * settings.tolerance;
    GiState inc;
    runGiFrame(h.cview(), 10.0f, sunSkyAndKey(), settings, inc);
    runGiFrame(crater.cview(), 10.0f, sunSkyAndKey(), settings, inc);
    const VisibilityCache& cache = inc.visibilityCache;
    REQUIRE(cache.perAzimuth.size() == cache.coarseBound.size());
    int fine = 0, coarse = 0;
    for (std::size_t v = 0; v < cache.coarseBound.size(); ++v) {
        INFO("visibility tile " << v << ", coarse bound " << cache.coarseBound[v]);
        // the first planned frame: every drift from the anchor was 0
        if (cache.perAzimuth[v]) {
            ++fine;
            CHECK(cache.coarseBound[v] > share);
            CHECK(cache.envBound[v] <= cache.coarseBound[v]);  // finer, and not looser here
        } else {
            ++coarse;
            CHECK(cache.coarseBound[v] <= share);
            CHECK(cache.envBound[v] == cache.coarseBound[v]);
            CHECK(cache.geometryBound[v] == cache.coarseBound[v]);
        }
    }
    MESSAGE(fine << " visibility tiles bounded per azimuth, " << coarse << " by their coarse bound");
    CHECK(fine > 0);
    CHECK(coarse > 0);
    // the key light's fraction: its range bound where the coarse one would
    // take more than the share, which it never does elsewhere
    const KeyLight key = sunSkyAndKey().keys[0];
    const float keyShade = std::max({key.rgb[0], key.rgb[1], key.rgb[2]});
    for (std::size_t t = 0; t < cache.keyExcursion.size(); ++t)
        if (!cache.overRange[t]) CHECK(cache.keyExcursion[t] * keyShade <= share);
    // and the frame stays within the tolerance of a full one
    GiSettings off = settings;
    off.incremental = false;
    GiState full;
    runGiFrame(crater.cview(), 10.0f, sunSkyAndKey(), off, full);
    double worst = 0.0;
    for (std::size_t i = 0; i < full.shade.ambient.v.size(); ++i)
        worst = std::max(worst, std::fabs(static_cast<double>(inc.shade.ambient.v[i]) - full.shade.ambient.v[i]));
    CHECK(worst <= settings.tolerance);
}

namespace {

// A ridge rising 5 cm a frame moves the shadow a low key light (rgb as
// given) casts from it: texels far behind it drift slowly in and out of its
// penumbra. Frame 12 repeats frame 11's surface under a light 20 times as
// bright (the same region: its cached visibility stays, its drift counts
// anew); the ridge then rises on. The largest shade difference of the
// incremental frames from full ones, and the share of key tiles kept in
// frames 1-11.
struct RidgeRun {
    double worst = 0.0, keptShare = 0.0;
};
RidgeRun ridgeUnderKeyLight(float tolerance, float red, float green) {
    const Grid base = bumpy(160, 96);
    GiLighting light;
    light.environment = ShRgb{};  // the key light alone
    KeyLight key;
    key.azimuthDeg = 180.0f;  // the light lies towards -x: the ridge shades +x
    key.elevationDeg = 6.0f;
    key.radiusDeg = 3.0f;
    key.rgb[0] = red;
    key.rgb[1] = green;
    light.keys.push_back(key);
    GiSettings settings = withBounces(GiSettings{}, 1, 0);
    settings.tolerance = tolerance;
    GiSettings off = settings;
    off.incremental = false;
    GiState inc;
    RidgeRun out;
    for (int f = 0; f < 18; ++f) {
        if (f == 12)
            for (float& c : light.keys[0].rgb) c *= 20.0f;
        const int rise = f < 12 ? f : f - 1;
        Grid h = base;
        for (int y = 0; y < h.ny; ++y)
            for (int x = 20; x < 23; ++x) h(x, y) += 4.0f + 0.05f * static_cast<float>(rise);
        runGiFrame(h.cview(), 10.0f, light, settings, inc);
        GiState full;
        runGiFrame(h.cview(), 10.0f, light, off, full);
        for (std::size_t c = 0; c < 3; ++c)
            for (std::size_t i = 0; i < full.shade.rgb[c].v.size(); ++i)
                out.worst =
                    std::max(out.worst, std::fabs(static_cast<double>(inc.shade.rgb[c].v[i]) - full.shade.rgb[c].v[i]));
        if (f > 0 && f < 12) out.keptShare += (1.0 - inc.visibilityCache.keyTiles.dirtyFraction()) / 11.0;
    }
    return out;
}

}  // namespace

TEST_CASE("gi.frame_change: a key light's shade stays within the tolerance of a full frame as a ridge rises") {
    // The key lights' drift is in their own shade units (a bright light, a
    // small window), so every texel's key shade stays within the tolerance
    // of a full recompute while most tiles keep their cached visibility,
    // also after the light is made brighter on a frame whose heights did not
    // change (a large tolerance lets the cached shadows lag far enough to show it).
    struct Case {
        float tolerance, red, green;
    };
    for (const Case& c : {Case{0.02f, 3.0f, 2.0f}, Case{0.2f, 1.0f, 1.0f}}) {
        const float tolerance = c.tolerance;
        const RidgeRun r = ridgeUnderKeyLight(tolerance, c.red, c.green);
        MESSAGE("rising ridge, key light alone, tolerance "
                << tolerance << ": largest shade difference from full frames " << r.worst << ", " << 100.0 * r.keptShare
                << " % of the key tiles kept per frame");
        CHECK(r.worst <= tolerance);
        CHECK(r.keptShare > 0.2);
    }
}

TEST_CASE("gi.frame_change: a full refresh every N frames equals a full recompute bit for bit") {
    const Grid h = bumpy(96, 80);
    GiLighting light = sunSkyAndKey();
    GiSettings settings = withBounces(GiSettings{}, 2, 1);
    settings.tolerance = 0.05f;
    settings.refreshEvery = 3;
    GiState inc;
    Grid moving = h;
    for (int f = 1; f <= 7; ++f) {
        moving(40 + f, 30) += 0.5f;  // a small change each frame, below the tolerance far from it
        light.keys[0].rgb[2] *= 1.001f;
        runGiFrame(moving.cview(), 2.0f, light, settings, inc);
        GiSettings off = settings;
        off.incremental = false;
        GiState full;
        runGiFrame(moving.cview(), 2.0f, light, off, full);
        CAPTURE(f);
        if (f % 3 == 0) {
            CHECK(inc.receiversRecomputed == 1.0);
            CHECK(inc.indirectRecomputed == 1.0);
            CHECK(sameOutputs(inc, full));
        } else if (f > 1) {
            CHECK(inc.receiversRecomputed < 1.0);
        }
    }
}

TEST_CASE("gi.frame_change: amortisation follows the accumulated change, so it works on animated heights too") {
    const Grid h = bumpy(96, 80);
    GiLighting light = sunSkyAndKey();
    for (float tolerance : {0.0f, 0.05f}) {
        GiSettings settings = withBounces(GiSettings{}, 2, 1);
        settings.tolerance = tolerance;
        settings.indirect.amortise = true;
        GiState st;
        Grid moving = h;
        runGiFrame(moving.cview(), 2.0f, light, settings, st);
        int directOnly = 0, indirectOnly = 0;
        for (int f = 1; f <= 6; ++f) {
            moving(50, 40) += 0.002f;  // a tiny change every frame
            light.keys[0].azimuthDeg += 0.5f;
            runGiFrame(moving.cview(), 2.0f, light, settings, st);
            directOnly += st.directUpdated && !st.indirectUpdated;
            indirectOnly += st.indirectUpdated && !st.directUpdated;
            if (!st.directUpdated) continue;
            // a direct frame sees every change the indirect-only frames before it skipped
            GiSettings off = settings;
            off.incremental = false;
            off.indirect.amortise = false;
            GiState full;
            runGiFrame(moving.cview(), 2.0f, light, off, full);
            double worst = 0.0;
            for (std::size_t c = 0; c < 3; ++c)
                for (std::size_t i = 0; i < full.shade.rgb[c].v.size(); ++i)
                    worst =
                        std::max(worst, std::fabs(static_cast<double>(st.shade.rgb[c].v[i]) - full.shade.rgb[c].v[i]));
            CAPTURE(f);
            CHECK(worst <= 3.0 * tolerance + 1e-6);  // the sun-and-sky shade: a few times the unit-sky tolerance
        }
        INFO("tolerance " << tolerance);
        if (tolerance == 0.0f) {
            CHECK(directOnly + indirectOnly == 0);  // any change at all: every frame updates both
        } else {
            CHECK(directOnly >= 2);
            CHECK(indirectOnly >= 2);
        }
    }
}

TEST_CASE("gi.frame_change: the passes that redo the changed rows alone give the full passes' bits") {
    // gradients, footprint boxes, raw phases and receiver heights: a band of
    // rows changed (at the edges too), redone from the last result, against
    // the same passes over every row
    const GiSettings settings;
    for (int s : {1, 2, 3, 4})
        for (const RowSpan band : {RowSpan{0, 1}, RowSpan{5, 6}, RowSpan{17, 23}, RowSpan{38, 41}, RowSpan{40, 41}}) {
            CAPTURE(s);
            CAPTURE(band.y0);
            CAPTURE(band.y1);
            const Grid before = bumpy(37, 41);
            Grid after = before;
            for (int y = band.y0; y < band.y1; ++y)
                for (int x = 0; x < after.nx; x += 3) after(x, y) += 0.7f * static_cast<float>(1 + (x + y) % 5);
            Grid gx, gy, fullX, fullY;
            FootprintBox box, fullBox;
            HeightPyramid pyr, fullPyr;
            computeGradient(before.cview(), 2.0f, gx, gy);
            computeFootprintBox(gx.cview(), gy.cview(), s, box);
            buildHeightPyramid(before.cview(), 2.0f, s, settings.pyramid, pyr);
            computeGradient(after.cview(), 2.0f, gx, gy, band);
            computeFootprintBox(gx.cview(), gy.cview(), s, box, band.grown(1));
            buildHeightPyramid(after.cview(), 2.0f, s, settings.pyramid, pyr,
                               CellBox{0, band.y0, CellBox::kAll, band.y1});
            computeGradient(after.cview(), 2.0f, fullX, fullY);
            computeFootprintBox(fullX.cview(), fullY.cview(), s, fullBox);
            buildHeightPyramid(after.cview(), 2.0f, s, settings.pyramid, fullPyr);
            CHECK(gi_test::sameBits(gx.v, fullX.v));
            CHECK(gi_test::sameBits(gy.v, fullY.v));
            CHECK(gi_test::sameBits(box.loX, fullBox.loX));
            CHECK(gi_test::sameBits(box.hiX, fullBox.hiX));
            CHECK(gi_test::sameBits(box.loY, fullBox.loY));
            CHECK(gi_test::sameBits(box.hiY, fullBox.hiY));
            CHECK(gi_test::sameBits(pyr.rawPhase, fullPyr.rawPhase));
            REQUIRE(pyr.levels.size() == fullPyr.levels.size());
            for (std::size_t l = 0; l < pyr.levels.size(); ++l)
                CHECK(gi_test::sameBits(pyr.levels[l].v, fullPyr.levels[l].v));
        }
}

TEST_CASE("gi.frame_change: a peak that rises above the field's top and falls again is lit as in full frames") {
    // the scans stop where nothing ahead can rise above a receiver's horizon,
    // reading the field's top height; incremental frames take it from the
    // rows they redid, so a peak raised above every other height (and
    // lowered again) must be seen as a full frame sees it
    Grid h = bumpy(64, 56);
    GiSettings settings = withBounces(GiSettings{}, 2, 1);
    settings.tolerance = 0.0f;
    const GiLighting light = sunSkyAndKey();
    GiState st;
    CHECK(incrementalMatchesFull(h, 2.0f, light, settings, st));
    for (const float rise : {30.0f, 60.0f, -60.0f, -30.0f}) {
        CAPTURE(rise);
        for (int y = 40; y < 43; ++y)
            for (int x = 21; x < 24; ++x) h(x, y) += rise;
        CHECK(incrementalMatchesFull(h, 2.0f, light, settings, st));
    }
}

TEST_CASE("gi.frame_change: the changed heights' box holds exactly the cells that differ bit for bit") {
    const Grid before = bumpy(40, 30);
    const GiLighting light = sunSkyAndKey();
    const GiSettings settings;
    FrameInputs record;
    recordFrameInputs(before.cview(), 2.0f, light, settings, nullptr, everythingChanged(light.keys.size()), record);
    struct Edit {
        std::vector<std::pair<int, int>> cells;
        CellBox box;
    };
    const std::vector<Edit> edits = {
        {{{0, 0}}, {0, 0, 1, 1}},
        {{{39, 29}}, {39, 29, 40, 30}},
        {{{5, 3}, {20, 17}}, {5, 3, 21, 18}},
        {{{30, 2}, {4, 9}, {17, 5}}, {4, 2, 31, 10}},  // a later row's cells left of the first row's
        {{{12, 0}, {12, 29}}, {12, 0, 13, 30}},
    };
    for (const Edit& e : edits) {
        Grid after = before;
        for (auto [x, y] : e.cells) after(x, y) += 0.25f;
        const FrameChange c = compareFrameInputs(record, after.cview(), 2.0f, light, settings, nullptr);
        CHECK(c.geometry);
        CHECK(c.heightsOnly);
        CHECK(c.heightBox.x0 == e.box.x0);
        CHECK(c.heightBox.y0 == e.box.y0);
        CHECK(c.heightBox.x1 == e.box.x1);
        CHECK(c.heightBox.y1 == e.box.y1);
    }
    // -0 against 0 is a change of bits: the pyramid would keep the other sign
    Grid zero = before;
    zero(7, 8) = 0.0f;
    recordFrameInputs(zero.cview(), 2.0f, light, settings, nullptr, everythingChanged(light.keys.size()), record);
    Grid negative = zero;
    negative(7, 8) = -0.0f;
    const FrameChange signs = compareFrameInputs(record, negative.cview(), 2.0f, light, settings, nullptr);
    CHECK(signs.geometry);
    CHECK(signs.heightBox.x0 == 7);
    CHECK(signs.heightBox.x1 == 8);
    CHECK_FALSE(compareFrameInputs(record, zero.cview(), 2.0f, light, settings, nullptr).geometry);
}
