#include "gi/indirect_blocker_radiance.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/parallel.h"
#include "core/simd.h"
#include "gi/blocker_radiance.h"
#include "gi/indirect_scan_tables.h"

namespace terrain::gi {

namespace {

using namespace simd;

// One row and azimuth's exact moments into the row's E sums at the
// receivers [x0, x1) (x0 a multiple of 16), per channel (pad floats each):
// sums[c] += result[c].
template <class V>
[[gnu::always_inline]] inline void accumulateIrradianceImpl(const float* result, float* sums, int pad, int x0, int x1,
                                                            int nxr) {
    constexpr int L = LaneTraits<V>::n;
    const int nv = std::min(x1, nxr / L * L);
    for (int c = 0; c < 3; ++c) {
        float* __restrict e = sums + static_cast<std::size_t>(c) * pad;
        const float* __restrict w = result + static_cast<std::size_t>(c) * pad;
        for (int X = x0; X < nv; X += L) store(e + X, load<V>(e + X) + load<V>(w + X));
        for (int X = nv; X < x1; ++X) e[X] += w[X];
    }
}
void accumulateIrradianceSse(const float* result, float* sums, int pad, int x0, int x1, int nxr) {
    accumulateIrradianceImpl<F4>(result, sums, pad, x0, x1, nxr);
}
[[gnu::target("avx2"), gnu::flatten]] void accumulateIrradianceAvx2(const float* result, float* sums, int pad, int x0,
                                                                    int x1, int nxr) {
    accumulateIrradianceImpl<F8>(result, sums, pad, x0, x1, nxr);
}

// Receiver tiles: the state must hold a previous result of this receiver
// grid, which the clean receivers keep.
void checkCachedReceivers(const HeightPyramid& pyr, int azimuths, const BlockerRadianceState& st) {
    const std::size_t planeR = static_cast<std::size_t>(pyr.nxr) * pyr.nyr;
    bool same = st.nxr == pyr.nxr && st.nyr == pyr.nyr && st.subsample == pyr.subsample && st.azimuths == azimuths;
    for (const std::vector<float>& e : st.receiverShade) same = same && e.size() == planeR;
    if (pyr.subsample > 1) same = same && st.farSlope.size() == planeR * static_cast<std::size_t>(azimuths);
    if (!same)
        throw InputError(
            "blocker radiance: receiver tiles need the previous result of this receiver grid and these "
            "azimuths in the state");
}

}  // namespace

BlockerRadianceIndirect::BlockerRadianceIndirect(const IndirectInputs& in, const IndirectSettings& settings,
                                                 IndirectState& st)
    : in_(in), settings_(settings), st_(st), scan_(in, CastingMoments::Irradiance, st) {}

void BlockerRadianceIndirect::beginFrame() {
    if (in_.only) checkCachedReceivers(in_.heights, in_.op.azimuths, st_.blocker);
    prepareBlockerRadiance(in_.heights, in_.op.azimuths, st_.blocker);
    scan_.beginFrame();
}

void BlockerRadianceIndirect::buildPyramid(int, const BounceSource& previous) {
    scan_.buildPyramid(previous, settings_.radiance);
}

void BlockerRadianceIndirect::scan(int b) {
    scan_.buildStepTable();
    // the receivers' horizons do not change between bounces
    const bool horizons = b == 1 && in_.heights.subsample > 1;
    scan_.forEachBlockWithWork([&](int block) { scanBlock(block, horizons); });
}

// Casting sets and the exact irradiance at one block of receiver rows
// (horizons: and the receivers' horizons, BlockerRadianceState::farSlope),
// over the rows' spans (receiver tiles).
void BlockerRadianceIndirect::scanBlock(int block, bool horizons) {
    const int nxr = in_.heights.nxr, nyr = in_.heights.nyr, pad = scan_.pad();
    const std::size_t planeR = static_cast<std::size_t>(nxr) * nyr;
    void (*const accumulate)(const float*, float*, int, int, int, int) =
        simd::wideEnabled() ? accumulateIrradianceAvx2 : accumulateIrradianceSse;
    IndirectScratch& sc = scan_.scratch();
    const RowBlock rb = scan_.rowBlock(block);
    // the rows' receiver heights and gradients
    scan_.loadRows(rb, sc);
    // E sums and, with the horizons, each distance group's occlusion (the
    // indirect cache's weights) zeroed over the lanes the scan writes: the
    // rows' spans, each to its padded end (a local change's few tiles)
    for (int r = 0; r < rb.rows; ++r)
        for (const ColumnSpan& span : scan_.spans(rb.yBegin + r)) {
            // planes of pad floats from `first`, each zeroed over the span's lanes
            const auto zero = [&](float* first, int planes) {
                for (int p = 0; p < planes; ++p)
                    std::fill(first + static_cast<std::size_t>(p) * pad + span.x0,
                              first + static_cast<std::size_t>(p) * pad + indirectRowPad(span.x1), 0.0f);
            };
            zero(sc.irradiance.data() + 3 * static_cast<std::size_t>(r) * pad, 3);
            if (horizons) zero(sc.groupOccludersOf(r), kDistanceGroups);
        }
    for (int j = 0; j < in_.op.azimuths; ++j) {
        const AzimuthSteps az = scan_.azimuth(j, false, horizons);
        scan_.castRows(az, j, rb, sc);
        for (int r = 0; r < rb.rows; ++r) {
            const int Y = rb.yBegin + r;
            float* far = horizons ? st_.blocker.farSlope.data() + static_cast<std::size_t>(j) * planeR +
                                        static_cast<std::size_t>(Y) * nxr
                                  : nullptr;
            const float* horizon = sc.stateOf(r);
            for (const ColumnSpan& span : scan_.spans(Y)) {
                // the receivers' horizon along this azimuth (the walk's running maximum)
                if (horizons) std::copy(horizon + span.x0, horizon + span.x1, far + span.x0);
                accumulate(sc.resultOf(r), sc.irradiance.data() + 3 * static_cast<std::size_t>(r) * pad, pad, span.x0,
                           span.x1, nxr);
            }
        }
    }
    receiverIrradiance(rb, sc);
    if (horizons) storeGroupOcclusion(rb, sc);
}

// Each distance group's occlusion at the block's receivers, summed over the
// azimuths by the walks (BlockerRadianceState::receiverGroupOcclusion).
void BlockerRadianceIndirect::storeGroupOcclusion(const RowBlock& rb, IndirectScratch& sc) {
    const int nxr = in_.heights.nxr, pad = scan_.pad();
    const std::size_t planeR = static_cast<std::size_t>(nxr) * in_.heights.nyr;
    for (int r = 0; r < rb.rows; ++r) {
        const std::size_t at = static_cast<std::size_t>(rb.yBegin + r) * nxr;
        for (int g = 0; g < kDistanceGroups; ++g) {
            const float* sums = sc.groupOccludersOf(r) + static_cast<std::size_t>(g) * pad;
            float* out = st_.blocker.receiverGroupOcclusion.data() + static_cast<std::size_t>(g) * planeR + at;
            for (const ColumnSpan& span : scan_.spans(rb.yBegin + r))
                std::copy(sums + span.x0, sums + span.x1, out + span.x0);
        }
    }
}

// E / pi at the block's receivers (BlockerRadianceState::receiverShade):
// box weights (2 pi / m) / pi over the azimuths, over |n|.
void BlockerRadianceIndirect::receiverIrradiance(const RowBlock& rb, const IndirectScratch& sc) {
    const int nxr = in_.heights.nxr, pad = scan_.pad();
    const float eScale = 2.0f / static_cast<float>(in_.op.azimuths);  // (2 pi / m) / pi
    for (int r = 0; r < rb.rows; ++r) {
        const std::size_t ro = static_cast<std::size_t>(r) * pad;
        const std::size_t at = static_cast<std::size_t>(rb.yBegin + r) * nxr;
        const float* gx = sc.gx.data() + ro;
        const float* gy = sc.gy.data() + ro;
        for (const ColumnSpan& span : scan_.spans(rb.yBegin + r))
            for (int c = 0; c < 3; ++c) {
                const float* e = sc.irradiance.data() + 3 * ro + static_cast<std::size_t>(c) * pad;
                float* out = st_.blocker.receiverShade[static_cast<std::size_t>(c)].data() + at;
                for (int X = span.x0; X < span.x1; ++X)
                    out[X] = eScale / std::sqrt(1.0f + gx[X] * gx[X] + gy[X] * gy[X]) * e[X];
            }
    }
}

// The texel passes redo the texels of the caller's texel tiles (every texel
// without them), reading the clean receivers' cached horizons and E; the
// occlusion, a function of the geometry alone, is kept whole when the
// geometry is the last call's.
void BlockerRadianceIndirect::shade(int b, ShadeMaps& out) {
    const bool keepOcclusion = in_.sameGeometry && st_.blocker.occlusionValid;
    if (b == 1 && in_.heights.subsample > 1 && !keepOcclusion)
        computeTexelOcclusion(in_.heights, in_.gradX, in_.gradY, in_.op.phi, in_.texels, in_.texelRuns, st_.blocker);
    shadeBlockerRadiance(st_.blocker, in_.albedo, in_.texels, in_.texelRuns, out.rgb);
}

}  // namespace terrain::gi
