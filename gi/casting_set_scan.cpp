#include "gi/casting_set_scan.h"

#include <algorithm>
#include <cstring>

#include "core/bfloat16.h"
#include "core/simd.h"
#include "gi/indirect_scan_tables.h"
#include "gi/sh.h"

namespace terrain::gi {

namespace {

// The kernel is written once over a lane type V: F4 (SSE2, the baseline) or
// F8 (AVX2, chosen at run time where the processor has it): core/simd.h.
using namespace simd;

constexpr int kShFields = 3 * kShCount;  // GlossyNlp: RGB x 16 SH planes of the exit radiance

// Step i's taps: the two height samples of the receivers' row and each
// channel's two radiance samples, with their weights; with GlossyNlp the
// exit-radiance planes' samples instead (each plane's origin + o + X, its
// second sample dB further) and the direction back to the receiver.
template <class V>
struct StepTaps {
    const float *a, *b;
    V wa, wb, inv;
    const float* ra[3];
    const float* rb[3];
    V rwa[3], rwb[3];
    const std::uint16_t* const* planes;  // GlossyNlp: kShFields origins (bfloat16)
    std::ptrdiff_t o, dB;
    // GlossyNlp: the samples the block reads next (the next row's at this
    // step, or the first row's at the next step), asked for early
    const std::uint16_t* const* nextPlanes;
    std::ptrdiff_t nextO, nextDB;
    V back[2];   // -(cos phi, sin phi)
    bool clamp;  // members send max(0, u)
    int group;   // Irradiance: the step's distance group (-1: none summed)
    // Irradiance, Nlp: the samples the block reads next (as nextPlanes):
    // the two height taps and each channel's first radiance tap
    const float *nextA, *nextB;
    const float* nextR[3];
};

template <class V, CastingMoments K>
[[gnu::always_inline]] inline StepTaps<V> stepTaps(const AzimuthSteps& az, int i, int Y, int nextI, int nextY) {
    StepTaps<V> tp;
    const ScanStep& st = az.heights[i];
    const std::ptrdiff_t o = Y * st.rowStep;
    tp.a = st.field + (o + st.offA);
    tp.b = st.field + (o + st.offB);
    tp.wa = splat<V>(st.w[0][0]);
    tp.wb = splat<V>(st.w[1][0]);
    tp.inv = splat<V>(st.w[2][0]);
    if constexpr (K == CastingMoments::GlossyNlp) {
        const ScanStep& rs = az.glossy[i];
        tp.planes = az.glossyFields + static_cast<std::size_t>(i) * kShFields;
        tp.o = Y * rs.rowStep;
        tp.dB = rs.offB - rs.offA;
        const ScanStep& ns = az.glossy[nextI];
        tp.nextPlanes = az.glossyFields + static_cast<std::size_t>(nextI) * kShFields;
        tp.nextO = nextY * ns.rowStep;
        tp.nextDB = ns.offB - ns.offA;
        tp.rwa[0] = splat<V>(rs.w[0][0]);
        tp.rwb[0] = splat<V>(rs.w[1][0]);
        tp.back[0] = splat<V>(-az.cosPhi);
        tp.back[1] = splat<V>(-az.sinPhi);
        tp.clamp = az.clampNegative;
        return tp;
    }
    tp.group = az.distanceGroups ? az.distanceGroups[i] : -1;
    const ScanStep& ns = az.heights[nextI];
    tp.nextA = ns.field + (nextY * ns.rowStep + ns.offA);
    tp.nextB = ns.field + (nextY * ns.rowStep + ns.offB);
    for (int c = 0; c < 3; ++c) {
        const ScanStep& nr = az.radiance[c][nextI];
        tp.nextR[c] = nr.field + (nextY * nr.rowStep + nr.offA);
    }
    for (int c = 0; c < 3; ++c) {
        const ScanStep& rs = az.radiance[c][i];
        const std::ptrdiff_t ro = Y * rs.rowStep;
        tp.ra[c] = rs.field + (ro + rs.offA);
        tp.rb[c] = rs.field + (ro + rs.offB);
        tp.rwa[c] = splat<V>(rs.w[0][0]);
        tp.rwb[c] = splat<V>(rs.w[1][0]);
    }
    return tp;
}

// ---- algorithm: the casting set and Eq. 12 for one row of receivers --------
// The walk over the height steps (Eq. 17): at each step where some lane has a
// new casting-set member, the clamped segment's moments (0 in the other
// lanes) are multiplied with the radiance samples there and summed per
// channel (each lane's sums in step order).
//
// The row is walked step by step: at step i every group of L receivers still
// walking reads its 2 height taps and, where some lane has a new casting-set
// member, the 3 channels' radiance taps: each step's reads sweep one
// contiguous stretch of its field (hardware prefetch follows them), and the
// groups' running values live in the row scratch (IndirectScratch::state).
// Per lane the same operations in the same order as walking each group alone
// (step order; lanes without a new member add exactly 0), so the result does
// not depend on the schedule.
template <class V, CastingMoments K>
struct CastingRow {
    using I = typename LaneTraits<V>::I;
    static constexpr int L = LaneTraits<V>::n;
    static constexpr bool Exact = K == CastingMoments::Irradiance;
    static constexpr bool Glossy = K == CastingMoments::GlossyNlp;
    static constexpr int nMo = Exact ? 1 : kCastingMoments;  // moments per segment

    const ReceiverRow* in = nullptr;
    int pad = 0;
    // state planes (pad floats each): M the running maximum, g the tangent
    // slope, q1 (Nlp) the sin of the last segment end, F (Irradiance) F at the
    // last segment end, then 3 x nMo sums A
    float *M = nullptr, *g = nullptr, *q1 = nullptr, *F = nullptr, *A = nullptr;
    float* groupOcc = nullptr;  // Irradiance: each distance group's |Delta F| (IndirectScratch::groupOccludersOf)
    int* steps = nullptr;       // per lane: the valid prefix (row limit applied)
    int* active = nullptr;      // groups still walking
    int nActive = 0;
    const V one = splat<V>(1.0f), half = splat<V>(0.5f), zero = splat<V>(0.0f);
    const V lim = splat<V>(1e6f), nlim = splat<V>(-1e6f);

    // Row r of the block: its running values in the scratch (IndirectScratch::stateOf).
    void init(const ReceiverRow& row, IndirectScratch& sc, int r) {
        in = &row;
        pad = sc.pad;
        M = sc.stateOf(r);
        g = M + pad;
        q1 = M + 2 * pad;
        F = M + 3 * pad;
        A = M + 4 * pad;
        groupOcc = sc.groupOccludersOf(r);
        steps = sc.groupSteps.data() + static_cast<std::size_t>(r) * pad;
        active = sc.active.data() + static_cast<std::size_t>(r) * pad;
    }

    // Group G's running values before the first step; returns its longest valid prefix.
    [[gnu::always_inline]] int startGroup(int G, const AzimuthSteps& az, I rowLimit) {
        const int X0 = G * L;
        I c;
        std::memcpy(&c, az.stepsPerColumn + X0, sizeof c);
        c = c < rowLimit ? c : rowLimit;
        std::memcpy(steps + X0, &c, sizeof c);
        int nAny = 0;
        for (int l = 0; l < L; ++l) nAny = std::max(nAny, static_cast<int>(c[l]));
        store(M + X0, splat<V>(kNoBlocker));
        // omega_min: the tangent plane's slope along the azimuth (Section 3)
        const V gv = load<V>(in->gx + X0) * splat<V>(az.cosPhi) + load<V>(in->gy + X0) * splat<V>(az.sinPhi);
        store(g + X0, gv);
        if constexpr (!Exact) {
            const V t = gv < nlim ? nlim : (gv > lim ? lim : gv);
            const V r = one / sqrtv(one + t * t);  // cos of the lower bound
            store(q1 + X0, t * r);
        } else {
            // F(t) = f2 - g f1 at the clamped segment end (f1, f2 the clamped
            // cosine's antiderivatives); F is smallest at t = g (the receiver's
            // plane), so ends below g keep F(g)
            const V te = gv < nlim ? nlim : (gv > lim ? lim : gv);
            const V re = one / sqrtv(one + te * te), se = te * re;
            store(F + X0, half * (se * se) - gv * (half * (atanv(te) + se * re)));
        }
        for (int p = 0; p < 3 * nMo; ++p) store(A + static_cast<std::size_t>(p) * pad + X0, zero);
        return nAny;
    }

    // GlossyNlp: what each new member sends back to its receiver per
    // channel, u = Ebar . Y(-d) at its own (unclamped) elevation; 0 in the
    // lanes without a new member (their basis is 0, their samples finite).
    [[gnu::always_inline]] void glossyRadiance(const StepTaps<V>& tp, I nw, V t, int X0, V u[3]) const {
        V tm = t < nlim ? nlim : (t > lim ? lim : t);
        tm = nw ? tm : zero;
        const V ic = one / sqrtv(one + tm * tm);
        V y[kShCount];
        shBasisLanes<V>(tp.back[0] * ic, tp.back[1] * ic, -(tm * ic), y);
        for (int f = 0; f < kShCount; ++f) y[f] = nw ? y[f] : zero;
        // The groups of a row walk each step left to right: once per 64-byte
        // line (32 values, 4 groups), each of the 48 planes' line 3 ahead and
        // the line the block reads next at this column (the next row's, or
        // after the last row the first row's at the next step) are asked for
        // early: the hardware's prefetchers do not follow 96 streams at once,
        // and a row's first lines would otherwise come late (README, "Glossy
        // indirect light", has the gains).
        const bool prefetch = (X0 & 31) == 0;
        for (int c = 0; c < 3; ++c) {
            V sum = zero;
            for (int f = 0; f < kShCount; ++f) {
                const std::uint16_t* pa = tp.planes[c * kShCount + f] + (tp.o + X0);
                if (prefetch) {
                    const std::uint16_t* pn = tp.nextPlanes[c * kShCount + f] + (tp.nextO + X0);
                    __builtin_prefetch(pn);
                    __builtin_prefetch(pn + tp.nextDB);
                    __builtin_prefetch(pa + 96);
                    __builtin_prefetch(pa + tp.dB + 96);
                }
                sum += (tp.rwa[0] * loadBfloat16<V>(pa) + tp.rwb[0] * loadBfloat16<V>(pa + tp.dB)) * y[f];
            }
            u[c] = tp.clamp ? vmax(sum, zero) : sum;
        }
    }

    // The new members' segments [c_(i-1), c_i] clamped to [omega_min, pi/2]:
    // their moments times the radiance samples, into the sums A.
    [[gnu::always_inline]] void addSegments(const StepTaps<V>& tp, I nw, V t, int X0) {
        const V gl = load<V>(g + X0);
        V tc = t < gl ? gl : t;
        tc = tc < nlim ? nlim : (tc > lim ? lim : tc);
        const V r = one / sqrtv(one + tc * tc), sNew = tc * r;  // cos, sin of the end
        V mo[nMo];
        if constexpr (!Exact) {
            const V p = load<V>(q1 + X0);
            const V sv = nw ? sNew : p;  // no new member: an empty segment (exactly 0)
            const V p2 = p * p, s2 = sv * sv;
            mo[0] = sv - p;
            mo[1] = s2 - p2;
            mo[2] = s2 * sv - p2 * p;
            mo[3] = s2 * s2 - p2 * p2;
            store(q1 + X0, sv);
        } else {
            const V f = load<V>(F + X0);
            const V fNew = half * (sNew * sNew) - gl * (half * (atanv(tc) + sNew * r));
            const V fv = (nw & (tc >= gl)) ? fNew : f;  // below the receiver's plane: nothing
            mo[0] = fv - f;
            store(F + X0, fv);
            if (tp.group >= 0) {
                // |Delta F|: float rounding may make a difference of increasing F negative
                float* occ = groupOcc + static_cast<std::size_t>(tp.group) * pad + X0;
                store(occ, load<V>(occ) + (mo[0] < zero ? zero - mo[0] : mo[0]));
            }
        }
        // moments x radiance (lanes without a new member have zero moments;
        // the radiance read there is finite: inside the field's padding and guard)
        V u[3];
        if constexpr (Glossy)
            glossyRadiance(tp, nw, t, X0, u);
        else
            for (int c = 0; c < 3; ++c) u[c] = tp.rwa[c] * load<V>(tp.ra[c] + X0) + tp.rwb[c] * load<V>(tp.rb[c] + X0);
        for (int c = 0; c < 3; ++c) {
            for (int p = 0; p < nMo; ++p) {
                float* acc = A + static_cast<std::size_t>(c * nMo + p) * pad + X0;
                store(acc, load<V>(acc) + u[c] * mo[p]);
            }
        }
    }

    // Step i (iv) for the group at X0; false once the group is done: no lane
    // has a step i + 1 in its prefix (step i + 1's samples may lie outside the
    // field then, past its padding), or none can gain a member.
    [[gnu::always_inline]] bool stepGroup(const StepTaps<V>& tp, I iv, V hMax, int X0) {
        I stp;
        std::memcpy(&stp, steps + X0, sizeof stp);
        if constexpr (K != CastingMoments::GlossyNlp) {
            // once per 64-byte line of the row, the lines the block reads
            // next at this column: a local change's spans are a tile or two
            // wide, too short a stream for the hardware's prefetchers, and
            // each step's reads came cold (README, "Cold reads and an idle thread")
            if ((X0 & 15) == 0) {
                __builtin_prefetch(tp.nextA + X0);
                __builtin_prefetch(tp.nextB + X0);
                for (int c = 0; c < 3; ++c) __builtin_prefetch(tp.nextR[c] + X0);
            }
        }
        const V h0 = load<V>(in->h0 + X0);
        const V t =
            (((tp.wa * load<V>(tp.a + X0) + tp.wb * load<V>(tp.b + X0)) - h0) - load<V>(in->margin + X0)) * tp.inv;
        V m = load<V>(M + X0);
        const I nw = (iv < stp) & (t > m);  // Eq. 17: above every earlier sample
        if (laneBits(nw) == 0) {
            // past the point where even the field's highest height would not
            // beat any lane's running maximum, no new member can come: the
            // group is done (lanes whose ray has left the domain are done too)
            const I done = (iv + 1 >= stp) | (m >= (hMax - h0) * tp.inv);
            return laneBits(~done) != 0;
        }
        m = nw ? t : m;
        store(M + X0, m);
        addSegments(tp, nw, t, X0);
        return laneBits(iv + 1 < stp) != 0;
    }

    // Before the first step: the groups of the row's spans with a step to
    // walk; returns the row's longest valid prefix.
    [[gnu::always_inline]] int start(const AzimuthSteps& az) {
        const I rowLimit = I{} + in->steps;
        int nMax = 0;
        nActive = 0;
        for (const ColumnSpan& span : in->spans)
            for (int G = span.x0 / L; G < indirectRowPad(span.x1) / L; ++G) {
                const int nAny = startGroup(G, az, rowLimit);
                nMax = std::max(nMax, nAny);
                if (nAny > 0) active[nActive++] = G;
            }
        return nMax;
    }

    // Step i of the groups still walking; false once none is (past the row's
    // longest prefix none is).
    [[gnu::always_inline]] bool step(const AzimuthSteps& az, int i, int nextI, int nextY) {
        const StepTaps<V> tp = stepTaps<V, K>(az, i, in->Y, nextI, nextY);
        const I iv = I{} + i;
        const V hMax = splat<V>(in->hMax);
        int kept = 0;
        for (int q = 0; q < nActive; ++q) {
            const int G = active[q];
            if (stepGroup(tp, iv, hMax, G * L)) active[kept++] = G;
        }
        nActive = kept;
        return nActive > 0;
    }

    // The sums per channel into out: the exact moment (Irradiance), or the
    // NLP coefficients by Eq. 10's closed form as a polynomial in s (Nlp).
    [[gnu::always_inline]] void finish(float* out) const {
        const V k0 = splat<V>(0.70710678118654752440f), k1 = splat<V>(0.61237243569579452455f);
        const V k2 = splat<V>(0.79056941504209483300f), k3 = splat<V>(0.23385358667337133659f);
        for (int c = 0; c < 3; ++c)
            for (const ColumnSpan& span : in->spans)
                for (int X0 = span.x0; X0 < indirectRowPad(span.x1); X0 += L) {
                    V Ac[nMo];
                    for (int p = 0; p < nMo; ++p) Ac[p] = load<V>(A + static_cast<std::size_t>(c * nMo + p) * pad + X0);
                    if constexpr (Exact) {
                        store(out + static_cast<std::size_t>(c) * pad + X0, Ac[0]);
                    } else {
                        float* base = out + static_cast<std::size_t>(c) * 4 * pad + X0;
                        store(base, k0 * Ac[0]);
                        store(base + pad, k1 * Ac[1]);
                        store(base + 2 * pad, k2 * (Ac[2] - Ac[0]));
                        store(base + 3 * pad, k3 * (splat<V>(5.0f) * Ac[3] - splat<V>(6.0f) * Ac[1]));
                    }
                }
    }
};

// The block's rows walk the steps together: at step i every row's groups
// still walking, row after row. Consecutive rows read neighbouring rows of
// the step's level, so each sample line serves the block's rows while it is
// in cache (the 48-plane glossy pyramid is far larger than the cache).
template <class V, CastingMoments K>
[[gnu::always_inline]] inline void castRowsImpl(const AzimuthSteps& az, std::span<const ReceiverRow> rows,
                                                IndirectScratch& sc) {
    CastingRow<V, K> walk[kMaxScanRows];
    const int n = static_cast<int>(rows.size());
    int nMax = 0;
    for (int r = 0; r < n; ++r) {
        walk[r].init(rows[static_cast<std::size_t>(r)], sc, r);
        nMax = std::max(nMax, walk[r].start(az));
    }
    for (int i = 0; i < nMax; ++i) {
        bool walking = false;
        for (int r = 0; r < n; ++r) {
            // the rows the block reads after this one (prefetch)
            const bool last = r + 1 == n;
            const int nextI = last ? std::min(i + 1, nMax - 1) : i;
            const int nextY = rows[last ? 0 : static_cast<std::size_t>(r) + 1].Y;
            if (walk[r].nActive > 0) walking |= walk[r].step(az, i, nextI, nextY);
        }
        if (!walking) break;
    }
    for (int r = 0; r < n; ++r) walk[r].finish(sc.resultOf(r));
}

template <CastingMoments K>
void castRowsSse(const AzimuthSteps& az, std::span<const ReceiverRow> rows, IndirectScratch& sc) {
    castRowsImpl<F4, K>(az, rows, sc);
}
template <CastingMoments K>
[[gnu::target("avx2"), gnu::flatten]] void castRowsAvx2(const AzimuthSteps& az, std::span<const ReceiverRow> rows,
                                                        IndirectScratch& sc) {
    castRowsImpl<F8, K>(az, rows, sc);
}

}  // namespace

void sizeIndirectScratch(IndirectScratch& sc, int rows, int pad, bool irradiance) {
    const std::size_t rowFloats = static_cast<std::size_t>(rows) * pad;
    sc.pad = pad;
    sc.gx.resize(rowFloats);
    sc.gy.resize(rowFloats);
    sc.h0.resize(rowFloats);
    sc.margin.resize(rowFloats);
    if (irradiance) sc.irradiance.resize(rowFloats * 3);
    sc.result.resize(static_cast<std::size_t>(IndirectScratch::kResultPlanes) * rowFloats);
    sc.state.resize(static_cast<std::size_t>(IndirectScratch::kStatePlanes) * rowFloats);
    sc.groupSteps.resize(rowFloats);
    sc.active.resize(rowFloats);
}

CastRowsFn castRowsFor(CastingMoments moments) {
    const bool wide = simd::wideEnabled();
    switch (moments) {
        case CastingMoments::Nlp:
            return wide ? castRowsAvx2<CastingMoments::Nlp> : castRowsSse<CastingMoments::Nlp>;
        case CastingMoments::Irradiance:
            return wide ? castRowsAvx2<CastingMoments::Irradiance> : castRowsSse<CastingMoments::Irradiance>;
        case CastingMoments::GlossyNlp:
            break;
    }
    return wide ? castRowsAvx2<CastingMoments::GlossyNlp> : castRowsSse<CastingMoments::GlossyNlp>;
}

}  // namespace terrain::gi
