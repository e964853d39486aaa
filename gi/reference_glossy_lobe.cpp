#include "gi/reference_glossy_lobe.h"

#include <algorithm>
#include <cmath>

#include "core/parallel.h"
#include "gi/reference.h"
#include "gi/sh.h"

namespace terrain::gi {

double SkyHorizons::at(float px, float py, double phi) const {
    // azimuth: linear between the two tabulated neighbours (periodic)
    double u = phi / (2.0 * kPi) * azimuths - 0.5;
    u -= std::floor(u / azimuths) * azimuths;
    const int a0 = std::min(static_cast<int>(u), azimuths - 1), a1 = (a0 + 1) % azimuths;
    const double fa = u - a0;
    // position: bilinear between the four grid points
    const int x0 = std::clamp(static_cast<int>(px), 0, std::max(nx - 2, 0));
    const int y0 = std::clamp(static_cast<int>(py), 0, std::max(ny - 2, 0));
    const int x1 = std::min(x0 + 1, nx - 1), y1 = std::min(y0 + 1, ny - 1);
    const double fx = std::clamp(static_cast<double>(px) - x0, 0.0, 1.0);
    const double fy = std::clamp(static_cast<double>(py) - y0, 0.0, 1.0);
    const auto corner = [&](int x, int y) {
        const float* s = &slope[(static_cast<std::size_t>(y) * nx + x) * azimuths];
        return (1.0 - fa) * s[a0] + fa * s[a1];
    };
    const double top = (1.0 - fx) * corner(x0, y0) + fx * corner(x1, y0);
    const double bottom = (1.0 - fx) * corner(x0, y1) + fx * corner(x1, y1);
    return (1.0 - fy) * top + fy * bottom;
}

void buildSkyHorizons(ConstGridView heights, float cellSize, int azimuths, SkyHorizons& out) {
    const int nx = heights.nx, ny = heights.ny, M = std::max(azimuths, 1);
    out.nx = nx;
    out.ny = ny;
    out.azimuths = M;
    out.slope.assign(static_cast<std::size_t>(nx) * ny * M, 0.0f);
    double heightMax = -1e300;
    for (int y = 0; y < ny; ++y)
        for (int x = 0; x < nx; ++x) heightMax = std::max(heightMax, static_cast<double>(heights(x, y)));
    std::vector<double> cs(static_cast<std::size_t>(M)), sn(static_cast<std::size_t>(M));
    for (int a = 0; a < M; ++a) {
        const double phi = 2.0 * kPi * (a + 0.5) / M;
        cs[static_cast<std::size_t>(a)] = std::cos(phi);
        sn[static_cast<std::size_t>(a)] = std::sin(phi);
    }
    parallelFor(0, ny, 1, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y)
            for (int x = 0; x < nx; ++x) {
                float* s = &out.slope[(static_cast<std::size_t>(y) * nx + x) * M];
                for (int a = 0; a < M; ++a)
                    s[a] =
                        static_cast<float>(referenceMaxSlope(heights, cellSize, x, y, cs[static_cast<std::size_t>(a)],
                                                             sn[static_cast<std::size_t>(a)], heightMax));
            }
    });
}

bool skyVisible(const SkyHorizons& hz, float px, float py, const double n[3], const double w[3]) {
    if (n[0] * w[0] + n[1] * w[1] + n[2] * w[2] <= 0.0) return false;
    const double horiz = std::sqrt(w[0] * w[0] + w[1] * w[1]);
    if (horiz < 1e-12) return w[2] > 0.0;
    return w[2] > hz.at(px, py, std::atan2(w[1], w[0])) * horiz;
}

void exactLobeRadiance(const SkyHorizons& hz, const ShRgb& lighting, float px, float py, const double n[3],
                       const double r[3], double S, const LobeLayout& layout, double out[3]) {
    double t[3], b[3];
    lobeFrame(r, t, b);
    double acc[3] = {0.0, 0.0, 0.0};
    for (int i = 0; i < layout.rings; ++i)
        for (int j = 0; j < layout.ringDirections(i); ++j) {
            double w[3];
            lobeDirection(r, t, b, S, layout, i, j, w);
            if (!skyVisible(hz, px, py, n, w)) continue;
            double L[3];
            evaluateShRgb(lighting, w[0], w[1], w[2], L);
            for (int c = 0; c < 3; ++c) acc[c] += L[c];
        }
    const double weight = 1.0 / layout.directions();
    for (int c = 0; c < 3; ++c) out[c] = acc[c] * weight;
}

}  // namespace terrain::gi
