#include "gi/indirect_scan_tables.h"

#include <cmath>

#include "core/parallel.h"

namespace terrain::gi {

void loadReceiverRow(const HeightPyramid& pyr, ConstGridView gradX, ConstGridView gradY, int Y, int pad, float* gx,
                     float* gy, float* h0, float* margin) {
    const int s = pyr.subsample, nxr = pyr.nxr;
    const float* hRow = pyr.rawPhaseRow(0, s * Y);
    for (int X = 0; X < pad; ++X) {
        const bool in = X < nxr;
        gx[X] = in ? gradX(s * X, s * Y) : 0.0f;
        gy[X] = in ? gradY(s * X, s * Y) : 0.0f;
        h0[X] = in ? hRow[X] : 0.0f;
        margin[X] = std::fabs(h0[X]) * kHeightMarginRel;
    }
}

void buildIndirectStepTable(const HeightPyramid& pyr, const std::vector<double>& phi, int pad,
                            std::vector<ScanStep>& heightSteps, std::vector<int>& stepsPerColumn,
                            std::vector<int>& stepsPerRow, const RadianceStepFn& radiance) {
    const int m = static_cast<int>(phi.size()), nSteps = static_cast<int>(pyr.steps.size());
    const int nxr = pyr.nxr, nyr = pyr.nyr;
    parallelFor(0, m, 1, [&](int j0, int j1) {
        for (int j = j0; j < j1; ++j) {
            const double c = std::cos(phi[static_cast<std::size_t>(j)]);
            const double sn = std::sin(phi[static_cast<std::size_t>(j)]);
            const std::size_t base = static_cast<std::size_t>(j) * nSteps;
            // a receiver's sequence is its prefix of steps inside the domain
            // (for the heights and the radiance samples alike)
            ValidPrefix prefix(nxr, nyr, pad, stepsPerColumn.data() + static_cast<std::size_t>(j) * pad,
                               stepsPerRow.data() + static_cast<std::size_t>(j) * nyr);
            for (int i = 0; i < nSteps; ++i) {
                const ScanStepInfo h = scanStepInfo(pyr, i, c, sn);
                heightSteps[base + static_cast<std::size_t>(i)] = h.step;
                prefix.narrow(h);
                radiance(i, c, sn, base + static_cast<std::size_t>(i), prefix);
                prefix.commit(i);
            }
        }
    });
}

// The planes share one layout (PackedPyramids::geometry): one step geometry,
// each plane's origin.
void buildGlossyStepTable(const HeightPyramid& pyr, const PackedPyramids& planes, const std::vector<double>& phi,
                          int pad, std::vector<ScanStep>& heightSteps, std::vector<int>& stepsPerColumn,
                          std::vector<int>& stepsPerRow, std::vector<ScanStep>& planeSteps,
                          std::vector<const std::uint16_t*>& planeOrigins) {
    const HeightPyramid& geometry = planes.geometry;
    const auto steps = [&](int i, double c, double sn, std::size_t at, ValidPrefix& prefix) {
        const ScanStepInfo r = scanStepInfo(geometry, i, c, sn);
        planeSteps[at] = r.step;
        const std::uint16_t** origins = planeOrigins.data() + at * static_cast<std::size_t>(planes.count);
        const int level = geometry.steps[static_cast<std::size_t>(i)].level;
        for (int f = 0; f < planes.count; ++f) origins[f] = planes.address(f, level, r.step.field + r.step.offA);
        prefix.narrow(r);
    };
    buildIndirectStepTable(pyr, phi, pad, heightSteps, stepsPerColumn, stepsPerRow, steps);
}

}  // namespace terrain::gi
