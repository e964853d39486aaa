#include "gi/visibility.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <span>

#include "core/error.h"
#include "core/parallel.h"
#include "core/simd.h"
#include "gi/nlp.h"

namespace terrain::gi {

namespace {

constexpr int kMaxBlocks = 64;
constexpr int kRowPad = 16;  // receivers per kernel call at most (4 x 4 or 2 x 8 lanes); rows are padded to it

using namespace simd;

inline int padLanes(int n) { return (n + kRowPad - 1) / kRowPad * kRowPad; }

// ---- algorithm: the step table (Eq. 14, level offset o_v) ---------------------
// For azimuth (c, sn) and step i: where each receiver samples, with which
// bilinear weights, and which receivers' samples lie inside the domain.
// Raw steps (level < 0) sample the full-resolution heights in cells (receiver
// X at column s X); level steps sample the level blown out to the receiver
// grid (receiver X at X). Either way all receivers of a row share one
// fractional offset, so the weights are per step, not per receiver.
struct StepGeometry {
    ScanStep step;
    int xFirst = 0, xLast = -1, yFirst = 0, yLast = -1;  // valid receivers
    int tapX = 0, tapY = 0;                              // the first tap's texel offset (ScanStepInfo)
    bool alongX = true;                                  // the second tap is the next row (else column)
    double dx = 0.0, dy = 0.0;                           // sample offset in field texels
    int k = 1, fieldNx = 0, fieldNy = 0;                 // receiver spacing in field texels, field size
};

void validRange(double d, int k, int fieldN, int receivers, int& first, int& last) {
    // receivers R with k R + d in [0, fieldN - 1]
    first = std::max(0, static_cast<int>(std::ceil(-d / k)));
    last = std::min(receivers - 1, static_cast<int>(std::floor((fieldN - 1 - d) / k)));
    while (first <= last && k * first + d < 0.0) ++first;  // guard against rounding at the ends
    while (last >= first && k * last + d > fieldN - 1) --last;
    if (first > last) {
        first = 0;
        last = -1;
    }
}

StepGeometry makeStepAt(const HeightPyramid& pyr, const PyramidStep& ps, double c, double sn) {
    const int s = pyr.subsample;
    const bool raw = ps.level < 0;
    StepGeometry g;
    ScanStep& st = g.step;
    // Sample on a grid line of the field it reads (as the reference march
    // does): the step is moved along the ray to the nearest crossing of the
    // lines across the ray's major axis, where the bilinear field is linear
    // between two texels (two taps instead of four). The move is at most half a
    // texel along that axis; 1 / tau is that of the moved sample.
    const double unit = raw ? 1.0 : static_cast<double>(s);  // texel spacing of the field, cells
    const bool alongX = std::abs(c) >= std::abs(sn);
    const double major = alongX ? c : sn;
    const double texels = std::max(1.0, std::round(std::abs(ps.tauCells * major) / unit));
    const double tau = texels * unit / std::abs(major);
    double dx = tau * c, dy = tau * sn;
    if (alongX)
        dx = std::copysign(texels * unit, c);
    else
        dy = std::copysign(texels * unit, sn);
    int k, fieldNx, fieldNy;
    if (raw) {
        k = s;
        fieldNx = pyr.nx;
        fieldNy = pyr.ny;
    } else {
        k = 1;
        dx /= s;
        dy /= s;
        fieldNx = pyr.nxr;
        fieldNy = pyr.nyr;
    }
    validRange(dx, k, fieldNx, pyr.nxr, g.xFirst, g.xLast);
    validRange(dy, k, fieldNy, pyr.nyr, g.yFirst, g.yLast);
    g.dx = dx;
    g.dy = dy;
    g.k = k;
    g.fieldNx = fieldNx;
    g.fieldNy = fieldNy;
    const double c0d = std::floor(dx), r0d = std::floor(dy);
    const int c0 = static_cast<int>(c0d), r0 = static_cast<int>(r0d);
    g.tapX = c0;
    g.tapY = r0;
    g.alongX = alongX;
    const float f = static_cast<float>(alongX ? dy - r0d : dx - c0d);  // the other coordinate's fraction
    const float weights[3] = {1.0f - f, f, static_cast<float>(1.0 / (tau * pyr.cellSize))};
    for (int q = 0; q < 3; ++q)
        for (int l = 0; l < 4; ++l) st.w[q][l] = weights[q];
    if (raw) {
        // column s X + c0 lies in phase plane (c0 mod s) at X + floor(c0 / s)
        const int qa = ((c0 % s) + s) % s, qb = (((c0 + 1) % s) + s) % s;
        const int colA = (c0 - qa) / s, colB = (c0 + 1 - qb) / s;
        const std::ptrdiff_t w = pyr.rawPhaseWidth;
        st.field = pyr.rawPhaseData();
        st.rowStep = s * w;
        st.offA = qa * pyr.rawPhasePlane + r0 * w + colA;
        st.offB = alongX ? st.offA + w : qb * pyr.rawPhasePlane + r0 * w + colB;  // next row / next column
    } else {
        const PaddedField& fl = pyr.levels[static_cast<std::size_t>(ps.level)];
        st.field = fl.data();
        st.rowStep = fl.stride;
        st.offA = r0 * fl.stride + c0;
        st.offB = st.offA + (alongX ? fl.stride : 1);
    }
    return g;
}

StepGeometry makeStep(const HeightPyramid& pyr, int i, double c, double sn) {
    return makeStepAt(pyr, pyr.steps[static_cast<std::size_t>(i)], c, sn);
}

// The blocking slope of one receiver at one step (the scalar form of the
// kernel's lanes: the same operations in the same order).
inline float sampleSlope(const ScanStep& st, std::ptrdiff_t index, float h0) {
    return (stepSample(st, index) - h0) * st.w[2][0];
}

// ---- algorithm: per-step visitors over the slope sequence ---------------------
// A visitor sees the slopes of NV vectors of receivers step by step. all(i, s):
// step i, every lane valid. some(i, s, valid): step i where only the lanes of
// `valid` are (the others' rays have left the domain; their s is garbage); the
// kernel calls some() once more at i = (longest sequence) with no lane valid,
// so a visitor can close what is still open. steps: each lane's sequence length.
// Lane type V: F4 (SSE2) or F8 (AVX2), core/simd.h; the same lane-wise
// operations either way.

// Plain maximum over the samples.
template <class V, int NV>
struct SampleMaxVisitor {
    using I = typename LaneTraits<V>::I;
    V m[NV];
    SampleMaxVisitor() {
        for (int k = 0; k < NV; ++k) m[k] = splat<V>(kNoBlocker);
    }
    // m = maxps(m, s): the larger; equal values are the same number (no -0 arises)
    void all(int, const V* s) {
        for (int k = 0; k < NV; ++k) m[k] = m[k] > s[k] ? m[k] : s[k];
    }
    void some(int, const V* s, const I* valid, const I*) {
        for (int k = 0; k < NV; ++k) m[k] = (valid[k] & (s[k] > m[k])) ? s[k] : m[k];
    }
    void result(float* out) const {
        for (int k = 0; k < NV; ++k) store(out + LaneTraits<V>::n * k, m[k]);
    }
};

// Eq. 16: the maximum of the cubic interpolant through the samples, at the
// knots (the samples) and the midpoints (-s_{i-1} + 9 s_i + 9 s_{i+1} - s_{i+2}) / 16
// of consecutive valid samples, ends replicated. The interpolant can rise
// between samples, recovering part of a peak that falls between two steps.
// At step i the midpoint between i-2 and i-1 is closed: p3, p2, p1 hold
// s_{i-3}, s_{i-2}, s_{i-1} (s_{-1} = s_0).
template <class V, int NV>
struct BsplineMaxVisitor {
    using I = typename LaneTraits<V>::I;
    V m[NV], p1[NV], p2[NV], p3[NV];
    BsplineMaxVisitor() {
        for (int k = 0; k < NV; ++k) m[k] = p1[k] = p2[k] = p3[k] = splat<V>(kNoBlocker);
    }
    static V mid(V sm, V s0, V s1, V s2) { return (9.0f * (s0 + s1) - (sm + s2)) * (1.0f / 16.0f); }
    void all(int i, const V* s) {
        for (int k = 0; k < NV; ++k) {
            if (i == 0) p1[k] = p2[k] = p3[k] = s[k];
            m[k] = m[k] > s[k] ? m[k] : s[k];
            if (i >= 2) {
                const V md = mid(p3[k], p2[k], p1[k], s[k]);
                m[k] = m[k] > md ? m[k] : md;
            }
            p3[k] = p2[k];
            p2[k] = p1[k];
            p1[k] = s[k];
        }
    }
    void some(int i, const V* s, const I* valid, const I* steps) {
        const I iv = I{} + i;
        for (int k = 0; k < NV; ++k) {
            const V v = valid[k] ? s[k] : p1[k];  // past the end: replicate the last sample
            if (i == 0) {
                p1[k] = p2[k] = p3[k] = v;  // invalid lanes: empty sequence, stays kNoBlocker
            }
            m[k] = (valid[k] & (v > m[k])) ? v : m[k];
            if (i >= 2) {
                const V md = mid(p3[k], p2[k], p1[k], v);
                m[k] = ((iv <= steps[k]) & (md > m[k])) ? md : m[k];
            }
            p3[k] = p2[k];
            p2[k] = p1[k];
            p1[k] = v;
        }
    }
    void result(float* out) const {
        for (int k = 0; k < NV; ++k) store(out + LaneTraits<V>::n * k, m[k]);
    }
};

// ---- algorithm: the scan of L NV receivers (X0 .. X0 + L NV - 1 of row Y) -------
// h0: the row's receiver heights; steps: valid-prefix length
// of each lane; all lanes are valid for i < nAll, none for i >= nAny.
template <class V, int NV, class Visitor>
[[gnu::always_inline]] inline void scanLanes(const ScanStep* table, const float* const* rowPtr, int X0, const float* h0,
                                             const typename LaneTraits<V>::I* steps, int nAll, int nAny,
                                             Visitor& visit) {
    using I = typename LaneTraits<V>::I;
    constexpr int L = LaneTraits<V>::n;
    V h[NV];
    for (int k = 0; k < NV; ++k) h[k] = load<V>(h0 + X0 + L * k);
    auto sample = [&](int i, V* s) {
        const ScanStep& st = table[i];
        const float* a = rowPtr[2 * i] + X0;
        const float* b = rowPtr[2 * i + 1] + X0;
        const V wa = splat<V>(st.w[0][0]), wb = splat<V>(st.w[1][0]), inv = splat<V>(st.w[2][0]);
        for (int k = 0; k < NV; ++k) s[k] = ((wa * load<V>(a + L * k) + wb * load<V>(b + L * k)) - h[k]) * inv;
    };
    for (int i = 0; i < nAll; ++i) {
        V s[NV];
        sample(i, s);
        visit.all(i, s);
    }
    // Steps where some rays have left the domain: the row is inside (the row
    // limit is common to all lanes), the outside lanes read neighbouring
    // columns (inside the field's guard) and are masked out.
    for (int i = nAll; i <= nAny; ++i) {
        V s[NV];
        I valid[NV];
        const I iv = I{} + i;
        for (int k = 0; k < NV; ++k) valid[k] = iv < steps[k];
        if (i < nAny)
            sample(i, s);
        else
            for (int k = 0; k < NV; ++k) s[k] = splat<V>(0.0f);
        visit.some(i, s, valid, steps);
    }
}

// The receivers a row's kernels run over: each span from its start (a
// multiple of 16) to its end rounded up to the 16-receiver group (the padded
// row's end for a span ending at nxr: as in a whole row).
inline int spanEnd(const ColumnSpan& span) { return padLanes(span.x1); }

// Maximum blocking slope of the receivers of a row's spans for one azimuth,
// in groups of `lanes` receivers (NV vectors). rowPtr: scratch for 2 x
// rowSteps pointers (each step's taps at receiver 0 of row Y).
template <class V, int lanes, template <class, int> class Visitor>
[[gnu::always_inline]] inline void scanRow(const ScanStep* table, const int* colSteps, int rowSteps, int Y,
                                           const float* h0, std::span<const ColumnSpan> spans, float* out,
                                           const float** rowPtr) {
    using I = typename LaneTraits<V>::I;
    constexpr int L = LaneTraits<V>::n, NV = lanes / L;
    for (int i = 0; i < rowSteps; ++i) {
        const ScanStep& st = table[i];
        const std::ptrdiff_t o = Y * st.rowStep;
        rowPtr[2 * i] = st.field + (o + st.offA);
        rowPtr[2 * i + 1] = st.field + (o + st.offB);
    }
    const I rowLimit = I{} + rowSteps;
    for (const ColumnSpan& span : spans)
        for (int X0 = span.x0; X0 < spanEnd(span); X0 += lanes) {
            I steps[NV];
            I lo = rowLimit, hi = I{};
            for (int k = 0; k < NV; ++k) {
                I c;
                std::memcpy(&c, colSteps + X0 + L * k, sizeof c);
                steps[k] = c < rowLimit ? c : rowLimit;
                lo = steps[k] < lo ? steps[k] : lo;
                hi = steps[k] > hi ? steps[k] : hi;
            }
            int nAll = lo[0], nAny = hi[0];
            for (int l = 1; l < L; ++l) {
                nAll = std::min(nAll, static_cast<int>(lo[l]));
                nAny = std::max(nAny, static_cast<int>(hi[l]));
            }
            Visitor<V, NV> visit;
            scanLanes<V, NV>(table, rowPtr, X0, h0, steps, nAll, nAny, visit);
            visit.result(out + X0);
        }
}

// ---- algorithm: Eq. 11 and the folded wedge operator for one azimuth -------
// NLP vectors of the receivers of a row's spans (4 rows of nxrPad), then
// V += G_j w_j over the sparse pattern, each entry a contiguous multiply-add
// over the row. omega_min: elevation of the tangent plane along the azimuth
// (Section 3).
template <class V>
[[gnu::always_inline]] inline void nlpRow(const float* __restrict maxSlope, const float* __restrict gx,
                                          const float* __restrict gy, float cosPhi, float sinPhi,
                                          const VisibilityTarget& target, float* __restrict nlp,
                                          std::span<const ColumnSpan> spans, int nxrPad) {
    constexpr int L = LaneTraits<V>::n;
    const V c = splat<V>(cosPhi), sn = splat<V>(sinPhi);
    const V one = splat<V>(1.0f), lim = splat<V>(1e6f), nlim = splat<V>(-1e6f);
    const V k0 = splat<V>(0.70710678118654752440f), k1 = splat<V>(0.61237243569579452455f);
    const V k2 = splat<V>(0.79056941504209483300f), k3 = splat<V>(0.23385358667337133659f);
    const V five = splat<V>(5.0f), four = splat<V>(4.0f);
    const V sLow = splat<V>(target.sinLow), sHigh = splat<V>(target.sinHigh);
    for (const ColumnSpan& span : spans)
        for (int X = span.x0; X < spanEnd(span); X += L) {
            const V tangent = load<V>(gx + X) * c + load<V>(gy + X) * sn;
            const V ms = load<V>(maxSlope + X);
            V t = ms < tangent ? tangent : ms;
            t = t < nlim ? nlim : (t > lim ? lim : t);  // sinFromSlope
            const V s = t / sqrtv(one + t * t);
            V w0, w1, w2, w3;
            if (target.window) {
                // nlpVisibleBetween(lo, hi): occlusion(hi) - occlusion(lo)
                const V lo = s < sLow ? sLow : s;
                const V hi = lo < sHigh ? sHigh : lo;
                const V cl = one - lo * lo, ch = one - hi * hi;
                w0 = (hi + one) * k0 - (lo + one) * k0;
                w1 = (-k1) * ch - (-k1) * cl;
                w2 = (-k2) * hi * ch - (-k2) * lo * cl;
                w3 = k3 * ch * (five * ch - four) - k3 * cl * (five * cl - four);
            } else {
                // nlpVisibleAbove(s)
                const V c2 = one - s * s;
                w0 = (one - s) * k0;
                w1 = k1 * c2;
                w2 = k2 * s * c2;
                w3 = (-k3) * c2 * (five * c2 - four);
            }
            store(nlp + X, w0);
            store(nlp + nxrPad + X, w1);
            store(nlp + 2 * nxrPad + X, w2);
            store(nlp + 3 * nxrPad + X, w3);
        }
}

// V += G_j w_j for a batch of azimuths (1 or 2) at the receivers of a row's
// spans, each SH row of V read and written once per batch; the additions run
// in the same order as one azimuth and one entry after the other
// (bit-identical to the plain sequence). Receivers below the row's last
// multiple of 16 go 16 at a time, the rest one by one, whatever the spans.
// opValues: the folded operator's entries of each azimuth.
template <class V>
[[gnu::always_inline]] inline void accumulateRows(const float* const* nlp, const float* const* opValues, int batch,
                                                  const std::uint8_t* patRow, const std::uint8_t* patNlp, int patSize,
                                                  float* const* vRows, int nxr, std::span<const ColumnSpan> spans,
                                                  int nxrPad) {
    constexpr int kMaxTerms = 8, L = LaneTraits<V>::n, NA = 16 / L;
    int e = 0;
    while (e < patSize) {
        const int r = patRow[e];
        int e1 = e;
        while (e1 < patSize && patRow[e1] == r && e1 - e < kMaxTerms / 2) ++e1;
        // the terms of this SH row, in addition order: azimuth, then entry
        const float* w[kMaxTerms];
        V g[kMaxTerms];
        float gs[kMaxTerms];
        int nt = 0;
        for (int a = 0; a < batch; ++a)
            for (int q = e; q < e1; ++q) {
                w[nt] = nlp[a] + static_cast<std::size_t>(patNlp[q]) * nxrPad;
                gs[nt] = opValues[a][q];
                g[nt] = splat<V>(gs[nt]);
                ++nt;
            }
        float* __restrict v = vRows[r];
        for (const ColumnSpan& span : spans) {
            // 16 receivers at a time: independent addition chains
            const int n16 = std::min(span.x1, nxr / 16 * 16);
            for (int X = span.x0; X < n16; X += 16) {
                V acc[NA];
                for (int k = 0; k < NA; ++k) acc[k] = load<V>(v + X + L * k);
                for (int t = 0; t < nt; ++t)
                    for (int k = 0; k < NA; ++k) acc[k] += g[t] * load<V>(w[t] + X + L * k);
                for (int k = 0; k < NA; ++k) store(v + X + L * k, acc[k]);
            }
            for (int X = n16; X < span.x1; ++X) {
                float acc = v[X];
                for (int t = 0; t < nt; ++t) acc += gs[t] * w[t][X];
                v[X] = acc;
            }
        }
        e = e1;
    }
}

// One row's azimuth batch (1 or 2 azimuths from j0) over the receivers of
// the row's spans: the scans, their maximum slopes out, NLP vectors and
// V += G_j w_j.
struct RowBatch {
    const ScanStep* steps;  // the step table (azimuths x nSteps)
    int nSteps, nxr, nyr, nxrPad, Y, j0, batch;
    std::span<const ColumnSpan> spans;  // the receivers of row Y to compute
    const int* stepsPerColumn;          // azimuths x nxrPad
    const int* stepsPerRow;             // azimuths x nyr
    const float* cosSin;                // azimuths x 2
    const float* h0;                    // the row's receiver heights
    const float* gradX;                 // receiver, footprint lo, hi (x nxrPad)
    const float* gradY;
    bool foot;  // footprint rows present
    BlockingMax blockingMax;
    const VisibilityTarget* target;
    const FoldedWedgeOperator* op;
    float* maxRow;         // nxrPad scratch
    float* nlp;            // 2 x 4 x nxrPad scratch
    const float** rowPtr;  // 2 x nSteps scratch
    float* maxSlope;       // out.maxSlope (azimuths x planes)
    float* const* vRows;   // the row of each SH plane of V
};

template <class V>
[[gnu::always_inline]] inline void rowBatchImpl(const RowBatch& r) {
    const float* nlps[2];
    const float* ops[2];
    const std::size_t planeSize = static_cast<std::size_t>(r.nxr) * r.nyr;
    const int P = r.op->patternSize();
    for (int a = 0; a < r.batch; ++a) {
        const int j = r.j0 + a;
        const ScanStep* table = r.steps + static_cast<std::size_t>(j) * r.nSteps;
        const int* colSteps = r.stepsPerColumn + static_cast<std::size_t>(j) * r.nxrPad;
        const int rowSteps = r.stepsPerRow[static_cast<std::size_t>(j) * r.nyr + static_cast<std::size_t>(r.Y)];
        if (r.blockingMax == BlockingMax::Samples)
            scanRow<V, 16, SampleMaxVisitor>(table, colSteps, rowSteps, r.Y, r.h0, r.spans, r.maxRow, r.rowPtr);
        else
            scanRow<V, 8, BsplineMaxVisitor>(table, colSteps, rowSteps, r.Y, r.h0, r.spans, r.maxRow, r.rowPtr);
        float* maxOut = r.maxSlope + planeSize * j + static_cast<std::size_t>(r.Y) * r.nxr;
        for (const ColumnSpan& span : r.spans) std::copy(r.maxRow + span.x0, r.maxRow + span.x1, maxOut + span.x0);
        if (P == 0) continue;  // horizons only (horizonsOnly): no V
        float* nlp = r.nlp + static_cast<std::size_t>(a) * 4 * r.nxrPad;
        const float cj = r.cosSin[2 * static_cast<std::size_t>(j)], sj = r.cosSin[2 * static_cast<std::size_t>(j) + 1];
        const float* tgx = r.foot ? r.gradX + (cj >= 0.0f ? 1 : 2) * r.nxrPad : r.gradX;
        const float* tgy = r.foot ? r.gradY + (sj >= 0.0f ? 1 : 2) * r.nxrPad : r.gradY;
        nlpRow<V>(r.maxRow, tgx, tgy, cj, sj, *r.target, nlp, r.spans, r.nxrPad);
        nlps[a] = nlp;
        ops[a] = r.op->values.data() + static_cast<std::size_t>(j) * P;
    }
    accumulateRows<V>(nlps, ops, r.batch, r.op->patternRow.data(), r.op->patternNlp.data(), P, r.vRows, r.nxr, r.spans,
                      r.nxrPad);  // nothing for P = 0
}

void rowBatchSse(const RowBatch& r) { rowBatchImpl<simd::F4>(r); }
[[gnu::target("avx2"), gnu::flatten]] void rowBatchAvx2(const RowBatch& r) { rowBatchImpl<simd::F8>(r); }

// ---- per frame: the step table and the valid-prefix lengths -----------------
// Step table of azimuth j (cos c, sin sn) and the valid-prefix length of each
// receiver column and row.
void buildAzimuthSteps(const HeightPyramid& pyr, int j, double c, double sn, int nxrPad, StepTables& t) {
    const int nxr = pyr.nxr, nyr = pyr.nyr;
    const int nSteps = static_cast<int>(pyr.steps.size());
    const std::size_t base = static_cast<std::size_t>(j) * nSteps;
    int* vc = t.validColumns.data() + 2 * base;
    int* vr = t.validRows.data() + 2 * base;
    for (int i = 0; i < nSteps; ++i) {
        const StepGeometry g = makeStep(pyr, i, c, sn);
        t.steps[base + static_cast<std::size_t>(i)] = g.step;
        vc[2 * i] = g.xFirst;
        vc[2 * i + 1] = g.xLast;
        vr[2 * i] = g.yFirst;
        vr[2 * i + 1] = g.yLast;
    }
    // a receiver's sequence is the prefix of steps before its first invalid one
    int* colSteps = t.stepsPerColumn.data() + static_cast<std::size_t>(j) * nxrPad;
    for (int X = 0; X < nxrPad; ++X) {
        int n = 0;
        if (X < nxr)
            while (n < nSteps && vc[2 * n] <= X && X <= vc[2 * n + 1]) ++n;
        colSteps[X] = n;
    }
    int* rowSteps = t.stepsPerRow.data() + static_cast<std::size_t>(j) * nyr;
    for (int Y = 0; Y < nyr; ++Y) {
        int n = 0;
        while (n < nSteps && vr[2 * n] <= Y && Y <= vr[2 * n + 1]) ++n;
        rowSteps[Y] = n;
    }
}

// The step tables of every azimuth of op, and each azimuth's cos and sin in
// float, into state.tables.front(): the kept tables of the same key when
// there are (they are a function of it alone), else built anew in place of
// the least recently used.
void buildStepTables(const HeightPyramid& pyr, const FoldedWedgeOperator& op, int nxrPad, VisibilityState& state) {
    StepTableKey key = stepTableKey(pyr, op.phi, nxrPad);
    std::vector<StepTables>& kept = state.tables;
    // the front is the most recently used
    auto found = std::find_if(kept.begin(), kept.end(), [&](const StepTables& t) { return t.key == key; });
    if (found == kept.end()) {
        if (kept.size() < VisibilityState::kKeptTables) kept.emplace_back();
        found = kept.end() - 1;
        found->key = StepTableKey{};  // not valid until built
    }
    std::rotate(kept.begin(), found, found + 1);
    StepTables& t = kept.front();
    if (t.key == key) return;

    const int m = op.azimuths, nyr = pyr.nyr;
    const int nSteps = static_cast<int>(pyr.steps.size());
    const std::size_t tableSize = static_cast<std::size_t>(m) * nSteps;
    t.steps.resize(tableSize);
    t.validColumns.resize(2 * tableSize);
    t.validRows.resize(2 * tableSize);
    t.stepsPerColumn.resize(static_cast<std::size_t>(m) * nxrPad);
    t.stepsPerRow.resize(static_cast<std::size_t>(m) * nyr);
    parallelFor(0, m, 1, [&](int j0, int j1) {
        for (int j = j0; j < j1; ++j) {
            const double c = std::cos(op.phi[static_cast<std::size_t>(j)]);
            const double sn = std::sin(op.phi[static_cast<std::size_t>(j)]);
            buildAzimuthSteps(pyr, j, c, sn, nxrPad, t);
        }
    });

    t.cosSin.resize(2 * static_cast<std::size_t>(m));
    for (int j = 0; j < m; ++j) {
        const double phi = op.phi[static_cast<std::size_t>(j)];
        t.cosSin[2 * static_cast<std::size_t>(j)] = static_cast<float>(std::cos(phi));
        t.cosSin[2 * static_cast<std::size_t>(j) + 1] = static_cast<float>(std::sin(phi));
    }
    t.key = std::move(key);
}

void resizeBlockScratch(int nBlocks, int nxrPad, int nSteps, VisibilityState& state) {
    state.blocks.resize(static_cast<std::size_t>(nBlocks));
    for (VisibilityScratch& b : state.blocks) {
        b.maxRow.resize(static_cast<std::size_t>(nxrPad));
        b.gradX.resize(static_cast<std::size_t>(3) * nxrPad);  // receiver, footprint lo, hi
        b.gradY.resize(static_cast<std::size_t>(3) * nxrPad);
        b.h0.resize(static_cast<std::size_t>(nxrPad));
        b.nlp.resize(static_cast<std::size_t>(8) * nxrPad);
        b.rowPtr.resize(2 * static_cast<std::size_t>(nSteps));
    }
}

// ---- per receiver row ----------------------------------------------------------
// What every receiver row of one computeVisibility call reads and writes.
struct VisibilityRows {
    const HeightPyramid& pyr;
    ConstGridView gradX, gradY;
    const VisibilitySettings& settings;
    const VisibilityTarget& target;
    const FootprintBox* box;  // footprint box (sub-sampling) or null: the receiver's own tangent plane
    VisibilityState& state;
    VisibilityField& out;
    int nxrPad, nSteps;
    void (*rowBatch)(const RowBatch&);  // rowBatchSse or rowBatchAvx2
};

// h0 and the height gradients of the receivers of row Y's spans into the
// block's scratch, each span up to its padded end (padding lanes: 0), and
// the footprint box rows, padded the same way. Only the spans' columns: a
// local change's rows read a few tiles of the row.
void loadReceiverRow(const VisibilityRows& r, int Y, std::span<const ColumnSpan> spans, VisibilityScratch& sc) {
    const int nxr = r.pyr.nxr, s = r.pyr.subsample, nxrPad = r.nxrPad;
    const float* hRow = r.pyr.rawPhaseRow(0, s * Y);
    const FootprintBox* box = r.box;
    const std::size_t at = static_cast<std::size_t>(Y) * nxr;
    float* loX = sc.gradX.data() + nxrPad;
    float* loY = sc.gradY.data() + nxrPad;
    for (const ColumnSpan& span : spans)
        for (int X = span.x0; X < std::min(spanEnd(span), nxrPad); ++X) {
            const auto x = static_cast<std::size_t>(X);
            if (X >= nxr) {  // a padding lane
                sc.gradX[x] = sc.gradY[x] = sc.h0[x] = 0.0f;
                if (box) loX[X] = loX[nxrPad + X] = loY[X] = loY[nxrPad + X] = 0.0f;
                continue;
            }
            sc.gradX[x] = r.gradX(s * X, s * Y);
            sc.gradY[x] = r.gradY(s * X, s * Y);
            sc.h0[x] = hRow[X];
            if (!box) continue;
            loX[X] = box->loX[at + x];
            loX[nxrPad + X] = box->hiX[at + x];
            loY[X] = box->loY[at + x];
            loY[nxrPad + X] = box->hiY[at + x];
        }
}

// V of the receivers of row Y's spans (loaded by loadReceiverRow): every
// azimuth, two at a time.
void visibilityOfRow(const VisibilityRows& r, int Y, std::span<const ColumnSpan> spans, VisibilityScratch& sc) {
    const int nxr = r.pyr.nxr, nyr = r.pyr.nyr, m = r.target.op->azimuths;
    VisibilityState& state = r.state;
    float* vRows[kShCount];
    for (int i = 0; i < r.out.planes; ++i) {
        vRows[i] = r.out.plane(i) + static_cast<std::size_t>(Y) * nxr;
        for (const ColumnSpan& span : spans) std::fill(vRows[i] + span.x0, vRows[i] + span.x1, 0.0f);
    }
    const StepTables& t = state.tables.front();  // this scan's (buildStepTables)
    for (int j0 = 0; j0 < m; j0 += 2) {
        const RowBatch rb{t.steps.data(),
                          r.nSteps,
                          nxr,
                          nyr,
                          r.nxrPad,
                          Y,
                          j0,
                          std::min(2, m - j0),
                          spans,
                          t.stepsPerColumn.data(),
                          t.stepsPerRow.data(),
                          t.cosSin.data(),
                          sc.h0.data(),
                          sc.gradX.data(),
                          sc.gradY.data(),
                          r.box != nullptr,
                          r.settings.blockingMax,
                          &r.target,
                          r.target.op,
                          sc.maxRow.data(),
                          sc.nlp.data(),
                          sc.rowPtr.data(),
                          r.out.maxSlope.data(),
                          vRows};
        r.rowBatch(rb);
    }
}

}  // namespace

void computeFootprintBox(ConstGridView gradX, ConstGridView gradY, int s, FootprintBox& out, RowSpan changedGradients) {
    const int nx = gradX.nx, ny = gradX.ny, nxr = receiverCount(nx, s), nyr = receiverCount(ny, s), half = s / 2;
    const std::size_t n = static_cast<std::size_t>(nxr) * nyr;
    if (out.nxr != nxr || out.nyr != nyr || out.subsample != s || out.loX.size() != n) changedGradients = {};
    // receiver Y reads the rows s Y - half .. s Y + half (clamped to the
    // field, which moves none of them out of a span that holds the edge row)
    const RowSpan g = changedGradients.cut(ny);
    const RowSpan receivers = RowSpan{(g.y0 - half + s - 1) / s, (g.y1 - 1 + half) / s + 1}.cut(nyr);
    out.nxr = nxr;
    out.nyr = nyr;
    out.subsample = s;
    out.loX.resize(n);
    out.hiX.resize(n);
    out.loY.resize(n);
    out.hiY.resize(n);
    // Per receiver row: each column's lowest and highest gradients over the
    // footprint's rows (whole rows, which the compiler vectorises), then per
    // receiver those of its footprint's columns. Minima and maxima are exact,
    // so the order of the comparisons changes no value (where +0 and -0
    // meet, at most the sign of a zero).
    parallelForRows(receivers, nxr, [&](int Y0, int Y1) {
        std::vector<float> columns(4 * static_cast<std::size_t>(nx));
        float* colLoX = columns.data();
        float* colHiX = colLoX + nx;
        float* colLoY = colHiX + nx;
        float* colHiY = colLoY + nx;
        for (int Y = Y0; Y < Y1; ++Y) {
            // the footprint's rows (one without sub-sampling), clamped to the field
            const int r0 = std::max(s * Y - half, 0), r1 = s * Y, r2 = std::min(s * Y + half, ny - 1);
            const float *ax = gradX.row(r0), *bx = gradX.row(r1), *cx = gradX.row(r2);
            const float *ay = gradY.row(r0), *by = gradY.row(r1), *cy = gradY.row(r2);
            for (int x = 0; x < nx; ++x) {
                colLoX[x] = std::min(std::min(ax[x], bx[x]), cx[x]);
                colHiX[x] = std::max(std::max(ax[x], bx[x]), cx[x]);
                colLoY[x] = std::min(std::min(ay[x], by[x]), cy[x]);
                colHiY[x] = std::max(std::max(ay[x], by[x]), cy[x]);
            }
            // the footprint's columns, clamped to the field
            const std::size_t at = static_cast<std::size_t>(Y) * nxr;
            for (int X = 0; X < nxr; ++X) {
                const int c0 = std::max(s * X - half, 0), c1 = s * X, c2 = std::min(s * X + half, nx - 1);
                out.loX[at + X] = std::min(std::min(colLoX[c0], colLoX[c1]), colLoX[c2]);
                out.hiX[at + X] = std::max(std::max(colHiX[c0], colHiX[c1]), colHiX[c2]);
                out.loY[at + X] = std::min(std::min(colLoY[c0], colLoY[c1]), colLoY[c2]);
                out.hiY[at + X] = std::max(std::max(colHiY[c0], colHiY[c1]), colHiY[c2]);
            }
        }
    });
}

StepTableKey stepTableKey(const HeightPyramid& pyr, const std::vector<double>& phi, int nxrPad) {
    StepTableKey k{.phi = phi,
                   .nxrPad = nxrPad,
                   .nx = pyr.nx,
                   .ny = pyr.ny,
                   .nxr = pyr.nxr,
                   .nyr = pyr.nyr,
                   .subsample = pyr.subsample,
                   .cellSize = pyr.cellSize,
                   .raw = pyr.rawPhaseData(),
                   .rawWidth = pyr.rawPhaseWidth,
                   .rawPlane = pyr.rawPhasePlane};
    for (const PyramidStep& ps : pyr.steps) {
        k.tauCells.push_back(ps.tauCells);
        k.stepLevels.push_back(ps.level);
    }
    for (const PaddedField& f : pyr.levels) {
        k.levelData.push_back(f.data());
        k.levelStrides.push_back(f.stride);
    }
    return k;
}

ScanStepInfo scanStepInfo(const HeightPyramid& pyr, int i, double cosPhi, double sinPhi) {
    return scanStepInfoAt(pyr, pyr.steps[static_cast<std::size_t>(i)], cosPhi, sinPhi);
}

ScanStepInfo scanStepInfoAt(const HeightPyramid& pyr, const PyramidStep& step, double cosPhi, double sinPhi) {
    const StepGeometry g = makeStepAt(pyr, step, cosPhi, sinPhi);
    ScanStepInfo info;
    info.step = g.step;
    info.xFirst = g.xFirst;
    info.xLast = g.xLast;
    info.yFirst = g.yFirst;
    info.yLast = g.yLast;
    info.tapX = g.tapX;
    info.tapY = g.tapY;
    info.nextX = g.alongX ? 0 : 1;
    info.nextY = g.alongX ? 1 : 0;
    return info;
}

ValidPrefix::ValidPrefix(int nxr, int nyr, int pad, int* colSteps, int* rowSteps)
    : xLo_(0), xHi_(nxr - 1), yLo_(0), yHi_(nyr - 1), col_(colSteps), row_(rowSteps) {
    std::fill(colSteps, colSteps + pad, 0);
    std::fill(rowSteps, rowSteps + nyr, 0);
}

void ValidPrefix::narrow(const ScanStepInfo& s) {
    xLo_ = std::max(xLo_, s.xFirst);
    xHi_ = std::min(xHi_, s.xLast);
    yLo_ = std::max(yLo_, s.yFirst);
    yHi_ = std::min(yHi_, s.yLast);
}

void ValidPrefix::commit(int step) {
    // receivers still inside at this step: those inside at every step so far
    for (int X = xLo_; X <= xHi_; ++X) col_[X] = step + 1;
    for (int Y = yLo_; Y <= yHi_; ++Y) row_[Y] = step + 1;
}

float maxBlockingSlopeOfSequence(const float* slopes, int count, BlockingMax rule) {
    float out = kNoBlocker;
    if (count <= 0) return out;
    out = slopes[0];
    for (int i = 1; i < count; ++i) out = out < slopes[i] ? slopes[i] : out;
    if (rule == BlockingMax::Samples) return out;
    for (int i = 0; i + 1 < count; ++i) {
        const float sm = slopes[std::max(i - 1, 0)], s0 = slopes[i], s1 = slopes[i + 1];
        const float s2 = slopes[std::min(i + 2, count - 1)];
        const float mid = (9.0f * (s0 + s1) - (sm + s2)) * (1.0f / 16.0f);
        out = out < mid ? mid : out;
    }
    return out;
}

float scanReceiverScalar(const HeightPyramid& pyr, int X, int Y, double phi, BlockingMax rule) {
    const double c = std::cos(phi), sn = std::sin(phi);
    const int s = pyr.subsample;
    const float h0 = pyr.rawPhaseRow(0, s * Y)[X];
    std::vector<float> seq;
    for (int i = 0; i < static_cast<int>(pyr.steps.size()); ++i) {
        // own bounds test on the (moved) sample position
        const StepGeometry g = makeStep(pyr, i, c, sn);
        const double px = g.k * X + g.dx, py = g.k * Y + g.dy;
        if (!(px >= 0.0 && px <= g.fieldNx - 1 && py >= 0.0 && py <= g.fieldNy - 1)) break;
        seq.push_back(sampleSlope(g.step, Y * g.step.rowStep + X, h0));
    }
    return maxBlockingSlopeOfSequence(seq.data(), static_cast<int>(seq.size()), rule);
}

void computeVisibility(const HeightPyramid& pyr, ConstGridView gradX, ConstGridView gradY,
                       const VisibilitySettings& settings, const VisibilityTarget& target, VisibilityState& state,
                       VisibilityField& out, const ReceiverTiles* only) {
    const FoldedWedgeOperator& op = *target.op;
    const int nxr = pyr.nxr, nyr = pyr.nyr, s = pyr.subsample;
    const int nxrPad = padLanes(nxr);
    const int m = op.azimuths;
    const int nSteps = static_cast<int>(pyr.steps.size());
    const std::size_t planeSize = static_cast<std::size_t>(nxr) * nyr;
    const int planes = op.shRows;
    if (only && (out.nxr != nxr || out.nyr != nyr || out.planes != planes || out.sh.size() != planeSize * planes ||
                 out.maxSlope.size() != planeSize * m))
        throw InputError(
            "computeVisibility: receiver tiles need the previous result of this receiver grid and these "
            "azimuths in the output");
    dirtySpans(only, nxr, nyr, state.spans);
    out.nxr = nxr;
    out.nyr = nyr;
    out.planes = planes;
    out.sh.resize(planeSize * planes);
    out.maxSlope.resize(planeSize * m);
    if (state.spans.empty()) return;  // no dirty tile (or no receiver): every receiver keeps its value

    buildStepTables(pyr, op, nxrPad, state);
    const int nBlocks = std::max(1, std::min(nyr, kMaxBlocks));
    resizeBlockScratch(nBlocks, nxrPad, nSteps, state);
    // footprint box rows (sub-sampling), when the box is this grid's
    const FootprintBox* box = target.footprint && s > 1 && target.footprint->nxr == nxr && target.footprint->nyr == nyr
                                  ? target.footprint
                                  : nullptr;
    const VisibilityRows rows{pyr,
                              gradX,
                              gradY,
                              settings,
                              target,
                              box,
                              state,
                              out,
                              nxrPad,
                              nSteps,
                              simd::wideEnabled() ? rowBatchAvx2 : rowBatchSse};
    // ---- schedule: fixed row blocks in parallel, rows serially within a block,
    // every azimuth of a row before the next row (the row's h0 / tau table is
    // built once for all azimuths).
    // (receiver tiles: only the blocks with a dirty span are handed out, and
    // their rows without one are skipped)
    const auto blockRows = [&](int block) {
        return RowSpan{static_cast<int>(static_cast<long long>(nyr) * block / nBlocks),
                       static_cast<int>(static_cast<long long>(nyr) * (block + 1) / nBlocks)};
    };
    blocksWithRows(
        nBlocks, blockRows, [&](int Y) { return !state.spans.ofRow(Y).empty(); }, state.busyBlocks);
    parallelForEach(state.busyBlocks, [&](int block) {
        VisibilityScratch& sc = state.blocks[static_cast<std::size_t>(block)];
        const RowSpan r = blockRows(block);
        for (int Y = r.y0; Y < r.y1; ++Y) {
            const std::span<const ColumnSpan> spans = state.spans.ofRow(Y);
            if (spans.empty()) continue;
            loadReceiverRow(rows, Y, spans, sc);
            visibilityOfRow(rows, Y, spans, sc);
        }
    });
}

}  // namespace terrain::gi
