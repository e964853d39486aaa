// gi/shading_rows: an incremental frame after a local height change shades
// only the texel rows whose inputs changed, and its output is a full
// recompute's bit for bit, for any thread count.
#include <algorithm>
#include <array>
#include <numeric>
#include <string>
#include <vector>

#include <doctest/doctest.h>

#include "core/error.h"
#include "core/parallel.h"
#include "gi/frame.h"
#include "gi/shading_rows.h"
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

int flagged(const std::vector<std::uint8_t>& rows) { return std::accumulate(rows.begin(), rows.end(), 0); }

}  // namespace

TEST_CASE("gi.shading_rows: the rows of changed heights, their neighbours and the dirty tiles' receivers") {
    const Grid before = bumpy(40, 70);
    ReceiverTiles env, keys;
    const int s = 2, nyr = 35;  // receiver rows 0..34; tiles of 16 receivers: tile rows 0..2
    env.reset(20, nyr, 16, false);
    keys.reset(20, nyr, 16, false);
    std::vector<std::uint8_t> rows;
    changedShadingRows(before.cview(), before.cview(), env, keys, s, rows);
    CHECK(rows.size() == 70u);
    CHECK(flagged(rows) == 0);  // nothing changed: nothing to shade
    Grid after = before;
    after(7, 30) += 0.5f;  // row 30: the gradients of rows 29..31
    after(3, 0) -= 1.0f;   // the border row: rows 0 and 1 (one-sided differences)
    changedShadingRows(before.cview(), after.cview(), env, keys, s, rows);
    for (int y = 0; y < 70; ++y) {
        CAPTURE(y);
        CHECK((rows[static_cast<std::size_t>(y)] != 0) == (y <= 1 || (y >= 29 && y <= 31)));
    }
    // a dirty key-light tile of tile row 1 (receiver rows 16..31): the texel
    // rows that read one of them (texel y reads receiver rows y / 2 and the next)
    keys.setDirty(1, 1);
    changedShadingRows(before.cview(), before.cview(), env, keys, s, rows);
    for (int y = 0; y < 70; ++y) {
        CAPTURE(y);
        const ReceiverLerp r = receiverLerp(y, s, nyr);
        CHECK((rows[static_cast<std::size_t>(y)] != 0) == ((r.i0 >= 16 && r.i0 <= 31) || (r.i1 >= 16 && r.i1 <= 31)));
    }
    CHECK_THROWS_AS(changedShadingRows(bumpy(40, 69).cview(), before.cview(), env, keys, s, rows), InputError);
}

// The direct light of the state's current inputs (cached or new V, the
// gradients, the lights), shaded over every row.
std::array<Grid, 3> reshadeEveryRow(const GiState& st, const GiSettings& settings, const GiLighting& light) {
    GiState fresh = st;
    shadeDirect(light, settings, nullptr, fresh);
    return fresh.shade.rgb;
}

bool sameRgb(const std::array<Grid, 3>& a, const std::array<Grid, 3>& b) {
    bool same = true;
    for (std::size_t c = 0; c < 3; ++c) same = same && gi_test::sameBits(a[c].v, b[c].v);
    return same;
}

TEST_CASE("gi.shading_rows: local height changes shade some rows, the rest is what every row would get") {
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
                int kept = 0;
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
                    // the rows kept are those every row's shading would give
                    CHECK(sameRgb(states[0].shade.rgb, reshadeEveryRow(states[0], settings, light)));
                    if (f > 0) kept += h.ny - flagged(states[0].shadingRows);
                }
                MESSAGE(s << "x, exact key " << exactKey << ", tolerance " << tolerance << ": " << kept
                          << " texel rows kept over 3 local changes");
                if (tolerance > 0.0f && s == 1) CHECK(kept > 0);
            }
}
