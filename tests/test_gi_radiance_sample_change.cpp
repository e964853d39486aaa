// gi/radiance_sample_change: the moves of a radiance pyramid's samples from
// an anchor, per tile, against every sample the scan reads evaluated before
// and after; the levels redone over a box against whole comparisons; the
// anchor's rows copied over a box against a whole copy.
#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include <doctest/doctest.h>

#include "gi/radiance_sample_change.h"
#include "gi/visibility.h"
#include "gi/wedge.h"
#include "tests/gi_test_terrain.h"

using namespace terrain;
using namespace terrain::gi;

namespace {

constexpr float kCell = 3.0f;  // metres

// Radiance channels of a bumpy field: smooth shading with a little noise.
std::array<Grid, 3> radianceOf(int nx, int ny, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 0.05f);
    std::array<Grid, 3> r;
    for (std::size_t c = 0; c < 3; ++c) {
        r[c] = Grid(nx, ny);
        for (int y = 0; y < ny; ++y)
            for (int x = 0; x < nx; ++x)
                r[c](x, y) = 0.5f + 0.3f * std::sin(0.13f * x + 0.7f * c) * std::cos(0.09f * y) + u(rng);
    }
    return r;
}

// The sample step i of azimuth (c, sn) gives receiver (X, Y) in one channel,
// as the scan reads it (gi/visibility.cpp, sampleSlope before the slope).
float sampleOf(const HeightPyramid& p, int i, double c, double sn, int X, int Y) {
    const ScanStep st = scanStepInfo(p, i, c, sn).step;
    const std::ptrdiff_t at = static_cast<std::ptrdiff_t>(Y) * st.rowStep + X;
    return st.w[0][0] * st.field[at + st.offA] + st.w[1][0] * st.field[at + st.offB];
}

}  // namespace

TEST_CASE("gi.radiance_sample_change: every sample the scan reads moves by at most its tile's bound") {
    const int nx = 97, ny = 61;
    const Grid h = gi_test::bumpy(nx, ny);
    for (int s : {1, 2, 4}) {
        CAPTURE(s);
        HeightPyramid heights;
        buildHeightPyramid(h.cview(), kCell, s, PyramidSettings{}, heights);
        const std::array<Grid, 3> base = radianceOf(nx, ny, 3);
        std::mt19937 rng(17 + s);
        std::uniform_real_distribution<float> u(-1.0f, 1.0f);
        const auto patch = [&](int x, int y, int) { return std::hypot(x - 20.0f, y - 40.0f) < 4.0f ? 0.6f : 0.0f; };
        const auto cell = [&](int x, int y, int c) { return x == 70 && y == 9 && c == 1 ? -0.4f : 0.0f; };
        const auto noise = [&](int, int, int) { return 0.01f * u(rng); };
        const auto corner = [&](int x, int y, int) { return x >= nx - 3 && y >= ny - 3 ? 0.5f : 0.0f; };
        for (const auto& [name, change] : std::vector<std::pair<const char*, std::function<float(int, int, int)>>>{
                 {"patch", patch}, {"one cell", cell}, {"noise", noise}, {"corner", corner}}) {
            const std::string caseName = name;
            CAPTURE(caseName);
            const gi_test::ChangedRadiance changed = gi_test::changedRadiance(base, change, false);
            const std::array<Grid, 3>& after = changed.after;
            const Grid& dL = changed.dL;
            RadiancePyramid before, now;
            buildRadiancePyramid(base, heights, RadiancePyramidSettings{}, before);
            buildRadiancePyramid(after, heights, RadiancePyramidSettings{}, now);
            // the engine's split, and every level bounded through its octave images
            for (int from : {kOctaveBoundFrom, 1}) {
                CAPTURE(from);
                RadianceLevelChange levels;
                levels.octaveBoundFrom = from;
                recordAnchorLevels(before, levels);
                buildLevelChanges(now, CellBox{}, levels);
                if (from == 1) REQUIRE(levels.firstOctave == 1);  // all but octave 0
                MaxChangePyramid raw;
                buildMaxChangePyramid(dL.cview(), raw);
                const FoldedWedgeOperator op = foldFullCircle(8, AzimuthInterp::Linear);
                constexpr int T = 16;
                std::vector<float> tileBound, groupBound;
                boundSampleChangeFromLevels(raw, levels, now.fields[0], T, op.phi, tileBound, groupBound);
                const int tilesX = tileCount(heights.nxr, T), m = op.azimuths;
                // every receiver's every sample, every channel: the true move
                double worst = 0.0, excess = 0.0;
                std::vector<float> trueTile(tileBound.size(), 0.0f);
                for (int j = 0; j < m; ++j) {
                    const double c = std::cos(op.phi[static_cast<std::size_t>(j)]);
                    const double sn = std::sin(op.phi[static_cast<std::size_t>(j)]);
                    for (int i = 0; i < static_cast<int>(heights.steps.size()); ++i) {
                        const ScanStepInfo si = scanStepInfo(now.fields[0], i, c, sn);
                        for (int Y = si.yFirst; Y <= si.yLast; ++Y)
                            for (int X = si.xFirst; X <= si.xLast; ++X) {
                                const std::size_t t = static_cast<std::size_t>(Y / T) * tilesX + X / T;
                                const float bound = tileBound[t * m + static_cast<std::size_t>(j)];
                                const float group =
                                    groupBound[t * kDistanceGroups +
                                               static_cast<std::size_t>(
                                                   distanceGroup(heights.steps[static_cast<std::size_t>(i)].tauCells))];
                                for (std::size_t ch = 0; ch < 3; ++ch) {
                                    const double d =
                                        std::fabs(static_cast<double>(sampleOf(now.fields[ch], i, c, sn, X, Y)) -
                                                  sampleOf(before.fields[ch], i, c, sn, X, Y));
                                    excess = std::max(excess, d - std::min(bound, group) * (1.0 + 1e-6));
                                    if (bound > 0.0f) worst = std::max(worst, d / bound);
                                    float& tt = trueTile[t * m + static_cast<std::size_t>(j)];
                                    tt = std::max(tt, static_cast<float>(d));
                                }
                            }
                    }
                }
                CHECK(excess <= 0.0);
                // the bound is the largest texel move the tile's samples read:
                // never far above the largest true sample move (the two taps'
                // blend can only lower it)
                double loosest = 1.0;
                for (std::size_t k = 0; k < tileBound.size(); ++k)
                    if (trueTile[k] > 0.0f)
                        loosest = std::max(loosest, static_cast<double>(tileBound[k] / trueTile[k]));
                MESSAGE(s << "x, " << caseName << ", octaves from " << from << ": largest sample move / bound " << worst
                          << ", loosest tile " << loosest);
                // a local change: some tiles read nothing that moved, and say so
                if (caseName == "one cell" || caseName == "corner")
                    CHECK(*std::min_element(tileBound.begin(), tileBound.end()) == 0.0f);
            }
        }
    }
}

TEST_CASE("gi.radiance_sample_change: levels compared over a box of changed texels equal whole comparisons") {
    const int nx = 130, ny = 83;
    const Grid h = gi_test::bumpy(nx, ny);
    for (int s : {1, 2}) {
        CAPTURE(s);
        HeightPyramid heights;
        buildHeightPyramid(h.cview(), kCell, s, PyramidSettings{}, heights);
        const std::array<Grid, 3> base = radianceOf(nx, ny, 5);
        RadiancePyramid anchor;
        buildRadiancePyramid(base, heights, RadiancePyramidSettings{}, anchor);
        RadianceLevelChange boxed, whole;
        // half the levels texel by texel, the others through their octave images
        boxed.octaveBoundFrom = whole.octaveBoundFrom = 2;
        recordAnchorLevels(anchor, boxed);
        recordAnchorLevels(anchor, whole);
        REQUIRE(boxed.exactLevels > 0);
        REQUIRE(boxed.exactLevels < boxed.levels);
        // changes that come and go: each frame's radiance differs from the
        // anchor's only inside the box it names (joined over the frames, as
        // the cache keeps anchorChanged)
        const std::vector<CellBox> boxes = {{60, 30, 64, 33}, {0, 0, 3, 2}, {nx - 5, ny - 4, nx, ny}, {20, 70, 90, 83}};
        CellBox since = CellBox::none();
        for (const CellBox& b : boxes) {
            CAPTURE(b.x0);
            std::array<Grid, 3> frame = base;
            for (std::size_t c = 0; c < 3; ++c)
                for (int y = b.y0; y < b.y1; ++y)
                    for (int x = b.x0; x < b.x1; ++x) frame[c](x, y) += 0.25f + 0.1f * static_cast<float>(c);
            RadiancePyramid now;
            buildRadiancePyramid(frame, heights, RadiancePyramidSettings{}, now);
            since = b;  // this frame differs from the anchor inside b alone
            buildLevelChanges(now, since, boxed);
            buildLevelChanges(now, CellBox{}, whole);
            REQUIRE(boxed.change.size() == whole.change.size());
            for (std::size_t l = 0; l < boxed.change.size(); ++l) {
                CAPTURE(l);
                CHECK(boxed.change[l].levels[0].v == whole.change[l].levels[0].v);
                CHECK(maxChangeAll(boxed.change[l]) == maxChangeAll(whole.change[l]));
            }
            REQUIRE(boxed.octaveChange.size() == whole.octaveChange.size());
            REQUIRE(!boxed.octaveChange.empty());
            for (std::size_t o = 0; o < boxed.octaveChange.size(); ++o) {
                CAPTURE(o);
                CHECK(boxed.octaveChange[o].levels[0].v == whole.octaveChange[o].levels[0].v);
                CHECK(maxChangeAll(boxed.octaveChange[o]) > 0.0f);
            }
        }
        // moving the anchor over a box: the rows that may differ are copied
        std::array<Grid, 3> moved = base;
        for (std::size_t c = 0; c < 3; ++c) moved[c](100, 50) += 0.5f;
        RadiancePyramid movedPyramid;
        buildRadiancePyramid(moved, heights, RadiancePyramidSettings{}, movedPyramid);
        RadianceLevelChange partial = boxed, fresh;
        fresh.octaveBoundFrom = boxed.octaveBoundFrom;
        recordAnchorLevels(movedPyramid, partial, CellBox{100, 50, 101, 51});
        recordAnchorLevels(movedPyramid, fresh);
        for (std::size_t k = 0; k < fresh.anchor.size(); ++k) CHECK(partial.anchor[k].v == fresh.anchor[k].v);
        for (std::size_t k = 0; k < fresh.anchorOctaves.size(); ++k)
            CHECK(partial.anchorOctaves[k].v == fresh.anchorOctaves[k].v);
        // a box that misses the change leaves the old rows: the box is what is copied
        RadianceLevelChange missed = boxed;
        recordAnchorLevels(movedPyramid, missed, CellBox{0, 0, 2, 2});
        bool differs = false;
        for (std::size_t k = 0; k < fresh.anchor.size(); ++k) differs |= missed.anchor[k].v != fresh.anchor[k].v;
        CHECK(differs);
    }
}
