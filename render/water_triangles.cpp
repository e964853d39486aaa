#include "render/water_triangles.h"

#include <algorithm>

namespace terrain::render {

void markShownWater(const std::vector<float>& heights, std::vector<std::uint8_t>& shown) {
    shown.resize(heights.size() / 2);
    for (std::size_t i = 0; i < shown.size(); ++i) shown[i] = heights[2 * i + 1] >= kShownWaterDepth ? 1 : 0;
}

std::int64_t appendShownTriangles(const std::uint16_t* triangles, std::int64_t count, const MeshPlacement& p,
                                  const std::vector<std::uint8_t>& shown, std::vector<std::uint16_t>& out) {
    auto isShown = [&](std::uint16_t id) {
        const int x = std::min(p.originX + (id % p.row) * p.step, p.nx - 1);
        const int y = std::min(p.originY + (id / p.row) * p.step, p.ny - 1);
        return shown[static_cast<std::size_t>(y) * p.nx + x] != 0;
    };
    const std::size_t before = out.size();
    for (std::int64_t t = 0; t + 2 < count; t += 3) {
        const std::uint16_t* c = triangles + t;
        if (isShown(c[0]) || isShown(c[1]) || isShown(c[2])) out.insert(out.end(), c, c + 3);
    }
    return static_cast<std::int64_t>(out.size() - before);
}

void shownGridTriangles(int nx, int ny, const std::vector<std::uint8_t>& shown, std::vector<std::uint32_t>& out) {
    out.clear();
    for (int y = 0; y + 1 < ny; ++y)
        for (int x = 0; x + 1 < nx; ++x) {
            const std::uint32_t a = static_cast<std::uint32_t>(y * nx + x), b = a + 1,
                                c = a + static_cast<std::uint32_t>(nx), d = c + 1;
            if (shown[a] || shown[d] || shown[b]) out.insert(out.end(), {a, b, d});
            if (shown[a] || shown[d] || shown[c]) out.insert(out.end(), {a, d, c});
        }
}

}  // namespace terrain::render
