#include "gi/indirect_bounces.h"

#include <algorithm>
#include <chrono>
#include <utility>

#include "core/parallel.h"

namespace terrain::gi {

namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

// Sizes the sum of the bounces (full resolution; zeroed when several bounces
// add into it) and the bounce means.
void prepareIndirectSum(int nx, int ny, int bounces, IndirectState& st) {
    for (int c = 0; c < 3; ++c) {
        Grid& g = st.indirect[static_cast<std::size_t>(c)];
        g.ensureSize(nx, ny);
        if (bounces > 1) std::fill(g.v.begin(), g.v.end(), 0.0f);
    }
    st.bounceMean.resize(static_cast<std::size_t>(bounces));
}

// Mean over the texels and channels (RGB average): blocks of rows summed
// in parallel, each into four partial sums (independent additions, so the
// loop is not one long chain of dependent ones), folded in row order.
// `blocks` holds the sum of each block of rows: when they are of this
// field's size, only the blocks holding `redo`'s rows are summed again (the
// others' rows have not changed since their sums were taken), else every
// block. The same value as summing every block.
double meanOf(const std::array<Grid, 3>& rgb, RowSpan redo, RowBlockSums& blocks) {
    constexpr int kRowsPerBlock = 16;
    const int nx = rgb[0].nx, ny = rgb[0].ny;
    const int nBlocks = (ny + kRowsPerBlock - 1) / kRowsPerBlock;
    std::vector<double>& sums = blocks.sums;
    if (blocks.nx != nx || sums.size() != static_cast<std::size_t>(nBlocks)) {
        sums.assign(static_cast<std::size_t>(nBlocks), 0.0);
        blocks.nx = nx;
        redo = {};
    }
    redo = redo.cut(ny);
    const int b0 = redo.y0 / kRowsPerBlock;
    const int b1 = redo.y1 > redo.y0 ? (redo.y1 + kRowsPerBlock - 1) / kRowsPerBlock : b0;
    parallelFor(b0, b1, 1, [&](int first, int last) {
        for (int b = first; b < last; ++b) {
            double lanes[4] = {};
            for (const Grid& g : rgb)
                for (int y = b * kRowsPerBlock; y < std::min(ny, (b + 1) * kRowsPerBlock); ++y) {
                    const float* row = g.data() + static_cast<std::size_t>(y) * nx;
                    int x = 0;
                    for (; x + 4 <= nx; x += 4)
                        for (int k = 0; k < 4; ++k) lanes[k] += row[x + k];
                    for (; x < nx; ++x) lanes[0] += row[x];
                }
            sums[static_cast<std::size_t>(b)] = (lanes[0] + lanes[1]) + (lanes[2] + lanes[3]);
        }
    });
    double sum = 0.0;
    for (const double s : sums) sum += s;
    return sum / (3.0 * static_cast<double>(std::max<std::size_t>(1, rgb[0].v.size())));
}

}  // namespace

void runBounces(const IndirectInputs& in, const IndirectSettings& settings, IndirectStrategy& strategy,
                IndirectState& st) {
    const auto t0 = Clock::now();
    st.timings = IndirectTimings{};
    // the sum is redone where this call's inputs or light may differ from the last call's
    const bool totalOfLastCall = st.totalValid;
    st.totalValid = false;
    // one bounce over texel runs: the indirect light changed there alone
    const bool restricted = totalOfLastCall && settings.bounces == 1 && in.texelRuns != nullptr;
    if (settings.bounces != 1) st.meanOfRows.sums.clear();  // the row sums are of one bounce's light
    strategy.beginFrame();
    prepareIndirectSum(in.heights.nx, in.heights.ny, settings.bounces, st);
    // the RGB pyramid may be redone where bounce 0 changed only when it is
    // the last call's bounce 0 (IndirectScan::buildPyramid says so again),
    // and not at all when the caller built it for this call
    const CellBox redo = in.radianceCurrent ? CellBox::none() : in.directChanged;
    BounceSource source{&in.direct, in.directShade, st.radianceOfDirect ? redo : CellBox{}};
    st.radianceOfDirect = false;
    for (int b = 1; b <= settings.bounces; ++b) {
        // ---- pyramid of bounce b - 1 (Section 5.3) ------------------------------------
        auto t = Clock::now();
        strategy.buildPyramid(b, source);
        st.timings.pyramid += msSince(t);

        // ---- step table and casting-set scan --------------------------------------------
        t = Clock::now();
        strategy.scan(b);
        st.timings.scan += msSince(t);

        // ---- shading at full-resolution normals: L_b ---------------------------------
        t = Clock::now();
        ShadeMaps& out = st.bounceShade[static_cast<std::size_t>(b & 1)];
        if (settings.bounces == 1) {
            // one bounce: the sum is L_1, shaded straight into it (no second field of it)
            std::swap(out.rgb, st.indirect);
            strategy.shade(b, out);
            std::swap(out.rgb, st.indirect);
            // restricted to texel runs, the light changed in their rows alone
            st.bounceMean[0] =
                meanOf(st.indirect, restricted ? boundingBox(*in.texelRuns).rows() : RowSpan{}, st.meanOfRows);
        } else {
            strategy.shade(b, out);
            accumulateBounce(out.rgb, b, st);
            source = {&out.rgb, &out};
        }
        st.timings.shading += msSince(t);
    }
    sumDirectAndIndirect(in.direct, st, restricted ? in.directChanged.joined(boundingBox(*in.texelRuns)) : CellBox{});
    st.timings.total = msSince(t0);
}

void accumulateBounce(const std::array<Grid, 3>& exit, int b, IndirectState& st) {
    for (int c = 0; c < 3; ++c) {
        Grid& acc = st.indirect[static_cast<std::size_t>(c)];
        const Grid& add = exit[static_cast<std::size_t>(c)];
        for (std::size_t i = 0; i < acc.v.size(); ++i) acc.v[i] += add.v[i];
    }
    RowBlockSums blocks;  // every block: the bounces' sums are not kept
    st.bounceMean[static_cast<std::size_t>(b - 1)] = meanOf(exit, {}, blocks);
}

void sumDirectAndIndirect(const std::array<Grid, 3>& direct, IndirectState& st, CellBox changed) {
    st.totalValid = false;
    for (int c = 0; c < 3; ++c) {
        Grid& tot = st.total[static_cast<std::size_t>(c)];
        const Grid& ind = st.indirect[static_cast<std::size_t>(c)];
        if (tot.nx != ind.nx || tot.ny != ind.ny) changed = {};
        tot.ensureSize(ind.nx, ind.ny);
        const Grid& d = direct[static_cast<std::size_t>(c)];
        const CellBox box = changed.cut(ind.nx, ind.ny);
        if (box.empty()) continue;
        parallelForRows(box.rows(), box.x1 - box.x0, [&](int y0, int y1) {
            for (int y = y0; y < y1; ++y) {
                const std::size_t row = static_cast<std::size_t>(y) * ind.nx;
                for (std::size_t i = row + box.x0; i < row + box.x1; ++i) tot.v[i] = d.v[i] + ind.v[i];
            }
        });
    }
    st.totalValid = true;
}

void setUShadingLights(IndirectState& st) {
    for (int c = 0; c < 3; ++c) {
        ShadingLight& L = st.lights[static_cast<std::size_t>(c)];
        L.visibility = &st.u[static_cast<std::size_t>(c)];
        for (int ch = 0; ch < 3; ++ch) {
            ShMatrix& mtx = L.product[static_cast<std::size_t>(ch)];
            mtx.fill(0.0);
            if (ch == c)
                for (int i = 0; i < kShCount; ++i) mtx[static_cast<std::size_t>(i * kShCount + i)] = 1.0;
        }
    }
}

}  // namespace terrain::gi
