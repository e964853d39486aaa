#pragma once
// The near field of sub-sampled texels. With sub-sampling s the receivers'
// scans start one receiver spacing out (gi/pyramid.h), so their horizons,
// interpolated to the texels between them (Fig. 7 of Nowrouzezahrai & Snyder
// 2009), miss what lies within s cells of such a texel: a gully one cell wide
// between two receivers on its rims is open sky to both. Each texel takes its
// own blocking slopes at the first s crossings of each azimuth's ray with the
// grid lines across the ray's major axis (at distance k / |major component|
// cells, k = 1..s, where the bilinear field is linear between two texels, as
// the scan samples) and keeps the highest.
#include <algorithm>
#include <span>
#include <vector>

#include "core/grid.h"

namespace terrain::gi {

/// One near-field sample of texel (x, y) along one azimuth:
/// wA h(x + ax, y + ay) + wB h(x + bx, y + by) at distance 1 / invTau metres.
struct NearFieldStep {
    int ax = 0, ay = 0, bx = 0, by = 0;
    float wA = 1.0f, wB = 0.0f, invTau = 0.0f;
};

/// The samples of every azimuth (cosSin: cos, sin pairs): azimuths x s steps.
void buildNearFieldSteps(std::span<const float> cosSin, int subsample, float cellSize, std::vector<NearFieldStep>& out);

/// Raises horizon[x] (blocking slopes of texel row y along one azimuth, nx
/// floats) to the texels' own slopes at that azimuth's `steps` (those whose
/// sample lies inside the field), over the texels [xBegin, xEnd) (default:
/// the row). Element-wise float arithmetic: the same bits whatever vector
/// width the compiler gives it.
[[gnu::always_inline]] inline void raiseToNearField(ConstGridView heights, int y, std::span<const NearFieldStep> steps,
                                                    float* horizon, int xBegin = 0, int xEnd = -1) {
    const int nx = heights.nx, ny = heights.ny;
    const float* h0 = heights.row(y);
    for (const NearFieldStep& st : steps) {
        if (std::min(y + st.ay, y + st.by) < 0 || std::max(y + st.ay, y + st.by) >= ny) continue;
        const int x0 = std::max({xBegin, -st.ax, -st.bx});
        const int x1 = std::min({xEnd < 0 ? nx : xEnd, nx - st.ax, nx - st.bx});
        const float* hA = heights.row(y + st.ay) + st.ax;
        const float* hB = heights.row(y + st.by) + st.bx;
        const float wA = st.wA, wB = st.wB, inv = st.invTau;
        for (int x = x0; x < x1; ++x) {
            const float slope = (wA * hA[x] + wB * hB[x] - h0[x]) * inv;
            horizon[x] = horizon[x] > slope ? horizon[x] : slope;
        }
    }
}

}  // namespace terrain::gi
