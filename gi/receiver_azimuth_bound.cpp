#include "gi/receiver_azimuth_bound.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

#include "core/error.h"
#include "core/parallel.h"
#include "core/simd.h"
#include "gi/visibility.h"

namespace terrain::gi {

bool changeLevelsFit(const ChangeLevels& levels, const HeightPyramid& pyr) {
    const HeightPyramid& b = levels.bound;
    return levels.valid && b.nx == pyr.nx && b.ny == pyr.ny && b.subsample == pyr.subsample &&
           b.cellSize == pyr.cellSize && b.settings == pyr.settings;
}

void buildChangeLevels(const MaxChangePyramid& dh, const HeightPyramid& pyr, ChangeLevels& out) {
    if (dh.levels.empty() || dh.nx != pyr.nx || dh.ny != pyr.ny)
        throw InputError("change levels: the height change and the pyramid differ in size");
    const bool same = changeLevelsFit(out, pyr);
    const ConstGridView input = dh.levels[0].cview();
    const CellBox nonZero = changedCells(dh);
    out.largest = maxChangeAll(dh);
    // the input can differ from the last build's only where either is
    // non-zero; the pyramid is redone where it does: nothing without a
    // change (no walk reads the pyramid then: it keeps the last one, and
    // `built` its box) or with the last build's input again (a pit dropped,
    // filled and dropped), one pit's reach when a change adds a pit to
    // those already since the anchor
    const CellBox redo = same
                             ? (nonZero.empty() ? CellBox::none()
                                                : differingCellsIn(out.input.cview(), input, out.built.joined(nonZero)))
                             : CellBox{};
    if (!same || !redo.empty()) {
        out.valid = false;  // until built
        buildHeightPyramid(input, pyr.cellSize, pyr.subsample, pyr.settings, out.bound, redo);
        copyGrid(input, out.input, same ? redo.rows() : RowSpan{0, input.ny});
        out.built = nonZero;
    }
    // the field's own steps (a radiance field's are the height pyramid's taus, gi/radiance_pyramid.h)
    out.bound.steps = pyr.steps;
    out.valid = true;
}

namespace {

// The texels of the field step i reads (a level on the receiver grid, or the
// raw heights in cells) that are within reach of a cell of `cells`, the box
// of non-zero |dh|: a level texel X (at cell s X) reads the cells within
// levelReachCells of it. A box that reaches the field's edge takes the
// padding beyond it too (replicated edges).
CellBox changedTexels(const HeightPyramid& b, int level, const CellBox& cells) {
    if (cells.empty()) return CellBox::none();
    constexpr int kFar = 1 << 28;
    const int s = level < 0 ? 1 : b.subsample, n[2] = {level < 0 ? b.nx : b.nxr, level < 0 ? b.ny : b.nyr};
    const double reach = level < 0 ? 0.0 : levelReachCells(b, level);
    const int lo[2] = {cells.x0, cells.y0}, hi[2] = {cells.x1, cells.y1};
    int out[2][2];
    for (int a = 0; a < 2; ++a) {
        const int first = static_cast<int>(std::ceil((lo[a] - reach) / s));
        const int last = static_cast<int>(std::floor((hi[a] - 1 + reach) / s));
        out[a][0] = first <= 0 ? -kFar : first;
        out[a][1] = last >= n[a] - 1 ? kFar : last + 1;
    }
    return {out[0][0], out[1][0], out[0][1], out[1][1]};
}

// Each azimuth's walk (ChangeWalk) into levels.walks: its steps stop at the
// first from which on no step's slope can move by more than the floor (each
// sample and the receiver's own height moved by at most the largest |dh|,
// M: 2 M over the step's length); each step knows its field's texels of
// non-zero |dh| bound (from levels.built, the cells of non-zero |dh|). The
// steps' taps are levels.stepInfo, taken again only when the pyramid's
// layout or the azimuths differ from the last call's.
void buildWalks(const HeightPyramid& b, std::span<const double> phi, float largest, float floor, ChangeLevels& levels) {
    const CellBox& built = levels.built;
    std::vector<ChangeWalk>& walks = levels.walks;
    std::vector<float>& tail = levels.tails;
    const std::size_t nSteps = b.steps.size();
    walks.resize(phi.size());
    tail.resize(nSteps + 1);
    StepTableKey key = stepTableKey(b, std::vector<double>(phi.begin(), phi.end()), 0);
    if (!(key == levels.stepsKey)) {
        levels.stepInfo.resize(phi.size() * nSteps);
        for (std::size_t j = 0; j < phi.size(); ++j)
            for (std::size_t i = 0; i < nSteps; ++i)
                levels.stepInfo[j * nSteps + i] =
                    scanStepInfo(b, static_cast<int>(i), std::cos(phi[j]), std::sin(phi[j]));
        levels.stepsKey = std::move(key);
    }
    for (std::size_t j = 0; j < phi.size(); ++j) {
        std::vector<ChangeWalk::Step>& steps = walks[j].steps;
        steps.resize(nSteps);
        int x0 = 0, x1 = b.nxr - 1, y0 = 0, y1 = b.nyr - 1;
        for (std::size_t i = 0; i < nSteps; ++i) {
            const ScanStepInfo& info = levels.stepInfo[j * nSteps + i];
            x0 = std::max(x0, info.xFirst);
            x1 = std::min(x1, info.xLast);
            y0 = std::max(y0, info.yFirst);
            y1 = std::min(y1, info.yLast);
            const int level = b.steps[i].level;
            steps[i] = {info.step,
                        x0,
                        x1,
                        y0,
                        y1,
                        level < 0 ? b.subsample : 1,
                        info.tapX,
                        info.tapY,
                        info.nextX,
                        info.nextY,
                        changedTexels(b, level, built),
                        distanceGroup(b.steps[i].tauCells)};
        }
        tail[nSteps] = 0.0f;  // tail[i]: the bound of steps i and on
        for (std::size_t i = nSteps; i-- > 0;)
            tail[i] = std::max(tail[i + 1], floatNotBelow(2.0 * largest * steps[i].step.w[2][0]));
        std::size_t walked = 0;
        while (walked < nSteps && tail[walked] > floor) ++walked;
        steps.resize(walked);
        walks[j].tail = tail[walked];
    }
}

// A block of consecutive receiver rows Y0 .. Y0 + rows - 1 that share their
// spans: the walks take its rows together, step by step (each step's taps
// of consecutive rows lie in consecutive rows of its field, so the lines
// one row reads are followed by their neighbours while the prefetchers see
// the stride; a row at a time, every step read a new field cold). `dh0`:
// |dh| at each row's receivers' own cells; `own`: the cells of non-zero
// |dh| (whose receivers may have a height change of their own).
constexpr int kWalkRows = 8;
struct WalkBlock {
    int Y0, rows, s;
    std::array<const float*, kWalkRows> dh0;
    CellBox own;
    // bit r: row Y0 + r's receivers in [x0, x1) may have a change of their own
    std::uint32_t ownRows(int x0, int x1) const {
        std::uint32_t bits = 0;
        const bool columns = s * (x1 - 1) >= own.x0 && s * x0 < own.x1;
        for (int r = 0; r < rows && columns; ++r)
            if (s * (Y0 + r) >= own.y0 && s * (Y0 + r) < own.y1) bits |= 1u << r;
        return bits;
    }
};

// Calls step(r, bs, fa, fb, a, e) for each walked step of `walk` and each
// row Y0 + r of the block whose taps that row's receivers [a, e] of the
// span [x0, x1) read (fa, fb: the two tap rows, indexed by the receiver's
// column): up to the first step none of them is inside the domain at (the
// valid ranges only shrink: once out, for good), skipping the steps whose
// taps read no texel of non-zero |dh| bound unless the row's receivers have
// a change of their own (bit r of `ownRows`: a step's sample then adds 0).
template <class Step>
[[gnu::always_inline]] inline void forEachReadingStep(const ChangeWalk& walk, int Y0, int rows, int x0, int x1,
                                                      std::uint32_t ownRows, Step&& step) {
    for (const ChangeWalk::Step& bs : walk.steps) {
        const int a = std::max(x0, bs.x0), e = std::min(x1 - 1, bs.x1);
        const int r0 = std::max(Y0, bs.y0) - Y0, r1 = std::min(Y0 + rows - 1, bs.y1) - Y0;
        if (a > e || r0 > r1) break;
        const int tx0 = bs.k * a + bs.tapX, tx1 = bs.k * e + bs.tapX + bs.nextX + 1;
        const CellBox& c = bs.changed;
        const bool columns = tx1 > c.x0 && tx0 < c.x1;
        if (!columns && ownRows == 0) continue;
        const ScanStep& st = bs.step;
        for (int r = r0; r <= r1; ++r) {
            const int Y = Y0 + r;
            const int ty0 = bs.k * Y + bs.tapY, ty1 = ty0 + bs.nextY + 1;
            if (!((ownRows >> r) & 1u) && (!columns || ty1 <= c.y0 || ty0 >= c.y1)) continue;
            const std::ptrdiff_t row = static_cast<std::ptrdiff_t>(Y) * st.rowStep;
            step(r, bs, st.field + st.offA + row, st.field + st.offB + row, a, e);
        }
    }
}

// The block's span [x0, x1) along one azimuth into the rows o + r * stride:
// each receiver's largest slope bound of its walked steps, at least the
// tail's.
template <class V>
[[gnu::always_inline]] inline void walkSpan(const ChangeWalk& walk, const WalkBlock& block, int x0, int x1, float* o,
                                            std::size_t stride) {
    for (int r = 0; r < block.rows; ++r)
        for (int X = x0; X < x1; ++X) o[static_cast<std::size_t>(r) * stride + X] = walk.tail;
    forEachReadingStep(
        walk, block.Y0, block.rows, x0, x1, block.ownRows(x0, x1),
        [&](int r, const ChangeWalk::Step& bs, const float* fa, const float* fb, int a, int e) {
            const ScanStep& st = bs.step;
            const float* dh0 = block.dh0[static_cast<std::size_t>(r)];
            float* out = o + static_cast<std::size_t>(r) * stride;
            const V wa = simd::splat<V>(st.w[0][0]), wb = simd::splat<V>(st.w[1][0]);
            const V inv = simd::splat<V>(st.w[2][0]);
            constexpr int L = simd::kLaneCount<V>;
            int X = a;
            for (; X + L <= e + 1; X += L) {
                const V v = (wa * simd::load<V>(fa + X) + wb * simd::load<V>(fb + X) + simd::load<V>(dh0 + X)) * inv;
                simd::store(out + X, simd::vmax(simd::load<V>(out + X), v));
            }
            for (; X <= e; ++X)
                out[X] = std::max(out[X], (st.w[0][0] * fa[X] + st.w[1][0] * fb[X] + dh0[X]) * st.w[2][0]);
        });
}

// The same walk bounding the samples' own moves, w_a D[a] + w_b D[b]: their
// largest along the azimuth into the rows o + r * stride, and in each
// distance group into groups + g * groupStride + r * stride (raised, not
// set: the caller starts them at 0 and walks every azimuth). Walked with no
// floor (its tail is 0).
template <class V>
[[gnu::always_inline]] inline void walkMoveSpan(const ChangeWalk& walk, const WalkBlock& block, int x0, int x1,
                                                float* o, float* groups, std::size_t stride, std::size_t groupStride) {
    for (int r = 0; r < block.rows; ++r)
        for (int X = x0; X < x1; ++X) o[static_cast<std::size_t>(r) * stride + X] = 0.0f;
    forEachReadingStep(walk, block.Y0, block.rows, x0, x1, 0u,
                       [&](int r, const ChangeWalk::Step& bs, const float* fa, const float* fb, int a, int e) {
                           const ScanStep& st = bs.step;
                           float* out = o + static_cast<std::size_t>(r) * stride;
                           float* g = groups + static_cast<std::size_t>(bs.group) * groupStride +
                                      static_cast<std::size_t>(r) * stride;
                           const V wa = simd::splat<V>(st.w[0][0]), wb = simd::splat<V>(st.w[1][0]);
                           constexpr int L = simd::kLaneCount<V>;
                           int X = a;
                           for (; X + L <= e + 1; X += L) {
                               const V v = wa * simd::load<V>(fa + X) + wb * simd::load<V>(fb + X);
                               simd::store(out + X, simd::vmax(simd::load<V>(out + X), v));
                               simd::store(g + X, simd::vmax(simd::load<V>(g + X), v));
                           }
                           for (; X <= e; ++X) {
                               const float v = st.w[0][0] * fa[X] + st.w[1][0] * fb[X];
                               out[X] = std::max(out[X], v);
                               g[X] = std::max(g[X], v);
                           }
                       });
}

// Every azimuth's walk over the block's spans; azimuth j's bounds of row
// Y0 + r go to rows + j * azimuthStride + r * rowStride (indexed by the
// receiver's column).
using WalkRows = void (*)(const std::vector<ChangeWalk>&, std::span<const ColumnSpan>, const WalkBlock&, float*,
                          std::size_t, std::size_t);

template <class V>
[[gnu::always_inline]] inline void walkRowsWith(const std::vector<ChangeWalk>& walks, std::span<const ColumnSpan> spans,
                                                const WalkBlock& block, float* rows, std::size_t azimuthStride,
                                                std::size_t rowStride) {
    for (std::size_t j = 0; j < walks.size(); ++j)
        for (const ColumnSpan& span : spans)
            walkSpan<V>(walks[j], block, span.x0, span.x1, rows + j * azimuthStride, rowStride);
}
void walkRowsSse(const std::vector<ChangeWalk>& walks, std::span<const ColumnSpan> spans, const WalkBlock& block,
                 float* rows, std::size_t azimuthStride, std::size_t rowStride) {
    walkRowsWith<simd::F4>(walks, spans, block, rows, azimuthStride, rowStride);
}
[[gnu::target("avx2"), gnu::flatten]] void walkRowsAvx2(const std::vector<ChangeWalk>& walks,
                                                        std::span<const ColumnSpan> spans, const WalkBlock& block,
                                                        float* rows, std::size_t azimuthStride, std::size_t rowStride) {
    walkRowsWith<simd::F8>(walks, spans, block, rows, azimuthStride, rowStride);
}

// Every azimuth's sample-move walk over the block's spans: azimuth j's
// largest moves of row Y0 + r to rows + j * plane + r * rowStride, distance
// group g's over every azimuth to groups + g * plane + r * rowStride
// (indexed by the receiver's column).
using WalkMoveRows = void (*)(const std::vector<ChangeWalk>&, std::span<const ColumnSpan>, const WalkBlock&, float*,
                              float*, std::size_t, std::size_t);
template <class V>
[[gnu::always_inline]] inline void walkMoveRowsWith(const std::vector<ChangeWalk>& walks,
                                                    std::span<const ColumnSpan> spans, const WalkBlock& block,
                                                    float* rows, float* groups, std::size_t plane,
                                                    std::size_t rowStride) {
    for (const ColumnSpan& span : spans)
        for (std::size_t g = 0; g < kDistanceGroups; ++g)
            for (int r = 0; r < block.rows; ++r) {
                float* row = groups + g * plane + static_cast<std::size_t>(r) * rowStride;
                std::fill(row + span.x0, row + span.x1, 0.0f);
            }
    for (std::size_t j = 0; j < walks.size(); ++j)
        for (const ColumnSpan& span : spans)
            walkMoveSpan<V>(walks[j], block, span.x0, span.x1, rows + j * plane, groups, rowStride, plane);
}
void walkMoveRowsSse(const std::vector<ChangeWalk>& walks, std::span<const ColumnSpan> spans, const WalkBlock& block,
                     float* rows, float* groups, std::size_t plane, std::size_t rowStride) {
    walkMoveRowsWith<simd::F4>(walks, spans, block, rows, groups, plane, rowStride);
}
[[gnu::target("avx2"), gnu::flatten]] void walkMoveRowsAvx2(const std::vector<ChangeWalk>& walks,
                                                            std::span<const ColumnSpan> spans, const WalkBlock& block,
                                                            float* rows, float* groups, std::size_t plane,
                                                            std::size_t rowStride) {
    walkMoveRowsWith<simd::F8>(walks, spans, block, rows, groups, plane, rowStride);
}

// The walks of `levels` over the receivers of `only`'s dirty tiles: calls
// block(spans, b) for each block of consecutive receiver rows with the same
// spans (at most kWalkRows, b: what the slope walks read of its rows), in
// parallel (the walks are levels.walks).
template <class Block>
void forEachWalkedBlock(ChangeLevels& levels, const HeightPyramid& pyr, std::span<const double> phi,
                        const ReceiverTiles* only, float floor, Block&& block) {
    const HeightPyramid& b = levels.bound;
    if (!levels.valid || b.nx != pyr.nx || b.ny != pyr.ny || b.nxr != pyr.nxr || b.nyr != pyr.nyr ||
        b.steps.size() != pyr.steps.size())
        throw InputError("receiver azimuth bound: the change levels were not built for this pyramid");
    buildWalks(b, phi, levels.largest, std::max(floor, 0.0f), levels);
    const DirtySpans& spans = levels.spans;
    dirtySpans(only, b.nxr, b.nyr, levels.spans);
    // blocks of rows with a span, each cut where the spans differ (a tile
    // row's rows share theirs)
    std::vector<RowSpan>& blocks = levels.walkedBlocks;
    blocks.clear();
    for (int Y = 0; Y < b.nyr;) {
        const int start = Y++;
        if (spans.ofRow(start).empty()) continue;
        while (Y < b.nyr && Y - start < kWalkRows && std::ranges::equal(spans.ofRow(start), spans.ofRow(Y))) ++Y;
        blocks.push_back({start, Y});
    }
    parallelFor(0, static_cast<int>(blocks.size()), 1, [&](int k0, int k1) {
        for (int k = k0; k < k1; ++k) {
            const RowSpan rows = blocks[static_cast<std::size_t>(k)];
            WalkBlock wb{rows.y0, rows.y1 - rows.y0, b.subsample, {}, levels.built};
            // |dh| at the receivers' own cells: raw phase 0 of row s Y
            for (int r = 0; r < wb.rows; ++r)
                wb.dh0[static_cast<std::size_t>(r)] = b.rawPhaseRow(0, b.subsample * (rows.y0 + r));
            block(spans.ofRow(rows.y0), wb);
        }
    });
}
}  // namespace

void boundSlopeChangePerReceiverAzimuth(ChangeLevels& levels, const HeightPyramid& pyr, std::span<const double> phi,
                                        const ReceiverTiles* only, float floor, std::vector<float>& out) {
    const std::size_t planeR = static_cast<std::size_t>(pyr.nxr) * pyr.nyr;
    out.assign(phi.size() * planeR, 0.0f);
    if (levels.largest == 0.0f && levels.valid) return;  // no height changed
    const WalkRows walkRows = simd::wideEnabled() ? walkRowsAvx2 : walkRowsSse;
    forEachWalkedBlock(levels, pyr, phi, only, floor, [&](std::span<const ColumnSpan> spans, const WalkBlock& block) {
        walkRows(levels.walks, spans, block, out.data() + static_cast<std::size_t>(block.Y0) * pyr.nxr, planeR,
                 static_cast<std::size_t>(pyr.nxr));
    });
}

void boundEnvironmentPerReceiver(ChangeLevels& levels, const MaxChangePyramid& dh, const HeightPyramid& pyr,
                                 std::span<const double> phi, float lipschitz, const ReceiverTiles* only, float floor,
                                 std::vector<float>& out, int subsetStride, std::vector<float>* subsetOut) {
    const int nxr = pyr.nxr, m = static_cast<int>(phi.size());
    if (m < 1) throw InputError("boundEnvironmentPerReceiver: at least one azimuth");
    if (subsetOut && (subsetStride < 1 || m % subsetStride != 0))
        throw InputError("boundEnvironmentPerReceiver: the subset's stride must divide the azimuths");
    const std::size_t planeR = static_cast<std::size_t>(nxr) * pyr.nyr;
    out.assign(planeR, 0.0f);
    if (subsetOut) subsetOut->assign(planeR, 0.0f);
    if (levels.largest == 0.0f && levels.valid) return;  // no height changed
    // per worker slot: a block's slope bounds per row and azimuth, then one
    // receiver's, then a row's gradient bounds; and the gradients' column scratch
    const std::size_t slots = static_cast<std::size_t>(workerSlots());
    const std::size_t rowStride = static_cast<std::size_t>(m) * nxr;
    levels.rows.resize(slots);
    levels.columns.resize(slots);
    for (std::vector<float>& r : levels.rows) r.resize(kWalkRows * rowStride + m + nxr);
    const WalkRows walkRows = simd::wideEnabled() ? walkRowsAvx2 : walkRowsSse;
    forEachWalkedBlock(levels, pyr, phi, only, floor, [&](std::span<const ColumnSpan> spans, const WalkBlock& block) {
        const std::size_t slot = static_cast<std::size_t>(workerSlot());
        float* slopes = levels.rows[slot].data();
        float* perAzimuth = slopes + kWalkRows * rowStride;
        float* gradients = perAzimuth + m;
        walkRows(levels.walks, spans, block, slopes, static_cast<std::size_t>(nxr), rowStride);
        for (int rb = 0; rb < block.rows; ++rb) {
            const int Y = block.Y0 + rb;
            const float* rowSlopes = slopes + static_cast<std::size_t>(rb) * rowStride;
            for (const ColumnSpan& span : spans) {
                receiverGradientBounds(dh, pyr, Y, span.x0, span.x1, gradients, levels.columns[slot]);
                for (int X = span.x0; X < span.x1; ++X) {
                    const std::size_t r = static_cast<std::size_t>(Y) * nxr + static_cast<std::size_t>(X);
                    const float gradient = gradients[X];
                    for (int j = 0; j < m; ++j)
                        perAzimuth[static_cast<std::size_t>(j)] =
                            lipschitz * rowSlopes[static_cast<std::size_t>(j) * nxr + static_cast<std::size_t>(X)];
                    out[r] = ambientChangeBoundPerAzimuth(perAzimuth, m, gradient, 1.0f, false);
                    if (!subsetOut) continue;
                    // every subsetStride-th azimuth, gathered to the front
                    for (int k = 0; k < m / subsetStride; ++k)
                        perAzimuth[static_cast<std::size_t>(k)] =
                            perAzimuth[static_cast<std::size_t>(k * subsetStride)];
                    (*subsetOut)[r] = ambientChangeBoundPerAzimuth(perAzimuth, m / subsetStride, gradient, 1.0f, false);
                }
            }
        }
    });
}

void boundSampleMovePerReceiver(ChangeLevels& levels, const HeightPyramid& field, std::span<const double> phi,
                                const ReceiverTiles* only, std::vector<float>& azimuthMove,
                                std::vector<float>& groupMove) {
    const std::size_t planeR = static_cast<std::size_t>(field.nxr) * field.nyr;
    azimuthMove.resize(phi.size() * planeR);
    groupMove.resize(static_cast<std::size_t>(kDistanceGroups) * planeR);
    const WalkMoveRows walkRows = simd::wideEnabled() ? walkMoveRowsAvx2 : walkMoveRowsSse;
    // no floor: a move does not shrink with the distance (the walks' tails are 0)
    forEachWalkedBlock(levels, field, phi, only, 0.0f, [&](std::span<const ColumnSpan> spans, const WalkBlock& block) {
        const std::size_t row = static_cast<std::size_t>(block.Y0) * field.nxr;
        walkRows(levels.walks, spans, block, azimuthMove.data() + row, groupMove.data() + row, planeR,
                 static_cast<std::size_t>(field.nxr));
    });
}

}  // namespace terrain::gi
