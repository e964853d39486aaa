// Glossy indirect light: the SH radiance-vector pyramid
// (gi/indirect_sh_kernel, gi/glossy_exit_radiance), the per-texel Phong exponent map and the glossy
// reference (gi/reference_glossy).
#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <doctest/doctest.h>

#include "core/bfloat16.h"
#include "core/error.h"
#include "core/parallel.h"
#include "gi/frame.h"
#include "gi/glossy_exit_radiance.h"
#include "gi/glossy_lobe_gather.h"
#include "gi/reference_gi.h"
#include "gi/reference_glossy_lobe.h"
#include "tests/gi_test_terrain.h"

using namespace terrain;
using namespace terrain::gi;
using gi_test::hills;
using gi_test::meanOver;
using gi_test::valley;

namespace {

GiSettings glossySettings(Brdf brdf, float exponent, int bounces, GlossyIndirect mode, int subsample = 1) {
    GiSettings s = GiSettings{};
    s.subsample = subsample;
    s.shading.brdf = brdf;
    s.shading.phongExponent = exponent;
    s.shading.specularWeight = 0.5f;
    s.indirect.bounces = bounces;
    s.indirect.glossy = mode;
    return s;
}

// One lobe-gather bounce (Phong 32, sub-sampling s) seen by a viewer whose
// reflection in flat ground rises `elevation` above the horizon towards
// `azimuth` (radians, from +x towards +y).
GiSettings lobeGatherReflectingTowards(double elevation, double azimuth, int s) {
    GiSettings g = glossySettings(Brdf::Phong, 32.0f, 1, GlossyIndirect::LobeScan, s);
    g.shading.viewDir[0] = static_cast<float>(-std::cos(elevation) * std::cos(azimuth));
    g.shading.viewDir[1] = static_cast<float>(-std::cos(elevation) * std::sin(azimuth));
    g.shading.viewDir[2] = static_cast<float>(std::sin(elevation));
    return g;
}

// One-bounce glossy reference settings (Phong of exponent S) with the given
// quadrature: fixed directions, horizon azimuths and lobe quadrature.
ReferenceGiSettings glossyReference(float S, int directions, int azimuths, const LobeLayout& lobe) {
    ReferenceGiSettings rs;
    rs.directions = directions;
    rs.azimuths = azimuths;
    rs.lobe = lobe;
    rs.bounces = 1;
    rs.shading = glossySettings(Brdf::Phong, S, 1, GlossyIndirect::VectorPyramid).shading;
    return rs;
}

// The one-bounce reference of the 41 x 41 V valley tests: many directions and
// horizon azimuths, the given shading.
ReferenceGiSettings valleyReference(const ShadingSettings& shading) {
    ReferenceGiSettings rs;
    rs.directions = 2048;
    rs.azimuths = 128;
    rs.bounces = 1;
    rs.shading = shading;
    return rs;
}

// Relative RMS difference of a's green indirect light from b's over the
// interior of an n x 9 valley (two cells of border left out).
double valleyInteriorChange(const ReferenceGiResult& a, const ReferenceGiResult& b, int n) {
    double d2 = 0.0, r2 = 0.0;
    for (int y = 2; y < 7; ++y)
        for (int x = 2; x < n - 2; ++x) {
            const double v = a.indirect[1](x, y), w = b.indirect[1](x, y);
            d2 += (v - w) * (v - w);
            r2 += w * w;
        }
    REQUIRE(r2 > 0.0);
    return std::sqrt(d2 / r2);
}

std::vector<float> allChannels(const std::array<Grid, 3>& g) {
    std::vector<float> v;
    for (const Grid& c : g) v.insert(v.end(), c.v.begin(), c.v.end());
    return v;
}

}  // namespace

TEST_CASE("gi.glossy: the exit-radiance vector E . Y(w) is the Phong lobe about the reflection of w") {
    // E = Rot_N(pi)(w_s g (.) I) + sqrt(4 pi) D e_00 must give
    // D + w_s sum_lm g_l I_lm Y_lm(R_N(w)) for every direction w (exact per band).
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    double worst = 0.0;
    for (int trial = 0; trial < 50; ++trial) {
        float n[3] = {u(rng), u(rng), std::fabs(u(rng)) + 0.2f};
        const float nl = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (float& c : n) c /= nl;
        float I[kShCount];
        for (float& c : I) c = u(rng);
        float ph[kShOrder];
        phongLobeFactors(1.0 + 100.0 * (trial % 7), ph);
        const float ws = 0.7f, D = 0.3f;
        float E[kShCount];
        glossyExitVector(I, n[0], n[1], n[2], ph, ws, D, E);
        for (int k = 0; k < 20; ++k) {
            double w[3] = {u(rng), u(rng), u(rng)};
            const double wl = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
            for (double& c : w) c /= wl;
            const double d = 2.0 * (n[0] * w[0] + n[1] * w[1] + n[2] * w[2]);
            double yR[kShCount], yw[kShCount];
            shEvaluate(d * n[0] - w[0], d * n[1] - w[1], d * n[2] - w[2], yR);
            shEvaluate(w[0], w[1], w[2], yw);
            double expect = D, got = 0.0;
            for (int i = 0; i < kShCount; ++i) {
                expect += ws * ph[shBand(i)] * I[i] * yR[i];
                got += E[i] * yw[i];
            }
            worst = std::max(worst, std::fabs(got - expect));
        }
    }
    MESSAGE("max |E . Y(w) - lobe(R_N(w))| = " << worst);
    CHECK(worst < 2e-5);
}

TEST_CASE(
    "gi.glossy: the exit radiance texel by texel is its planes' values in bfloat16 (either alone, both lane widths)") {
    // The lobe gather reads E texel by texel, the vector pyramid its planes:
    // written by the same kernel, 8 or 4 texels at a time and the rest one
    // by one (a width of 37 leaves a remainder), each value once.
    const int nx = 37, ny = 11, s = 2, nxr = receiverCount(nx, s), nyr = receiverCount(ny, s);
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    Grid gx(nx, ny, 0.0f), gy(nx, ny, 0.0f);
    for (float& v : gx.v) v = 0.5f * u(rng);
    for (float& v : gy.v) v = 0.5f * u(rng);
    std::vector<float> incident(static_cast<std::size_t>(nxr) * nyr * kGlossyFields);
    for (float& v : incident) v = u(rng);
    std::array<Grid, 3> shade;
    for (Grid& g : shade) {
        g = Grid(nx, ny, 0.0f);
        for (float& v : g.v) v = 0.5f + 0.5f * u(rng);
    }
    const ShadingSettings shading = glossySettings(Brdf::Phong, 24.0f, 1, GlossyIndirect::LobeScan).shading;
    const std::size_t values = static_cast<std::size_t>(nx) * ny * kGlossyFields, plane = values / kGlossyFields;
    const bool wide = simd::wideEnabled();
    for (bool w : {wide, !wide}) {
        if (simd::setWideEnabled(w) != w) continue;  // this machine has one width only
        GlossyExitScratch scratch;
        std::vector<float> planes(values), planesAlone(values);
        std::vector<std::uint16_t> texels(values), texelsAlone(values);
        glossyExitRadiance(gx.cview(), gy.cview(), s, nxr, nyr, incident.data(), shade, nullptr, shading, scratch,
                           {planes.data(), texels.data()});
        glossyExitRadiance(gx.cview(), gy.cview(), s, nxr, nyr, incident.data(), shade, nullptr, shading, scratch,
                           {planesAlone.data(), nullptr});
        glossyExitRadiance(gx.cview(), gy.cview(), s, nxr, nyr, incident.data(), shade, nullptr, shading, scratch,
                           {nullptr, texelsAlone.data()});
        long mismatches = 0;
        for (std::size_t k = 0; k < plane; ++k)
            for (int f = 0; f < kGlossyFields; ++f)
                mismatches += texels[k * kGlossyFields + static_cast<std::size_t>(f)] !=
                              toBfloat16(planes[static_cast<std::size_t>(f) * plane + k]);
        CAPTURE(w);
        CHECK(mismatches == 0);
        CHECK(planes == planesAlone);
        CHECK(texels == texelsAlone);
    }
    simd::setWideEnabled(wide);
}

TEST_CASE("gi.glossy: a flat plane gets exactly no glossy indirect light (fast path and reference)") {
    const Grid h(37, 23, 250.0f);
    const AlbedoMap a = uniformAlbedo(37, 23, 0.8f);
    for (Brdf brdf : {Brdf::Phong, Brdf::LambertPlusPhong})
        for (int b : {1, 3}) {
            GiLighting light;
            light.environment = sunSkyLight();
            for (GlossyIndirect mode : {GlossyIndirect::VectorPyramid, GlossyIndirect::LobeScan}) {
                GiState st;
                runGiFrame(h.view(), 2.0f, light, glossySettings(brdf, 20.0f, b, mode, 2), st, &a);
                for (const Grid& g : st.indirect.indirect)
                    for (float v : g.v) REQUIRE(v == 0.0f);
            }
            ReferenceGiSettings rs;
            rs.directions = 256;
            rs.azimuths = 32;
            rs.bounces = b;
            rs.shading = glossySettings(brdf, 20.0f, b, GlossyIndirect::VectorPyramid).shading;
            ReferenceGiResult ref;
            renderReferenceGi(h.view(), 2.0f, light.environment, &a, rs, ref);
            for (const Grid& g : ref.indirect)
                for (float v : g.v) REQUIRE(v == 0.0f);
        }
}

TEST_CASE("gi.glossy: each bounce adds less (albedo < 1) and the exact reference is never negative") {
    const Grid h = hills(48, 9.0f);
    const AlbedoMap a = uniformAlbedo(48, 48, 0.6f);
    for (Brdf brdf : {Brdf::Phong, Brdf::LambertPlusPhong}) {
        GiState st;
        runGiFrame(h.view(), 1.0f, GiLighting{}, glossySettings(brdf, 16.0f, 3, GlossyIndirect::VectorPyramid), st, &a);
        const auto& m = st.indirect.bounceMean;
        MESSAGE("bounce means " << m[0] << " " << m[1] << " " << m[2]);
        CHECK(m[0] > 0.0);
        CHECK(m[1] < m[0]);
        CHECK(m[2] < m[1]);
        // The exact reference integrates a positive sky against positive
        // lobes: no ringing, so nothing below zero.
        ReferenceGiSettings rs;
        rs.directions = 1024;
        rs.azimuths = 64;
        rs.lobe = LobeLayout::uniform(8);
        rs.bounces = 1;
        rs.shading = glossySettings(brdf, 16.0f, 1, GlossyIndirect::VectorPyramid).shading;
        ReferenceGiResult ref;
        renderReferenceGi(h.view(), 1.0f, uniformSkyLight(1.0f), &a, rs, ref);
        float rlo = 0.0f, rhi = 0.0f;
        for (const Grid& g : ref.indirect)
            for (float v : g.v) {
                rlo = std::min(rlo, v);
                rhi = std::max(rhi, v);
            }
        MESSAGE("reference bounce 1 [" << rlo << ", " << rhi << "]");
        CHECK(rlo >= 0.0f);
        CHECK(rhi > 0.0f);
    }
}

namespace {

// Smallest value of any channel of any of the grids.
float smallest(std::initializer_list<const std::array<Grid, 3>*> maps) {
    float lo = std::numeric_limits<float>::infinity();
    for (const auto* m : maps)
        for (const Grid& g : *m)
            for (float v : g.v) lo = std::min(lo, v);
    return lo;
}

}  // namespace

TEST_CASE(
    "gi.glossy: with the positivity clamp no texel is negative (gentle, steep and flat terrain, every exponent)") {
    struct Terrain {
        const char* name;
        Grid h;
    };
    Grid cliff(40, 36, 0.0f);
    for (int y = 0; y < 36; ++y)
        for (int x = 20; x < 40; ++x) cliff(x, y) = 25.0f;
    const std::vector<Terrain> terrains = {{"gentle hills", hills(48, 3.0f)},
                                           {"gentle ridges", gi_test::bumpy(48, 40)},
                                           {"steep V valley", valley(41, 33, 1.5f)},
                                           {"cliff", cliff},
                                           {"flat", Grid(32, 24, 100.0f)}};
    GiLighting light;
    light.environment = sunSkyLight();
    int negativeWithoutClamp = 0, cases = 0;
    for (const Terrain& t : terrains) {
        const AlbedoMap a = uniformAlbedo(t.h.nx, t.h.ny, 0.8f);
        for (float S : {1.0f, 4.0f, 16.0f, 64.0f, 256.0f, 1000.0f})
            for (GlossyIndirect mode :
                 {GlossyIndirect::VectorPyramid, GlossyIndirect::ScalarPyramid, GlossyIndirect::LobeScan})
                for (Brdf brdf : {Brdf::Phong, Brdf::LambertPlusPhong}) {
                    GiSettings s = glossySettings(brdf, S, 1, mode, S < 10.0f ? 1 : 2);
                    GiState st;
                    runGiFrame(t.h.view(), 1.0f, light, s, st, &a);
                    const float lo = smallest({&st.shade.rgb, &st.indirect.indirect, &st.indirect.total});
                    if (lo < 0.0f)
                        FAIL_CHECK(t.name << ", S = " << S << ", mode " << static_cast<int>(mode) << ": smallest value "
                                          << lo);
                    s.shading.positivity = GlossyPositivity::Off;  // the paper's linear values
                    GiState off;
                    runGiFrame(t.h.view(), 1.0f, light, s, off, &a);
                    negativeWithoutClamp += smallest({&off.indirect.indirect}) < 0.0f;
                    ++cases;
                }
    }
    // the clamp is what makes them non-negative: without it the SH lobe rings below zero
    MESSAGE("cases with negative indirect light without the clamp: " << negativeWithoutClamp << " of " << cases);
    CHECK(negativeWithoutClamp > 10);
}

TEST_CASE("gi.glossy reference: the lobe quadrature against closed forms under a uniform sky") {
    // Flat open ground (nothing blocks), uniform unit sky: a lobe about the
    // zenith sees the sky alone (1); about the horizon exactly half of any
    // lobe is above the ground (0.5, by symmetry); for S = 1 about
    // elevation e, (1/pi) int max(0, w . R) over the upper hemisphere is
    // (1 + sin e) / 2.
    const Grid flat(9, 9, 0.0f);
    SkyHorizons hz;
    buildSkyHorizons(flat.view(), 1.0f, 64, hz);
    const ShRgb sky = uniformSkyLight(1.0f);
    double skyRadiance[3];
    evaluateShRgb(sky, 0.0, 0.0, 1.0, skyRadiance);
    const double up[3] = {0.0, 0.0, 1.0};
    const double horizon[3] = {0.6, 0.8, 0.0};
    const double e = 30.0 * 3.14159265358979323846 / 180.0;
    const double tilted[3] = {std::cos(e), 0.0, std::sin(e)};
    for (double S : {1.0, 8.0, 64.0, 1000.0}) {
        double out[3];
        exactLobeRadiance(hz, sky, 4.0f, 4.0f, up, up, S, LobeLayout::uniform(16), out);
        CHECK(out[0] / skyRadiance[0] == doctest::Approx(1.0).epsilon(1e-12));
        exactLobeRadiance(hz, sky, 4.0f, 4.0f, up, horizon, S, LobeLayout::uniform(16), out);
        CHECK(out[0] / skyRadiance[0] == doctest::Approx(0.5).epsilon(1e-12));
    }
    double coarse[3], fine[3];
    exactLobeRadiance(hz, sky, 4.0f, 4.0f, up, tilted, 1.0, LobeLayout::uniform(16), coarse);
    exactLobeRadiance(hz, sky, 4.0f, 4.0f, up, tilted, 1.0, LobeLayout::uniform(128), fine);
    const double expect = 0.5 * (1.0 + std::sin(e));
    MESSAGE("S = 1 at 30 degrees: 16 rings " << coarse[0] / skyRadiance[0] << ", 128 rings " << fine[0] / skyRadiance[0]
                                             << ", exact " << expect);
    CHECK(fine[0] / skyRadiance[0] == doctest::Approx(expect).epsilon(2e-3));
    CHECK(std::fabs(fine[0] / skyRadiance[0] - expect) < std::fabs(coarse[0] / skyRadiance[0] - expect) + 1e-9);
}

TEST_CASE("gi.glossy reference: converged in the lobe quadrature, and symmetric in a symmetric valley") {
    // Doubling the lobe rings (4x the directions per lobe, at the receivers
    // and at their first hits) changes the indirect light by little; a
    // valley symmetric about its floor line lights both walls alike.
    const int n = 21;
    const Grid h = valley(n, 9, 1.0f);
    const AlbedoMap a = uniformAlbedo(n, 9, 1.0f);
    for (float S : {8.0f, 64.0f}) {
        ReferenceGiSettings rs = glossyReference(S, 256, 128, LobeLayout::uniform(8));
        ReferenceGiResult r12, r24;  // 8 and 16 rings
        renderReferenceGi(h.view(), 1.0f, sunSkyLight(), &a, rs, r12);
        rs.lobe = LobeLayout::uniform(16);
        renderReferenceGi(h.view(), 1.0f, sunSkyLight(), &a, rs, r24);
        const double change = valleyInteriorChange(r12, r24, n);
        MESSAGE("S = " << S << ": 8 -> 16 rings, relative RMS change " << change);
        CHECK(change < 0.03);
        // under a uniform sky the walls mirror each other
        ReferenceGiResult u;
        rs.lobe = LobeLayout::uniform(8);
        renderReferenceGi(h.view(), 1.0f, uniformSkyLight(1.0f), &a, rs, u);
        double asym = 0.0, wall = 0.0;
        for (int x = 2; x < n - 2; ++x) {
            asym = std::max(asym, std::fabs(static_cast<double>(u.indirect[0](x, 4) - u.indirect[0](n - 1 - x, 4))));
            wall = std::max(wall, static_cast<double>(u.indirect[0](x, 4)));
        }
        MESSAGE("S = " << S << ": uniform sky, largest asymmetry " << asym / wall << " of the wall's largest value");
        CHECK(wall > 0.01);
        CHECK(asym < 0.02 * wall);
    }
}

TEST_CASE(
    "gi.glossy: V valley with Phong walls: the vector pyramid matches the glossy reference, the scalar one does not") {
    // Walls at 45 degrees under a uniform sky, viewer overhead. Towards the
    // viewer a wall reflects the opposite wall (the shade forwarded by the
    // scalar pyramid); towards the opposite wall it reflects the sky and the
    // valley floor line: with a sharp lobe the two differ, and only the
    // vector pyramid evaluates the lobe in the direction of the receiver.
    const int n = 41;
    const Grid h = valley(n, n, 1.0f);
    const AlbedoMap a = uniformAlbedo(n, n, 1.0f);
    const int c = n / 2;
    for (float exponent : {4.0f, 64.0f}) {
        GiLighting light;
        GiState vs, ss;
        GiSettings sv = glossySettings(Brdf::Phong, exponent, 1, GlossyIndirect::VectorPyramid);
        sv.visibility.azimuths = 32;
        GiSettings sc = sv;
        sc.indirect.glossy = GlossyIndirect::ScalarPyramid;
        runGiFrame(h.view(), 1.0f, light, sv, vs, &a);
        runGiFrame(h.view(), 1.0f, light, sc, ss, &a);
        const ReferenceGiSettings rs = valleyReference(sv.shading);
        ReferenceGiResult ref;
        renderReferenceGi(h.view(), 1.0f, light.environment, &a, rs, ref);
        const double wallV = meanOver(vs.indirect.indirect[0], c + 3, c + 10, 10, n - 10);
        const double wallS = meanOver(ss.indirect.indirect[0], c + 3, c + 10, 10, n - 10);
        const double wallR = meanOver(ref.indirect[0], c + 3, c + 10, 10, n - 10);
        MESSAGE("S = " << exponent << ": wall indirect vector " << wallV << ", scalar " << wallS << ", reference "
                       << wallR);
        CHECK(wallR > 0.01);
        CHECK(wallV == doctest::Approx(wallR).epsilon(0.15));
        if (exponent > 10.0f) CHECK(std::fabs(wallV - wallR) < 0.5 * std::fabs(wallS - wallR));
    }
}

TEST_CASE("gi.glossy: the lobe gather takes a third ring for wide lobes") {
    // rings 0: 3 rings below kWideLobeExponent, 2 from it up; a set count is kept
    for (double S : {1.0, 8.0, 15.9}) CHECK(gatherLobeLayout(S, 0, 5) == LobeLayout::growing(3, 5));
    for (double S : {16.0, 32.0, 1000.0}) CHECK(gatherLobeLayout(S, 0, 5) == LobeLayout::growing(2, 5));
    CHECK(gatherLobeLayout(8.0, 4, 3) == LobeLayout::growing(4, 3));
    CHECK(gatherLobeLayout(64.0, 1, 6) == LobeLayout::growing(1, 6));
    CHECK(IndirectSettings{}.lobeRings == 0);
}

TEST_CASE("gi.glossy: V valley with Phong walls: the lobe gather against the exact reference and its idealisation") {
    // The valley above: a wall's glossy light comes from the opposite wall
    // along the viewer's reflection. The lobe gather integrates each
    // receiver's own lobe; what the opposite wall sends it is its windowed
    // lobe (gi/glossy_lobe_members.h), the lobe-filtered sky times the part of
    // the lobe above the wall's horizon. With the gather's quadrature (its
    // rings and azimuths) and windowed members, the reference is the gather's
    // idealisation: the gather must follow it closely, and come closer to the
    // exact reference than members sending their order-4 exit radiance E . Y
    // do through the same quadrature (the reference's membersSh diagnostic
    // with the gather's rings and azimuths: 0.907 / 1.129 / 1.150 for S = 8 /
    // 64 / 256, where the exact wall has 0.857 / 1.000 / 1.000; the gather
    // 0.885 / 1.043 / 1.049). At S = 8 the quadrature's own error on this
    // wall (its idealisation 0.884) is as large as the members' difference,
    // so the members are compared through the gather's quadrature, not the
    // reference's.
    const int n = 41;
    const Grid h = valley(n, n, 1.0f);
    const AlbedoMap a = uniformAlbedo(n, n, 1.0f);
    const int c = n / 2;
    for (float exponent : {8.0f, 64.0f, 256.0f}) {
        GiLighting light;
        GiSettings sl = glossySettings(Brdf::Phong, exponent, 1, GlossyIndirect::LobeScan);
        sl.visibility.azimuths = 32;
        GiState ls;
        runGiFrame(h.view(), 1.0f, light, sl, ls, &a);
        ReferenceGiSettings rs = valleyReference(sl.shading);
        ReferenceGiResult exact, ideal, membersSh;
        renderReferenceGi(h.view(), 1.0f, light.environment, &a, rs, exact);
        rs.lobe = gatherLobeLayout(exponent, sl.indirect.lobeRings, sl.indirect.lobeInnerDirections);
        rs.receiverAzimuths = sl.indirect.lobeAzimuths;
        rs.membersSh = true;
        renderReferenceGi(h.view(), 1.0f, light.environment, &a, rs, membersSh);
        rs.membersSh = false;
        rs.membersWindowed = true;
        renderReferenceGi(h.view(), 1.0f, light.environment, &a, rs, ideal);
        auto wall = [&](const Grid& g) { return meanOver(g, c + 3, c + 10, 10, n - 10); };
        const double wallL = wall(ls.indirect.indirect[0]), wallR = wall(exact.indirect[0]);
        const double wallI = wall(ideal.indirect[0]), wallM = wall(membersSh.indirect[0]);
        MESSAGE("S = " << exponent << ": wall indirect lobe gather " << wallL << ", idealisation " << wallI
                       << ", exact reference " << wallR << " (members SH " << wallM << ")");
        CHECK(wallR > 0.01);
        CHECK(wallL == doctest::Approx(wallI).epsilon(0.05));
        CHECK(std::fabs(wallL - wallR) < 0.06 * wallR);
        CHECK(std::fabs(wallL - wallR) < std::fabs(wallM - wallR));
    }
}

TEST_CASE("gi.glossy: the lobe gather against the reference's own idealisation of it on hills at 1x and 2x") {
    // The reference with the gather's quadrature (its rings and azimuths) and
    // windowed members (membersWindowed) is what the gather would give
    // without the pyramids' steps and filtering and with exact horizons: the
    // difference is the scan's own error.
    // With 2x sub-sampling every texel still gathers its own lobe, seeing its
    // receiver's samples from where it stands (its height and distance), so
    // the error stays near the 1x one (walked as if from the receiver, the
    // 2x error was 0.064 / 0.066 above the 1x one for S = 8 / 64), where the
    // vector pyramid, shading interpolated U, loses more.
    const Grid h = hills(48, 8.0f);
    const AlbedoMap a = uniformAlbedo(48, 48, 0.8f);
    GiLighting light;
    light.environment = sunSkyLight();
    auto relative = [](const Grid& v, const Grid& w) {
        double d2 = 0.0, r2 = 0.0;
        for (int y = 5; y < 43; ++y)
            for (int x = 5; x < 43; ++x) {
                d2 += (v(x, y) - w(x, y)) * (v(x, y) - w(x, y));
                r2 += static_cast<double>(w(x, y)) * w(x, y);
            }
        return std::sqrt(d2 / r2);
    };
    const IndirectSettings gather;
    for (float S : {8.0f, 64.0f}) {
        ReferenceGiSettings rs =
            glossyReference(S, 512, 64, gatherLobeLayout(S, gather.lobeRings, gather.lobeInnerDirections));
        rs.membersWindowed = true;
        rs.receiverAzimuths = gather.lobeAzimuths;
        ReferenceGiResult ideal, exact;
        renderReferenceGi(h.view(), 1.0f, light.environment, &a, rs, ideal);
        rs = glossyReference(S, 512, 64, LobeLayout::uniform(8));
        renderReferenceGi(h.view(), 1.0f, light.environment, &a, rs, exact);
        double err[2] = {0.0, 0.0};
        for (int s : {1, 2}) {
            GiState st, vs;
            runGiFrame(h.view(), 1.0f, light, glossySettings(Brdf::Phong, S, 1, GlossyIndirect::LobeScan, s), st, &a);
            runGiFrame(h.view(), 1.0f, light, glossySettings(Brdf::Phong, S, 1, GlossyIndirect::VectorPyramid, s), vs,
                       &a);
            const double toIdeal = relative(st.indirect.indirect[1], ideal.indirect[1]);
            err[s - 1] = relative(st.indirect.indirect[1], exact.indirect[1]);
            const double vector = relative(vs.indirect.indirect[1], exact.indirect[1]);
            MESSAGE("S = " << S << ", " << s << "x: relative RMS difference gather vs its idealisation " << toIdeal
                           << ", vs the exact reference " << err[s - 1] << " (vector pyramid " << vector << ")");
            CHECK(toIdeal < (s == 1 ? 0.08 : 0.15));
            CHECK(err[s - 1] < (s == 1 ? 0.25 : 0.3));
            if (S > 10.0f) CHECK(err[s - 1] < vector);
            // the walks' dense raw steps against the pyramid's own steps
            GiSettings coarse = glossySettings(Brdf::Phong, S, 1, GlossyIndirect::LobeScan, s);
            coarse.indirect.lobeNearStepsPerOctave = coarse.pyramid.levelsPerOctave;
            coarse.indirect.lobeNearOctaves = coarse.pyramid.levelOffset;
            GiState cs;
            runGiFrame(h.view(), 1.0f, light, coarse, cs, &a);
            const double coarseErr = relative(cs.indirect.indirect[1], exact.indirect[1]);
            MESSAGE("  with the pyramid's steps alone: " << coarseErr);
            CHECK(err[s - 1] < coarseErr);
        }
        // at 2x the members' horizons are their receivers', interpolated
        CHECK(err[1] < err[0] + 0.045);
    }
}

TEST_CASE("gi.glossy: the lobe gather's walks reach a ridge past flat ground (a texel stops on every band ahead)") {
    // Flat ground with a ridge 100-130 cells east of the texels checked,
    // seen by lobes about a reflection 10 degrees above the eastern horizon:
    // the walks cross bands whose samples are all at ground level before the
    // ridge's, so a texel stopped on the band at hand (or on a wrong band's
    // highest sample) would lose the ridge's light. Flat ground alone sends
    // none (the test above).
    const int nx = 160, ny = 24;
    const Grid flat(nx, ny, 0.0f);
    Grid ridge = flat;
    for (int y = 0; y < ny; ++y)
        for (int x = 130; x < 140; ++x) ridge(x, y) = 60.0f;
    const AlbedoMap a = uniformAlbedo(nx, ny, 0.8f);
    GiLighting light;
    light.environment = sunSkyLight();
    for (int s : {1, 2}) {
        const GiSettings g = lobeGatherReflectingTowards(10.0 * kPi / 180.0, 0.0, s);
        GiState withRidge, without;
        runGiFrame(ridge.view(), 1.0f, light, g, withRidge, &a);
        runGiFrame(flat.view(), 1.0f, light, g, without, &a);
        const double lit = meanOver(withRidge.indirect.indirect[1], 10, 31, 8, 16);
        const double none = meanOver(without.indirect.indirect[1], 10, 31, 8, 16);
        MESSAGE(s << "x: glossy indirect light 100-130 cells before the ridge " << lit << ", without it " << none);
        CHECK(none == 0.0);
        CHECK(lit > 0.01);
    }
}

TEST_CASE("gi.glossy: the lobe gather's light before a wall is smooth across a distance band (no ray left out)") {
    // Flat ground and a wall 12 cells high from x = 40 on, seen by lobes
    // about a reflection 25 degrees above the eastern horizon: a texel d
    // cells before the wall sees it in the walk's band of d, and the rays
    // that clear every band are not walked. Bounding a band's samples from
    // its far end instead of its nearest step (twice as far) drops the rays
    // between 12 / 32 and 12 / 17 at d = 17, just past the band from 16 to
    // 32 cells, and the light there falls to 0.55-0.6 of the texel before
    // (0.78 or more where nothing is left out).
    const int nx = 64, ny = 16, wall = 40;
    Grid h(nx, ny, 0.0f);
    for (int y = 0; y < ny; ++y)
        for (int x = wall; x < nx; ++x) h(x, y) = 12.0f;
    const AlbedoMap a = uniformAlbedo(nx, ny, 0.8f);
    GiLighting light;
    light.environment = sunSkyLight();
    for (int s : {1, 2}) {
        GiState st;
        runGiFrame(h.view(), 1.0f, light, lobeGatherReflectingTowards(25.0 * kPi / 180.0, 0.0, s), st, &a);
        const Grid& green = st.indirect.indirect[1];
        for (int d = 10; d < 24; ++d) {
            const double nearer = meanOver(green, wall - d, wall - d + 1, 4, 12);
            const double farther = meanOver(green, wall - d - 1, wall - d, 4, 12);
            CAPTURE(s);
            CAPTURE(d);
            CHECK(nearer > 0.0);
            CHECK(farther > 0.7 * nearer);
            CHECK(farther < 1.1 * nearer);
        }
    }
}

TEST_CASE("gi.glossy: the lobe gather sees a block at the edge of a lobe's azimuths") {
    // Flat ground and a block 10 high, 8-12 cells east of the texels
    // checked and 3 cells wide: lobes of exponent 32 about a reflection 30
    // degrees up at azimuth 25 degrees (north of east) reach azimuths from
    // about 3 to 47 degrees, and only those near east see the block. A texel
    // whose lobe clears its walks along every azimuth it reaches has no rays;
    // taking that span too narrow (the azimuths around the reflection's
    // alone) leaves these texels dark.
    const int nx = 48, ny = 32, y0 = 16;
    Grid h(nx, ny, 0.0f);
    for (int y = y0 - 1; y <= y0 + 1; ++y)
        for (int x = 22; x <= 26; ++x) h(x, y) = 10.0f;
    const AlbedoMap a = uniformAlbedo(nx, ny, 0.8f);
    GiLighting light;
    light.environment = sunSkyLight();
    for (int s : {1, 2}) {
        GiState st;
        runGiFrame(h.view(), 1.0f, light, lobeGatherReflectingTowards(30.0 * kPi / 180.0, 25.0 * kPi / 180.0, s), st,
                   &a);
        for (int x = 10; x <= 14; ++x) {
            CAPTURE(s);
            CAPTURE(x);
            CHECK(st.indirect.indirect[1](x, y0) > 0.01f);
        }
    }
}

TEST_CASE("gi.glossy: as the lobe widens (S -> 0) the vector pyramid becomes the scalar (isotropic) one") {
    // For S -> 0 the lobe factors e^{-l^2/(2S)} vanish for l >= 1: the exit
    // radiance is isotropic, E = sqrt(4 pi) shade e_00, and u = E . Y = the
    // shade, which is what the scalar pyramid forwards.
    const Grid h = hills(40, 8.0f);
    const AlbedoMap a = uniformAlbedo(40, 40, 0.8f);
    double prev = 1e30;
    for (float exponent : {8.0f, 1.0f, 0.05f}) {
        GiState vs, ss;
        const GiSettings sv = glossySettings(Brdf::LambertPlusPhong, exponent, 1, GlossyIndirect::VectorPyramid);
        GiSettings sc = sv;
        sc.indirect.glossy = GlossyIndirect::ScalarPyramid;
        runGiFrame(h.view(), 1.0f, GiLighting{}, sv, vs, &a);
        runGiFrame(h.view(), 1.0f, GiLighting{}, sc, ss, &a);
        double se = 0.0, sr = 0.0;
        for (std::size_t i = 0; i < vs.indirect.indirect[0].v.size(); ++i) {
            const double d = vs.indirect.indirect[0].v[i] - ss.indirect.indirect[0].v[i];
            se += d * d;
            sr += static_cast<double>(ss.indirect.indirect[0].v[i]) * ss.indirect.indirect[0].v[i];
        }
        const double rel = std::sqrt(se / sr);
        MESSAGE("S = " << exponent << ": relative RMS difference vector vs scalar " << rel);
        CHECK(rel < prev);
        prev = rel;
    }
    CHECK(prev < 1e-3);
}

TEST_CASE("gi.glossy: bit-identical for 1, 2, 3 and 8 threads (vector pyramid, lobe gather, exponent map, 2 bounces)") {
    const Grid h = hills(53, 10.0f);
    AlbedoMap a = uniformAlbedo(53, 53, 0.7f);
    Grid e(53, 53);
    for (int y = 0; y < 53; ++y)
        for (int x = 0; x < 53; ++x) e(x, y) = 2.0f + static_cast<float>((x * 5 + y * 3) % 17) * 4.0f;
    setPhongExponentMap(a, e);
    for (GlossyIndirect mode : {GlossyIndirect::VectorPyramid, GlossyIndirect::LobeScan})
        for (int s : {1, 2}) {
            std::vector<std::vector<float>> results;
            for (int threads : {1, 2, 3, 8}) {
                GiState st;
                GiLighting light;
                light.environment = sunSkyLight();
                withThreads(threads, [&] {
                    runGiFrame(h.view(), 1.5f, light, glossySettings(Brdf::LambertPlusPhong, 10.0f, 2, mode, s), st,
                               &a);
                });
                results.push_back(allChannels(st.indirect.total));
            }
            for (std::size_t i = 1; i < results.size(); ++i) CHECK(results[i] == results[0]);
        }
}

TEST_CASE("gi.glossy: an exponent map of constant S shades bit for bit like the scalar exponent S") {
    const Grid h = hills(36, 7.0f);
    for (float S : {1.0f, 12.5f, 300.0f}) {
        AlbedoMap plain = uniformAlbedo(36, 36, 0.75f), mapped = plain;
        setPhongExponentMap(mapped, Grid(36, 36, S));
        for (GlossyIndirect mode :
             {GlossyIndirect::VectorPyramid, GlossyIndirect::ScalarPyramid, GlossyIndirect::LobeScan}) {
            GiState a, b;
            const GiSettings s = glossySettings(Brdf::LambertPlusPhong, S, 1, mode, 2);
            runGiFrame(h.view(), 1.0f, GiLighting{}, s, a, &plain);
            GiSettings s2 = s;
            s2.shading.phongExponent = 3.0f;  // ignored where the map has values
            runGiFrame(h.view(), 1.0f, GiLighting{}, s2, b, &mapped);
            CHECK(allChannels(a.shade.rgb) == allChannels(b.shade.rgb));
            CHECK(allChannels(a.indirect.total) == allChannels(b.indirect.total));
        }
    }
    AlbedoMap bad;
    CHECK_THROWS_AS(setPhongExponentMap(bad, Grid(4, 4, std::nanf(""))), InputError);
    CHECK_THROWS_AS(setPhongExponentMap(bad, Grid(4, 4, -1.0f)), InputError);
}

TEST_CASE("gi.glossy: the exponent map changes the lobe where it varies") {
    // Half the field sharp, half wide: the sharp half's direct shade equals a
    // uniform sharp run there, the wide half a uniform wide run.
    const Grid h = hills(32, 6.0f);
    AlbedoMap mixed = uniformAlbedo(32, 32, 1.0f);
    Grid e(32, 32, 2.0f);
    for (int y = 0; y < 32; ++y)
        for (int x = 16; x < 32; ++x) e(x, y) = 200.0f;
    setPhongExponentMap(mixed, e);
    const AlbedoMap plain = uniformAlbedo(32, 32, 1.0f);
    GiLighting light;
    light.environment = sunSkyLight();
    GiState m, wide, sharp;
    runGiFrame(h.view(), 1.0f, light, glossySettings(Brdf::Phong, 7.0f, 0, GlossyIndirect::VectorPyramid), m, &mixed);
    runGiFrame(h.view(), 1.0f, light, glossySettings(Brdf::Phong, 2.0f, 0, GlossyIndirect::VectorPyramid), wide,
               &plain);
    runGiFrame(h.view(), 1.0f, light, glossySettings(Brdf::Phong, 200.0f, 0, GlossyIndirect::VectorPyramid), sharp,
               &plain);
    CHECK(m.shade.rgb[0](5, 9) == wide.shade.rgb[0](5, 9));
    CHECK(m.shade.rgb[0](25, 9) == sharp.shade.rgb[0](25, 9));
    CHECK(wide.shade.rgb[0](25, 9) != sharp.shade.rgb[0](25, 9));
}

TEST_CASE("gi.glossy: hard cases stay finite") {
    std::vector<Grid> cases;
    Grid cliff(31, 29, 0.0f);
    for (int y = 0; y < 29; ++y)
        for (int x = 15; x < 31; ++x) cliff(x, y) = 500.0f;
    cases.push_back(cliff);
    Grid spike(33, 33, 0.0f);
    spike(16, 16) = 1000.0f;
    cases.push_back(spike);
    Grid big = hills(27, 10.0f);
    for (float& v : big.v) v += 1e5f;
    cases.push_back(big);
    Grid neg = hills(19, 30.0f);
    for (float& v : neg.v) v -= 5000.0f;
    cases.push_back(neg);
    cases.push_back(Grid(1, 1, 3.0f));
    cases.push_back(Grid(2, 2, 3.0f));
    cases.push_back(valley(2, 7, 5.0f));
    for (const Grid& g : cases)
        for (int s : {1, 2, 4})
            for (GlossyIndirect mode : {GlossyIndirect::VectorPyramid, GlossyIndirect::LobeScan}) {
                const AlbedoMap a = uniformAlbedo(g.nx, g.ny, 0.9f);
                GiState st;
                GiLighting light;
                light.environment = sunSkyLight();
                runGiFrame(g.view(), 1.0f, light, glossySettings(Brdf::LambertPlusPhong, 50.0f, 2, mode, s), st, &a);
                for (const Grid& c : st.indirect.total)
                    for (float v : c.v) REQUIRE(std::isfinite(v));
            }
    // the reference too
    ReferenceGiSettings rs;
    rs.directions = 128;
    rs.azimuths = 16;
    rs.bounces = 1;
    rs.shading.brdf = Brdf::Phong;
    for (const Grid& g : cases) {
        ReferenceGiResult ref;
        renderReferenceGi(g.view(), 1.0f, sunSkyLight(), nullptr, rs, ref);
        for (const Grid& c : ref.total)
            for (float v : c.v) REQUIRE(std::isfinite(v));
    }
}

TEST_CASE("gi.glossy: a second frame allocates nothing new") {
    const Grid h = hills(40, 8.0f);
    const AlbedoMap a = uniformAlbedo(40, 40, 0.7f);
    GiState st;
    const GiSettings s = glossySettings(Brdf::Phong, 30.0f, 2, GlossyIndirect::VectorPyramid, 2);
    runGiFrame(h.view(), 1.0f, GiLighting{}, s, st, &a);
    const float* p0 = st.indirect.glossy.exitSh.data();
    const PackedPyramids& packed = st.indirect.glossy.pyramid;
    const std::uint16_t* p1 = packed.block.data();
    const float* p2 = st.indirect.blocks.at(0).state.data();
    Grid h2 = h;
    for (float& v : h2.v) v *= 1.3f;
    runGiFrame(h2.view(), 1.0f, GiLighting{}, s, st, &a);
    CHECK(st.indirect.glossy.exitSh.data() == p0);
    CHECK(packed.block.data() == p1);
    CHECK(st.indirect.blocks.at(0).state.data() == p2);
    GiSettings lobe = s;
    lobe.indirect.glossy = GlossyIndirect::LobeScan;
    GiState ls;
    runGiFrame(h.view(), 1.0f, GiLighting{}, lobe, ls, &a);
    const float* p3 = ls.indirect.glossy.lobes.gathered.data();
    const ScanStep* p4 = ls.indirect.glossy.lobes.heightSteps.data();
    runGiFrame(h2.view(), 1.0f, GiLighting{}, lobe, ls, &a);
    CHECK(ls.indirect.glossy.lobes.gathered.data() == p3);
    CHECK(ls.indirect.glossy.lobes.heightSteps.data() == p4);
}

TEST_CASE("gi.glossy reference: the order-4 diagnostics change what they name and nothing else") {
    // The V valley of the test above, S = 64 (the walls reflect each other
    // through sharp lobes). membersSh: the first hits send the Phong part of
    // their order-4 SH incident radiance; receiverSh: the receivers shade
    // theirs. Each moves the wall's indirect light away from the exact value
    // (the truncation it isolates: 12-14 % here), and neither touches the
    // direct light.
    const int n = 41, c = n / 2;
    const Grid h = valley(n, n, 1.0f);
    const AlbedoMap a = uniformAlbedo(n, n, 1.0f);
    const GiLighting light;
    auto reference = [&](bool membersSh, bool receiverSh) {
        ReferenceGiSettings rs = glossyReference(64.0f, 512, 64, LobeLayout::uniform(6));
        rs.membersSh = membersSh;
        rs.receiverSh = receiverSh;
        ReferenceGiResult r;
        renderReferenceGi(h.view(), 1.0f, light.environment, &a, rs, r);
        return r;
    };
    auto wall = [&](const ReferenceGiResult& r) { return meanOver(r.indirect[0], c + 3, c + 10, 10, n - 10); };
    const ReferenceGiResult exact = reference(false, false);
    const ReferenceGiResult members = reference(true, false);
    const ReferenceGiResult receivers = reference(false, true);
    MESSAGE("wall: exact " << wall(exact) << ", members SH " << wall(members) << ", receivers SH " << wall(receivers));
    CHECK(wall(exact) > 0.01);
    CHECK(std::fabs(wall(members) - wall(exact)) > 0.02 * wall(exact));
    CHECK(std::fabs(wall(receivers) - wall(exact)) > 0.02 * wall(exact));
    for (int ch = 0; ch < 3; ++ch) {
        CHECK(members.direct[ch].v == exact.direct[ch].v);
        CHECK(receivers.direct[ch].v == exact.direct[ch].v);
    }
}

TEST_CASE("gi.glossy reference: the scan-azimuth diagnostic converges to every ray's own hit") {
    // receiverAzimuths: each receiver lobe ray reads the first hits at its
    // elevation along the two nearest of m azimuths. With m large the two
    // rays are the lobe ray's neighbours, so the indirect light comes close
    // to the exact one; with 3 azimuths (none along the valley's cross
    // section) the walls lose what faces them; the direct light is the same.
    const int n = 21;
    const Grid h = valley(n, 9, 1.0f);
    const AlbedoMap a = uniformAlbedo(n, 9, 1.0f);
    ReferenceGiSettings rs = glossyReference(32.0f, 256, 128, LobeLayout::uniform(6));
    ReferenceGiResult exact, fine, coarse;
    renderReferenceGi(h.view(), 1.0f, sunSkyLight(), &a, rs, exact);
    rs.receiverAzimuths = 2048;
    renderReferenceGi(h.view(), 1.0f, sunSkyLight(), &a, rs, fine);
    rs.receiverAzimuths = 3;
    renderReferenceGi(h.view(), 1.0f, sunSkyLight(), &a, rs, coarse);
    const double fineChange = valleyInteriorChange(fine, exact, n),
                 coarseChange = valleyInteriorChange(coarse, exact, n);
    MESSAGE("relative RMS change from every ray's own hit: 2048 azimuths " << fineChange << ", 3 azimuths "
                                                                           << coarseChange);
    CHECK(fineChange < 0.01);
    CHECK(coarseChange > 0.1);
    for (int ch = 0; ch < 3; ++ch) CHECK(fine.direct[ch].v == exact.direct[ch].v);
    rs.receiverAzimuths = -1;
    CHECK_THROWS_AS(renderReferenceGi(h.view(), 1.0f, sunSkyLight(), &a, rs, coarse), InputError);
}
