#include "gi/radiance_pyramid.h"

#include <algorithm>
#include <cmath>

#include "core/parallel.h"

namespace terrain::gi {

namespace {

// Re-targets the steps of a field's pyramid to the height pyramid's taus: the
// scan walks both with one step index.
void matchSteps(const HeightPyramid& heights, const RadiancePyramidSettings& s, HeightPyramid& p) {
    const int nLevels = static_cast<int>(p.levels.size());
    p.steps.resize(heights.steps.size());
    for (std::size_t i = 0; i < heights.steps.size(); ++i) {
        PyramidStep st = heights.steps[i];
        const int l = static_cast<int>(std::lround(s.levelsPerOctave * std::log2(st.tauCells))) -
                      s.levelsPerOctave * s.levelOffset;
        st.level = l < 0 || nLevels == 0 ? -1 : std::min(l, nLevels - 1);
        p.steps[i] = st;
    }
}

void buildOne(ConstGridView field, const HeightPyramid& heights, const RadiancePyramidSettings& s, HeightPyramid& p) {
    PyramidSettings ps;
    ps.levelsPerOctave = s.levelsPerOctave;
    ps.levelOffset = s.levelOffset;
    ps.peakBlend = 0.0f;  // radiance: plain mean (box + B-spline) filtering
    buildHeightPyramid(field, heights.cellSize, heights.subsample, ps, p);
    matchSteps(heights, s, p);
}

}  // namespace

void buildRadiancePyramid(const std::array<Grid, 3>& radiance, const HeightPyramid& heights,
                          const RadiancePyramidSettings& settings, RadiancePyramid& out) {
    out.fields.resize(3);
    // the channels side by side (each build's own row loops are parallel too)
    parallelFor(0, 3, 1, [&](int c0, int c1) {
        for (int c = c0; c < c1; ++c)
            buildOne(radiance[static_cast<std::size_t>(c)].cview(), heights, settings,
                     out.fields[static_cast<std::size_t>(c)]);
    });
}

void buildScalarPyramids(const float* fields, int count, const HeightPyramid& heights,
                         const RadiancePyramidSettings& settings, RadiancePyramid& out) {
    out.fields.resize(static_cast<std::size_t>(count));
    const std::size_t n = static_cast<std::size_t>(heights.nx) * heights.ny;
    parallelFor(0, count, 1, [&](int c0, int c1) {
        for (int c = c0; c < c1; ++c) {
            const ConstGridView v(fields + n * static_cast<std::size_t>(c), heights.nx, heights.ny, heights.nx);
            buildOne(v, heights, settings, out.fields[static_cast<std::size_t>(c)]);
        }
    });
}

}  // namespace terrain::gi
