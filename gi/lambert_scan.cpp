#include "gi/lambert_scan.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "gi/indirect_scan_tables.h"

namespace terrain::gi {

namespace {

// The field's highest height (the raw heights; the pyramid levels are
// filters of it and so stay below it, up to float rounding: 1e-6 relative slack).
float fieldTopHeight(const HeightPyramid& pyr) {
    float hMax = -std::numeric_limits<float>::infinity();
    for (int y = 0; y < pyr.ny; ++y)
        for (int q = 0; q < pyr.subsample; ++q)
            for (int x = 0; x < pyr.rawPhaseWidth; ++x) hMax = std::max(hMax, pyr.rawPhaseRow(q, y)[x]);
    hMax += std::fabs(hMax) * 1e-6f + 1e-30f;
    return hMax;
}

}  // namespace

LambertScan::LambertScan(const IndirectInputs& in, CastingMoments moments, IndirectState& st)
    : in_(in),
      st_(st),
      moments_(moments),
      castRow_(castRowFor(moments)),
      pad_(indirectRowPad(in.heights.nxr)),
      nSteps_(static_cast<int>(in.heights.steps.size())),
      nBlocks_(std::max(1, (in.heights.nyr + kRowsPerBlock - 1) / kRowsPerBlock)),
      tableSize_(static_cast<std::size_t>(in.op.azimuths) * nSteps_) {}

void LambertScan::beginFrame() {
    const int m = in_.op.azimuths, nyr = in_.heights.nyr;
    st_.blocks.resize(static_cast<std::size_t>(workerSlots()));
    for (IndirectScratch& b : st_.blocks)
        sizeIndirectScratch(b, kRowsPerBlock, pad_, moments_ == CastingMoments::Irradiance);
    hMax_ = fieldTopHeight(in_.heights);
    st_.heightSteps.resize(tableSize_);
    st_.radianceSteps.resize(3 * tableSize_);
    st_.stepsPerColumn.resize(static_cast<std::size_t>(m) * pad_);
    st_.stepsPerRow.resize(static_cast<std::size_t>(m) * nyr);
    dirtySpans(in_.only, in_.heights.nxr, nyr, st_.spans);
}

void LambertScan::buildPyramid(const std::array<Grid, 3>& exit, const RadiancePyramidSettings& settings) {
    buildRadiancePyramid(exit, in_.heights, settings, st_.radiance);
}

void LambertScan::buildStepTable() {
    const auto channelSteps = [&](int i, double c, double sn, std::size_t at, ValidPrefix& prefix) {
        for (int ch = 0; ch < 3; ++ch) {
            const ScanStepInfo r = scanStepInfo(st_.radiance.fields[static_cast<std::size_t>(ch)], i, c, sn);
            st_.radianceSteps[static_cast<std::size_t>(ch) * tableSize_ + at] = r.step;
            prefix.narrow(r);
        }
    };
    buildIndirectStepTable(in_.heights, in_.op.phi, pad_, st_.heightSteps, st_.stepsPerColumn, st_.stepsPerRow,
                           channelSteps);
}

RowBlock LambertScan::rowBlock(int block) const {
    const int yBegin = block * kRowsPerBlock;
    return {yBegin, std::min(kRowsPerBlock, in_.heights.nyr - yBegin)};
}

bool LambertScan::hasWork(const RowBlock& rb) const {
    for (int r = 0; r < rb.rows; ++r)
        if (!spans(rb.yBegin + r).empty()) return true;
    return false;
}

void LambertScan::loadRows(const RowBlock& rb, IndirectScratch& sc) const {
    for (int r = 0; r < rb.rows; ++r) {
        const std::size_t ro = static_cast<std::size_t>(r) * pad_;
        loadReceiverRow(in_.heights, in_.gradX, in_.gradY, rb.yBegin + r, pad_, sc.gx.data() + ro, sc.gy.data() + ro,
                        sc.h0.data() + ro, sc.margin.data() + ro);
    }
}

AzimuthSteps LambertScan::azimuth(int j) const {
    const std::size_t base = static_cast<std::size_t>(j) * nSteps_;
    const double phi = in_.op.phi[static_cast<std::size_t>(j)];
    return {st_.heightSteps.data() + base,
            {st_.radianceSteps.data() + base, st_.radianceSteps.data() + tableSize_ + base,
             st_.radianceSteps.data() + 2 * tableSize_ + base},
            st_.stepsPerColumn.data() + static_cast<std::size_t>(j) * pad_,
            static_cast<float>(std::cos(phi)),
            static_cast<float>(std::sin(phi))};
}

void LambertScan::castRow(const AzimuthSteps& az, int j, int Y, int r, IndirectScratch& sc) const {
    const std::size_t ro = static_cast<std::size_t>(r) * pad_;
    const int rowSteps = st_.stepsPerRow[static_cast<std::size_t>(j) * in_.heights.nyr + static_cast<std::size_t>(Y)];
    const ReceiverRow row{
        Y, rowSteps, spans(Y), sc.h0.data() + ro, sc.margin.data() + ro, sc.gx.data() + ro, sc.gy.data() + ro, hMax_};
    castRow_(az, row, sc, pad_);
}

}  // namespace terrain::gi
