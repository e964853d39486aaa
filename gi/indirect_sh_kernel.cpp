#include "gi/indirect_sh_kernel.h"

#include <algorithm>
#include <cstdint>

#include "core/parallel.h"
#include "core/simd.h"
#include "gi/sh.h"

namespace terrain::gi {

namespace {

using namespace simd;

// One row and azimuth's NLP coefficients into U: U_c += G_j u_(c, j) over
// the sparse pattern of the folded wedge operator (Eq. 21).
struct URowSums {
    const float* nlp;  // 3 channels x 4 NLP x pad
    int pad, nxr;
    int patSize;
    const std::uint8_t *patRow, *patNlp;
    const float* vals;   // the operator's entries of this azimuth
    int nRows;           // SH rows of U that shading reads
    float* u[3];         // U of each channel: plane 0, row Y
    std::size_t planeR;  // plane stride
};

template <class V>
[[gnu::always_inline]] inline void accumulateUImpl(const URowSums& r) {
    constexpr int L = LaneTraits<V>::n;
    const int nv = r.nxr / L * L;
    auto axpy = [&](float* __restrict dst, const float* __restrict w, float gval) {
        const V g = splat<V>(gval);
        for (int X = 0; X < nv; X += L) store(dst + X, load<V>(dst + X) + g * load<V>(w + X));
        for (int X = nv; X < r.nxr; ++X) dst[X] += gval * w[X];
    };
    for (int e = 0; e < r.patSize; ++e) {
        const int row = r.patRow[e];
        if (row >= r.nRows) continue;
        const int l = r.patNlp[e];
        for (int c = 0; c < 3; ++c)
            axpy(r.u[c] + static_cast<std::size_t>(row) * r.planeR, r.nlp + static_cast<std::size_t>(c * 4 + l) * r.pad,
                 r.vals[e]);
    }
}
void accumulateUSse(const URowSums& r) { accumulateUImpl<F4>(r); }
[[gnu::target("avx2"), gnu::flatten]] void accumulateUAvx2(const URowSums& r) { accumulateUImpl<F8>(r); }

}  // namespace

ShKernelIndirect::ShKernelIndirect(const IndirectInputs& in, const IndirectSettings& settings, IndirectState& st)
    : in_(in),
      settings_(settings),
      st_(st),
      scan_(in, CastingMoments::Nlp, st),
      nRows_(in.shading.brdf == Brdf::Lambert ? 9 : kShCount) {}  // Lambert reads bands 0..2 only

void ShKernelIndirect::beginFrame() {
    const int nxr = in_.heights.nxr, nyr = in_.heights.nyr;
    const std::size_t planeR = static_cast<std::size_t>(nxr) * nyr;
    for (int c = 0; c < 3; ++c) {
        VisibilityField& u = st_.u[static_cast<std::size_t>(c)];
        u.nxr = nxr;
        u.nyr = nyr;
        if (u.sh.size() != planeR * kShCount) st_.uZeroFrom = kShCount;  // contents unknown
        u.sh.resize(planeR * kShCount);
    }
    // the planes shading does not read (Lambert: bands 0..2) stay 0; each scan
    // row clears only the planes it fills
    if (st_.uZeroFrom > nRows_) {
        for (VisibilityField& u : st_.u)
            std::fill(u.sh.begin() + static_cast<std::ptrdiff_t>(planeR) * nRows_, u.sh.end(), 0.0f);
        st_.uZeroFrom = nRows_;
    }
    scan_.beginFrame();
    setUShadingLights(st_);
}

void ShKernelIndirect::buildPyramid(const BounceSource& previous) {
    scan_.buildPyramid(*previous.rgb, settings_.radiance);
}

void ShKernelIndirect::scan(int) {
    scan_.buildStepTable();
    parallelFor(0, scan_.blockCount(), 1, [&](int b0, int b1) {
        for (int block = b0; block < b1; ++block) scanBlock(block);
    });
}

// Casting sets, Eq. 12 and U through the folded wedge operator for one block
// of receiver rows.
void ShKernelIndirect::scanBlock(int block) {
    const int nxr = in_.heights.nxr, nyr = in_.heights.nyr, pad = scan_.pad();
    const std::size_t planeR = static_cast<std::size_t>(nxr) * nyr;
    const FoldedWedgeOperator& op = in_.op;
    const int P = op.patternSize();
    void (*const accumulate)(const URowSums&) = simd::wideEnabled() ? accumulateUAvx2 : accumulateUSse;
    IndirectScratch& sc = st_.blocks[static_cast<std::size_t>(block)];
    const RowBlock rb = scan_.rowBlock(block);
    // the rows' receiver heights and gradients; U rows zeroed
    scan_.loadRows(rb, sc);
    for (int r = 0; r < rb.rows; ++r)
        for (int c = 0; c < 3; ++c)
            for (int i = 0; i < nRows_; ++i) {
                float* u = st_.u[static_cast<std::size_t>(c)].plane(i) + static_cast<std::size_t>(rb.yBegin + r) * nxr;
                std::fill(u, u + nxr, 0.0f);
            }
    for (int j = 0; j < op.azimuths; ++j) {
        const AzimuthSteps az = scan_.azimuth(j);
        const float* vals = op.values.data() + static_cast<std::size_t>(j) * P;
        for (int r = 0; r < rb.rows; ++r) {
            const int Y = rb.yBegin + r;
            scan_.castRow(az, j, Y, r, sc);
            float* uRow[3];
            for (int c = 0; c < 3; ++c)
                uRow[c] = st_.u[static_cast<std::size_t>(c)].plane(0) + static_cast<std::size_t>(Y) * nxr;
            accumulate({sc.result.data(),
                        pad,
                        nxr,
                        P,
                        op.patternRow.data(),
                        op.patternNlp.data(),
                        vals,
                        nRows_,
                        {uRow[0], uRow[1], uRow[2]},
                        planeR});
        }
    }
}

void ShKernelIndirect::shade(int, ShadeMaps& out) {
    shadeTexels(in_.gradX, in_.gradY, in_.heights.subsample, in_.envVisibility, st_.lights.data(), 3, in_.albedo,
                in_.shading, out, false);
}

}  // namespace terrain::gi
