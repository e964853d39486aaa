#pragma once
// The spread the results files give beside each median timing.
#include <algorithm>
#include <cstddef>
#include <vector>

namespace terrain::bench {

/// A sample of repeated timings: its median and, for its spread, the first
/// and third quartiles (linear between the order statistics at p (n - 1),
/// p = 1/4, 1/2 and 3/4; all 0 for no sample).
struct Spread {
    double median = 0.0, q1 = 0.0, q3 = 0.0;
    double iqr() const { return q3 - q1; }
};

inline Spread spreadOf(std::vector<double> v) {
    if (v.empty()) return {};
    std::sort(v.begin(), v.end());
    const auto quantile = [&](double p) {
        const double at = p * static_cast<double>(v.size() - 1);
        const auto i = static_cast<std::size_t>(at);
        const double f = at - static_cast<double>(i);
        return i + 1 < v.size() ? v[i] + f * (v[i + 1] - v[i]) : v[i];
    };
    return {quantile(0.5), quantile(0.25), quantile(0.75)};
}

}  // namespace terrain::bench
