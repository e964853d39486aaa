#pragma once
// The Pareto front of points that trade a cost (time) against an error, both
// to be made small: the points no other point beats in one and matches or
// beats in the other. Header-only so that tests/ can check it.
#include <cstddef>
#include <span>
#include <vector>

namespace terrain::bench {

struct CostAndError {
    double cost = 0.0, error = 0.0;
};

/// Whether b dominates a: no worse in both, better in at least one.
inline bool dominates(const CostAndError& b, const CostAndError& a) {
    return b.cost <= a.cost && b.error <= a.error && (b.cost < a.cost || b.error < a.error);
}

/// For each point, whether it is on the front (no point dominates it). Equal
/// points are all on it or all off it. Quadratic: a few dozen points.
inline std::vector<bool> paretoFront(std::span<const CostAndError> points) {
    std::vector<bool> front(points.size(), true);
    for (std::size_t i = 0; i < points.size(); ++i)
        for (const CostAndError& other : points)
            if (dominates(other, points[i])) {
                front[i] = false;
                break;
            }
    return front;
}

}  // namespace terrain::bench
