#include "gi/radiance_pyramid.h"

#include <algorithm>
#include <cmath>

#include "core/bfloat16.h"
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

void buildOne(ConstGridView field, const HeightPyramid& heights, const RadiancePyramidSettings& s, HeightPyramid& p,
              CellBox changed = {}) {
    PyramidSettings ps;
    ps.levelsPerOctave = s.levelsPerOctave;
    ps.levelOffset = s.levelOffset;
    ps.peakBlend = 0.0f;  // radiance: plain mean (box + B-spline) filtering
    buildHeightPyramid(field, heights.cellSize, heights.subsample, ps, p, changed);
    matchSteps(heights, s, p);
}

}  // namespace

void buildRadiancePyramid(const std::array<Grid, 3>& radiance, const HeightPyramid& heights,
                          const RadiancePyramidSettings& settings, RadiancePyramid& out, CellBox changed) {
    out.fields.resize(3);
    // the channels side by side (each build's own row loops are parallel too)
    parallelFor(0, 3, 1, [&](int c0, int c1) {
        for (int c = c0; c < c1; ++c)
            buildOne(radiance[static_cast<std::size_t>(c)].cview(), heights, settings,
                     out.fields[static_cast<std::size_t>(c)], changed);
    });
}

namespace {

// Field p's pyramid rounded into out's bfloat16 copy of field f.
void packField(const HeightPyramid& p, int f, PackedPyramids& out) {
    const std::size_t regions = p.levels.size() + 1;
    for (std::size_t l = 0; l < regions; ++l) {
        const std::vector<float>& v = l < p.levels.size() ? p.levels[l].v : p.rawPhase;
        packBfloat16(v.data(), v.size(), out.block.data() + out.regionAt[static_cast<std::size_t>(f) * regions + l]);
    }
}

// The block's layout: the regions one after the other, field by field,
// each starting on a cache line.
void layOut(const HeightPyramid& g, int count, PackedPyramids& out) {
    constexpr std::size_t kLine = 32;  // bfloat16 values per 64-byte line
    const std::size_t regions = g.levels.size() + 1;
    out.regionAt.resize(static_cast<std::size_t>(count) * regions);
    std::size_t at = 0;
    for (std::size_t r = 0; r < out.regionAt.size(); ++r) {
        const std::size_t l = r % regions;
        out.regionAt[r] = at;
        at += (l < g.levels.size() ? g.levels[l].v.size() : g.rawPhase.size()) + kLine - 1;
        at -= at % kLine;
    }
    out.block.resize(at);
}

}  // namespace

const std::uint16_t* PackedPyramids::address(int f, int level, const float* p) const {
    const std::size_t regions = geometry.levels.size() + 1;
    const std::size_t l = level < 0 ? regions - 1 : static_cast<std::size_t>(level);
    const float* base = level < 0 ? geometry.rawPhase.data() : geometry.levels[l].v.data();
    return block.data() + regionAt[static_cast<std::size_t>(f) * regions + l] + (p - base);
}

void buildPackedPyramids(const float* fields, int count, const HeightPyramid& heights,
                         const RadiancePyramidSettings& settings, PackedPyramids& out) {
    const std::size_t n = static_cast<std::size_t>(heights.nx) * heights.ny;
    const auto field = [&](int f) {
        return ConstGridView(fields + n * static_cast<std::size_t>(f), heights.nx, heights.ny, heights.nx);
    };
    out.count = count;
    buildOne(field(0), heights, settings, out.geometry);
    layOut(out.geometry, count, out);
    packField(out.geometry, 0, out);
    out.scratch.resize(static_cast<std::size_t>(workerSlots()));
    // the other fields side by side, each built in its thread's scratch (the
    // builds' own row loops are parallel too: isolated, so that no other
    // field starts on this thread meanwhile and takes the same scratch)
    parallelFor(1, count, 1, [&](int f0, int f1) {
        for (int f = f0; f < f1; ++f)
            isolated([&] {
                HeightPyramid& p = out.scratch[static_cast<std::size_t>(workerSlot())];
                buildOne(field(f), heights, settings, p);
                packField(p, f, out);
            });
    });
}

}  // namespace terrain::gi
