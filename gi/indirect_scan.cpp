#include "gi/indirect_scan.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "gi/glossy_exit_radiance.h"
#include "gi/indirect_scan_tables.h"

namespace terrain::gi {

namespace {

// The field's highest height (the raw heights; the pyramid levels are
// filters of it and so stay below it, up to float rounding: 1e-6 relative
// slack). Each block of rows keeps its highest height in `blocks`, which
// holds those of build `ofBuild`: when this pyramid redid rows of that
// build, only the blocks holding them are redone (a maximum is exact, so
// the value is that of a whole pass, and rows in parallel give it too).
float fieldTopHeight(const HeightPyramid& pyr, std::vector<float>& blocks, std::uint64_t& ofBuild) {
    constexpr int kRowsPerTopBlock = 32;
    constexpr float kNone = -std::numeric_limits<float>::infinity();
    const int nBlocks = (pyr.ny + kRowsPerTopBlock - 1) / kRowsPerTopBlock;
    RowSpan redo{0, pyr.ny};
    if (ofBuild != 0 && blocks.size() == static_cast<std::size_t>(nBlocks)) {
        if (ofBuild == pyr.buildId) redo = {0, 0};
        if (ofBuild == pyr.basedOn) redo = pyr.rawRowsRedone.cut(pyr.ny);
    }
    blocks.resize(static_cast<std::size_t>(nBlocks));
    ofBuild = 0;  // until the blocks are redone
    const int b0 = redo.y0 / kRowsPerTopBlock;
    const int b1 = redo.y1 > redo.y0 ? (redo.y1 + kRowsPerTopBlock - 1) / kRowsPerTopBlock : b0;
    parallelFor(b0, b1, 1, [&](int first, int last) {
        for (int b = first; b < last; ++b) {
            float m = kNone;
            for (int y = b * kRowsPerTopBlock; y < std::min(pyr.ny, (b + 1) * kRowsPerTopBlock); ++y)
                for (int q = 0; q < pyr.subsample; ++q)
                    for (int x = 0; x < pyr.rawPhaseWidth; ++x) m = std::max(m, pyr.rawPhaseRow(q, y)[x]);
            blocks[static_cast<std::size_t>(b)] = m;
        }
    });
    ofBuild = pyr.buildId;
    float hMax = kNone;
    for (const float m : blocks) hMax = std::max(hMax, m);
    hMax += std::fabs(hMax) * 1e-6f + 1e-30f;
    return hMax;
}

}  // namespace

IndirectScan::IndirectScan(const IndirectInputs& in, CastingMoments moments, IndirectState& st)
    : in_(in),
      st_(st),
      moments_(moments),
      castRows_(castRowsFor(moments)),
      pad_(indirectRowPad(in.heights.nxr)),
      nSteps_(static_cast<int>(in.heights.steps.size())),
      nBlocks_(std::max(1, (in.heights.nyr + kRowsPerBlock - 1) / kRowsPerBlock)),
      tableSize_(static_cast<std::size_t>(in.op.azimuths) * nSteps_) {}

void IndirectScan::beginFrame() {
    const int m = in_.op.azimuths, nyr = in_.heights.nyr;
    st_.blocks.resize(static_cast<std::size_t>(workerSlots()));
    for (IndirectScratch& b : st_.blocks)
        sizeIndirectScratch(b, kRowsPerBlock, pad_, moments_ == CastingMoments::Irradiance);
    hMax_ = fieldTopHeight(in_.heights, st_.topOfRows, st_.topOfBuild);
    st_.heightSteps.resize(tableSize_);
    if (moments_ == CastingMoments::GlossyNlp) {
        st_.glossy.steps.resize(tableSize_);
        st_.glossy.fields.resize(tableSize_ * kGlossyFields);
    } else {
        st_.radianceSteps.resize(3 * tableSize_);
    }
    st_.distanceGroups.resize(static_cast<std::size_t>(nSteps_));
    for (int i = 0; i < nSteps_; ++i)
        st_.distanceGroups[static_cast<std::size_t>(i)] =
            static_cast<std::uint8_t>(distanceGroup(in_.heights.steps[static_cast<std::size_t>(i)].tauCells));
    st_.stepsPerColumn.resize(static_cast<std::size_t>(m) * pad_);
    st_.stepsPerRow.resize(static_cast<std::size_t>(m) * nyr);
    dirtySpans(in_.only, in_.heights.nxr, nyr, st_.spans);
    blocksWithRows(
        nBlocks_,
        [&](int block) {
            const RowBlock rb = rowBlock(block);
            return RowSpan{rb.yBegin, rb.yBegin + rb.rows};
        },
        [&](int Y) { return !spans(Y).empty(); }, st_.blocksWithWork);
}

void IndirectScan::buildPyramid(const BounceSource& source, const RadiancePyramidSettings& settings) {
    st_.radianceOfDirect = false;  // until a build of bounce 0 is whole
    buildRadiancePyramid(*source.rgb, in_.heights, settings, st_.radiance, source.directChanged.value_or(CellBox{}));
    st_.radianceOfDirect = source.directChanged.has_value();
}

void IndirectScan::buildStepTable() {
    if (moments_ == CastingMoments::GlossyNlp) return buildGlossyStepTable();
    // the tables are a function of the pyramids' layout and the azimuths
    // (StepTableKey): kept while those are the same, across frames
    std::vector<StepTableKey> key{stepTableKey(in_.heights, in_.op.phi, pad_)};
    for (const HeightPyramid& f : st_.radiance.fields) key.push_back(stepTableKey(f, in_.op.phi, pad_));
    if (key == st_.radianceTableKey) return;
    st_.radianceTableKey.clear();  // not valid until built
    const auto channelSteps = [&](int i, double c, double sn, std::size_t at, ValidPrefix& prefix) {
        for (int ch = 0; ch < 3; ++ch) {
            const ScanStepInfo r = scanStepInfo(st_.radiance.fields[static_cast<std::size_t>(ch)], i, c, sn);
            st_.radianceSteps[static_cast<std::size_t>(ch) * tableSize_ + at] = r.step;
            prefix.narrow(r);
        }
    };
    buildIndirectStepTable(in_.heights, in_.op.phi, pad_, st_.heightSteps, st_.stepsPerColumn, st_.stepsPerRow,
                           channelSteps);
    st_.radianceTableKey = std::move(key);
}

// The exit-radiance planes' steps (IndirectState::glossy's pyramid).
void IndirectScan::buildGlossyStepTable() {
    st_.radianceTableKey.clear();  // the height tables are the glossy planes' now
    GlossyIndirectState& gs = st_.glossy;
    gi::buildGlossyStepTable(in_.heights, gs.pyramid, in_.op.phi, pad_, st_.heightSteps, st_.stepsPerColumn,
                             st_.stepsPerRow, gs.steps, gs.fields);
}

RowBlock IndirectScan::rowBlock(int block) const {
    const int yBegin = block * kRowsPerBlock;
    return {yBegin, std::min(kRowsPerBlock, in_.heights.nyr - yBegin)};
}

void IndirectScan::loadRows(const RowBlock& rb, IndirectScratch& sc) const {
    for (int r = 0; r < rb.rows; ++r) {
        const std::size_t ro = static_cast<std::size_t>(r) * pad_;
        loadReceiverRow(in_.heights, in_.gradX, in_.gradY, rb.yBegin + r, pad_, sc.gx.data() + ro, sc.gy.data() + ro,
                        sc.h0.data() + ro, sc.margin.data() + ro);
    }
}

AzimuthSteps IndirectScan::azimuth(int j, bool clampNegative, bool distanceGroups) const {
    const std::size_t base = static_cast<std::size_t>(j) * nSteps_;
    const double phi = in_.op.phi[static_cast<std::size_t>(j)];
    AzimuthSteps az{st_.heightSteps.data() + base,
                    {},
                    st_.stepsPerColumn.data() + static_cast<std::size_t>(j) * pad_,
                    static_cast<float>(std::cos(phi)),
                    static_cast<float>(std::sin(phi))};
    if (moments_ == CastingMoments::GlossyNlp) {
        az.glossy = st_.glossy.steps.data() + base;
        az.glossyFields = st_.glossy.fields.data() + base * kGlossyFields;
        az.clampNegative = clampNegative;
        return az;
    }
    for (std::size_t c = 0; c < 3; ++c) az.radiance[c] = st_.radianceSteps.data() + c * tableSize_ + base;
    if (distanceGroups && moments_ == CastingMoments::Irradiance) az.distanceGroups = st_.distanceGroups.data();
    return az;
}

void IndirectScan::castRows(const AzimuthSteps& az, int j, const RowBlock& rb, IndirectScratch& sc) const {
    std::array<ReceiverRow, kRowsPerBlock> rows;
    for (int r = 0; r < rb.rows; ++r) {
        const int Y = rb.yBegin + r;
        const std::size_t ro = static_cast<std::size_t>(r) * pad_;
        const int rowSteps =
            st_.stepsPerRow[static_cast<std::size_t>(j) * in_.heights.nyr + static_cast<std::size_t>(Y)];
        rows[static_cast<std::size_t>(r)] = {
            Y,    rowSteps, spans(Y), sc.h0.data() + ro, sc.margin.data() + ro, sc.gx.data() + ro, sc.gy.data() + ro,
            hMax_};
    }
    castRows_(az, std::span<const ReceiverRow>(rows.data(), static_cast<std::size_t>(rb.rows)), sc);
}

}  // namespace terrain::gi
