#include "gi/sky_view.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/error.h"
#include "core/parallel.h"
#include "gi/near_field.h"
#include "gi/reference.h"
#include "gi/shading.h"

namespace terrain::gi {

namespace {

// sin(max(0, atan t)) for a horizon slope t.
double sinOfRaisedSlope(double t) { return t > 0.0 ? t / std::sqrt(1.0 + t * t) : 0.0; }

}  // namespace

void skyViewFactor(const GiState& st, ConstGridView heights, Grid& out) {
    const VisibilityField& env = st.envVisibility;
    const int s = st.pyramid.subsample, nx = heights.nx, ny = heights.ny, nxr = env.nxr;
    const std::size_t plane = static_cast<std::size_t>(nxr) * env.nyr;
    const int m = static_cast<int>(st.envCosSin.size() / 2);
    if (s < 1 || st.gradX.nx != nx || st.gradX.ny != ny || nxr != (nx + s - 1) / s || env.nyr != (ny + s - 1) / s ||
        plane == 0 || env.maxSlope.size() != plane * m)
        throw InputError("sky-view factor: the state holds no frame of these heights");
    std::vector<NearFieldStep> near;
    buildNearFieldSteps(st.envCosSin, s, st.pyramid.cellSize, near);
    out.resize(nx, ny);
    std::vector<ReceiverLerp> columns;
    receiverLerps(nx, s, nxr, columns);
    parallelForRows(ny, nx * m, [&](int y0, int y1) {
        std::vector<float> horizon(static_cast<std::size_t>(nx));
        std::vector<double> sum(static_cast<std::size_t>(nx));
        for (int y = y0; y < y1; ++y) {
            const ReceiverLerp ry = receiverLerp(y, s, env.nyr);
            std::fill(sum.begin(), sum.end(), 0.0);
            for (int j = 0; j < m; ++j) {
                const float* t = env.maxSlope.data() + static_cast<std::size_t>(j) * plane;
                // raised to 0 before the blend: "nothing blocks" is a huge negative slope
                auto at = [&](int X, int Y) { return std::max(0.0f, t[static_cast<std::size_t>(Y) * nxr + X]); };
                for (int x = 0; x < nx; ++x) {
                    const ReceiverLerp& rx = columns[static_cast<std::size_t>(x)];
                    const float a = at(rx.i0, ry.i0) + rx.f * (at(rx.i1, ry.i0) - at(rx.i0, ry.i0));
                    const float b = at(rx.i0, ry.i1) + rx.f * (at(rx.i1, ry.i1) - at(rx.i0, ry.i1));
                    horizon[static_cast<std::size_t>(x)] = s == 1 ? at(x, y) : a + ry.f * (b - a);
                }
                if (s > 1)
                    raiseToNearField(heights, y,
                                     {near.data() + static_cast<std::size_t>(j) * s, static_cast<std::size_t>(s)},
                                     horizon.data());
                for (int x = 0; x < nx; ++x)
                    sum[static_cast<std::size_t>(x)] += sinOfRaisedSlope(horizon[static_cast<std::size_t>(x)]);
            }
            for (int x = 0; x < nx; ++x) out(x, y) = static_cast<float>(1.0 - sum[static_cast<std::size_t>(x)] / m);
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
