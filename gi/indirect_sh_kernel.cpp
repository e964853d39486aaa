#include "gi/indirect_sh_kernel.h"

#include <algorithm>
#include <cstdint>

#include "core/error.h"
#include "core/parallel.h"
#include "core/simd.h"
#include "gi/glossy_exit_radiance.h"
#include "gi/indirect.h"
#include "gi/sh.h"

namespace terrain::gi {

namespace {

using namespace simd;

// One row and azimuth's NLP coefficients into U at the receivers [x0, x1)
// (x0 a multiple of 16): U_c += G_j u_(c, j) over the sparse pattern of the
// folded wedge operator (Eq. 21).
struct URowSums {
    const float* nlp;  // 3 channels x 4 NLP x pad
    int pad, nxr, x0, x1;
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
    const int nv = std::min(r.x1, r.nxr / L * L);
    auto axpy = [&](float* __restrict dst, const float* __restrict w, float gval) {
        const V g = splat<V>(gval);
        for (int X = r.x0; X < nv; X += L) store(dst + X, load<V>(dst + X) + g * load<V>(w + X));
        for (int X = nv; X < r.x1; ++X) dst[X] += gval * w[X];
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
      exitVectors_(readsIncidentSh(settings, in.shading)),
      lobes_(exitVectors_ && settings.glossy == GlossyIndirect::LobeScan),
      scan_(in, exitVectors_ ? CastingMoments::GlossyNlp : CastingMoments::Nlp, st),
      nRows_(in.shading.brdf == Brdf::Lambert ? 9 : kShCount) {}  // Lambert reads bands 0..2 only

void ShKernelIndirect::beginFrame() {
    const int nxr = in_.heights.nxr, nyr = in_.heights.nyr;
    const std::size_t planeR = static_cast<std::size_t>(nxr) * nyr;
    if (exitVectors_) checkExitVectorInputs();
    // receiver tiles: the clean receivers keep the U of a previous scan
    if (in_.only)
        for (const VisibilityField& u : st_.u)
            if (u.nxr != nxr || u.nyr != nyr || u.sh.size() != planeR * kShCount)
                throw InputError("SH kernel: receiver tiles need the previous U of this receiver grid in the state");
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

// The exit-radiance vectors need the previous bounce's incident SH vectors
// (bounce 1: the direct shading's).
void ShKernelIndirect::checkExitVectorInputs() {
    const HeightPyramid& pyr = in_.heights;
    if (!in_.directShade) throw InputError("glossy vector pyramid: the direct shading (incident SH) is required");
    const ShadeMaps& direct = *in_.directShade;
    const std::size_t planeR = static_cast<std::size_t>(pyr.nxr) * pyr.nyr;
    if (direct.incident.size() != planeR * kGlossyFields || direct.nx != pyr.nx || direct.ny != pyr.ny)
        throw InputError("glossy vector pyramid: the direct shading is not a Phong shading of this field");
}

// The RGB pyramid of L_(b-1), or E of bounce b - 1 at full resolution and
// its 48 planes' pyramid (Section 5.3). The lobe gather reads E at full
// resolution texel by texel, so with LobeScan the planes and their pyramid
// are made only for a scan of U.
void ShKernelIndirect::buildPyramid(int b, const BounceSource& previous) {
    if (!exitVectors_) return scan_.buildPyramid(previous, settings_.radiance);
    const HeightPyramid& pyr = in_.heights;
    GlossyIndirectState& gs = st_.glossy;
    const std::size_t values = static_cast<std::size_t>(pyr.nx) * pyr.ny * kGlossyFields;
    const bool planes = !lobes_ || needsU(b), windowed = windowedMembers(b);
    if (planes) gs.exitSh.resize(values);
    if (lobes_ && !windowed) gs.exitTexels.resize(values);
    if (windowed)
        prepareLobeMembers(in_.gradX, in_.gradY, in_.envVisibility, pyr.subsample, *in_.memberLight, in_.albedo,
                           in_.shading, gs.members);
    glossyExitRadiance(in_.gradX, in_.gradY, pyr.subsample, pyr.nxr, pyr.nyr, previous.shade->incident.data(),
                       previous.shade->rgb, in_.albedo, in_.shading, gs.exitScratch,
                       {planes ? gs.exitSh.data() : nullptr, lobes_ && !windowed ? gs.exitTexels.data() : nullptr,
                        windowed ? gs.members.texels.data() + LobeMembers::kDiffuse : nullptr, LobeMembers::kRecord});
    if (planes) buildPackedPyramids(gs.exitSh.data(), kGlossyFields, pyr, settings_.radiance, gs.pyramid);
}

// The first bounce's members of the lobe gather send their windowed lobe
// (gi/glossy_lobe_members.h) when the lights they reflect are known.
bool ShKernelIndirect::windowedMembers(int b) const {
    return lobes_ && b == 1 && settings_.lobeMembers == GlossyLobeMembers::Windowed && in_.memberLight;
}

bool ShKernelIndirect::needsU(int b) const {
    return b < settings_.bounces || in_.shading.brdf == Brdf::LambertPlusPhong;
}

void ShKernelIndirect::scan(int b) {
    if (lobes_) {
        const GlossyLobeInputs lobeIn{in_.heights,
                                      in_.gradX,
                                      in_.gradY,
                                      windowedMembers(b) ? nullptr : st_.glossy.exitTexels.data(),
                                      windowedMembers(b) ? &st_.glossy.members : nullptr,
                                      in_.albedo,
                                      in_.shading,
                                      settings_.lobeAzimuths,
                                      settings_.lobeRings,
                                      settings_.lobeInnerDirections,
                                      settings_.lobeNearStepsPerOctave,
                                      settings_.lobeNearOctaves};
        gatherGlossyLobes(lobeIn, st_.glossy.lobes);
        if (!needsU(b)) return;
    }
    scan_.buildStepTable();
    scan_.forEachBlockWithWork([&](int block) { scanBlock(block); });
}

// Casting sets, Eq. 12 and U through the folded wedge operator for one block
// of receiver rows, over the rows' spans (receiver tiles).
void ShKernelIndirect::scanBlock(int block) {
    const int nxr = in_.heights.nxr, nyr = in_.heights.nyr, pad = scan_.pad();
    const std::size_t planeR = static_cast<std::size_t>(nxr) * nyr;
    const FoldedWedgeOperator& op = in_.op;
    const int P = op.patternSize();
    void (*const accumulate)(const URowSums&) = simd::wideEnabled() ? accumulateUAvx2 : accumulateUSse;
    IndirectScratch& sc = scan_.scratch();
    const RowBlock rb = scan_.rowBlock(block);
    // the rows' receiver heights and gradients; U zeroed in the spans
    scan_.loadRows(rb, sc);
    for (int r = 0; r < rb.rows; ++r)
        for (const ColumnSpan& span : scan_.spans(rb.yBegin + r))
            for (int c = 0; c < 3; ++c)
                for (int i = 0; i < nRows_; ++i) {
                    float* u =
                        st_.u[static_cast<std::size_t>(c)].plane(i) + static_cast<std::size_t>(rb.yBegin + r) * nxr;
                    std::fill(u + span.x0, u + span.x1, 0.0f);
                }
    for (int j = 0; j < op.azimuths; ++j) {
        const AzimuthSteps az = scan_.azimuth(j, in_.shading.positivity == GlossyPositivity::Clamp);
        const float* vals = op.values.data() + static_cast<std::size_t>(j) * P;
        scan_.castRows(az, j, rb, sc);
        for (int r = 0; r < rb.rows; ++r) {
            const int Y = rb.yBegin + r;
            float* uRow[3];
            for (int c = 0; c < 3; ++c)
                uRow[c] = st_.u[static_cast<std::size_t>(c)].plane(0) + static_cast<std::size_t>(Y) * nxr;
            for (const ColumnSpan& span : scan_.spans(Y))
                accumulate({sc.resultOf(r),
                            pad,
                            nxr,
                            span.x0,
                            span.x1,
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

// The texel pass stays whole with receiver tiles: it costs little beside the
// scan, and interpolates the clean receivers' cached U. With the exit-radiance
// vectors its incident SH feeds bounce b + 1.
// LobeScan: the gathered lobes are the Phong part; U, where it was scanned,
// gives the diffuse part of a mixture (shaded with no Phong weight) and the
// incident SH of the next bounce (a pure Phong shade of U is then replaced).
void ShKernelIndirect::shade(int b, ShadeMaps& out) {
    if (exitVectors_) out.keepIncident = true;
    if (!lobes_)
        return shadeTexels(in_.gradX, in_.gradY, in_.heights.subsample, in_.envVisibility, st_.lights.data(), 3,
                           in_.albedo, in_.shading, out, false);
    const bool mixture = in_.shading.brdf == Brdf::LambertPlusPhong;
    if (needsU(b)) {
        ShadingSettings diffuseOnly = in_.shading;
        diffuseOnly.specularWeight = 0.0f;
        shadeTexels(in_.gradX, in_.gradY, in_.heights.subsample, in_.envVisibility, st_.lights.data(), 3, in_.albedo,
                    mixture ? diffuseOnly : in_.shading, out, false);
    }
    out.nx = in_.heights.nx;
    out.ny = in_.heights.ny;
    shadeGlossyLobes(st_.glossy.lobes, in_.heights, in_.shading, mixture, out.rgb);
}

}  // namespace terrain::gi
