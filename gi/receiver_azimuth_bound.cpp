#include "gi/receiver_azimuth_bound.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/parallel.h"
#include "gi/visibility.h"

namespace terrain::gi {

void buildChangeLevels(const MaxChangePyramid& dh, const HeightPyramid& pyr, ChangeLevels& out) {
    if (dh.levels.empty() || dh.nx != pyr.nx || dh.ny != pyr.ny)
        throw InputError("change levels: the height change and the pyramid differ in size");
    const HeightPyramid& b = out.bound;
    const bool same = out.valid && b.nx == pyr.nx && b.ny == pyr.ny && b.subsample == pyr.subsample &&
                      b.cellSize == pyr.cellSize && b.settings == pyr.settings;
    const CellBox nonZero = changedCells(dh);
    const CellBox redo = same ? out.built.joined(nonZero) : CellBox{};
    out.valid = false;  // until built
    if (!same || !redo.empty())
        buildHeightPyramid(dh.levels[0].cview(), pyr.cellSize, pyr.subsample, pyr.settings, out.bound, redo);
    out.built = nonZero;
    out.valid = true;
}

namespace {

// One step of one azimuth as the bound reads it: the step's taps into the
// |dh| pyramid and the receivers whose samples lie inside the domain at this
// step and every earlier one (a receiver's valid prefix).
struct BoundStep {
    ScanStep step;
    int x0 = 0, x1 = -1, y0 = 0, y1 = -1;
};

std::vector<BoundStep> boundSteps(const HeightPyramid& b, std::span<const double> phi) {
    const std::size_t nSteps = b.steps.size();
    std::vector<BoundStep> out(phi.size() * nSteps);
    for (std::size_t j = 0; j < phi.size(); ++j) {
        const double c = std::cos(phi[j]), sn = std::sin(phi[j]);
        int x0 = 0, x1 = b.nxr - 1, y0 = 0, y1 = b.nyr - 1;
        for (std::size_t i = 0; i < nSteps; ++i) {
            const ScanStepInfo info = scanStepInfo(b, static_cast<int>(i), c, sn);
            x0 = std::max(x0, info.xFirst);
            x1 = std::min(x1, info.xLast);
            y0 = std::max(y0, info.yFirst);
            y1 = std::min(y1, info.yLast);
            out[j * nSteps + i] = {info.step, x0, x1, y0, y1};
        }
    }
    return out;
}

}  // namespace

void boundSlopeChangePerReceiverAzimuth(const ChangeLevels& levels, const HeightPyramid& pyr,
                                        std::span<const double> phi, const ReceiverTiles* only,
                                        std::vector<float>& out) {
    const HeightPyramid& b = levels.bound;
    if (!levels.valid || b.nx != pyr.nx || b.ny != pyr.ny || b.nxr != pyr.nxr || b.nyr != pyr.nyr ||
        b.steps.size() != pyr.steps.size())
        throw InputError("receiver azimuth bound: the change levels were not built for this pyramid");
    const int nxr = b.nxr, nyr = b.nyr, s = b.subsample;
    const std::size_t m = phi.size(), nSteps = b.steps.size(), planeR = static_cast<std::size_t>(nxr) * nyr;
    out.assign(m * planeR, 0.0f);
    const std::vector<BoundStep> steps = boundSteps(b, phi);
    DirtySpans spans;
    dirtySpans(only, nxr, nyr, spans);
    parallelForRows(RowSpan{0, nyr}, nxr * static_cast<int>(m), [&](int Y0, int Y1) {
        for (int Y = Y0; Y < Y1; ++Y) {
            const float* dh0 = b.rawPhaseRow(0, s * Y);  // |dh| at the receivers' own cells
            for (const ColumnSpan& span : spans.ofRow(Y))
                for (std::size_t j = 0; j < m; ++j) {
                    float* o = out.data() + (j * static_cast<std::size_t>(nyr) + static_cast<std::size_t>(Y)) * nxr;
                    for (std::size_t i = 0; i < nSteps; ++i) {
                        const BoundStep& bs = steps[j * nSteps + i];
                        const int x0 = std::max(span.x0, bs.x0), x1 = std::min(span.x1 - 1, bs.x1);
                        // the valid ranges only shrink: once empty, for good
                        if (Y < bs.y0 || Y > bs.y1 || x0 > x1) break;
                        const ScanStep& st = bs.step;
                        const float wa = st.w[0][0], wb = st.w[1][0], inv = st.w[2][0];
                        const float* fa = st.field + st.offA + static_cast<std::ptrdiff_t>(Y) * st.rowStep;
                        const float* fb = st.field + st.offB + static_cast<std::ptrdiff_t>(Y) * st.rowStep;
                        for (int X = x0; X <= x1; ++X) o[X] = std::max(o[X], (wa * fa[X] + wb * fb[X] + dh0[X]) * inv);
                    }
                }
        }
    });
}

void environmentBoundPerReceiver(std::span<const float> slopeBound, int azimuths, std::span<const float> gradientBound,
                                 float lipschitz, std::vector<float>& out) {
    const std::size_t m = static_cast<std::size_t>(azimuths);
    if (azimuths < 1 || slopeBound.size() % m != 0)
        throw InputError("environmentBoundPerReceiver: one slope bound per receiver and azimuth, at least one azimuth");
    const std::size_t n = slopeBound.size() / m;
    if (gradientBound.size() != n && gradientBound.size() != 1)
        throw InputError("environmentBoundPerReceiver: one gradient bound per receiver, or one for all");
    out.resize(n);
    parallelFor(0, static_cast<int>(n), 4096, [&](int r0, int r1) {
        std::vector<float> perAzimuth(m);
        for (int r = r0; r < r1; ++r) {
            for (std::size_t j = 0; j < m; ++j)
                perAzimuth[j] = lipschitz * slopeBound[j * n + static_cast<std::size_t>(r)];
            const float g = gradientBound.size() == 1 ? gradientBound[0] : gradientBound[static_cast<std::size_t>(r)];
            out[static_cast<std::size_t>(r)] =
                ambientChangeBoundPerAzimuth(perAzimuth.data(), azimuths, g, 1.0f, false);
        }
    });
}

}  // namespace terrain::gi
