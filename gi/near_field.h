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

/// One step's sample rows for texel row y, and the texels [x0, x1) of a
/// range whose sample lies inside the field (none when its rows do not).
struct NearFieldSampleRows {
    const float* hA = nullptr;
    const float* hB = nullptr;
    float wA = 0.0f, wB = 0.0f, inv = 0.0f;
    int x0 = 0, x1 = 0;
};
inline NearFieldSampleRows nearFieldSampleRows(ConstGridView heights, int y, const NearFieldStep& st, int xBegin,
                                               int xEnd) {
    NearFieldSampleRows r{.x0 = xBegin, .x1 = xBegin};
    if (std::min(y + st.ay, y + st.by) < 0 || std::max(y + st.ay, y + st.by) >= heights.ny) return r;
    r.hA = heights.row(y + st.ay) + st.ax;
    r.hB = heights.row(y + st.by) + st.bx;
    r.wA = st.wA;
    r.wB = st.wB;
    r.inv = st.invTau;
    r.x0 = std::max({xBegin, -st.ax, -st.bx});
    r.x1 = std::max(r.x0, std::min({xEnd, heights.nx - st.ax, heights.nx - st.bx}));
    return r;
}

/// horizon[x] = max(horizon[x], the step's slope) over [x0, x1); h0 the texels' row.
[[gnu::always_inline]] inline void raiseByStep(const float* h0, const NearFieldSampleRows& r, float* horizon, int x0,
                                               int x1) {
    for (int x = x0; x < x1; ++x) {
        const float slope = (r.wA * r.hA[x] + r.wB * r.hB[x] - h0[x]) * r.inv;
        horizon[x] = horizon[x] > slope ? horizon[x] : slope;
    }
}

/// raiseByStep with r, then with q, in one pass (the horizon read and written once).
[[gnu::always_inline]] inline void raiseByStepPair(const float* h0, const NearFieldSampleRows& r,
                                                   const NearFieldSampleRows& q, float* horizon, int x0, int x1) {
    for (int x = x0; x < x1; ++x) {
        const float slopeR = (r.wA * r.hA[x] + r.wB * r.hB[x] - h0[x]) * r.inv;
        const float slopeQ = (q.wA * q.hA[x] + q.wB * q.hB[x] - h0[x]) * q.inv;
        const float raised = horizon[x] > slopeR ? horizon[x] : slopeR;
        horizon[x] = raised > slopeQ ? raised : slopeQ;
    }
}

/// Raises horizon[x] (blocking slopes of texel row y along one azimuth, nx
/// floats) to the texels' own slopes at that azimuth's `steps` (those whose
/// sample lies inside the field), over the texels [xBegin, xEnd) (default:
/// the row), each texel's steps in their order. Steps go two at a time
/// where both samples lie inside (the horizons' reads and writes were a
/// tenth of the exact ambient at 2x), one at a time at the edges.
/// Element-wise float arithmetic: the same bits whatever vector width the
/// compiler gives it.
[[gnu::always_inline]] inline void raiseToNearField(ConstGridView heights, int y, std::span<const NearFieldStep> steps,
                                                    float* horizon, int xBegin = 0, int xEnd = -1) {
    if (xEnd < 0) xEnd = heights.nx;
    const float* h0 = heights.row(y);
    for (std::size_t k = 0; k < steps.size(); k += 2) {
        const NearFieldSampleRows r = nearFieldSampleRows(heights, y, steps[k], xBegin, xEnd);
        if (k + 1 == steps.size()) {
            raiseByStep(h0, r, horizon, r.x0, r.x1);
            break;
        }
        const NearFieldSampleRows q = nearFieldSampleRows(heights, y, steps[k + 1], xBegin, xEnd);
        // [both0, both1): the texels both samples reach; outside it at most one does
        const int both0 = std::max(r.x0, q.x0), both1 = std::max(both0, std::min(r.x1, q.x1));
        raiseByStep(h0, r, horizon, r.x0, std::min(r.x1, both0));
        raiseByStep(h0, q, horizon, q.x0, std::min(q.x1, both0));
        raiseByStepPair(h0, r, q, horizon, both0, both1);
        raiseByStep(h0, r, horizon, std::max(r.x0, both1), r.x1);
        raiseByStep(h0, q, horizon, std::max(q.x0, both1), q.x1);
    }
}

}  // namespace terrain::gi
