// The benchmarks' Pareto front (bench/pareto.h): speed-vs-error marks its points with it.
#include <vector>

#include <doctest/doctest.h>

#include "bench/pareto.h"

using terrain::bench::CostAndError;
using terrain::bench::paretoFront;

TEST_CASE("pareto: a point beaten in one and matched in the other is off the front") {
    // (1, 5) and (3, 1) trade; (2, 5) costs more than (1, 5) for the same error;
    // (4, 2) loses to (3, 1) in both; (5, 0.5) is the most accurate
    const std::vector<CostAndError> p{{1, 5}, {2, 5}, {3, 1}, {4, 2}, {5, 0.5}};
    CHECK(paretoFront(p) == std::vector<bool>{true, false, true, false, true});
}

TEST_CASE("pareto: equal points are all on the front, the cheapest and the most accurate always") {
    const std::vector<CostAndError> p{{2, 2}, {2, 2}, {1, 9}, {9, 1}, {3, 3}};
    CHECK(paretoFront(p) == std::vector<bool>{true, true, true, true, false});
    CHECK(paretoFront(std::vector<CostAndError>{}).empty());
    CHECK(paretoFront(std::vector<CostAndError>{{7, 7}}) == std::vector<bool>{true});
}

TEST_CASE("pareto: same cost, the smaller error wins; same error, the smaller cost wins") {
    const std::vector<CostAndError> p{{1, 2}, {1, 3}, {0.5, 3}};
    CHECK(paretoFront(p) == std::vector<bool>{true, false, true});
}
