#pragma once
// The four grid points about a position and their bilinear weights, for
// reads at points that fall anywhere (the lobe gather's hits).
#include <algorithm>
#include <cmath>
#include <cstddef>

namespace terrain::gi {

/// Grid point i00 (row-major, clamped to the grid), the offsets of its
/// neighbours along x and y (0 along an axis of one point) and the weights.
struct BilinearTap {
    std::size_t i00, dx, dy;
    float w00, w10, w01, w11;
    /// The field v (value of point i at v[i * stride]) at the tap.
    [[gnu::always_inline]] float at(const float* v, std::size_t stride) const {
        return w00 * v[i00 * stride] + w10 * v[(i00 + dx) * stride] + w01 * v[(i00 + dy) * stride] +
               w11 * v[(i00 + dx + dy) * stride];
    }
};

/// The tap of an n x ny grid at (p, q) in its own cells.
[[gnu::always_inline]] inline BilinearTap bilinearTap(int n, int ny, double p, double q) {
    const int ix = std::clamp(static_cast<int>(std::floor(p)), 0, std::max(n - 2, 0));
    const int iy = std::clamp(static_cast<int>(std::floor(q)), 0, std::max(ny - 2, 0));
    const float fx = std::clamp(static_cast<float>(p - ix), 0.0f, 1.0f);
    const float fy = std::clamp(static_cast<float>(q - iy), 0.0f, 1.0f);
    return {static_cast<std::size_t>(iy) * static_cast<std::size_t>(n) + static_cast<std::size_t>(ix),
            n > 1 ? std::size_t{1} : std::size_t{0},
            ny > 1 ? static_cast<std::size_t>(n) : std::size_t{0},
            (1.0f - fx) * (1.0f - fy),
            fx * (1.0f - fy),
            (1.0f - fx) * fy,
            fx * fy};
}

}  // namespace terrain::gi
