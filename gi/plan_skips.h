#pragma once
// When an incremental frame stops planning tiles. A plan (the bounds of
// gi/visibility_cache.h or gi/indirect_cache.h) pays off by the tiles it
// keeps; on a terrain that changes everywhere (rain on an eroding terrain)
// it keeps few, and a run of frames then recomputes everything without one.
#include <algorithm>

namespace terrain::gi {

/// A plan that finds at least this share of the tiles dirty has cost more
/// than it saved: its bounds cost a large part of the pass it restricts
/// (README, "Global illumination: incremental frames"), and the tiles it
/// keeps save only their share of the pass.
inline constexpr double kMostlyDirty = 0.75;

/// After such a plan the next frames recompute everything without computing
/// the bounds: a terrain that changes everywhere (rain on an eroding
/// terrain) would dirty most tiles again, and the bounds would only add
/// their cost. kFramesWithoutPlan frames after the first such plan, and
/// after each next one in a row twice as many plus one, up to
/// kMostFramesWithoutPlan; a plan that keeps more tiles starts again from
/// kFramesWithoutPlan, and a frame whose inputs did not change ends the run
/// (the terrain stopped changing everywhere; runGiFrame). Recomputing is
/// always within the tolerance, and the choice depends on the frames alone
/// (deterministic).
inline constexpr int kFramesWithoutPlan = 7;
inline constexpr int kMostFramesWithoutPlan = 31;

/// A plan refines its tiles' bounds per receiver (walks over the change,
/// gi/receiver_azimuth_bound.h) only where the tiles' own bounds leave at
/// most this share of them to recompute: a receiver's walk costs about as
/// much as the scan it may spare it (and the change's pyramid as a partial
/// pyramid build), so it pays where few tiles are left. Where most are
/// (rain-fed `erosion`, every frame), refining the visibility's tiles made
/// the 300-frame run at 256² 108.5 % of full frames' time instead of 102 %.
inline constexpr double kRefineAtMost = 0.5;

/// The frames without a plan of one cache that plans tiles.
struct PlanSkips {
    int left = 0;    // frames left that recompute everything unplanned
    int length = 0;  // of the last run of them, 0 after a plan that kept enough tiles
};

/// Whether this frame skips its plan (and counts it down).
inline bool skipsPlan(PlanSkips& s) {
    if (s.left == 0) return false;
    --s.left;
    return true;
}

/// After a plan that found `dirty` of `tiles` dirty: the next run of frames
/// without a plan, if any.
inline void countAfterPlan(int dirty, int tiles, PlanSkips& s) {
    if (static_cast<double>(dirty) < kMostlyDirty * tiles) {
        s.length = 0;
        return;
    }
    s.length = s.length == 0 ? kFramesWithoutPlan : std::min(kMostFramesWithoutPlan, 2 * s.length + 1);
    s.left = s.length;
}

}  // namespace terrain::gi
