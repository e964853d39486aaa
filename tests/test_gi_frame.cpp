// gi/frame: one GI frame end to end: a flat plane, state reuse across frames
// and sizes, input checks, amortisation (Section 7) and thread determinism.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include <doctest/doctest.h>

#include "core/error.h"
#include "core/parallel.h"
#include "gi/frame.h"
#include "tests/gi_test_terrain.h"

using namespace terrain;
using namespace terrain::gi;
using gi_test::bumpy;
using gi_test::gridOf;
using gi_test::sameBits;
using gi_test::sameOutputs;
using gi_test::sunSkyAndKey;
using gi_test::withBounces;

namespace {

double worstDeviation(const Grid& g, float value) {
    double worst = 0.0;
    for (float v : g.v) worst = std::max(worst, std::fabs(static_cast<double>(v) - value));
    return worst;
}

}  // namespace

TEST_CASE("gi.frame: a flat plane under a uniform unit sky: ambient and shade 1 within 1e-6, indirect exactly 0") {
    for (int settingsKind = 0; settingsKind < 2; ++settingsKind)
        for (int s : {1, 2, 4})
            for (const auto& size : {std::pair{64, 64}, std::pair{37, 29}}) {
                const int nx = size.first, ny = size.second;  // plain locals: INFO captures them
                const GiSettings settings = withBounces(settingsKind == 0 ? paperGiSettings() : GiSettings{}, s, 1);
                const Grid h(nx, ny, 312.5f);
                const AlbedoMap a = uniformAlbedo(nx, ny, 0.6f);
                for (const AlbedoMap* albedo : {static_cast<const AlbedoMap*>(nullptr), &a}) {
                    GiState st;
                    runGiFrame(h.cview(), 5.0f, GiLighting{}, settings, st, albedo);
                    const float shade = albedo ? 0.6f : 1.0f;
                    INFO((settingsKind == 0 ? "paper" : "engine")
                         << " settings, s " << s << ", " << nx << "x" << ny << (albedo ? ", albedo 0.6" : ""));
                    CHECK(worstDeviation(st.shade.ambient, 1.0f) <= 1e-6);
                    for (std::size_t i = 0; i < 3; ++i) {
                        CHECK(worstDeviation(st.shade.rgb[i], shade) <= 1e-6);
                        CHECK(std::count(st.indirect.indirect[i].v.begin(), st.indirect.indirect[i].v.end(), 0.0f) ==
                              static_cast<long>(st.indirect.indirect[i].size()));
                        CHECK(sameBits(st.indirect.total[i].v, st.shade.rgb[i].v));
                    }
                }
            }
}

TEST_CASE(
    "gi.frame: state reuse: a repeated frame is bit-identical, a new size or sub-sampling matches a fresh state") {
    const Grid a = bumpy(64, 64), b = bumpy(48, 80);
    const GiLighting light = sunSkyAndKey();
    const GiSettings s2 = withBounces(GiSettings{}, 2, 1), s4 = withBounces(GiSettings{}, 4, 1);
    const AlbedoMap albA = uniformAlbedo(64, 64, 0.7f), albB = uniformAlbedo(48, 80, 0.7f);
    auto fresh = [&](const Grid& h, const GiSettings& s, const AlbedoMap& alb) {
        GiState st;
        runGiFrame(h.cview(), 2.0f, light, s, st, &alb);
        return st;
    };
    const GiState freshA = fresh(a, s2, albA), freshB = fresh(b, s2, albB), freshB4 = fresh(b, s4, albB);
    GiState st;
    runGiFrame(a.cview(), 2.0f, light, s2, st, &albA);
    CHECK(sameOutputs(st, freshA));
    runGiFrame(a.cview(), 2.0f, light, s2, st, &albA);
    CHECK(sameOutputs(st, freshA));
    runGiFrame(b.cview(), 2.0f, light, s2, st, &albB);  // 64x64 -> 48x80
    CHECK(sameOutputs(st, freshB));
    runGiFrame(b.cview(), 2.0f, light, s4, st, &albB);  // 2x -> 4x
    CHECK(sameOutputs(st, freshB4));
    runGiFrame(a.cview(), 2.0f, light, s2, st, &albA);  // and back
    CHECK(sameOutputs(st, freshA));
    CHECK(!sameOutputs(freshB, freshB4));  // the comparison sees the sub-sampling
}

TEST_CASE("gi.frame: NaN/Inf heights, a bad cell size or sub-sampling throw InputError and leave the state usable") {
    const Grid h = bumpy(24, 20);
    const GiSettings ok = withBounces(GiSettings{}, 2, 1);
    GiState st;
    for (float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
                      -std::numeric_limits<float>::infinity()}) {
        Grid g = h;
        g(17, 11) = bad;
        CHECK_THROWS_AS(runGiFrame(g.cview(), 1.0f, GiLighting{}, ok, st), InputError);
    }
    for (float cell :
         {0.0f, -1.0f, -0.0f, std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()})
        CHECK_THROWS_AS(runGiFrame(h.cview(), cell, GiLighting{}, ok, st), InputError);
    for (int s : {0, 3, 8, -2}) {
        GiSettings bad = ok;
        bad.subsample = s;
        CHECK_THROWS_AS(runGiFrame(h.cview(), 1.0f, GiLighting{}, bad, st), InputError);
    }
    CHECK_THROWS_AS(runGiFrame(ConstGridView{}, 1.0f, GiLighting{}, ok, st), InputError);
    // after the rejected frames the state gives what a fresh one gives
    runGiFrame(h.cview(), 1.0f, sunSkyAndKey(), ok, st);
    GiState fresh;
    runGiFrame(h.cview(), 1.0f, sunSkyAndKey(), ok, fresh);
    CHECK(sameOutputs(st, fresh));
    // incremental frames check the heights that differ from the recorded
    // ones: a bad height is caught alone, beside other changes and with a
    // new cell size, and the state is still usable after it
    for (float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
        Grid g = h;
        g(3, 2) = bad;
        CHECK_THROWS_AS(runGiFrame(g.cview(), 1.0f, sunSkyAndKey(), ok, st), InputError);
        g(20, 17) += 1.0f;
        CHECK_THROWS_AS(runGiFrame(g.cview(), 1.0f, sunSkyAndKey(), ok, st), InputError);
        CHECK_THROWS_AS(runGiFrame(g.cview(), 2.0f, sunSkyAndKey(), ok, st), InputError);
    }
    runGiFrame(h.cview(), 1.0f, sunSkyAndKey(), ok, st);
    CHECK(sameOutputs(st, fresh));
}

TEST_CASE(
    "gi.frame: amortised static frames alternate direct and indirect updates, and each total equals the full frame's") {
    // gi/frame.h: without incremental frames, with settings.indirect.amortise and geometryChanged = false,
    // after a full frame the static frames update the direct light (phase 0)
    // and the indirect light (phase 1) in turn; a geometry change, or a frame
    // of another size or settings, updates both and restarts at phase 0.
    const Grid h = bumpy(48, 40);
    const AlbedoMap alb = uniformAlbedo(48, 40, 0.65f);
    const GiLighting light = sunSkyAndKey();
    // Amortisation as the caller drives it (geometryChanged); incremental
    // frames would skip these static frames altogether (gi.frame_change tests).
    GiSettings full = withBounces(GiSettings{}, 2, 1);
    full.incremental = false;
    GiSettings amort = full;
    amort.indirect.amortise = true;
    GiState ref;
    runGiFrame(h.cview(), 1.0f, light, full, ref, &alb);
    GiState st;
    runGiFrame(h.cview(), 1.0f, light, amort, st, &alb);  // geometryChanged starts true
    CHECK((st.directUpdated && st.indirectUpdated));
    auto staticFrames = [&](int count, const char* when) {
        for (int f = 0; f < count; ++f) {
            st.geometryChanged = false;
            runGiFrame(h.cview(), 1.0f, light, amort, st, &alb);
            INFO(when << ", static frame " << f);
            CHECK(st.directUpdated == (f % 2 == 0));
            CHECK(st.indirectUpdated == (f % 2 == 1));
            CHECK(sameOutputs(st, ref));
        }
    };
    staticFrames(5, "after the first frame");
    st.geometryChanged = true;
    runGiFrame(h.cview(), 1.0f, light, amort, st, &alb);
    CHECK((st.directUpdated && st.indirectUpdated));
    staticFrames(3, "after a geometry change");
    // another sub-sampling is another key: a full frame, then the phases restart
    GiSettings amort4 = amort;
    amort4.subsample = 4;
    st.geometryChanged = false;
    runGiFrame(h.cview(), 1.0f, light, amort4, st, &alb);
    CHECK((st.directUpdated && st.indirectUpdated));
    runGiFrame(h.cview(), 1.0f, light, amort, st, &alb);
    CHECK((st.directUpdated && st.indirectUpdated));
    CHECK(sameOutputs(st, ref));
    staticFrames(2, "after a settings change");
    // without amortise, or without bounces, static frames update everything there is
    for (int bounces : {1, 0}) {
        GiSettings s = withBounces(full, 2, bounces);
        GiState plain;
        for (int f = 0; f < 3; ++f) {
            plain.geometryChanged = f == 0;
            s.indirect.amortise = bounces == 0;  // amortise without bounces: nothing to alternate
            runGiFrame(h.cview(), 1.0f, light, s, plain, &alb);
            CHECK(plain.directUpdated);
            CHECK(plain.indirectUpdated == (bounces > 0));
        }
    }
}

TEST_CASE("gi.frame: shade, ambient and indirect are bit-identical for 1, 2 and 3 threads") {
    const Grid h = bumpy(57, 50);
    const AlbedoMap alb = uniformAlbedo(57, 50, 0.55f);
    const GiLighting light = sunSkyAndKey();
    for (int s : {1, 2})
        for (int kind = 0; kind < 2; ++kind) {
            const GiSettings settings = withBounces(kind == 0 ? GiSettings{} : paperGiSettings(), s, 2);
            auto run = [&] {
                GiState st;
                runGiFrame(h.cview(), 1.5f, light, settings, st, &alb);
                return st;
            };
            const GiState one = withThreads(1, run);
            double mean = 0.0;
            for (float v : one.indirect.indirect[0].v) mean += v;
            CHECK(mean > 0.0);  // the bumps light each other: the comparison is not of zeros
            for (int t : {2, 3})
                CHECK_MESSAGE(sameOutputs(withThreads(t, run), one), "s " << s << ", " << t << " threads");
        }
}
