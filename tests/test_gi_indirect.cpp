// Indirect light on the fast path: gi/indirect, gi/radiance_pyramid
// and the amortised frame, checked against gi/reference_gi.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <doctest/doctest.h>

#include "core/parallel.h"
#include "gi/frame.h"
#include "gi/reference_gi.h"
#include "tests/gi_test_terrain.h"

using namespace terrain;
using namespace terrain::gi;
using gi_test::hills;
using gi_test::meanOver;
using gi_test::valley;

namespace {

GiSettings indirectSettings(int bounces, int subsample = 1) {
    GiSettings s = GiSettings{};
    s.subsample = subsample;
    s.indirect.bounces = bounces;
    return s;
}

// Relative RMSE of a against b over the interior (border fraction excluded).
[[maybe_unused]] double relRmse(const Grid& a, const Grid& b, float border) {
    const int bx = static_cast<int>(border * a.nx), by = static_cast<int>(border * a.ny);
    double se = 0.0, sr = 0.0;
    int n = 0;
    for (int y = by; y < a.ny - by; ++y)
        for (int x = bx; x < a.nx - bx; ++x) {
            const double d = a(x, y) - b(x, y);
            se += d * d;
            sr += static_cast<double>(b(x, y)) * b(x, y);
            ++n;
        }
    return std::sqrt(se / n) / std::sqrt(sr / n);
}

}  // namespace

TEST_CASE("gi.indirect: V-shaped valley with white walls under a uniform sky matches the reference") {
    const int n = 49;
    const Grid h = valley(n, n, 1.0f);
    const AlbedoMap a = uniformAlbedo(n, n, 1.0f);
    GiLighting light;
    GiState st;
    const GiSettings s = indirectSettings(1);
    runGiFrame(h.view(), 1.0f, light, s, st, &a);
    ReferenceGiSettings rs;
    rs.directions = 4096;
    rs.azimuths = 256;
    rs.bounces = 1;
    ReferenceGiResult ref;
    renderReferenceGi(h.view(), 1.0f, light.environment, &a, rs, ref);
    const int c = n / 2;
    const double fast = meanOver(st.indirect.indirect[0], c - 1, c + 2, 12, n - 12);
    const double exact = meanOver(ref.indirect[0], c - 1, c + 2, 12, n - 12);
    const double fastWall = meanOver(st.indirect.indirect[0], c + 6, c + 12, 12, n - 12);
    const double exactWall = meanOver(ref.indirect[0], c + 6, c + 12, 12, n - 12);
    MESSAGE("valley bottom indirect: fast " << fast << ", reference " << exact << "; wall: fast " << fastWall
                                            << ", reference " << exactWall << "; direct bottom fast "
                                            << meanOver(st.shade.rgb[0], c - 1, c + 2, 12, n - 12) << " ref "
                                            << meanOver(ref.direct[0], c - 1, c + 2, 12, n - 12));
    CHECK(fast > 0.05);
    CHECK(fast == doctest::Approx(exact).epsilon(0.10));
    CHECK(fastWall == doctest::Approx(exactWall).epsilon(0.10));
}

TEST_CASE("gi.indirect: a flat plane gets exactly no indirect light for any bounce count") {
    for (int s : {1, 2, 4})
        for (int b : {1, 2, 3, 5}) {
            const Grid h(37, 23, 123.0f);
            const AlbedoMap a = uniformAlbedo(37, 23, 0.9f);
            GiState st;
            runGiFrame(h.view(), 2.0f, GiLighting{}, indirectSettings(b, s), st, &a);
            for (int c = 0; c < 3; ++c)
                for (float v : st.indirect.indirect[static_cast<std::size_t>(c)].v) REQUIRE(v == 0.0f);
            CHECK(st.indirect.total[0](10, 10) == st.shade.rgb[0](10, 10));
        }
}

TEST_CASE("gi.indirect: indirect >= 0, each bounce adds less than the last, below the albedo / (1 - albedo) bound") {
    const int n = 64;
    const Grid h = hills(n, 12.0f);
    const float albedo = 0.6f;
    const AlbedoMap a = uniformAlbedo(n, n, albedo);
    GiState st;
    runGiFrame(h.view(), 1.0f, GiLighting{}, indirectSettings(4), st, &a);
    float directMax = 0.0f;
    for (float v : st.shade.rgb[0].v) directMax = std::max(directMax, v);
    float minInd = 1e30f, maxInd = 0.0f;
    for (float v : st.indirect.indirect[0].v) {
        minInd = std::min(minInd, v);
        maxInd = std::max(maxInd, v);
    }
    const auto& m = st.indirect.bounceMean;
    MESSAGE("bounce means " << m[0] << ", " << m[1] << ", " << m[2] << ", " << m[3] << "; indirect min " << minInd
                            << ", max " << maxInd << ", bound " << directMax * albedo / (1.0f - albedo));
    CHECK(minInd >= -1e-3f * directMax);  // SH ringing of order-4 U may dip a hair below 0
    CHECK(m[0] > 0.0);
    for (int b = 1; b < 4; ++b) CHECK(m[static_cast<std::size_t>(b)] < m[static_cast<std::size_t>(b - 1)]);
    CHECK(maxInd <= directMax * albedo / (1.0f - albedo));
}

TEST_CASE("gi.indirect: a red wall bleeds red onto a white floor, not green") {
    Grid h(48, 24, 0.0f);
    AlbedoMap a = uniformAlbedo(48, 24, 0.8f);
    for (int y = 0; y < 24; ++y)
        for (int x = 27; x < 48; ++x) {
            h(x, y) = std::min(16.0f, 3.0f * static_cast<float>(x - 27));
            a.channel[1](x, y) = 0.05f;
            a.channel[2](x, y) = 0.05f;
        }
    GiState st;
    runGiFrame(h.view(), 1.0f, GiLighting{}, indirectSettings(1), st, &a);
    const double r = meanOver(st.indirect.indirect[0], 18, 26, 6, 18);
    const double g = meanOver(st.indirect.indirect[1], 18, 26, 6, 18);
    const double b = meanOver(st.indirect.indirect[2], 18, 26, 6, 18);
    MESSAGE("floor beside the red wall: indirect R " << r << ", G " << g << ", B " << b);
    CHECK(r > 0.02);
    CHECK(r > 4.0 * g);
    CHECK(g == doctest::Approx(b).epsilon(1e-3));
}

TEST_CASE("gi.indirect: outputs are bit-identical for 1, 2, 3 and 8 threads") {
    const Grid h = hills(71, 10.0f);
    AlbedoMap a = uniformAlbedo(71, 71, 0.7f);
    for (int y = 0; y < 71; ++y)
        for (int x = 0; x < 71; ++x)
            a.channel[1](x, y) = 0.3f + 0.4f * static_cast<float>((x * 7 + y * 3) % 11) / 11.0f;
    for (int s : {1, 2}) {
        std::vector<std::vector<float>> results;
        for (int threads : {1, 2, 3, 8}) {
            GiState st;
            withThreads(threads, [&] { runGiFrame(h.view(), 1.5f, GiLighting{}, indirectSettings(2, s), st, &a); });
            std::vector<float> all;
            for (int c = 0; c < 3; ++c)
                all.insert(all.end(), st.indirect.indirect[static_cast<std::size_t>(c)].v.begin(),
                           st.indirect.indirect[static_cast<std::size_t>(c)].v.end());
            results.push_back(all);
        }
        for (std::size_t i = 1; i < results.size(); ++i) CHECK(results[i] == results[0]);
    }
}

TEST_CASE("gi.indirect: hard cases stay finite") {
    auto finite = [](const GiState& st) {
        for (int c = 0; c < 3; ++c)
            for (float v : st.indirect.total[static_cast<std::size_t>(c)].v)
                if (!std::isfinite(v) || v < -1e-2f) return false;
        return true;
    };
    std::vector<std::pair<std::string, Grid>> cases;
    {
        Grid g(40, 40, 0.0f);
        for (int y = 0; y < 40; ++y)
            for (int x = 20; x < 40; ++x) g(x, y) = 1000.0f;
        cases.emplace_back("1000 m cliff", g);
    }
    {
        Grid g(33, 33, 0.0f);
        g(16, 16) = 500.0f;
        cases.emplace_back("one-texel spike", g);
    }
    {
        Grid g = hills(32, 30.0f);
        for (float& v : g.v) v += 1.0e5f;
        cases.emplace_back("1e5 m heights", g);
    }
    {
        Grid g = hills(32, 30.0f);
        for (float& v : g.v) v -= 3000.0f;
        cases.emplace_back("negative heights", g);
    }
    cases.emplace_back("1x1", Grid(1, 1, 5.0f));
    cases.emplace_back("2x2", hills(2, 3.0f));
    cases.emplace_back("non-power-of-two 37x37", hills(37, 5.0f));
    {
        Grid g(37, 19, 0.0f);  // not square: a ramp with a ridge across it
        for (int y = 0; y < 19; ++y)
            for (int x = 0; x < 37; ++x) g(x, y) = 0.3f * static_cast<float>(x) + (y == 9 ? 6.0f : 0.0f);
        cases.emplace_back("37x19 ramp and ridge", g);
    }
    {
        Grid g(1, 9, 0.0f);  // one column
        for (int y = 0; y < 9; ++y) g(0, y) = static_cast<float>((y * 7) % 5);
        cases.emplace_back("1x9", g);
    }
    for (auto& [name, g] : cases)
        for (int s : {1, 2, 4}) {
            GiState st;
            const AlbedoMap a = uniformAlbedo(g.nx, g.ny, 0.8f);
            runGiFrame(g.view(), 1.0f, GiLighting{}, indirectSettings(2, s), st, &a);
            const std::string& caseName = name;  // INFO captures it: a plain reference, not the binding
            INFO(caseName << " at " << s << "x");
            CHECK(finite(st));
        }
}

TEST_CASE("gi.indirect: amortised frames equal the full update once two frames have passed on static geometry") {
    const int n = 48;
    const Grid h = hills(n, 8.0f);
    const AlbedoMap a = uniformAlbedo(n, n, 0.7f);
    GiSettings full = indirectSettings(1, 2);
    GiSettings amort = full;
    amort.indirect.amortise = true;
    GiLighting l1, l2;
    l2.environment = sunSkyLight();
    GiState sf, sa;
    // frame 0: geometry new; frames 1, 2: static geometry, the light changed at frame 1
    for (int f = 0; f < 3; ++f) {
        const GiLighting& l = f == 0 ? l1 : l2;
        sa.geometryChanged = f == 0;
        runGiFrame(h.view(), 1.0f, l, amort, sa, &a);
        runGiFrame(h.view(), 1.0f, l, full, sf, &a);
        if (f == 0) CHECK((sa.directUpdated && sa.indirectUpdated));
        if (f == 1) {
            CHECK((sa.directUpdated && !sa.indirectUpdated));
            CHECK(sa.shade.rgb[0].v == sf.shade.rgb[0].v);
            CHECK(sa.indirect.indirect[0].v != sf.indirect.indirect[0].v);  // still the previous light's bounce
        }
        if (f == 2) {
            CHECK((!sa.directUpdated && sa.indirectUpdated));
            for (int c = 0; c < 3; ++c) {
                CHECK(sa.indirect.indirect[static_cast<std::size_t>(c)].v ==
                      sf.indirect.indirect[static_cast<std::size_t>(c)].v);
                CHECK(sa.indirect.total[static_cast<std::size_t>(c)].v ==
                      sf.indirect.total[static_cast<std::size_t>(c)].v);
            }
        }
    }
    // a geometry change updates both at once (incremental frames see it themselves)
    Grid moved = h;
    moved(n / 2, n / 2) += 1.0f;
    runGiFrame(moved.view(), 1.0f, l2, amort, sa, &a);
    CHECK(sa.geometryChanged);
    CHECK((sa.directUpdated && sa.indirectUpdated));
}

TEST_CASE("gi.indirect: a second frame allocates nothing new") {
    const Grid h = hills(40, 8.0f);
    const AlbedoMap a = uniformAlbedo(40, 40, 0.7f);
    GiState st;
    runGiFrame(h.view(), 1.0f, GiLighting{}, indirectSettings(2, 2), st, &a);
    const float* p0 = st.indirect.indirect[0].data();
    const float* p1 = st.indirect.u[0].sh.data();
    const float* p2 =
        st.indirect.radiance.fields[1].levels.empty() ? nullptr : st.indirect.radiance.fields[1].levels[0].data();
    Grid h2 = h;
    for (float& v : h2.v) v *= 1.5f;
    runGiFrame(h2.view(), 1.0f, GiLighting{}, indirectSettings(2, 2), st, &a);
    CHECK(st.indirect.indirect[0].data() == p0);
    CHECK(st.indirect.u[0].sh.data() == p1);
    if (p2) CHECK(st.indirect.radiance.fields[1].levels[0].data() == p2);
}

TEST_CASE("gi.indirect: converges to the reference as m, k, o grow and as sub-sampling goes 4x -> 2x -> 1x") {
    const int n = 48;
    const Grid h = hills(n, 6.0f);
    const AlbedoMap a = uniformAlbedo(n, n, 1.0f);
    GiLighting light;
    ReferenceGiSettings rs;
    rs.directions = 4096;
    rs.azimuths = 256;
    rs.bounces = 1;
    rs.marchStep = 0.25f;
    ReferenceGiResult ref;
    renderReferenceGi(h.view(), 1.0f, light.environment, &a, rs, ref);
    auto error = [&](int m, int k, int o, int s) {
        GiSettings g = indirectSettings(1, s);
        g.visibility.azimuths = m;
        g.indirect.azimuths = 0;  // the indirect scan follows m
        g.pyramid.levelsPerOctave = k;
        g.pyramid.levelOffset = o;
        g.indirect.radiance.levelsPerOctave = k;
        g.indirect.radiance.levelOffset = o;
        GiState st;
        runGiFrame(h.view(), 1.0f, light, g, st, &a);
        return relRmse(st.indirect.indirect[0], ref.indirect[0], 0.1f);
    };
    const double e0 = error(8, 2, 0, 1), e1 = error(16, 4, 1, 1), e2 = error(32, 4, 2, 1), e3 = error(64, 8, 4, 1);
    MESSAGE("indirect rel. RMSE vs reference: (m, k, o) = (8, 2, 0) " << e0 << ", (16, 4, 1) " << e1 << ", (32, 4, 2) "
                                                                      << e2 << ", (64, 8, 4) " << e3);
    CHECK(e1 < e0);
    CHECK(e3 < e1);
    CHECK(e3 < 0.08);
    // sub-sampling at the converged settings (at (32, 4, 2) the engine's 2x is
    // within 0.001 of its 1x on these smooth hills: 0.0505 vs 0.0512)
    const double s4 = error(64, 8, 4, 4), s2 = error(64, 8, 4, 2), s1 = e3;
    MESSAGE("sub-sampling: 4x " << s4 << ", 2x " << s2 << ", 1x " << s1);
    CHECK(s2 < s4);
    CHECK(s1 < s2);
}

TEST_CASE(
    "gi.indirect: exact cosine at the receivers (and blocker radiance between them) matches the reference bounce, is "
    "deterministic, and is 0 on a plane") {
    constexpr int kModeCount = 2;
    const LambertIndirect kModes[kModeCount] = {LambertIndirect::ShKernel, LambertIndirect::BlockerRadiance};
    // a V valley and a conical pit, albedo 0.6, uniform sky, one bounce, 1x and 2x
    const int n = 49;
    Grid pit(n, n);
    const float c = 0.5f * static_cast<float>(n - 1);
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) pit(x, y) = 0.8f * std::hypot(static_cast<float>(x) - c, static_cast<float>(y) - c);
    const Grid vee = valley(n, n, 1.0f);
    const AlbedoMap a = uniformAlbedo(n, n, 0.6f);
    GiLighting light;
    ReferenceGiSettings rs;
    rs.directions = 4096;
    rs.azimuths = 256;
    rs.bounces = 1;
    for (int shape = 0; shape < 2; ++shape) {
        const Grid& h = shape == 0 ? vee : pit;
        ReferenceGiResult ref;
        renderReferenceGi(h.view(), 1.0f, light.environment, &a, rs, ref);
        for (int s : {1, 2}) {
            double err[kModeCount] = {0.0, 0.0};
            for (int mode = 0; mode < kModeCount; ++mode) {
                GiSettings gs = indirectSettings(1, s);
                gs.indirect.lambert = kModes[mode];
                GiState st;
                runGiFrame(h.view(), 1.0f, light, gs, st, &a);
                err[mode] = relRmse(st.indirect.indirect[0], ref.indirect[0], 0.25f);
                for (float v : st.indirect.indirect[1].v) REQUIRE(std::isfinite(v));
            }
            MESSAGE(std::string(shape == 0 ? "valley " : "pit ")
                    << s << "x: indirect rel. RMSE SH kernel " << err[0] << ", blocker radiance " << err[1]);
            // measured (SH kernel / blocker radiance; engine settings, 8 indirect
            // azimuths, max-decimated pyramid): valley 1x 0.054 / 0.061, 2x 0.075 /
            // 0.062; pit 1x 0.029 / 0.035, 2x 0.026 / 0.033 (with the half-mean
            // pyramid the blocker kernel was at most 0.005 above the SH kernel: the
            // steeper walls of the max pyramid favour the SH kernel on this cone)
            CHECK(err[1] < (s == 1 ? 0.07 : 0.10));
            CHECK(err[1] < err[0] + 0.01);
        }
    }
    // flat plane: exactly 0; bit-identical for 1, 2 and 3 threads
    Grid flat(40, 40, 7.25f);
    const Grid hl = hills(47, 10.0f);
    const AlbedoMap ah = uniformAlbedo(47, 47, 0.6f);
    for (int mode = 0; mode < kModeCount; ++mode)
        for (int s : {1, 2, 4}) {
            GiSettings gs = indirectSettings(2, s);
            gs.indirect.lambert = kModes[mode];
            GiState st;
            runGiFrame(flat.view(), 1.0f, light, gs, st, nullptr);
            for (int ch = 0; ch < 3; ++ch)
                for (float v : st.indirect.indirect[static_cast<std::size_t>(ch)].v) REQUIRE(v == 0.0f);
            std::vector<std::vector<float>> results;
            for (int threads : {1, 2, 3}) {
                GiState sh;
                withThreads(threads, [&] { runGiFrame(hl.view(), 1.5f, GiLighting{}, gs, sh, &ah); });
                std::vector<float> all;
                for (int ch = 0; ch < 3; ++ch)
                    all.insert(all.end(), sh.indirect.indirect[static_cast<std::size_t>(ch)].v.begin(),
                               sh.indirect.indirect[static_cast<std::size_t>(ch)].v.end());
                results.push_back(all);
            }
            CHECK(results[1] == results[0]);
            CHECK(results[2] == results[0]);
        }
}

TEST_CASE("gi.indirect: kept step tables give a fresh state's bits as the layout, cell size and strategy change") {
    // one state through frames whose indirect step tables differ in one
    // input each (the glossy vector bounces write the same tables), against
    // a fresh state per frame
    struct Frame {
        int nx, ny;
        float cell;
        int subsample, azimuths;
        bool glossy;
    };
    const Frame frames[] = {{64, 48, 1.0f, 2, 8, false}, {64, 48, 1.0f, 2, 8, false}, {64, 48, 1.5f, 2, 8, false},
                            {70, 48, 1.5f, 2, 8, false}, {70, 48, 1.5f, 2, 6, false}, {70, 48, 1.5f, 1, 6, false},
                            {70, 48, 1.5f, 1, 6, true},  {70, 48, 1.5f, 1, 6, false}, {64, 48, 1.0f, 2, 8, false}};
    GiState kept;
    for (const Frame& f : frames) {
        CAPTURE(f.nx);
        CAPTURE(f.cell);
        CAPTURE(f.subsample);
        CAPTURE(f.azimuths);
        CAPTURE(f.glossy);
        const Grid g = gi_test::bumpy(f.nx, f.ny);
        GiSettings settings = indirectSettings(1, f.subsample);
        settings.incremental = false;
        settings.indirect.azimuths = f.azimuths;
        if (f.glossy) {
            settings.shading.brdf = Brdf::Phong;
            settings.indirect.glossy = GlossyIndirect::VectorPyramid;
        }
        GiState fresh;
        runGiFrame(g.cview(), f.cell, GiLighting{}, settings, kept);
        runGiFrame(g.cview(), f.cell, GiLighting{}, settings, fresh);
        for (int c = 0; c < 3; ++c) CHECK(kept.indirect.indirect[c].v == fresh.indirect.indirect[c].v);
    }
}
