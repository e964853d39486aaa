#include "gi/sky_view.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/error.h"
#include "core/parallel.h"
#include "gi/reference.h"
#include "gi/shading.h"

namespace terrain::gi {

namespace {

// sin(max(0, atan t)) for a horizon slope t.
double sinOfRaisedSlope(double t) { return t > 0.0 ? t / std::sqrt(1.0 + t * t) : 0.0; }

}  // namespace

void skyViewFactor(const VisibilityField& env, int subsample, int nx, int ny, Grid& out) {
    const int s = subsample, nxr = env.nxr, nyr = env.nyr;
    const std::size_t plane = static_cast<std::size_t>(nxr) * nyr;
    if (s < 1 || nxr != (nx + s - 1) / s || nyr != (ny + s - 1) / s || plane == 0 || env.maxSlope.size() % plane != 0)
        throw InputError("sky-view factor: the horizons are not of this grid and sub-sampling");
    const int m = static_cast<int>(env.maxSlope.size() / plane);
    out.resize(nx, ny);
    parallelForRows(ny, nx * m, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) {
            const ReceiverLerp ry = receiverLerp(y, s, nyr);
            for (int x = 0; x < nx; ++x) {
                const ReceiverLerp rx = receiverLerp(x, s, nxr);
                double sum = 0.0;
                for (int j = 0; j < m; ++j) {
                    const float* t = env.maxSlope.data() + static_cast<std::size_t>(j) * plane;
                    // raised to 0 before the blend: "nothing blocks" is a huge negative slope
                    auto at = [&](int X, int Y) { return std::max(0.0f, t[static_cast<std::size_t>(Y) * nxr + X]); };
                    const float a = at(rx.i0, ry.i0) + rx.f * (at(rx.i1, ry.i0) - at(rx.i0, ry.i0));
                    const float b = at(rx.i0, ry.i1) + rx.f * (at(rx.i1, ry.i1) - at(rx.i0, ry.i1));
                    sum += sinOfRaisedSlope(s == 1 ? at(x, y) : a + ry.f * (b - a));
                }
                out(x, y) = static_cast<float>(1.0 - sum / m);
            }
        }
    });
}

void referenceSkyViewFactor(ConstGridView heights, float cellSize, int azimuths, Grid& out) {
    if (azimuths < 1) throw InputError("sky-view factor: at least one azimuth");
    const int nx = heights.nx, ny = heights.ny;
    double heightMax = -HUGE_VAL;
    for (int y = 0; y < ny; ++y)
        for (int x = 0; x < nx; ++x) heightMax = std::max(heightMax, static_cast<double>(heights(x, y)));
    std::vector<double> cosPhi(static_cast<std::size_t>(azimuths)), sinPhi(cosPhi.size());
    for (int j = 0; j < azimuths; ++j) {
        const double phi = 2.0 * kPi * (j + 0.5) / azimuths;
        cosPhi[static_cast<std::size_t>(j)] = std::cos(phi);
        sinPhi[static_cast<std::size_t>(j)] = std::sin(phi);
    }
    out.resize(nx, ny);
    parallelForRows(ny, nx * azimuths, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y)
            for (int x = 0; x < nx; ++x) {
                double sum = 0.0;
                for (std::size_t j = 0; j < cosPhi.size(); ++j)
                    sum +=
                        sinOfRaisedSlope(referenceMaxSlope(heights, cellSize, x, y, cosPhi[j], sinPhi[j], heightMax));
                out(x, y) = static_cast<float>(1.0 - sum / azimuths);
            }
    });
}

}  // namespace terrain::gi
