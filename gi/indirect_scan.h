#pragma once
// The casting-set scan of the indirect strategies (gi/indirect_sh_kernel.h,
// gi/indirect_blocker_radiance.h): per bounce the previous bounce's radiance
// pyramid (RGB; with CastingMoments::GlossyNlp the 48 planes of the
// exit-radiance SH vectors, IndirectState::glossy, which the strategy
// builds), the step table of heights and radiance, and the casting-set
// kernel (gi/casting_set_scan.h) row by row.
//
// Schedule: like gi/visibility: a per-bounce step table, fixed blocks of
// kRowsPerBlock receiver rows in parallel; within a block azimuth by azimuth,
// the block's rows walking the steps together (gi/casting_set_scan.h),
// every receiver written by one block: bit-identical for any thread count; no allocation after the first
// frame of a given size and settings.
//
// Receiver tiles (IndirectInputs::only): rows are scanned over their dirty
// column spans only (spans(Y)), blocks without any skipped
// (forEachBlockWithWork); each
// scanned receiver gets the bits of a full scan.
#include <array>
#include <cstddef>
#include <span>
#include <vector>

#include "core/grid.h"
#include "core/parallel.h"
#include "gi/casting_set_scan.h"
#include "gi/indirect_bounces.h"
#include "gi/indirect_inputs.h"
#include "gi/indirect_state.h"
#include "gi/radiance_pyramid.h"
#include "gi/receiver_tiles.h"

namespace terrain::gi {

/// The receiver rows of one block: [yBegin, yBegin + rows).
struct RowBlock {
    int yBegin, rows;
};

class IndirectScan {
public:
    static constexpr int kRowsPerBlock = kMaxScanRows;

    /// A scan that sums `moments` over the casting sets, in st's buffers.
    IndirectScan(const IndirectInputs& in, CastingMoments moments, IndirectState& st);

    /// Sizes the step tables and the scratch of each worker slot
    /// (IndirectScratch::irradiance with CastingMoments::Irradiance), finds the
    /// field's highest height and the receiver spans to scan (InputError:
    /// tiles of another receiver grid).
    void beginFrame();
    /// The RGB radiance pyramid of the previous bounce's exit radiance (Section 5.3;
    /// not with GlossyNlp).
    /// The RGB radiance pyramid of `source`, over the texels its
    /// directChanged names where that is set (the state's pyramid is then the
    /// last call's bounce 0, IndirectState::radianceOfDirect).
    void buildPyramid(const BounceSource& source, const RadiancePyramidSettings& settings);
    /// The bounce's step table: height and radiance steps, valid prefixes
    /// (GlossyNlp: of IndirectState::glossy's pyramid).
    void buildStepTable();

    /// fn(block) for each block with a span to scan (beginFrame finds them),
    /// in parallel: only those are handed out, so that a few dirty tiles'
    /// blocks are shared among the threads rather than falling to one of
    /// them with the field's empty blocks around them.
    template <class Fn>
    void forEachBlockWithWork(Fn&& fn) const {
        parallelForEach(st_.blocksWithWork, std::forward<Fn>(fn));
    }
    /// The calling thread's scratch: a block keeps nothing in it once done,
    /// so each worker slot's serves every block that thread runs.
    IndirectScratch& scratch() const { return st_.blocks[static_cast<std::size_t>(workerSlot())]; }
    RowBlock rowBlock(int block) const;
    /// The receiver columns of row Y to scan (the whole row without tiles).
    std::span<const ColumnSpan> spans(int Y) const { return st_.spans.ofRow(Y); }
    /// The block's receiver rows (loadReceiverRow) into its scratch.
    void loadRows(const RowBlock& rb, IndirectScratch& sc) const;
    /// Azimuth j's step tables; clampNegative: GlossyNlp's members send
    /// max(0, u); distanceGroups: Irradiance sums each distance group's
    /// occlusion (IndirectScratch::groupOccludersOf).
    AzimuthSteps azimuth(int j, bool clampNegative = false, bool distanceGroups = false) const;
    /// Scans the block's rows along azimuth j (loaded by loadRows): row r's
    /// results in sc.resultOf(r), at the receivers of spans(yBegin + r).
    void castRows(const AzimuthSteps& az, int j, const RowBlock& rb, IndirectScratch& sc) const;

    int pad() const { return pad_; }

private:
    void buildGlossyStepTable();

    const IndirectInputs& in_;
    IndirectState& st_;
    CastingMoments moments_;
    CastRowsFn castRows_;
    int pad_, nSteps_, nBlocks_;
    std::size_t tableSize_;  // azimuths x steps
    float hMax_ = 0.0f;
};

}  // namespace terrain::gi
