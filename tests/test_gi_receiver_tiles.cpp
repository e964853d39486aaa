// gi/receiver_tiles: tile-restricted scans (change-driven GI). Starting from
// a full result on terrain A, a scan of terrain B restricted to dirty tiles
// must give, bit for bit, B's full result at the dirty tiles' receivers and
// leave A's values everywhere else: visibility (V and maxSlope, environment
// and key light), the blocker-radiance scan (E, horizons) and the SH kernel's
// U; for any thread count and either SIMD width.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <doctest/doctest.h>

#include "core/error.h"
#include "core/parallel.h"
#include "core/simd.h"
#include "gi/frame.h"
#include "gi/indirect_blocker_radiance.h"
#include "gi/indirect_sh_kernel.h"
#include "gi/receiver_tiles.h"
#include "tests/gi_test_terrain.h"

using namespace terrain;
using namespace terrain::gi;
using gi_test::gridOf;
using gi_test::sameBits;

namespace {

constexpr float kCell = 1.5f;

// Terrain A (variant 0) and terrain B (variant 1): different bumps everywhere.
Grid terrainVariant(int nx, int ny, int variant) {
    const double p = 0.7 * variant;
    return gridOf(nx, ny, [&](int x, int y) {
        return static_cast<float>(5.0 * std::sin(0.21 * x + p) * std::cos(0.17 * y - p) +
                                  2.0 * std::sin(0.63 * x + 0.41 * y + 2.0 * p) + 0.02 * x);
    });
}

// One terrain's scan inputs, as a frame prepares them.
struct Field {
    HeightPyramid pyr;
    Grid gx, gy;
    FootprintBox box;
};

void prepareField(const Grid& h, int s, Field& f) {
    buildHeightPyramid(h.cview(), kCell, s, GiSettings{}.pyramid, f.pyr);
    computeGradient(h.cview(), kCell, f.gx, f.gy);
    if (s > 1) computeFootprintBox(f.gx.cview(), f.gy.cview(), s, f.box);
}

// The dirty patterns of the tests: none, one tile, a checkerboard, all, the
// last (partial) tile row and column, and a random third.
std::vector<std::pair<std::string, std::vector<std::uint8_t>>> patterns(int tilesX, int tilesY, std::mt19937& rng) {
    const std::size_t n = static_cast<std::size_t>(tilesX) * tilesY;
    std::vector<std::pair<std::string, std::vector<std::uint8_t>>> out;
    out.emplace_back("none", std::vector<std::uint8_t>(n, 0));
    std::vector<std::uint8_t> one(n, 0);
    one[std::uniform_int_distribution<std::size_t>(0, n - 1)(rng)] = 1;
    out.emplace_back("one tile", one);
    std::vector<std::uint8_t> checker(n), edge(n), random(n);
    for (int ty = 0; ty < tilesY; ++ty)
        for (int tx = 0; tx < tilesX; ++tx) {
            const std::size_t t = static_cast<std::size_t>(ty) * tilesX + tx;
            checker[t] = (tx + ty) % 2 == 0;
            edge[t] = tx == tilesX - 1 || ty == tilesY - 1;
            random[t] = std::uniform_int_distribution<int>(0, 2)(rng) == 0;
        }
    out.emplace_back("checkerboard", checker);
    out.emplace_back("all", std::vector<std::uint8_t>(n, 1));
    out.emplace_back("last tile row and column", edge);
    out.emplace_back("random", random);
    return out;
}

// Planes of nxr x nyr (any number): dirtyValues at the dirty tiles' receivers, cleanValues elsewhere.
std::vector<float> mergeByTiles(const std::vector<float>& dirtyValues, const std::vector<float>& cleanValues,
                                const ReceiverTiles& t) {
    std::vector<float> out = cleanValues;
    const std::size_t plane = static_cast<std::size_t>(t.nxr) * t.nyr;
    for (std::size_t i = 0; i < out.size(); ++i) {
        const int X = static_cast<int>(i % plane % t.nxr), Y = static_cast<int>(i % plane / t.nxr);
        if (t.isDirty(X / t.tileSize, Y / t.tileSize)) out[i] = dirtyValues[i];
    }
    return out;
}

// ---- visibility -------------------------------------------------------------------
struct VisibilityCase {
    FoldedWedgeOperator op;
    VisibilityTarget target;
    VisibilitySettings settings;
};

VisibilityCase visibilityCase(bool key, const Field& f, int s, BlockingMax rule) {
    VisibilityCase c;
    c.settings.blockingMax = rule;
    if (key) {
        KeyLight light;
        light.azimuthDeg = 135.0f;
        light.elevationDeg = 30.0f;
        light.radiusDeg = 3.0f;
        const KeyLightExtent ext = keyLightExtent(light);
        c.settings.azimuths = GiSettings{}.keyLightAzimuths;
        c.op = foldPartialRange(ext.phiStart, ext.phiEnd, c.settings.azimuths);
        c.target.window = true;
        c.target.sinLow = ext.sinLow;
        c.target.sinHigh = ext.sinHigh;
    } else {
        c.op = foldFullCircle(c.settings.azimuths, c.settings.interp);
    }
    c.target.op = &c.op;
    c.target.footprint = s > 1 ? &f.box : nullptr;
    return c;
}

void visibilityOf(const Field& f, const VisibilityCase& c, VisibilityField& out, const ReceiverTiles* only = nullptr) {
    VisibilityState state;
    computeVisibility(f.pyr, f.gx.cview(), f.gy.cview(), c.settings, c.target, state, out, only);
}

// B restricted to `tiles` over A's full result, against the merge of the full results.
void checkVisibilityTiles(const Field& b, const VisibilityCase& cb, const VisibilityField& fullA,
                          const VisibilityField& fullB, const ReceiverTiles& tiles) {
    VisibilityField v = fullA;
    visibilityOf(b, cb, v, &tiles);
    CHECK(sameBits(v.sh, mergeByTiles(fullB.sh, fullA.sh, tiles)));
    CHECK(sameBits(v.maxSlope, mergeByTiles(fullB.maxSlope, fullA.maxSlope, tiles)));
}

// ---- the Lambert indirect scans ------------------------------------------------------
// A synthetic direct light (the first bounce's radiance), the same for A and B.
std::array<Grid, 3> directLight(int nx, int ny) {
    std::array<Grid, 3> d;
    for (int c = 0; c < 3; ++c)
        d[static_cast<std::size_t>(c)] = gridOf(nx, ny, [&](int x, int y) {
            return static_cast<float>(0.5 + 0.4 * std::sin(0.13 * x + 0.7 * c) * std::cos(0.09 * y));
        });
    return d;
}

// The receiver outputs of bounce 1's scan (LambertIndirect: BlockerRadiance:
// E and, with sub-sampling, the horizons; ShKernel: U), restricted to `only`
// when given, over whatever `st` holds.
std::vector<float> scanOutputs(const Field& f, LambertIndirect kind, IndirectState& st,
                               const ReceiverTiles* only = nullptr) {
    const GiSettings gs;
    const FoldedWedgeOperator op = foldFullCircle(gs.indirect.azimuths, gs.visibility.interp);
    const VisibilityField env;
    const std::array<Grid, 3> direct = directLight(f.pyr.nx, f.pyr.ny);
    const IndirectInputs in{.heights = f.pyr,
                            .gradX = f.gx.cview(),
                            .gradY = f.gy.cview(),
                            .op = op,
                            .envVisibility = env,
                            .direct = direct,
                            .directShade = nullptr,
                            .albedo = nullptr,
                            .shading = gs.shading,
                            .only = only};
    std::vector<float> out;
    if (kind == LambertIndirect::BlockerRadiance) {
        BlockerRadianceIndirect strategy(in, gs.indirect, st);
        strategy.beginFrame();
        strategy.buildPyramid(1, {&direct, nullptr});
        strategy.scan(1);
        for (const std::vector<float>& e : st.blocker.receiverShade) out.insert(out.end(), e.begin(), e.end());
        out.insert(out.end(), st.blocker.farSlope.begin(), st.blocker.farSlope.end());
    } else {
        ShKernelIndirect strategy(in, gs.indirect, st);
        strategy.beginFrame();
        strategy.buildPyramid(1, {&direct, nullptr});
        strategy.scan(1);
        for (const VisibilityField& u : st.u) out.insert(out.end(), u.sh.begin(), u.sh.end());
    }
    return out;
}

const char* kindName(LambertIndirect k) { return k == LambertIndirect::BlockerRadiance ? "blocker" : "sh"; }

}  // namespace

TEST_CASE("gi.tiles: sizes, counts, fractions and merged column spans") {
    ReceiverTiles t;
    t.reset(100, 40, 32, false);
    CHECK(t.tilesX == 4);
    CHECK(t.tilesY == 2);
    CHECK(t.dirtyCount() == 0);
    CHECK(t.dirtyFraction() == 0.0);
    t.setDirty(1, 0);
    t.setDirty(2, 0);
    t.setDirty(3, 1);  // the last, partial tile: 4 x 8 receivers
    CHECK(t.dirtyCount() == 3);
    CHECK(t.dirtyFraction() == doctest::Approx((2.0 * 32 * 32 + 4 * 8) / (100.0 * 40)));
    DirtySpans sp;
    dirtySpans(&t, 100, 40, sp);
    REQUIRE(sp.ofRow(0).size() == 1);
    CHECK(sp.ofRow(31)[0].x0 == 32);
    CHECK(sp.ofRow(31)[0].x1 == 96);  // adjacent tiles merged
    REQUIRE(sp.ofRow(32).size() == 1);
    CHECK(sp.ofRow(39)[0].x0 == 96);
    CHECK(sp.ofRow(39)[0].x1 == 100);  // the row's end
    dirtySpans(nullptr, 100, 40, sp);
    for (int Y : {0, 39}) {
        REQUIRE(sp.ofRow(Y).size() == 1);
        CHECK(sp.ofRow(Y)[0].x0 == 0);
        CHECK(sp.ofRow(Y)[0].x1 == 100);
    }
    CHECK_THROWS_AS(t.reset(100, 40, 24, true), InputError);   // not a multiple of 16
    CHECK_THROWS_AS(dirtySpans(&t, 101, 40, sp), InputError);  // tiles of another grid
}

TEST_CASE("gi.tiles: visibility recomputes the dirty tiles bit-identically and leaves the others") {
    std::mt19937 rng(12345);
    for (const std::array<int, 2> size : {std::array<int, 2>{200, 136}, std::array<int, 2>{97, 61}})
        for (int s : {1, 2, 4}) {
            Field a, b;
            prepareField(terrainVariant(size[0], size[1], 0), s, a);
            prepareField(terrainVariant(size[0], size[1], 1), s, b);
            for (bool key : {false, true}) {
                // Eq. 16's visitor (8-receiver groups) on the smaller terrain's environment
                const BlockingMax rule =
                    !key && size[0] == 97 ? BlockingMax::BsplineKnotsAndMidpoints : BlockingMax::Samples;
                const VisibilityCase ca = visibilityCase(key, a, s, rule), cb = visibilityCase(key, b, s, rule);
                VisibilityField fullA, fullB;
                visibilityOf(a, ca, fullA);
                visibilityOf(b, cb, fullB);
                REQUIRE(!sameBits(fullA.sh, fullB.sh));
                for (int tileSize : {16, 32}) {
                    ReceiverTiles tiles;
                    tiles.reset(a.pyr.nxr, a.pyr.nyr, tileSize, false);
                    for (const auto& [name, dirty] : patterns(tiles.tilesX, tiles.tilesY, rng)) {
                        CAPTURE(size[0]);
                        CAPTURE(s);
                        CAPTURE(key);
                        CAPTURE(tileSize);
                        const std::string& pattern = name;  // CAPTURE takes it: a plain reference, not the binding
                        CAPTURE(pattern);
                        tiles.dirty = dirty;
                        checkVisibilityTiles(b, cb, fullA, fullB, tiles);
                    }
                }
            }
        }
}

TEST_CASE("gi.tiles: visibility with tiles needs a previous result of the same grid") {
    Field a;
    prepareField(terrainVariant(97, 61, 0), 2, a);
    const VisibilityCase c = visibilityCase(false, a, 2, BlockingMax::Samples);
    ReceiverTiles tiles;
    tiles.reset(a.pyr.nxr, a.pyr.nyr, 16, true);
    VisibilityField empty;
    CHECK_THROWS_AS(visibilityOf(a, c, empty, &tiles), InputError);
    VisibilityField full;
    visibilityOf(a, c, full);
    ReceiverTiles other;
    other.reset(a.pyr.nxr + 1, a.pyr.nyr, 16, true);
    CHECK_THROWS_AS(visibilityOf(a, c, full, &other), InputError);
    const VisibilityCase key = visibilityCase(true, a, 2, BlockingMax::Samples);  // other azimuth count
    CHECK_THROWS_AS(visibilityOf(a, key, full, &tiles), InputError);
}

TEST_CASE("gi.tiles: the Lambert scans recompute the dirty tiles' receivers bit-identically") {
    std::mt19937 rng(777);
    for (const std::array<int, 2> size : {std::array<int, 2>{200, 136}, std::array<int, 2>{97, 61}})
        for (int s : {1, 2, 4})
            for (LambertIndirect kind : {LambertIndirect::BlockerRadiance, LambertIndirect::ShKernel}) {
                Field a, b;
                prepareField(terrainVariant(size[0], size[1], 0), s, a);
                prepareField(terrainVariant(size[0], size[1], 1), s, b);
                IndirectState stA, stB;
                const std::vector<float> fullA = scanOutputs(a, kind, stA);
                const std::vector<float> fullB = scanOutputs(b, kind, stB);
                REQUIRE(!sameBits(fullA, fullB));
                for (int tileSize : {16, 32}) {
                    ReceiverTiles tiles;
                    tiles.reset(a.pyr.nxr, a.pyr.nyr, tileSize, false);
                    for (const auto& [name, dirty] : patterns(tiles.tilesX, tiles.tilesY, rng)) {
                        CAPTURE(size[0]);
                        CAPTURE(s);
                        CAPTURE(kindName(kind));
                        CAPTURE(tileSize);
                        const std::string& pattern = name;  // CAPTURE takes it: a plain reference, not the binding
                        CAPTURE(pattern);
                        tiles.dirty = dirty;
                        IndirectState st = stA;  // A's full result, then B over the tiles
                        const std::vector<float> got = scanOutputs(b, kind, st, &tiles);
                        CHECK(sameBits(got, mergeByTiles(fullB, fullA, tiles)));
                    }
                }
            }
}

TEST_CASE("gi.tiles: the Lambert scans with tiles need a previous result of the same grid") {
    Field a;
    prepareField(terrainVariant(97, 61, 0), 2, a);
    ReceiverTiles tiles;
    tiles.reset(a.pyr.nxr, a.pyr.nyr, 16, true);
    for (LambertIndirect kind : {LambertIndirect::BlockerRadiance, LambertIndirect::ShKernel}) {
        CAPTURE(kindName(kind));
        IndirectState st;
        CHECK_THROWS_AS(scanOutputs(a, kind, st, &tiles), InputError);
        scanOutputs(a, kind, st);
        ReceiverTiles other;
        other.reset(a.pyr.nxr, a.pyr.nyr + 1, 16, true);
        CHECK_THROWS_AS(scanOutputs(a, kind, st, &other), InputError);
        CHECK_NOTHROW(scanOutputs(a, kind, st, &tiles));
    }
}

TEST_CASE("gi.tiles: tile-restricted scans are bit-identical for 1, 2, 3 threads and SSE2 / AVX2") {
    const bool wasWide = simd::wideEnabled();
    const bool haveWide = simd::setWideEnabled(true);
    std::mt19937 rng(99);
    Field a, b;
    prepareField(terrainVariant(200, 136, 0), 2, a);
    prepareField(terrainVariant(200, 136, 1), 2, b);
    ReceiverTiles tiles;
    tiles.reset(a.pyr.nxr, a.pyr.nyr, 16, false);
    tiles.dirty = patterns(tiles.tilesX, tiles.tilesY, rng)[5].second;  // random
    REQUIRE(tiles.dirtyCount() > 0);
    const VisibilityCase ca = visibilityCase(false, a, 2, BlockingMax::Samples);
    const VisibilityCase cb = visibilityCase(false, b, 2, BlockingMax::Samples);
    VisibilityField fullA;
    visibilityOf(a, ca, fullA);
    IndirectState blockerA, shA;
    scanOutputs(a, LambertIndirect::BlockerRadiance, blockerA);
    scanOutputs(a, LambertIndirect::ShKernel, shA);
    // every output of one configuration, concatenated
    const auto outputs = [&](bool wide, int threads) {
        simd::setWideEnabled(wide);
        std::vector<float> all;
        withThreads(threads, [&] {
            VisibilityField v = fullA;
            visibilityOf(b, cb, v, &tiles);
            all.insert(all.end(), v.sh.begin(), v.sh.end());
            all.insert(all.end(), v.maxSlope.begin(), v.maxSlope.end());
            IndirectState st = blockerA;
            const std::vector<float> e = scanOutputs(b, LambertIndirect::BlockerRadiance, st, &tiles);
            all.insert(all.end(), e.begin(), e.end());
            st = shA;
            const std::vector<float> u = scanOutputs(b, LambertIndirect::ShKernel, st, &tiles);
            all.insert(all.end(), u.begin(), u.end());
        });
        return all;
    };
    const std::vector<float> ref = outputs(haveWide, 1);
    for (int threads : {2, 3}) {
        CAPTURE(threads);
        CHECK(sameBits(outputs(haveWide, threads), ref));
    }
    if (haveWide)
        CHECK(sameBits(outputs(false, 2), ref));
    else
        MESSAGE("no AVX2 on this processor: only the SSE2 path exists");
    simd::setWideEnabled(wasWide);
}
