// gi/shading_tiles: an incremental frame after a local height change shades
// only the texels whose inputs changed, and its output is a full
// recompute's bit for bit, for any thread count.
#include <algorithm>
#include <array>
#include <sstream>
#include <string>
#include <vector>

#include <doctest/doctest.h>

#include "core/error.h"
#include "core/parallel.h"
#include "gi/ambient_horizon.h"
#include "gi/frame.h"
#include "gi/shading_tiles.h"
#include "tests/gi_test_terrain.h"

using namespace terrain;
using namespace terrain::gi;
using gi_test::bumpy;
using gi_test::incrementalMatchesFull;
using gi_test::sameOutputs;
using gi_test::sunSkyAndKey;
using gi_test::withBounces;

namespace {

constexpr float kCell = 10.0f;  // metres: the local changes stay within the tolerance of far tiles

// The runs as rows [y0, y1) that share their runs: "y0-y1:x0-x1,x0-x1 ...".
std::string summary(const TexelRuns& r) {
    std::ostringstream out;
    const char* gap = "";
    for (int y = 0; y < r.ny;) {
        int y1 = y + 1;
        const auto same = [&](int a, int b) {
            const auto ra = r.ofRow(a), rb = r.ofRow(b);
            return std::equal(ra.begin(), ra.end(), rb.begin(), rb.end(),
                              [](const ColumnSpan& p, const ColumnSpan& q) { return p.x0 == q.x0 && p.x1 == q.x1; });
        };
        while (y1 < r.ny && same(y, y1)) ++y1;
        if (r.hasRow(y)) {
            out << gap << y << "-" << y1 << ":";
            const char* comma = "";
            for (const ColumnSpan& c : r.ofRow(y)) {
                out << comma << c.x0 << "-" << c.x1;
                comma = ",";
            }
            gap = " ";
        }
        y = y1;
    }
    return out.str();
}

}  // namespace

TEST_CASE(
    "gi.shading_tiles: the texels within reach of changed heights, those reading the dirty tiles' receivers and the "
    "key lights' changed receivers") {
    // 40 x 70 texels at 2x: 20 x 35 receivers, tiles of 16: 2 x 3 tiles,
    // texel columns 0..31 and 32..39, rows 0..31, 32..63 and 64..69; reach 4
    const Grid before = bumpy(40, 70);
    ReceiverTiles env;
    std::vector<ReceiverRun> keys;
    TexelRuns ambient, shading;
    std::vector<TexelRect> rects;
    const int s = 2;
    env.reset(20, 35, 16, false);
    CHECK(shadingReach(s) == 4);
    const auto redo = [&](const Grid& after) {
        changedDirectTexels(before.cview(), after.cview(), env, keys, s, rects, ambient, shading);
    };
    redo(before);
    CHECK(summary(shading).empty());  // nothing changed: nothing to shade
    CHECK(texelCount(shading) == 0);
    Grid after = before;
    after(7, 29) += 0.5f;  // within 4 rows of tile row 1 (from row 32), 25 columns from column 32
    redo(after);
    CHECK(summary(shading) == "0-64:0-32");
    CHECK(summary(ambient) == summary(shading));
    after = before;
    after(39, 69) = -0.0f == before(39, 69) ? 1.0f : -0.0f;  // a bit changed in the last texel
    redo(after);
    CHECK(summary(shading) == "64-70:32-40");
    // one key-light receiver changed, (5, 20): the texels whose lower
    // receiver is it or the one before, 8..11 x 38..41
    keys = {{20, 5, 6}};
    redo(before);
    CHECK(summary(shading) == "38-42:8-12");
    CHECK(summary(ambient).empty());  // the ambient reads no key light
    // key-light receivers 16..19 x 16..31 (tile (1, 1)): the texels that read
    // them, from the last texels of the receivers before (15)
    keys.clear();
    for (int y = 16; y < 32; ++y) keys.push_back({y, 16, 20});
    redo(before);
    CHECK(summary(shading) == "30-64:30-40");
    CHECK(summary(ambient).empty());
    CHECK(texelCount(shading) == 34 * 10);
    // with a changed height as well: the ambient redoes the height's tiles,
    // the shading those and the key tile's readers
    after = before;
    after(7, 29) += 0.5f;
    redo(after);
    CHECK(summary(ambient) == "0-64:0-32");
    CHECK(summary(shading) == "0-30:0-32 30-64:0-40");
    env.setDirty(0, 2);  // an environment tile (receivers 0..15 x 32..34, the last texel rows): both read it
    redo(after);
    CHECK(summary(ambient) == "0-70:0-32");
    CHECK(summary(shading) == "0-30:0-32 30-64:0-40 64-70:0-32");
    env.setDirty(0, 2, false);
    CHECK_THROWS_AS(changedDirectTexels(bumpy(40, 69).cview(), before.cview(), env, keys, s, rects, ambient, shading),
                    InputError);
    const std::vector<ReceiverRun> outside{{35, 0, 1}};  // a receiver row past the grid
    CHECK_THROWS_AS(changedDirectTexels(before.cview(), before.cview(), env, outside, s, rects, ambient, shading),
                    InputError);
}

TEST_CASE("gi.shading_tiles: the runs of rectangles are merged per row and cut to the field") {
    TexelRuns r;
    const std::vector<TexelRect> rects{{5, 0, 10, 2}, {8, 1, 12, 3}, {12, 1, 14, 2}, {-3, 2, 2, 4}, {20, 0, 30, 1}};
    texelRunsOfRects(rects, 25, 5, r);
    CHECK(summary(r) == "0-1:5-10,20-25 1-2:5-14 2-3:0-2,8-12 3-4:0-2");
    CHECK(texelCount(r) == 5 + 5 + 9 + 2 + 4 + 2);
    // their bounding box: the first to the last row with a run, the leftmost
    // to the rightmost run's columns (what the radiance pyramid redoes)
    const CellBox box = boundingBox(r);
    CHECK(box.x0 == 0);
    CHECK(box.y0 == 0);
    CHECK(box.x1 == 25);
    CHECK(box.y1 == 4);
    texelRunsOfRects(std::vector<TexelRect>{{7, 3, 9, 4}, {2, 1, 4, 2}}, 25, 5, r);
    const CellBox two = boundingBox(r);
    CHECK(two.x0 == 2);
    CHECK(two.y0 == 1);
    CHECK(two.x1 == 9);
    CHECK(two.y1 == 4);
    texelRunsOfRects({}, 25, 5, r);
    CHECK(boundingBox(r).empty());
}

TEST_CASE(
    "gi.shading_tiles: a copy of the runs finds the box of the texels that changed in them, whatever lies between") {
    // two runs far apart: the changes inside them, not their bounding box
    TexelRuns r;
    texelRunsOfRects(std::vector<TexelRect>{{1, 1, 4, 3}, {20, 6, 23, 8}}, 25, 10, r);
    Grid g(25, 10);
    for (std::size_t i = 0; i < g.v.size(); ++i) g.v[i] = static_cast<float>(i);
    std::vector<float> before;
    copyRuns(g.cview(), r, before);
    CHECK(before.size() == static_cast<std::size_t>(texelCount(r)));
    CHECK(before.front() == g(1, 1));
    CHECK(before.back() == g(22, 7));
    // unchanged, and changed outside the runs only: nothing found
    CHECK(differingInRuns(before, g.cview(), r).empty());
    g(10, 5) = -1.0f;
    CHECK(differingInRuns(before, g.cview(), r).empty());
    // one texel in each run: the box from one to the other
    g(2, 2) = 0.5f;
    const CellBox one = differingInRuns(before, g.cview(), r);
    CHECK((one.x0 == 2 && one.y0 == 2 && one.x1 == 3 && one.y1 == 3));
    g(21, 6) = 0.25f;
    const CellBox both = differingInRuns(before, g.cview(), r);
    CHECK((both.x0 == 2 && both.y0 == 2 && both.x1 == 22 && both.y1 == 7));
    // a copy of other runs is refused
    texelRunsOfRects(std::vector<TexelRect>{{1, 1, 4, 3}}, 25, 10, r);
    CHECK_THROWS_AS(differingInRuns(before, g.cview(), r), InputError);
}

namespace {

// The direct light of the state's current inputs (cached or new V, the
// gradients, the lights), shaded over every texel.
std::array<Grid, 3> reshadeEveryTexel(const GiState& st, const GiSettings& settings, const GiLighting& light) {
    GiState fresh = st;
    shadeDirect(light, settings, nullptr, fresh);
    return fresh.shade.rgb;
}

// The exact ambient of the state's current horizons and gradients over every
// texel (the sky's parts too when the state keeps them).
bool ambientAsEveryTexelWould(const GiState& st, const GiSettings& settings, ConstGridView heights) {
    const bool footprint = settings.subsample > 1 && settings.visibility.footprintTangent;
    const AmbientInputs in{st.gradX.cview(),   st.gradY.cview(),  heights,      kCell,
                           settings.subsample, &st.envVisibility, st.envCosSin, footprint ? &st.footprint : nullptr};
    Grid ambient, below, rising;
    AmbientScratch scratch;
    ambientFromHorizons(in, {ambient, st.shade.skyParts ? &below : nullptr, st.shade.skyParts ? &rising : nullptr},
                        scratch, nullptr);
    bool same = gi_test::sameBits(ambient.v, st.shade.ambient.v);
    if (st.shade.skyParts)
        same = same && gi_test::sameBits(below.v, st.shade.skyBelow.v) &&
               gi_test::sameBits(rising.v, st.shade.skyRising.v);
    return same;
}

int changedReceivers(const std::vector<ReceiverRun>& runs) {
    int n = 0;
    for (const ReceiverRun& r : runs) n += r.x1 - r.x0;
    return n;
}

bool sameRgb(const std::array<Grid, 3>& a, const std::array<Grid, 3>& b) {
    bool same = true;
    for (std::size_t c = 0; c < 3; ++c) same = same && gi_test::sameBits(a[c].v, b[c].v);
    return same;
}

}  // namespace

TEST_CASE("gi.shading_tiles: local height changes shade some tiles, the rest is what every texel would get") {
    const Grid h = bumpy(256, 256);
    // a crater inside, a bump on the first rows, a cliff collapsing along the last row
    std::vector<Grid> surfaces(4, h);
    for (int y = 120; y < 136; ++y)
        for (int x = 120; x < 136; ++x) surfaces[1](x, y) -= 6.0f;
    for (int y = 0; y < 3; ++y)
        for (int x = 20; x < 30; ++x) surfaces[2](x, y) += 2.0f;
    for (int x = 200; x < 256; ++x) surfaces[3](x, 255) -= 8.0f;
    const GiLighting light = sunSkyAndKey();
    const int threads[] = {1, 2, 3, 8};
    for (int s : {1, 2})
        for (bool exactKey : {true, false})
            for (float tolerance : {0.0f, 0.02f}) {
                CAPTURE(s);
                CAPTURE(exactKey);
                CAPTURE(tolerance);
                GiSettings settings = withBounces(GiSettings{}, s, 1);
                settings.keyLightExactCosine = exactKey;
                settings.tolerance = tolerance;
                std::vector<GiState> states(4);
                long long kept = 0;
                int keySame = 0;
                for (std::size_t f = 0; f < surfaces.size(); ++f) {
                    CAPTURE(f);
                    for (std::size_t i = 0; i < states.size(); ++i)
                        withThreads(threads[i], [&] {
                            if (tolerance == 0.0f)  // exact: bit for bit the full frames
                                CHECK(incrementalMatchesFull(surfaces[f], kCell, light, settings, states[i]));
                            else
                                runGiFrame(surfaces[f].cview(), kCell, light, settings, states[i]);
                        });
                    for (std::size_t i = 1; i < states.size(); ++i) CHECK(sameOutputs(states[i], states[0]));
                    // the texels kept are those every texel's shading would give
                    CHECK(sameRgb(states[0].shade.rgb, reshadeEveryTexel(states[0], settings, light)));
                    CHECK(ambientAsEveryTexelWould(states[0], settings, surfaces[f].cview()));
                    const TexelRuns& t = states[0].shadingRuns;
                    const long long texels = static_cast<long long>(surfaces[f].nx) * surfaces[f].ny;
                    if (f > 0) kept += texels - texelCount(t);
                    // the key receivers whose visibility the scan left as it was are not shaded
                    const ReceiverTiles& keyPlan = states[0].visibilityCache.keyTiles;
                    const int keyTiles = keyPlan.dirtyCount();  // whole tiles: 256 or 128 receivers a side
                    if (f > 0)
                        keySame += keyTiles * keyPlan.tileSize * keyPlan.tileSize -
                                   changedReceivers(states[0].keyReceiversChanged);
                    // the ambient redoes no texel the shading keeps
                    if (f > 0 && keyTiles > 0) {
                        const TexelRuns& a = states[0].ambientRuns;
                        for (int y = 0; y < a.ny; ++y)
                            for (const ColumnSpan& run : a.ofRow(y)) {
                                const auto in = t.ofRow(y);
                                CHECK(std::any_of(in.begin(), in.end(), [&](const ColumnSpan& c) {
                                    return c.x0 <= run.x0 && run.x1 <= c.x1;
                                }));
                            }
                    }
                }
                MESSAGE(s << "x, exact key " << exactKey << ", tolerance " << tolerance << ": " << kept
                          << " texels kept over 3 local changes");
                if (tolerance > 0.0f) CHECK(kept > 0);
                CHECK(keySame > 0);
            }
}
