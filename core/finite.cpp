#include "core/finite.h"

#include <cmath>

#include "core/error.h"
#include "core/parse.h"

namespace terrain {

bool allFinite(std::span<const float> values) {
    for (float v : values)
        if (!std::isfinite(v)) return false;
    return true;
}

void requireFinite(const Grid& g, const std::string& what) {
    for (std::size_t i = 0; i < g.v.size(); ++i) {
        if (std::isfinite(g.v[i])) continue;
        const std::size_t nx = static_cast<std::size_t>(g.nx > 0 ? g.nx : 1);
        throw InputError(what + " has a non-finite value (" + formatNumber(g.v[i]) +
                         ") at x=" + std::to_string(i % nx) + ", y=" + std::to_string(i / nx));
    }
}

}  // namespace terrain
