// gi/indirect_cache: the indirect light re-gathers the receiver tiles whose
// sources or geometry drifted beyond the tolerance, bit for bit a full
// recompute at tolerance 0, and the radiance bound it adds up holds.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include <doctest/doctest.h>

#include "core/parallel.h"
#include "gi/blocker_radiance.h"
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

// What the indirect light reads of a frame run on `st`, with `source` as
// bounce 0 (every receiver and texel; the callers narrow it).
IndirectInputs indirectInputsOf(const GiState& st, const GiSettings& settings, const FoldedWedgeOperator& op,
                                const std::array<Grid, 3>& source) {
    return {.heights = st.pyramid,
            .gradX = st.gradX.cview(),
            .gradY = st.gradY.cview(),
            .op = op,
            .envVisibility = st.envVisibility,
            .direct = source,
            .directShade = nullptr,
            .albedo = nullptr,
            .shading = settings.shading};
}

// Whether every texel's total is its direct plus its indirect light, bit for
// bit (the sum is redone only where either may have changed).
bool totalIsDirectPlusIndirect(const std::array<Grid, 3>& direct, const IndirectState& out) {
    for (std::size_t c = 0; c < 3; ++c)
        for (std::size_t i = 0; i < direct[c].v.size(); ++i) {
            const float sum = direct[c].v[i] + out.indirect[c].v[i];
            if (std::memcmp(&sum, &out.total[c].v[i], sizeof(float)) != 0) return false;
        }
    return true;
}
bool totalIsDirectPlusIndirect(const GiState& st) { return totalIsDirectPlusIndirect(st.shade.rgb, st.indirect); }

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
    int lowered = 0;  // tiles whose receivers' own bounds lowered the tile's (checked above the changes too)
    for (int s : {1, 2, 4}) {
        const GiSettings settings = withBounces(GiSettings{}, s, 1);
        GiState st;
        runGiFrame(h.cview(), kCell, sunSkyAndKey(), settings, st);
        const FoldedWedgeOperator op = foldFullCircle(settings.indirect.azimuths, settings.visibility.interp);
        const auto gather = [&](const std::array<Grid, 3>& source, IndirectState& out) {
            computeIndirect(indirectInputsOf(st, settings, op, source), settings.indirect, out);
        };
        const std::array<Grid, 3> base = st.shade.rgb;
        IndirectState before;
        gather(base, before);
        if (s > 1) {
            // the distance groups' occlusions add up to each receiver's occlusion (the running sum's last plane)
            const BlockerRadianceState& b = before.blocker;
            const std::size_t plane = static_cast<std::size_t>(b.nxr) * b.nyr, m = static_cast<std::size_t>(b.azimuths);
            double worst = 0.0;
            for (std::size_t k = 0; k < plane; ++k) {
                double groups = 0.0;
                for (std::size_t g = 0; g < kDistanceGroups; ++g) groups += b.receiverGroupOcclusion[g * plane + k];
                const double total = b.receiverOcclusionRunning[(m - 1) * plane + k];
                worst = std::max(worst, std::fabs(groups - total) / std::max(total, 1e-3));
            }
            CHECK(worst < 1e-4);
        }
        std::mt19937 rng(11 + s);
        std::uniform_real_distribution<float> u(-1.0f, 1.0f);
        const int nx = h.nx, ny = h.ny;
        // a bright patch, noise everywhere, a shadow edge moving across the field
        const auto bump = [&](int x, int y, int) { return std::hypot(x - 40.0f, y - 90.0f) < 6.0f ? 0.8f : 0.0f; };
        const auto corner = [&](int x, int y, int) { return std::hypot(x - 150.0f, y - 6.0f) < 5.0f ? 1.0f : 0.0f; };
        const auto noise = [&](int, int, int) { return 0.02f * u(rng); };
        const auto edge = [&](int x, int y, int c) { return (x + y / 3) % 37 == 0 ? (c == 0 ? -0.5f : 0.3f) : 0.0f; };
        for (const auto& [name, change] : std::vector<std::pair<const char*, std::function<float(int, int, int)>>>{
                 {"patch", bump}, {"corner patch", corner}, {"noise", noise}, {"edges", edge}}) {
            CAPTURE(s);
            const std::string caseName = name;
            CAPTURE(caseName);
            const gi_test::ChangedRadiance changed = gi_test::changedRadiance(base, change, true);
            const std::array<Grid, 3>& after = changed.after;
            IndirectState later;
            gather(after, later);
            // the frame's bound as the cache takes it: from the cached pass
            // (before) to this one's sources, on the same geometry
            IndirectCache cache;
            cache.anchorSource = base;
            recordAnchorLevels(before.radiance, cache.levels);
            const IndirectPlanInputs plan{.source = after,
                                          .heights = st.pyramid,
                                          .pyramid = later.radiance,
                                          .geometryTiles = nullptr,
                                          .phi = op.phi,
                                          .tolerance = 0.0f,
                                          .blocker = &before.blocker};
            boundRadianceChange(plan, cache);
            const std::vector<float>& bound = cache.radianceBound;
            // the samples' moves alone (the largest over the azimuths, read
            // from the pyramids per visibility tile), which the occlusions'
            // weights and factor only lower
            const int m = op.azimuths, tilesX = tileCount(st.pyramid.nxr, kIndirectTile);
            const int sampleTilesX = tileCount(st.pyramid.nxr, kVisibilityTile);
            const auto largestSampleMove = [&](std::size_t t) {
                const int X = static_cast<int>(t % tilesX) * kIndirectTile / kVisibilityTile;
                const int Y = static_cast<int>(t / tilesX) * kIndirectTile / kVisibilityTile;
                const auto az = cache.azimuthBound.begin() + static_cast<std::ptrdiff_t>((Y * sampleTilesX + X) * m);
                return *std::max_element(az, az + m);
            };
            // per tile its groups' largest is its azimuths' largest (every
            // step of every azimuth, grouped two ways)
            for (std::size_t t = 0; t < cache.groupBound.size() / kDistanceGroups; ++t) {
                const auto g = cache.groupBound.begin() + static_cast<std::ptrdiff_t>(t * kDistanceGroups);
                const auto a = cache.azimuthBound.begin() + static_cast<std::ptrdiff_t>(t * m);
                CHECK(*std::max_element(g, g + kDistanceGroups) == *std::max_element(a, a + m));
            }
            for (std::size_t t = 0; t < bound.size(); ++t) CHECK(bound[t] <= largestSampleMove(t));
            double meanBound = 0.0, meanSample = 0.0;
            for (std::size_t t = 0; t < bound.size(); ++t) {
                meanBound += bound[t] / static_cast<double>(bound.size());
                meanSample += largestSampleMove(t) / static_cast<double>(bound.size());
            }
            // every texel's exit radiance (white albedo) moves by at most the
            // largest bound of the receivers it reads
            double worstRatio = 0.0;
            const auto excessOver = [&](const std::vector<float>& tiles) {
                const auto tileBound = [&](int X, int Y) {
                    return tiles[static_cast<std::size_t>(Y / kIndirectTile) * tilesX + X / kIndirectTile];
                };
                double excess = 0.0;
                for (int y = 0; y < ny; ++y)
                    for (int x = 0; x < nx; ++x) {
                        const int X0 = std::min(x / s, st.pyramid.nxr - 1), Y0 = std::min(y / s, st.pyramid.nyr - 1);
                        const int X1 = std::min(X0 + 1, st.pyramid.nxr - 1);
                        const int Y1 = std::min(Y0 + 1, st.pyramid.nyr - 1);
                        const float b =
                            std::max({tileBound(X0, Y0), tileBound(X1, Y0), tileBound(X0, Y1), tileBound(X1, Y1)});
                        for (std::size_t c = 0; c < 3; ++c) {
                            const double d =
                                std::fabs(static_cast<double>(later.indirect[c](x, y)) - before.indirect[c](x, y));
                            excess = std::max(excess, d - (b * (1.0 + 1e-5) + 1e-6));
                            if (b > 0.0f && &tiles == &bound) worstRatio = std::max(worstRatio, d / b);
                        }
                    }
                return excess;
            };
            CHECK(excessOver(bound) <= 0.0);
            const float smallest = *std::min_element(cache.azimuthBound.begin(), cache.azimuthBound.end());
            MESSAGE(s << "x, " << caseName << ": largest change / bound " << worstRatio << "; sample bounds from "
                      << smallest << " to " << maxChangeAll(cache.change) << ", mean " << meanBound
                      << " (the sample bound alone: " << meanSample << ")");
            // with sub-sampling the occlusions lower the bound
            if (s > 1) CHECK(meanBound < meanSample);
            // with a tolerance, tiles whose share envelope bounds them within
            // half of it take that bound instead: never lower, the receivers'
            // weighing above half the tolerance; the tiles it would re-gather
            // take their receivers' own bounds where lower (where they are at
            // most half of the tiles; at tolerance 0 too, where far tiles saw
            // no change); and so every bound is still above every change (the
            // occlusion factor holds the tolerance too)
            IndirectCache tolerant;
            tolerant.anchorSource = base;
            recordAnchorLevels(before.radiance, tolerant.levels);
            IndirectPlanInputs withTolerance = plan;
            withTolerance.tolerance = 0.1f;
            boundRadianceChange(withTolerance, tolerant);
            CHECK(excessOver(tolerant.radianceBound) <= 0.0);
            int coarser = 0, refined = 0;
            for (std::size_t t = 0; t < bound.size(); ++t) {
                // the tile's bound before its occlusion factor, at tolerance 0
                const double weighed = static_cast<double>(bound[t]) / cache.occlusionFactor[t];
                const double expected = weighed * tolerant.occlusionFactor[t];
                if (tolerant.refined.dirty[t]) {
                    CHECK(tolerant.radianceBound[t] <= expected * (1.0 + 1e-6));
                    refined += tolerant.radianceBound[t] < expected * (1.0 - 1e-6) ? 1 : 0;
                    continue;
                }
                if (cache.refined.dirty[t]) continue;  // lowered at tolerance 0 already: no reference
                CHECK(tolerant.radianceBound[t] >= expected * (1.0 - 1e-6));
                if (tolerant.radianceBound[t] > 0.05f)
                    CHECK(tolerant.radianceBound[t] == doctest::Approx(expected).epsilon(1e-6));
                coarser += tolerant.radianceBound[t] > expected * (1.0 + 1e-6) ? 1 : 0;
            }
            MESSAGE(s << "x, " << caseName << ": " << refined << " tiles lowered by their receivers' own bounds");
            // small changes everywhere: some tile took its envelope's bound
            if (s > 1 && caseName == "noise") CHECK(coarser > 0);
            lowered += refined;
            // a local patch: tiles far from it are charged less than its full change
            if (caseName == "patch" || caseName == "corner patch") CHECK(smallest < maxChangeAll(cache.change));
        }
    }
    CHECK(lowered > 0);
}

// A uniform unit sky plus one key light, whose brightness the tests change,
// over a bumpy 96² field at 2x with one bounce and tolerance 0.01.
struct KeyLitField {
    Grid h = bumpy(96, 96);
    GiLighting light;
    GiSettings settings;
    KeyLitField() {
        KeyLight key;
        key.azimuthDeg = 60.0f;
        key.elevationDeg = 35.0f;
        light.keys.push_back(key);
        settings = withBounces(GiSettings{}, 2, 1);
        settings.tolerance = 0.01f;
    }
};

TEST_CASE("gi.indirect_cache: small source changes accumulate until they pass the tolerance") {
    KeyLitField field;  // the key light brightens a little each frame
    const Grid& h = field.h;
    GiLighting& light = field.light;
    const GiSettings& settings = field.settings;
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

TEST_CASE("gi.indirect_cache: after a plan that finds most tiles dirty, frames re-gather without planning") {
    // A key light three times as bright dirties every tile; the bound would
    // only add its cost to the next frames' full passes, so kFramesWithoutPlan
    // frames re-gather everything unplanned (a full frame's indirect light,
    // bit for bit); then planning resumes, and a change below the tolerance
    // re-gathers nothing.
    KeyLitField field;
    const Grid& h = field.h;
    GiLighting& light = field.light;
    const GiSettings& settings = field.settings;
    GiSettings off = settings;
    off.incremental = false;
    GiState inc;
    runGiFrame(h.cview(), kCell, light, settings, inc);
    light.keys[0].rgb[0] *= 3.0f;
    runGiFrame(h.cview(), kCell, light, settings, inc);
    CHECK(inc.indirectRecomputed == 1.0);
    CHECK(inc.indirectCache.skips.left == kFramesWithoutPlan);
    for (int k = 1; k <= kFramesWithoutPlan; ++k) {
        light.keys[0].rgb[0] *= 1.0001f;
        runGiFrame(h.cview(), kCell, light, settings, inc);
        GiState full;
        runGiFrame(h.cview(), kCell, light, off, full);
        CHECK(inc.indirectRecomputed == 1.0);
        CHECK(inc.indirectCache.skips.left == kFramesWithoutPlan - k);
        CHECK(largestDifference(inc.indirect.indirect, full.indirect.indirect) == 0.0);
    }
    light.keys[0].rgb[0] *= 1.0001f;
    runGiFrame(h.cview(), kCell, light, settings, inc);
    CHECK(inc.indirectRecomputed == 0.0);
    CHECK(inc.indirectCache.skips.length == 0);  // a plan that kept the tiles: the next run starts short again
}

TEST_CASE("gi.indirect_cache: a frame without a change ends the frames without a plan") {
    // A terrain that stopped changing everywhere (a paused erosion) and then
    // changes a little: that change is planned, not re-gathered in full.
    KeyLitField field;
    const Grid& h = field.h;
    GiLighting& light = field.light;
    const GiSettings& settings = field.settings;
    GiState inc;
    runGiFrame(h.cview(), kCell, light, settings, inc);
    light.keys[0].rgb[0] *= 3.0f;
    runGiFrame(h.cview(), kCell, light, settings, inc);
    REQUIRE(inc.indirectCache.skips.left == kFramesWithoutPlan);
    runGiFrame(h.cview(), kCell, light, settings, inc);  // the same inputs
    CHECK(inc.indirectCache.skips.left == 0);
    CHECK(inc.indirectCache.skips.length == 0);
    light.keys[0].rgb[0] *= 1.0001f;
    runGiFrame(h.cview(), kCell, light, settings, inc);
    CHECK(inc.indirectRecomputed == 0.0);
}

namespace {

// A bumpy 256^2 field and the same with a 16 x 16-cell crater 6 m deep at
// its centre, under a uniform unit sky (shade units are the ambient map's),
// lit at 2x with one bounce.
struct CraterField {
    Grid h = bumpy(256, 256);
    Grid crater = withCrater(h);
    GiLighting light;
    static Grid withCrater(Grid g) {
        for (int y = 120; y < 136; ++y)
            for (int x = 120; x < 136; ++x) g(x, y) -= 6.0f;
        return g;
    }
    static GiSettings settings(float tolerance) {
        GiSettings s = withBounces(GiSettings{}, 2, 1);
        s.tolerance = tolerance;
        return s;
    }
    // A full recompute of `g` with these settings otherwise.
    GiState fullFrame(const Grid& g, GiSettings s) const {
        s.incremental = false;
        GiState full;
        runGiFrame(g.cview(), 10.0f, light, s, full);
        return full;
    }
};

}  // namespace

TEST_CASE("gi.indirect_cache: with a local height change the indirect light stays within the tolerance") {
    const CraterField field;
    const GiSettings settings = CraterField::settings(0.02f);
    GiState inc;
    runGiFrame(field.h.cview(), 10.0f, field.light, settings, inc);
    runGiFrame(field.crater.cview(), 10.0f, field.light, settings, inc);
    const GiState full = field.fullFrame(field.crater, settings);
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

TEST_CASE("gi.indirect_cache: a crater dropped and filled again and again costs the same each time") {
    // The drifts are measured from an anchor (gi/anchored_drift.h): a change
    // that comes and goes is not added up frame after frame, so the tiles
    // recomputed on the tenth drop and fill are those of the second, and every
    // frame stays within the tolerance of a full one.
    const CraterField field;
    const GiSettings settings = CraterField::settings(0.05f);
    GiState inc;
    runGiFrame(field.h.cview(), 10.0f, field.light, settings, inc);
    std::vector<double> v, indirect;
    double worst = 0.0;
    for (int f = 1; f <= 20; ++f) {
        const Grid& now = f % 2 == 1 ? field.crater : field.h;
        runGiFrame(now.cview(), 10.0f, field.light, settings, inc);
        CHECK(totalIsDirectPlusIndirect(inc));
        const GiState full = field.fullFrame(now, settings);
        worst = std::max({worst, largestDifference(inc.shade.rgb, full.shade.rgb),
                          largestDifference(inc.indirect.indirect, full.indirect.indirect)});
        v.push_back(inc.receiversRecomputed);
        indirect.push_back(inc.indirectRecomputed);
    }
    MESSAGE("V recomputed on drops / fills: " << 100.0 * v[2] << " / " << 100.0 * v[3] << " %, indirect light "
                                              << 100.0 * indirect[2] << " / " << 100.0 * indirect[3] << " %");
    CHECK(worst <= settings.tolerance);
    CHECK(v[2] < 1.0);
    CHECK(indirect[2] < 1.0);
    CHECK(v[18] == v[2]);
    CHECK(v[19] == v[3]);
    CHECK(indirect[18] == indirect[2]);
    CHECK(indirect[19] == indirect[3]);
}

TEST_CASE("gi.indirect_cache: the tiles' kept largest occlusions equal ones taken afresh") {
    // Each tile's largest texel occlusion is kept between plans and taken
    // again only where the texel passes redid an occlusion: through drops
    // and fills of a crater, a plan's occlusion factors from the kept values
    // are those of a cache that takes every tile again.
    const CraterField field;
    const GiSettings settings = CraterField::settings(0.05f);
    GiState inc;
    runGiFrame(field.h.cview(), 10.0f, field.light, settings, inc);
    for (int f = 1; f <= 6; ++f) {
        runGiFrame((f % 2 == 1 ? field.crater : field.h).cview(), 10.0f, field.light, settings, inc);
        const CellBox redone = inc.indirectCache.occlusionsRedone;
        CHECK(!redone.empty());
        CHECK((redone.x1 - redone.x0) * static_cast<long>(redone.y1 - redone.y0) < 256L * 256 / 2);  // most tiles kept
        // a source that differs from the anchor, so that the plan weighs it
        std::array<Grid, 3> source = inc.shade.rgb;
        for (Grid& c : source) c(128, 128) += 0.5f;
        const IndirectPlanInputs in{.source = source,
                                    .heights = inc.pyramid,
                                    .pyramid = inc.indirect.radiance,
                                    .geometryTiles = nullptr,
                                    .phi = inc.indirectOperator.phi,
                                    .tolerance = settings.tolerance,
                                    .blocker = &inc.indirect.blocker};
        IndirectCache kept = inc.indirectCache, fresh = inc.indirectCache;
        fresh.largestOcclusion.clear();
        boundRadianceChange(in, kept);
        boundRadianceChange(in, fresh);
        REQUIRE(kept.occlusionFactor.size() == fresh.occlusionFactor.size());
        CHECK(kept.occlusionFactor == fresh.occlusionFactor);
        // the factors are the texels' occlusions, not the bound's default of 1
        CHECK(*std::min_element(kept.occlusionFactor.begin(), kept.occlusionFactor.end()) < 1.0f);
    }
}

namespace {

// The texel passes redone over every texel from the state an incremental
// frame left: the occlusion and the indirect light it would then hold.
struct WholeTexelPasses {
    Grid occlusion;
    std::array<Grid, 3> light;
};
WholeTexelPasses redoTexelPasses(const GiState& st, const AlbedoMap* albedo) {
    BlockerRadianceState copy = st.indirect.blocker;
    computeTexelOcclusion(st.pyramid, st.gradX.cview(), st.gradY.cview(), st.indirectOperator.phi, nullptr, nullptr,
                          copy);
    WholeTexelPasses out;
    shadeBlockerRadiance(copy, albedo, nullptr, nullptr, out.light);
    out.occlusion = copy.occlusion;
    return out;
}

bool sameBits(const Grid& a, const Grid& b) {
    return a.nx == b.nx && a.ny == b.ny && std::memcmp(a.v.data(), b.v.data(), sizeof(float) * a.v.size()) == 0;
}

}  // namespace

TEST_CASE("gi.indirect_cache: the texel passes redo only the texel tiles whose inputs changed") {
    // 256^2 at 2x: 4 x 4 tiles; a pit moving along x across a tile's edge, a
    // texel of new albedo on frame 2, a key light from frame 4, the pit filled
    // on frame 5, a bump on frame 6 beside the edge of a tile column. At
    // tolerance 0.1 some receiver tiles re-gather (their texels and those
    // reading them redo); at 1 none does, and only the heights' reach decides.
    const Grid h = bumpy(256, 256);
    for (float tolerance : {0.1f, 1.0f}) {
        GiLighting light;
        GiSettings settings = withBounces(GiSettings{}, 2, 1);
        settings.tolerance = tolerance;
        AlbedoMap albedo;
        for (Grid& c : albedo.channel) c.resize(256, 256, 0.6f);
        GiState inc;
        runGiFrame(h.cview(), 10.0f, light, settings, inc, &albedo);
        int partial = 0;
        for (int f = 1; f <= 6; ++f) {
            Grid g = h;
            if (f == 6) g(62, 200) += 1.0f;  // the texels of the next tile column read it
            if (f < 5)
                for (int y = 120; y < 128; ++y)
                    for (int x = 184 + 2 * f; x < 192 + 2 * f; ++x) g(x, y) -= 3.0f;
            if (f == 2) albedo.channel[1](100, 100) = 0.3f;
            if (f == 4) light.keys.push_back(KeyLight{});
            runGiFrame(g.cview(), 10.0f, light, settings, inc, &albedo);
            const ReceiverTiles& texels = inc.indirectCache.texels;
            const bool tiled =
                f != 2 && inc.indirectRecomputed < 1.0 && texels.dirtyCount() < static_cast<int>(texels.dirty.size());
            partial += tiled ? 1 : 0;
            INFO("tolerance " << tolerance << ", frame " << f << ": indirect re-gathered at "
                              << 100.0 * inc.indirectRecomputed << " %, texel tiles " << texels.dirtyCount() << " of "
                              << texels.dirty.size());
            // the tiles kept hold what redoing them would give, bit for bit
            const WholeTexelPasses whole = redoTexelPasses(inc, &albedo);
            CHECK(sameBits(whole.occlusion, inc.indirect.blocker.occlusion));
            for (std::size_t c = 0; c < 3; ++c) CHECK(sameBits(whole.light[c], inc.indirect.indirect[c]));
        }
        MESSAGE("tolerance " << tolerance << ": frames whose texel passes redid only some tiles: " << partial
                             << " of 5");
        CHECK(partial > 0);
    }
}

TEST_CASE(
    "gi.indirect_cache: texel passes: a height change reaches the tiles within s + 1 cells, a re-gather the texels "
    "that read its receivers") {
    // 200^2 at 2x: 100^2 receivers, tiles of 32 (the last one 4 wide); a
    // texel's tile is that of its lower receiver, clamped to 98
    const Grid before = bumpy(200, 200);
    HeightPyramid pyr;
    buildHeightPyramid(before.cview(), 1.0f, 2, PyramidSettings{}, pyr);
    ReceiverTiles gathered;
    gathered.reset(pyr.nxr, pyr.nyr, kVisibilityTile, false);
    IndirectCache cache;
    const auto dirtyTiles = [&](int cx, int cy) {
        Grid after = before;
        if (cx >= 0) after(cx, cy) += 1.0f;
        const IndirectTexelInputs in{.gathered = &gathered,
                                     .sameGeometry = cx < 0,
                                     .lastHeights = &before,
                                     .heights = after.cview(),
                                     .albedo = nullptr,
                                     .pyramid = pyr};
        const ReceiverTiles* t = planIndirectTexels(in, cache);
        REQUIRE(t != nullptr);
        std::vector<int> out;
        for (int i = 0; i < static_cast<int>(t->dirty.size()); ++i)
            if (t->dirty[static_cast<std::size_t>(i)] != 0) out.push_back(i);
        return out;
    };
    // texels 0..63 are tile column 0, 64..127 column 1, and so on; s + 1 = 3
    CHECK(dirtyTiles(10, 10) == std::vector<int>{0});
    CHECK(dirtyTiles(66, 10) == std::vector<int>{0, 1});  // 3 cells from texel 63
    CHECK(dirtyTiles(67, 10) == std::vector<int>{1});
    CHECK(dirtyTiles(61, 10) == std::vector<int>{0, 1});  // 3 cells before texel 64
    CHECK(dirtyTiles(60, 10) == std::vector<int>{0});
    CHECK(dirtyTiles(10, 66) == std::vector<int>{0, 4});
    CHECK(dirtyTiles(199, 10) == std::vector<int>{3});  // the last column (receivers 96..99) to the grid's end
    CHECK(dirtyTiles(193, 10) == std::vector<int>{2, 3});
    CHECK(dirtyTiles(67, 131) == std::vector<int>{9});
    CHECK(cache.texelRuns.ofRow(127).empty());
    for (int y : {128, 150, 191}) {  // tile (1, 2)'s own texels: columns 64..127, rows 128..191
        REQUIRE(cache.texelRuns.ofRow(y).size() == 1);
        CHECK((cache.texelRuns.ofRow(y)[0].x0 == 64 && cache.texelRuns.ofRow(y)[0].x1 == 128));
    }
    CHECK(cache.texelRuns.ofRow(192).empty());
    CHECK(dirtyTiles(-1, 0).empty());  // same geometry, nothing gathered
    CHECK(texelCount(cache.texelRuns) == 0);
    gathered.setDirty(1, 1);
    // the receivers' occlusion of tile (1, 1) alone, the texels that read its
    // receivers 32..63: from the last texels of receiver 31 (62, 63) on
    CHECK(dirtyTiles(-1, 0) == std::vector<int>{5});
    CHECK(cache.texelRuns.ofRow(61).empty());
    for (int y : {62, 100, 127}) {
        REQUIRE(cache.texelRuns.ofRow(y).size() == 1);
        CHECK((cache.texelRuns.ofRow(y)[0].x0 == 62 && cache.texelRuns.ofRow(y)[0].x1 == 128));
    }
    CHECK(cache.texelRuns.ofRow(128).empty());
    // a new albedo: every texel
    AlbedoMap albedo;
    albedo.channel[0] = Grid(200, 200, 0.5f);
    const IndirectTexelInputs in{.gathered = &gathered,
                                 .sameGeometry = true,
                                 .lastHeights = nullptr,
                                 .heights = before.cview(),
                                 .albedo = &albedo,
                                 .pyramid = pyr};
    CHECK(planIndirectTexels(in, cache) == nullptr);
    CHECK(planIndirectTexels(in, cache) != nullptr);  // recorded: the next pass with it is tiled again
}

TEST_CASE("gi.indirect_cache: bounce 0's radiance pyramid redone over the changed texels is a full build's") {
    const Grid h = bumpy(120, 96);
    for (int s : {1, 2}) {
        CAPTURE(s);
        const GiSettings settings = withBounces(GiSettings{}, s, 1);
        GiState st;
        runGiFrame(h.cview(), kCell, sunSkyAndKey(), settings, st);
        const FoldedWedgeOperator op = foldFullCircle(settings.indirect.azimuths, settings.visibility.interp);
        const auto gather = [&](const std::array<Grid, 3>& source, CellBox changed, int bounces, IndirectState& out) {
            IndirectInputs in = indirectInputsOf(st, settings, op, source);
            in.directChanged = changed;
            IndirectSettings is = settings.indirect;
            is.bounces = bounces;
            computeIndirect(in, is, out);
        };
        const auto samePyramid = [](const IndirectState& a, const IndirectState& b) {
            bool same = a.radiance.fields.size() == b.radiance.fields.size();
            for (std::size_t c = 0; same && c < a.radiance.fields.size(); ++c) {
                const HeightPyramid &pa = a.radiance.fields[c], &pb = b.radiance.fields[c];
                same = pa.levels.size() == pb.levels.size() && gi_test::sameBits(pa.rawPhase, pb.rawPhase);
                for (std::size_t l = 0; same && l < pa.levels.size(); ++l)
                    same = gi_test::sameBits(pa.levels[l].v, pb.levels[l].v);
            }
            return same;
        };
        const std::array<Grid, 3> base = st.shade.rgb;
        std::array<Grid, 3> after = base;
        const CellBox patch{70, 20, 83, 29};
        for (int y = patch.y0; y < patch.y1; ++y)
            for (int x = patch.x0; x < patch.x1; ++x) after[static_cast<std::size_t>(x % 3)](x, y) += 0.3f;
        IndirectState fresh;
        gather(after, CellBox{}, 1, fresh);
        // the last call's bounce 0 with the box of what changed
        IndirectState redone;
        gather(base, CellBox{}, 1, redone);
        gather(after, patch, 1, redone);
        CHECK(samePyramid(redone, fresh));
        CHECK(gi_test::sameBits(redone.indirect[0].v, fresh.indirect[0].v));
        CHECK(gi_test::sameBits(redone.total[2].v, fresh.total[2].v));
        // a box that misses the change keeps the old cells: the box is what is redone
        IndirectState missed;
        gather(base, CellBox{}, 1, missed);
        gather(after, CellBox{0, 0, 4, 4}, 1, missed);
        CHECK_FALSE(samePyramid(missed, fresh));
        // after two bounces the pyramid is bounce 1's: a box is not enough, it is rebuilt whole
        IndirectState twoBounces;
        gather(base, CellBox{}, 2, twoBounces);
        CHECK_FALSE(twoBounces.radianceOfDirect);
        gather(after, CellBox{0, 0, 4, 4}, 1, twoBounces);
        CHECK(twoBounces.radianceOfDirect);
        CHECK(samePyramid(twoBounces, fresh));
    }
}

TEST_CASE("gi.indirect_cache: the total is redone wherever the indirect light was, beyond the direct light's change") {
    // the direct light changes in a patch; the texel passes redo a region far
    // from it as well (the receivers there gathered the patch's light): the
    // total must follow the indirect light there too
    const Grid h = bumpy(128, 96);
    const GiSettings settings = withBounces(GiSettings{}, 2, 1);
    GiState st;
    runGiFrame(h.cview(), kCell, sunSkyAndKey(), settings, st);
    const FoldedWedgeOperator op = foldFullCircle(settings.indirect.azimuths, settings.visibility.interp);
    ReceiverTiles everyTile;
    everyTile.reset(st.pyramid.nxr, st.pyramid.nyr, kIndirectTile, true);
    const TexelRect patch{20, 10, 30, 18}, far{90, 60, 120, 90};
    TexelRuns runs;
    texelRunsOfRects(std::vector<TexelRect>{patch, far}, h.nx, h.ny, runs);
    const auto gather = [&](const std::array<Grid, 3>& source, bool restricted, CellBox changed, IndirectState& out) {
        IndirectInputs in = indirectInputsOf(st, settings, op, source);
        if (restricted) {
            in.only = in.texels = &everyTile;
            in.texelRuns = &runs;
            in.sameGeometry = true;
        }
        in.directChanged = changed;
        computeIndirect(in, settings.indirect, out);
    };
    std::array<Grid, 3> after = st.shade.rgb;
    for (int y = patch.y0; y < patch.y1; ++y)
        for (int x = patch.x0; x < patch.x1; ++x)
            for (Grid& g : after) g(x, y) += 2.0f;
    IndirectState out;
    gather(st.shade.rgb, false, CellBox{}, out);
    const std::array<Grid, 3> indirectBefore = out.indirect;
    gather(after, true, CellBox{patch.x0, patch.y0, patch.x1, patch.y1}, out);
    CHECK(totalIsDirectPlusIndirect(after, out));
    // the far region's indirect light did change (else the test shows nothing)
    bool farChanged = false;
    for (int y = far.y0; y < far.y1 && !farChanged; ++y)
        for (int x = far.x0; x < far.x1; ++x)
            farChanged = farChanged || out.indirect[1](x, y) != indirectBefore[1](x, y);
    CHECK(farChanged);
}

// The first plan after a full pass compares this frame's radiance pyramid
// with that pass's (the anchor's), whose levels it copies then (a pass on a
// grid the cache already holds does not): its bound equals one computed
// from scratch with the pass's pyramid recorded as the anchor's.
TEST_CASE("gi.indirect_cache: the first plan after a full pass compares with that pass's pyramid") {
    const int n = 160;
    const Grid h = bumpy(n, n);
    GiSettings settings = withBounces(GiSettings{}, 2, 1);
    settings.tolerance = 0.01f;
    const GiLighting light = sunSkyAndKey();
    AlbedoMap plain, patched;
    for (std::size_t c = 0; c < 3; ++c) {
        plain.channel[c] = Grid(n, n);
        std::fill(plain.channel[c].v.begin(), plain.channel[c].v.end(), 0.5f);
        patched.channel[c] = plain.channel[c];
        for (int y = 8; y < 18; ++y)
            for (int x = 8; x < 18; ++x) patched.channel[c](x, y) = 0.9f;
    }
    GiState st;
    runGiFrame(h.cview(), kCell, light, settings, st, &plain);  // the first pass on this grid
    GiSettings full = settings;
    full.incremental = false;
    runGiFrame(h.cview(), kCell, light, full, st, &plain);      // forgets the recorded inputs, so
    runGiFrame(h.cview(), kCell, light, settings, st, &plain);  // this is a full pass: the anchor
    const RadiancePyramid anchorPyramid = st.indirect.radiance;
    const std::array<Grid, 3> anchorSource = st.shade.rgb;
    const BlockerRadianceState blocker = st.indirect.blocker;
    runGiFrame(h.cview(), kCell, light, settings, st, &patched);
    // the frame planned, and kept some tiles
    CHECK(st.indirectRecomputed > 0.0);
    CHECK(st.indirectRecomputed < 1.0);
    IndirectCache fresh;
    fresh.anchorSource = anchorSource;
    recordAnchorLevels(anchorPyramid, fresh.levels);
    const FoldedWedgeOperator op = foldFullCircle(settings.indirect.azimuths, settings.visibility.interp);
    const IndirectPlanInputs in{.source = st.shade.rgb,
                                .heights = st.pyramid,
                                .pyramid = st.indirect.radiance,
                                .geometryTiles = nullptr,
                                .phi = op.phi,
                                .tolerance = settings.tolerance,
                                .blocker = &blocker};
    boundRadianceChange(in, fresh);
    CHECK(fresh.radianceBound == st.indirectCache.radianceBound);
}
