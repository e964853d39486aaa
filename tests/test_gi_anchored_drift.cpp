// gi/anchored_drift: tiles measured from an anchor recompute where their
// drift exceeds the tolerance, a change that comes and goes is not counted
// again each time, and the anchor moves where the terrain moves away from it.
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include <doctest/doctest.h>

#include "gi/anchored_drift.h"

using namespace terrain::gi;

TEST_CASE("gi.anchored_drift: a change that comes and goes is counted once") {
    // A pit dropped and filled ten times at tolerance 0.05: on drop frames
    // tile 0 is 0.08 from the anchor, tile 1 0.03; on fill frames both are
    // back at it. Summed per frame, tile 1's bounds would pass the tolerance
    // on the second drop; measured from the anchor they never do. Tile 0
    // recomputes on every frame: on drops its excursion, on fills its result
    // is away from the anchor; the anchor stays (the terrain came back).
    AnchoredDrift drift;
    drift.reset(2);
    std::vector<std::uint8_t> dirty(2);
    int tile0 = 0, tile1 = 0, reanchored = 0;
    for (int k = 0; k < 20; ++k) {
        const bool drop = k % 2 == 0;
        const std::vector<float> e = drop ? std::vector<float>{0.08f, 0.03f} : std::vector<float>{0.0f, 0.0f};
        reanchored += planAnchoredDrift(e, {}, 0.05f, drift, dirty) ? 1 : 0;
        tile0 += dirty[0];
        tile1 += dirty[1];
    }
    CHECK(tile0 == 20);
    CHECK(tile1 == 0);
    CHECK(reanchored == 0);
}

TEST_CASE("gi.anchored_drift: a steady drift moves the anchor instead of recomputing every frame") {
    // The terrain moves away from the anchor by 0.02 a frame at tile 0 and
    // 0.001 at tile 1. Tile 0 recomputes when its drift passes 0.05; the
    // next frame, its result away from the anchor and its excursion still
    // growing, the anchor moves there. Without that it would recompute on
    // every frame from the third on; with it, two frames in every four (the
    // per-frame sums: one in three).
    AnchoredDrift drift;
    drift.reset(2);
    std::vector<std::uint8_t> dirty(2);
    float e0 = 0.0f, e1 = 0.0f;
    std::vector<int> frames, reanchored;
    for (int f = 0; f < 12; ++f) {
        e0 += 0.02f;
        e1 += 0.001f;
        if (planAnchoredDrift(std::vector<float>{e0, e1}, {}, 0.05f, drift, dirty)) {
            reanchored.push_back(f);
            e0 = e1 = 0.0f;  // the excursions are measured from the new anchor
        }
        if (dirty[0]) frames.push_back(f);
        CHECK(dirty[1] == 0);
    }
    CHECK(frames == std::vector<int>{2, 3, 6, 7, 10, 11});
    CHECK(reanchored == std::vector<int>{3, 7, 11});
    CHECK(drift.fromAnchor[1] > 0.0f);  // tile 1 carries its drift across the anchors
}

TEST_CASE("gi.anchored_drift: forced tiles, free re-anchoring, tolerance 0 and a second pass on the same inputs") {
    AnchoredDrift drift;
    drift.reset(3);
    std::vector<std::uint8_t> dirty(3);
    const std::vector<std::uint8_t> forced{1, 0, 0};
    // tile 0 forced, tile 1 moved within the tolerance, tile 2 did not move
    CHECK_FALSE(planAnchoredDrift(std::vector<float>{0.2f, 0.01f, 0.0f}, forced, 0.05f, drift, dirty));
    CHECK(dirty == std::vector<std::uint8_t>{1, 0, 0});
    CHECK(drift.fromAnchor == std::vector<float>{0.2f, 0.0f, 0.0f});
    // every tile that moved is recomputed: moving the anchor here costs nothing
    CHECK(planAnchoredDrift(std::vector<float>{0.1f, 0.1f, 0.0f}, {}, 0.05f, drift, dirty));
    CHECK(dirty == std::vector<std::uint8_t>{1, 1, 0});
    CHECK(drift.fromAnchor == std::vector<float>{0.0f, 0.0f, 0.0f});
    // tolerance 0: any excursion recomputes, none keeps
    AnchoredDrift exact;
    exact.reset(2);
    planAnchoredDrift(std::vector<float>{1e-30f, 0.0f}, {}, 0.0f, exact, std::span(dirty).first(2));
    CHECK(dirty[0] == 1);
    CHECK(dirty[1] == 0);
    // the same inputs under a brighter light: the drift counts at the new scale
    AnchoredDrift again;
    again.reset(2);
    std::vector<std::uint8_t> two(2);
    planAnchoredDrift(std::vector<float>{0.03f, 0.01f}, std::vector<std::uint8_t>{0, 1}, 0.05f, again, two);
    CHECK(two == std::vector<std::uint8_t>{0, 1});
    CHECK(markDriftAgain(2.0f, 0.05f, again, two));
    CHECK(two == std::vector<std::uint8_t>{1, 0});  // 0.03 x 2 > 0.05; tile 1 was recomputed from these inputs
    CHECK(again.fromAnchor[0] == 0.03f);
    CHECK_FALSE(markDriftAgain(2.0f, 0.05f, again, two));  // both now at these inputs
}

TEST_CASE("gi.anchored_drift: a change that stays keeps its tiles through the drift from the last frame's inputs") {
    // Pits dropped one a frame and left, at tolerance 0.05. Tile 0 lies by
    // the first, tile 2 by the second, tile 1 far from both. From the anchor
    // (the heights before any pit) tile 0's result, computed with its pit,
    // is 0.08 away, and the change is 0.08 + a far pit's 0.005: 0.165 in all,
    // though since the last frame only the far pit came. Its drift from the
    // last frame's inputs (0) plus that change (0.005) keeps it; the pit
    // tiles vote no anchor move, so the far tile keeps its bounds from the
    // first anchor instead of their sum over re-anchorings.
    const float inf = std::numeric_limits<float>::infinity();
    const auto frame = [&](AnchoredDrift& d, const std::vector<float>& e, const std::vector<float>& since,
                           std::vector<std::uint8_t>& dirty) {
        AnchorVotes votes;
        markAnchoredDrift(e, since, {}, 1.0f, 0.05f, d, dirty, votes);
        advanceAnchoredDrift(e, since, dirty, votes.reanchor(), d);
        return votes.reanchor();
    };
    AnchoredDrift drift;
    drift.reset(3);
    std::vector<std::uint8_t> dirty(3);
    // the first pit: the last frame's inputs are the anchor's (no second path)
    CHECK_FALSE(frame(drift, {0.08f, 0.01f, 0.0f}, {inf, inf, inf}, dirty));
    CHECK(dirty == std::vector<std::uint8_t>{1, 0, 0});
    // the second: tile 0 kept by its drift since the last frame, tile 2 recomputed
    CHECK_FALSE(frame(drift, {0.085f, 0.02f, 0.08f}, {0.005f, 0.015f, 0.08f}, dirty));
    CHECK(dirty == std::vector<std::uint8_t>{0, 0, 1});
    CHECK(drift.fromAnchor == std::vector<float>{0.08f, 0.0f, 0.08f});  // the results the tiles hold
    CHECK(drift.sinceInputs[0] == 0.005f);
    CHECK(drift.sinceInputs[1] == 0.02f);  // the smaller: from the anchor (0 + 0.02), not 0.01 + 0.015
    // a third, far from every tile: nothing recomputed, the anchor stays
    CHECK_FALSE(frame(drift, {0.09f, 0.03f, 0.085f}, {0.005f, 0.01f, 0.005f}, dirty));
    CHECK(dirty == std::vector<std::uint8_t>{0, 0, 0});
    CHECK(drift.sinceInputs[0] == 0.01f);

    // measured from the anchor alone, tile 0 recomputes on the second pit
    // and its growing excursion moves the anchor there
    AnchoredDrift one;
    one.reset(3);
    CHECK_FALSE(frame(one, {0.08f, 0.01f, 0.0f}, {}, dirty));
    CHECK(frame(one, {0.085f, 0.02f, 0.08f}, {}, dirty));
    CHECK(dirty == std::vector<std::uint8_t>{1, 0, 1});
    CHECK(one.fromAnchor[1] == 0.02f);  // the far tile's bounds, summed over the anchors

    // tolerance 0: the second path keeps a tile only when its result is that
    // of the last frame's inputs and nothing within reach changed since
    AnchoredDrift exact;
    exact.reset(2);
    AnchorVotes votes;
    markAnchoredDrift(std::vector<float>{0.1f, 0.0f}, std::vector<float>{inf, inf}, {}, 1.0f, 0.0f, exact,
                      std::span(dirty).first(2), votes);
    advanceAnchoredDrift(std::vector<float>{0.1f, 0.0f}, std::vector<float>{inf, inf}, std::span(dirty).first(2), false,
                         exact);
    markAnchoredDrift(std::vector<float>{0.1f, 0.1f}, std::vector<float>{0.0f, 0.1f}, {}, 1.0f, 0.0f, exact,
                      std::span(dirty).first(2), votes);
    CHECK(dirty[0] == 0);  // recomputed from the last inputs, no change since
    CHECK(dirty[1] == 1);
}
