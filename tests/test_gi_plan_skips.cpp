// gi/plan_skips: after plans that keep few tiles, runs of frames recompute
// everything without a plan, growing while such plans follow one another.
#include <algorithm>

#include <doctest/doctest.h>

#include "gi/plan_skips.h"

using namespace terrain::gi;

TEST_CASE("gi.plan_skips: runs without a plan after mostly dirty plans, growing while they last") {
    PlanSkips s;
    countAfterPlan(74, 100, s);  // kept more than a quarter: plan again
    CHECK(s.left == 0);
    CHECK(!skipsPlan(s));
    int expected = kFramesWithoutPlan;
    for (int run = 0; run < 5; ++run) {
        countAfterPlan(75, 100, s);
        CHECK(s.left == expected);
        for (int k = 0; k < expected; ++k) CHECK(skipsPlan(s));
        CHECK(!skipsPlan(s));
        expected = std::min(kMostFramesWithoutPlan, 2 * expected + 1);
    }
    CHECK(s.length == kMostFramesWithoutPlan);
    countAfterPlan(10, 100, s);  // a plan that kept most tiles
    CHECK(s.length == 0);
    CHECK(s.left == 0);
    countAfterPlan(100, 100, s);
    CHECK(s.left == kFramesWithoutPlan);
}
