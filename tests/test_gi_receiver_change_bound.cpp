// Blocking-slope bounds per receiver. gi/receiver_change_bound (one bound
// for every azimuth, from max filters of the change pyramid) against
// boundSlopeChange with tiles of one receiver (which test_gi_change_bound
// checks against the engine's slopes): never below it, equal to it where
// every cell changed alike. gi/receiver_azimuth_bound (per azimuth, from the
// samples' own change) against the engine's slopes before and after each
// change, and its radiance walks against the samples of a radiance field's
// pyramids before and after.
#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <random>
#include <utility>
#include <vector>

#include <doctest/doctest.h>

#include "core/error.h"
#include "gi/change_bound.h"
#include "gi/frame.h"
#include "gi/pyramid.h"
#include "gi/radiance_pyramid.h"
#include "gi/receiver_azimuth_bound.h"
#include "gi/receiver_change_bound.h"
#include "gi/visibility.h"
#include "tests/gi_test_terrain.h"

using namespace terrain;
using namespace terrain::gi;

namespace {

constexpr float kCell = 2.0f;  // metres

// Hills with a little noise, and changes of several kinds: a bump, noise
// everywhere, spikes (one inside, some on the last row and column), a
// channel deepened along a wavy line.
Grid terrainOf(int nx, int ny) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> noise(-0.2f, 0.2f);
    Grid g(nx, ny);
    for (int y = 0; y < ny; ++y)
        for (int x = 0; x < nx; ++x)
            g(x, y) =
                12.0f * std::sin(0.12f * static_cast<float>(x)) * std::cos(0.09f * static_cast<float>(y)) + noise(rng);
    return g;
}

Grid changed(const Grid& base, int kind) {
    Grid g = base;
    std::mt19937 rng(17u + static_cast<unsigned>(kind));
    const int nx = g.nx, ny = g.ny;
    if (kind == 0) {
        for (int y = 0; y < ny; ++y)
            for (int x = 0; x < nx; ++x) {
                const float dx = static_cast<float>(x) - 0.4f * nx, dy = static_cast<float>(y) - 0.6f * ny;
                g(x, y) += 2.5f * std::exp(-(dx * dx + dy * dy) / 18.0f);
            }
    } else if (kind == 1) {
        std::uniform_real_distribution<float> u(-0.03f, 0.03f);
        for (float& v : g.v) v += u(rng);
    } else if (kind == 2) {
        g(nx / 3, ny / 5) += 7.0f;
        g(nx - 1, ny - 1) -= 4.0f;
        g(nx / 2, ny - 1) += 3.0f;
    } else {
        for (int y = 0; y < ny; ++y) {
            const int x = static_cast<int>(0.55f * nx + 5.0f * std::sin(0.3f * static_cast<float>(y)));
            for (int dx = -1; dx <= 1; ++dx)
                g(std::clamp(x + dx, 0, nx - 1), y) -= 0.01f * static_cast<float>(1 + y % 4);
        }
    }
    return g;
}

}  // namespace

TEST_CASE("gi.receiver_change_bound: per receiver never below the one-receiver tiles' bound") {
    struct Case {
        int nx, ny, subsample;
    };
    for (const Case c : {Case{97, 70, 1}, Case{120, 83, 2}, Case{150, 118, 4}, Case{300, 260, 2}}) {
        const Grid base = terrainOf(c.nx, c.ny);
        for (int kind = 0; kind < 4; ++kind) {
            CAPTURE(c.nx);
            CAPTURE(c.subsample);
            CAPTURE(kind);
            const Grid after = changed(base, kind);
            HeightPyramid pyr;
            buildHeightPyramid(after.cview(), kCell, c.subsample, PyramidSettings{}, pyr);
            MaxChangePyramid dh;
            buildMaxChangePyramid(base.cview(), after.cview(), dh);
            std::vector<float> perReceiver, tiles;
            boundSlopeChangePerReceiver(dh, pyr, perReceiver);
            boundSlopeChange(dh, pyr, 1, tiles);
            REQUIRE(perReceiver.size() == tiles.size());
            REQUIRE(perReceiver.size() == static_cast<std::size_t>(pyr.nxr) * static_cast<std::size_t>(pyr.nyr));
            int below = 0;
            std::vector<double> ratio;
            for (std::size_t r = 0; r < tiles.size(); ++r) {
                below += perReceiver[r] < tiles[r] ? 1 : 0;
                if (tiles[r] > 0.0f) ratio.push_back(perReceiver[r] / tiles[r]);
            }
            CHECK(below == 0);
            std::sort(ratio.begin(), ratio.end());
            if (!ratio.empty())
                MESSAGE(c.nx << " x " << c.ny << " s=" << c.subsample << " change " << kind
                             << ": per receiver / one-receiver tiles, median " << ratio[ratio.size() / 2]
                             << ", largest " << ratio.back());
        }
    }
}

TEST_CASE(
    "gi.receiver_change_bound: equal to the one-receiver tiles' bound where every cell changed alike; zero "
    "without a change") {
    for (int s : {1, 2, 3}) {
        CAPTURE(s);
        // heights on a grid of 1/16 m, so that raising each by 0.25 m changes each by exactly that
        Grid base = terrainOf(83, 61);
        for (float& v : base.v) v = std::round(16.0f * v) / 16.0f;
        Grid raised = base;
        for (float& v : raised.v) v += 0.25f;
        HeightPyramid pyr;
        buildHeightPyramid(raised.cview(), kCell, s, PyramidSettings{}, pyr);
        MaxChangePyramid dh;
        buildMaxChangePyramid(base.cview(), raised.cview(), dh);
        std::vector<float> perReceiver, tiles;
        boundSlopeChangePerReceiver(dh, pyr, perReceiver);
        boundSlopeChange(dh, pyr, 1, tiles);
        CHECK(perReceiver == tiles);
        CHECK(perReceiver.front() > 0.0f);
        buildMaxChangePyramid(base.cview(), base.cview(), dh);
        boundSlopeChangePerReceiver(dh, pyr, perReceiver);
        CHECK(std::all_of(perReceiver.begin(), perReceiver.end(), [](float v) { return v == 0.0f; }));
    }
    HeightPyramid pyr;
    buildHeightPyramid(terrainOf(40, 30).cview(), kCell, 1, PyramidSettings{}, pyr);
    MaxChangePyramid other;
    buildMaxChangePyramid(terrainOf(30, 30).cview(), other);
    std::vector<float> out;
    CHECK_THROWS_AS(boundSlopeChangePerReceiver(other, pyr, out), InputError);
}

namespace {

// The receivers' maximum blocking slopes of a frame on `h` (every azimuth of
// the environment's scan, out[(j nyr + Y) nxr + X]), with its state.
const std::vector<float>& slopesOf(const Grid& h, const GiSettings& settings, GiState& st) {
    runGiFrame(h.cview(), kCell, GiLighting{}, settings, st);
    return st.envVisibility.maxSlope;
}

float largestAbs(const Grid& g) {
    float m = 0.0f;
    for (float v : g.v) m = std::max(m, std::fabs(v));
    return m;
}

}  // namespace

TEST_CASE("gi.receiver_azimuth_bound: bounds every receiver's slope change along every azimuth of the engine's scan") {
    struct Case {
        int nx, ny, subsample;
        bool paper;  // paperGiSettings (Eq. 16's maximum, mean pyramid) instead of GiSettings{}
    };
    for (const Case c : {Case{97, 70, 1, false}, Case{120, 83, 2, false}, Case{150, 118, 4, false},
                         Case{80, 96, 1, true}, Case{300, 260, 2, false}}) {
        const GiSettings settings = gi_test::fullDirectFrames(c.paper, c.subsample);
        const float lipschitz = blockingMaxLipschitz(settings.visibility.blockingMax);
        const Grid base = terrainOf(c.nx, c.ny);
        GiState before, after;
        const std::vector<float> s0 = slopesOf(base, settings, before);
        ChangeLevels levels;  // reused across the changes: each build redoes the last one's box and its own
        for (int kind = 0; kind < 4; ++kind) {
            CAPTURE(c.nx);
            CAPTURE(c.subsample);
            CAPTURE(kind);
            const Grid h = changed(base, kind);
            const std::vector<float>& s1 = slopesOf(h, settings, after);
            const HeightPyramid& pyr = after.pyramid;
            MaxChangePyramid dh;
            buildMaxChangePyramid(base.cview(), h.cview(), dh);
            buildChangeLevels(dh, pyr, levels);
            const std::vector<double>& phi = after.envOperator.phi;
            std::vector<float> bound, tiles;
            boundSlopeChangePerReceiverAzimuth(levels, pyr, phi, nullptr, 0.0f, bound);
            const std::size_t planeR = static_cast<std::size_t>(pyr.nxr) * pyr.nyr, m = phi.size();
            REQUIRE(s1.size() == m * planeR);
            REQUIRE(bound.size() == m * planeR);
            boundSlopeChangePerAzimuth(dh, pyr, 1, static_cast<int>(m), tiles);
            // float rounding: a sample is some dozen operations deep, each off
            // by half an ulp of a height, over a step of at least one cell
            const double heightUlps = 64.0 * FLT_EPSILON * std::max(largestAbs(base), largestAbs(h)) / kCell;
            int over = 0;
            std::vector<double> toTiles;
            for (std::size_t j = 0; j < m; ++j)
                for (std::size_t r = 0; r < planeR; ++r) {
                    const std::size_t i = j * planeR + r;
                    const double change = std::fabs(static_cast<double>(s1[i]) - s0[i]);
                    const double allowance =
                        heightUlps + 4.0 * FLT_EPSILON * std::max(std::fabs(s0[i]), std::fabs(s1[i]));
                    over += change > lipschitz * bound[i] + allowance ? 1 : 0;
                    const float tile = tiles[r * m + j];
                    if (tile > 0.0f) toTiles.push_back(bound[i] / tile);
                }
            CHECK(over == 0);
            // the fused per-receiver V bound is the per-azimuth slopes' with the receiver's own gradients
            std::vector<float> env, perAzimuth(m);
            boundEnvironmentPerReceiver(levels, dh, pyr, phi, lipschitz, nullptr, 0.0f, env);
            REQUIRE(env.size() == planeR);
            int differing = 0;
            for (std::size_t r = 0; r < planeR; ++r) {
                for (std::size_t j = 0; j < m; ++j) perAzimuth[j] = lipschitz * bound[j * planeR + r];
                const int X = static_cast<int>(r % static_cast<std::size_t>(pyr.nxr));
                const int Y = static_cast<int>(r / static_cast<std::size_t>(pyr.nxr));
                differing += env[r] != ambientChangeBoundPerAzimuth(perAzimuth.data(), static_cast<int>(m),
                                                                    gradientBoundOfTile(dh, pyr, 1, X, Y), 1.0f, false);
            }
            CHECK(differing == 0);
            // the row-wise gradient bounds are the one-receiver tiles' (a whole row and a span inside it)
            std::vector<float> gradients(static_cast<std::size_t>(pyr.nxr)), scratch;
            int gradientsDiffering = 0;
            for (int Y = 0; Y < pyr.nyr; ++Y)
                for (const auto& [X0, X1] : {std::pair{0, pyr.nxr}, std::pair{3, pyr.nxr - 2}}) {
                    std::fill(gradients.begin(), gradients.end(), -1.0f);
                    receiverGradientBounds(dh, pyr, Y, X0, X1, gradients.data(), scratch);
                    for (int X = 0; X < pyr.nxr; ++X)
                        gradientsDiffering += gradients[static_cast<std::size_t>(X)] !=
                                              (X >= X0 && X < X1 ? gradientBoundOfTile(dh, pyr, 1, X, Y) : -1.0f);
                }
            CHECK(gradientsDiffering == 0);
            std::sort(toTiles.begin(), toTiles.end());
            if (!toTiles.empty())
                MESSAGE(c.nx << " x " << c.ny << " s=" << c.subsample << " change " << kind
                             << ": per receiver and azimuth / one-receiver tiles' bound, median "
                             << toTiles[toTiles.size() / 2] << ", p90 " << toTiles[toTiles.size() * 9 / 10]
                             << ", largest " << toTiles.back());
        }
    }
}

TEST_CASE(
    "gi.receiver_azimuth_bound: zero without a change; a redone or skipped build is a whole one's; a floor only raises "
    "it, to at most the floor; restricted to tiles, the same values there") {
    const Grid base = terrainOf(120, 90);
    HeightPyramid pyr;
    buildHeightPyramid(base.cview(), kCell, 2, PyramidSettings{}, pyr);
    const FoldedWedgeOperator op = foldFullCircle(16, AzimuthInterp::Linear);
    MaxChangePyramid dh;
    ChangeLevels levels, whole;
    std::vector<float> bound, wholeBound;
    buildMaxChangePyramid(base.cview(), base.cview(), dh);
    buildChangeLevels(dh, pyr, levels);
    boundSlopeChangePerReceiverAzimuth(levels, pyr, op.phi, nullptr, 0.0f, bound);
    CHECK(std::all_of(bound.begin(), bound.end(), [](float v) { return v == 0.0f; }));
    // a bump, no change, the bump again, a spike elsewhere, no change, the
    // spike again, the spikes and a pit beside them (a change added to one
    // that stays): a build redoes the cells where its |dh| differs from the
    // last one's, none without a change or with the last one's again (-1:
    // no change; 4: kind 2 and the pit), and the bounds are always a whole
    // build's
    const auto heightsOf = [&](int kind) {
        if (kind < 0) return base;
        Grid h = changed(base, kind == 4 ? 2 : kind);
        if (kind == 4)
            for (int y = 60; y < 70; ++y)
                for (int x = 90; x < 100; ++x) h(x, y) -= 5.0f;
        return h;
    };
    for (int kind : {0, -1, 0, 2, -1, 2, 4, 2}) {
        CAPTURE(kind);
        const Grid h = heightsOf(kind);
        buildMaxChangePyramid(base.cview(), h.cview(), dh);
        buildChangeLevels(dh, pyr, levels);
        whole = {};
        buildChangeLevels(dh, pyr, whole);
        if (kind >= 0) {
            REQUIRE(levels.bound.levels.size() == whole.bound.levels.size());
            for (std::size_t l = 0; l < whole.bound.levels.size(); ++l)
                CHECK(levels.bound.levels[l].v == whole.bound.levels[l].v);
            CHECK(levels.bound.rawPhase == whole.bound.rawPhase);
        }
        boundSlopeChangePerReceiverAzimuth(levels, pyr, op.phi, nullptr, 0.0f, bound);
        boundSlopeChangePerReceiverAzimuth(whole, pyr, op.phi, nullptr, 0.0f, wholeBound);
        CHECK(bound == wholeBound);
        CHECK((*std::max_element(bound.begin(), bound.end()) > 0.0f) == (kind >= 0));
    }
    // a floor: the walks stop early and charge their tails, never below the whole walk nor above the floor more
    for (float floor : {1e-3f, 1e-2f, 1e-1f}) {
        CAPTURE(floor);
        std::vector<float> floored;
        boundSlopeChangePerReceiverAzimuth(levels, pyr, op.phi, nullptr, floor, floored);
        REQUIRE(floored.size() == bound.size());
        int outside = 0, raised = 0;
        for (std::size_t i = 0; i < bound.size(); ++i) {
            outside += floored[i] < bound[i] || floored[i] > std::max(bound[i], floor) ? 1 : 0;
            raised += floored[i] > bound[i] ? 1 : 0;
        }
        CHECK(outside == 0);
        if (floor >= 0.1f) CHECK(raised > 0);  // a 7 m spike moves every slope by more than the smaller ones
    }
    // tiles of 16 receivers, every other one dirty
    ReceiverTiles only;
    only.reset(pyr.nxr, pyr.nyr, 16, false);
    for (int t = 0; t < only.tilesX * only.tilesY; t += 2) only.dirty[static_cast<std::size_t>(t)] = 1;
    std::vector<float> restricted;
    boundSlopeChangePerReceiverAzimuth(levels, pyr, op.phi, &only, 0.0f, restricted);
    REQUIRE(restricted.size() == bound.size());
    int mismatched = 0;
    for (std::size_t i = 0; i < bound.size(); ++i) {
        const std::size_t r = i % (static_cast<std::size_t>(pyr.nxr) * pyr.nyr);
        const int X = static_cast<int>(r) % pyr.nxr, Y = static_cast<int>(r) / pyr.nxr;
        const float expected = only.isDirty(X / 16, Y / 16) ? bound[i] : 0.0f;
        mismatched += restricted[i] != expected ? 1 : 0;
    }
    CHECK(mismatched == 0);
    HeightPyramid other;
    buildHeightPyramid(terrainOf(60, 40).cview(), kCell, 2, PyramidSettings{}, other);
    CHECK_THROWS_AS(boundSlopeChangePerReceiverAzimuth(levels, other, op.phi, nullptr, 0.0f, bound), InputError);
    MaxChangePyramid small;
    buildMaxChangePyramid(terrainOf(30, 30).cview(), small);
    CHECK_THROWS_AS(buildChangeLevels(small, pyr, levels), InputError);
}

TEST_CASE(
    "gi.receiver_azimuth_bound: a radiance field's sample moves bound every sample's move per receiver, azimuth and "
    "distance group") {
    struct Case {
        int nx, ny, subsample;
    };
    for (const Case c : {Case{97, 70, 1}, Case{120, 83, 2}, Case{150, 118, 4}}) {
        const Grid base = terrainOf(c.nx, c.ny);
        HeightPyramid heights;
        buildHeightPyramid(base.cview(), kCell, c.subsample, PyramidSettings{}, heights);
        // three channels of a radiance around 0.5, each changed by a scaled copy of a height change
        const auto radianceOf = [&](const Grid& h) {
            std::array<Grid, 3> rgb;
            for (std::size_t ch = 0; ch < 3; ++ch) {
                rgb[ch] = h;
                for (float& v : rgb[ch].v) v = 0.5f + 0.02f * static_cast<float>(ch + 1) * v;
            }
            return rgb;
        };
        const std::array<Grid, 3> before = radianceOf(base);
        RadiancePyramid p0, p1;
        buildRadiancePyramid(before, heights, RadiancePyramidSettings{}, p0);
        const FoldedWedgeOperator op = foldFullCircle(8, AzimuthInterp::Linear);
        const std::size_t m = op.phi.size();
        ChangeLevels levels;
        for (int kind = 0; kind < 4; ++kind) {
            CAPTURE(c.nx);
            CAPTURE(c.subsample);
            CAPTURE(kind);
            const std::array<Grid, 3> after = radianceOf(changed(base, kind));
            buildRadiancePyramid(after, heights, RadiancePyramidSettings{}, p1);
            MaxChangePyramid dl;
            const std::array<ConstGridView, 3> from{before[0].cview(), before[1].cview(), before[2].cview()};
            const std::array<ConstGridView, 3> to{after[0].cview(), after[1].cview(), after[2].cview()};
            buildMaxChangePyramid(from, to, dl, CellBox{});
            const HeightPyramid& field = p1.fields[0];
            buildChangeLevels(dl, field, levels);
            std::vector<float> azimuthMove, groupMove;
            boundSampleMovePerReceiver(levels, field, op.phi, nullptr, azimuthMove, groupMove);
            const std::size_t planeR = static_cast<std::size_t>(field.nxr) * field.nyr;
            REQUIRE(azimuthMove.size() == m * planeR);
            REQUIRE(groupMove.size() == kDistanceGroups * planeR);
            // every sample a receiver's scan reads (its valid prefix of steps), in every channel
            double worst = 0.0, excess = 0.0, zeroMoved = 0.0;
            for (std::size_t j = 0; j < m; ++j) {
                const double cs = std::cos(op.phi[j]), sn = std::sin(op.phi[j]);
                for (int Y = 0; Y < field.nyr; ++Y)
                    for (int X = 0; X < field.nxr; ++X) {
                        const std::size_t r = static_cast<std::size_t>(Y) * field.nxr + static_cast<std::size_t>(X);
                        for (int i = 0; i < static_cast<int>(field.steps.size()); ++i) {
                            const ScanStepInfo info = scanStepInfo(field, i, cs, sn);
                            if (X < info.xFirst || X > info.xLast || Y < info.yFirst || Y > info.yLast) break;
                            const int g = distanceGroup(field.steps[static_cast<std::size_t>(i)].tauCells);
                            const float bound = std::min(azimuthMove[j * planeR + r],
                                                         groupMove[static_cast<std::size_t>(g) * planeR + r]);
                            const std::ptrdiff_t at = static_cast<std::ptrdiff_t>(Y) * info.step.rowStep + X;
                            for (std::size_t ch = 0; ch < 3; ++ch) {
                                // the same step's taps in each channel's pyramid (one layout)
                                const ScanStepInfo a = scanStepInfo(p0.fields[ch], i, cs, sn);
                                const ScanStepInfo b = scanStepInfo(p1.fields[ch], i, cs, sn);
                                const float sample = stepSample(b.step, at);
                                const double move = std::fabs(static_cast<double>(sample) - stepSample(a.step, at));
                                // in real arithmetic: the pyramids' own rounding (up to about a
                                // hundred float epsilons of the radiance, through the octaves'
                                // means and syntheses) is not bounded
                                const double rounding = 256.0 * FLT_EPSILON * std::fabs(sample);
                                excess = std::max(excess, move - (bound + rounding));
                                // no move at all where the bound is 0
                                if (bound == 0.0f) zeroMoved = std::max(zeroMoved, move);
                                if (bound > 1e-4f) worst = std::max(worst, move / bound);
                            }
                        }
                    }
            }
            CHECK(excess <= 0.0);
            CHECK(zeroMoved == 0.0);
            MESSAGE(c.nx << " x " << c.ny << " s=" << c.subsample << " change " << kind
                         << ": largest sample move / its bound " << worst);
            // the same values walked over a few tiles alone
            ReceiverTiles only;
            only.reset(field.nxr, field.nyr, 16, false);
            only.dirty[0] = only.dirty[only.dirty.size() - 1] = 1;
            std::vector<float> az = azimuthMove, gr = groupMove;
            std::fill(az.begin(), az.end(), -1.0f);
            std::fill(gr.begin(), gr.end(), -1.0f);
            boundSampleMovePerReceiver(levels, field, op.phi, &only, az, gr);
            int mismatched = 0;
            for (std::size_t r = 0; r < planeR; ++r) {
                const int X = static_cast<int>(r % static_cast<std::size_t>(field.nxr)) / 16;
                const int Y = static_cast<int>(r / static_cast<std::size_t>(field.nxr)) / 16;
                const bool walked = only.isDirty(X, Y);
                for (std::size_t j = 0; j < m; ++j)
                    mismatched += az[j * planeR + r] != (walked ? azimuthMove[j * planeR + r] : -1.0f) ? 1 : 0;
                for (std::size_t g = 0; g < kDistanceGroups; ++g)
                    mismatched += gr[g * planeR + r] != (walked ? groupMove[g * planeR + r] : -1.0f) ? 1 : 0;
            }
            CHECK(mismatched == 0);
        }
    }
}
