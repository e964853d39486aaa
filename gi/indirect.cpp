#include "gi/indirect.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <type_traits>

#include "gi/nlp.h"
#include "gi/sh.h"
#include "core/error.h"
#include "core/parallel.h"
#include "core/simd.h"

namespace terrain::gi {

namespace {

using simd::load;
using simd::splat;
using simd::store;
using simd::F4;
using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

constexpr int kIndirectRows = 8;  // receiver rows per block
constexpr int kGroup = 8;  // rows are padded to a multiple of the widest lane group

inline int padGroup(int n) { return (n + kGroup - 1) / kGroup * kGroup; }

// The kernel is written once over a lane type V: F4 (SSE2, the baseline) or
// F8 (AVX2, chosen at run time where the processor has it): sim/simd.h.
using simd::F8;
using simd::LaneTraits;
using simd::laneBits;
using simd::sqrtv;
using simd::atanv;

// ---- algorithm: the casting set and Eq. 12 for one row of receivers --------
// The walk over the height steps (Eq. 17): at each step where some lane has a
// new casting-set member, the clamped segment's moments Delta(s^p), p = 1..4
// (0 in the other lanes) are multiplied with the radiance samples there and
// summed per channel (each lane's sums in step order).
// hTab: the height steps of this azimuth; rTab[c]: channel c's radiance steps.
// Out: 3 channels x 4 NLP coefficients, written at nlp[(c * 4 + l) * pad + X].
// Exact (LambertIndirect::ExactAtReceivers): a fifth moment per segment, the
// exact clamped-cosine irradiance at the receiver's own normal up to
// dphi / |n|: Delta f2 - g Delta f1 over the segment clamped to the
// receiver's plane (n = (-gx, -gy, 1), so d . n_h = -g); out at
// nlp[(12 + c) * pad + X]. The four NLP moments then use segments clamped to
// the footprint's lowered plane (lowSlope) instead.
struct RowInputs {
    const float *h0, *margin, *gx, *gy;
    const float* lowSlope;  // Exact: the lowered tangent slope per receiver (this azimuth)
    float hMax;             // highest height of the field: no sample rises above it
};

// Mode: kShOnly, kShAndExact, kExactOnly (1x: every texel is a receiver, so
// U's normal detail is never used and only the exact moment is needed; out:
// nlp[(12 + c) * pad + X] alone).
constexpr int kShOnly = 0, kShAndExact = 1, kExactOnly = 2;

// Row of receivers for one azimuth, step by step over the whole row: at
// step i every group of L receivers still walking reads its 2 height taps
// and, where some lane has a new casting-set member, the 3 channels'
// radiance taps: each step's reads sweep one contiguous stretch of its field
// (hardware prefetch follows them), and the groups' running values live in
// the row scratch (sc.state). Per lane the same operations in the same order
// as walking each group alone (step order; lanes without a new member add
// exactly 0), so the result does not depend on the schedule.
template <class V, int Mode>
[[gnu::always_inline]] inline void castRowImpl(const ScanStep* hTab, const ScanStep* const* rTab, const int* colSteps,
                                               int rowSteps, int Y, const RowInputs& in, float cosPhi, float sinPhi,
                                               IndirectScratch& sc, int pad) {
    using I = typename LaneTraits<V>::I;
    constexpr int L = LaneTraits<V>::n;
    constexpr bool Exact = Mode != kShOnly, Sh = Mode != kExactOnly;
    constexpr int nMo = (Sh ? 4 : 0) + (Exact ? 1 : 0);
    constexpr int e5 = nMo - 1;  // index of the exact moment
    const int nGroups = pad / L;
    // state planes (pad floats each): M, g, gLow, q1, F, then 3 x nMo sums A
    float* S = sc.state.data();
    float *M = S, *g = S + pad, *gLow = S + 2 * pad, *q1 = S + 3 * pad, *F = S + 4 * pad, *A = S + 5 * pad;
    int* steps = sc.groupSteps.data();  // per lane: the valid prefix (row limit applied)
    int* active = sc.active.data();     // groups still walking
    const V one = splat<V>(1.0f), half = splat<V>(0.5f), lim = splat<V>(1e6f), nlim = splat<V>(-1e6f), zero = splat<V>(0.0f);
    const I rowLimit = I{} + rowSteps;
    int nActive = 0, nMax = 0;
    for (int G = 0; G < nGroups; ++G) {
        const int X0 = G * L;
        I c;
        std::memcpy(&c, colSteps + X0, sizeof c);
        c = c < rowLimit ? c : rowLimit;
        std::memcpy(steps + X0, &c, sizeof c);
        int nAny = 0;
        for (int l = 0; l < L; ++l) nAny = std::max(nAny, static_cast<int>(c[l]));
        nMax = std::max(nMax, nAny);
        if (nAny > 0) active[nActive++] = G;
        store(M + X0, splat<V>(kNoBlocker));
        // omega_min: the tangent plane's slope along the azimuth (Section 3)
        const V gv = load<V>(in.gx + X0) * splat<V>(cosPhi) + load<V>(in.gy + X0) * splat<V>(sinPhi);
        V gl = gv;
        if constexpr (Sh && Exact) gl = load<V>(in.lowSlope + X0);
        store(g + X0, gv);
        store(gLow + X0, gl);
        const V t = gl < nlim ? nlim : (gl > lim ? lim : gl);
        const V r = one / sqrtv(one + t * t);  // cos of the lower bound
        store(q1 + X0, t * r);
        if constexpr (Exact) {
            // F(t) = f2 - g f1 at the clamped segment end (f1, f2 the clamped
            // cosine's antiderivatives); F is smallest at t = g (the receiver's
            // plane), so ends below g keep F(g)
            const V te = gv < nlim ? nlim : (gv > lim ? lim : gv);
            const V re = one / sqrtv(one + te * te), se = te * re;
            store(F + X0, half * (se * se) - gv * (half * (atanv(te) + se * re)));
        }
        for (int p = 0; p < 3 * nMo; ++p) store(A + static_cast<std::size_t>(p) * pad + X0, zero);
    }
    const V hMax = splat<V>(in.hMax);
    for (int i = 0; i < nMax && nActive > 0; ++i) {
        const ScanStep& st = hTab[i];
        const std::ptrdiff_t o = Y * st.rowStep;
        const float* a = st.field + (o + st.offA);
        const float* b = st.field + (o + st.offB);
        const V wa = splat<V>(st.w[0][0]), wb = splat<V>(st.w[1][0]), inv = splat<V>(st.w[2][0]);
        const float* ra[3];
        const float* rb[3];
        V rwa[3], rwb[3];
        for (int c = 0; c < 3; ++c) {
            const ScanStep& rs = rTab[c][i];
            const std::ptrdiff_t ro = Y * rs.rowStep;
            ra[c] = rs.field + (ro + rs.offA);
            rb[c] = rs.field + (ro + rs.offB);
            rwa[c] = splat<V>(rs.w[0][0]);
            rwb[c] = splat<V>(rs.w[1][0]);
        }
        const I iv = I{} + i;
        int kept = 0;
        for (int q = 0; q < nActive; ++q) {
            const int G = active[q];
            const int X0 = G * L;
            I stp;
            std::memcpy(&stp, steps + X0, sizeof stp);
            const V h0 = load<V>(in.h0 + X0);
            const V t = (((wa * load<V>(a + X0) + wb * load<V>(b + X0)) - h0) - load<V>(in.margin + X0)) * inv;
            V m = load<V>(M + X0);
            const I nw = (iv < stp) & (t > m);  // Eq. 17: above every earlier sample
            if (laneBits(nw) == 0) {
                // past the point where even the field's highest height would not
                // beat any lane's running maximum, no new member can come: the
                // group is done (lanes whose ray has left the domain are done too)
                const I done = (iv >= stp) | (m >= (hMax - h0) * inv);
                if (laneBits(~done) != 0) active[kept++] = G;
                continue;
            }
            active[kept++] = G;
            m = nw ? t : m;
            store(M + X0, m);
            // the segment [c_(i-1), c_i] clamped to [omega_min, pi/2]
            const V gl = load<V>(gLow + X0);
            V tc = t < gl ? gl : t;
            tc = tc < nlim ? nlim : (tc > lim ? lim : tc);
            const V r = one / sqrtv(one + tc * tc), sNew = tc * r;  // cos, sin of the end
            V mo[nMo];
            if constexpr (Sh) {
                const V p = load<V>(q1 + X0);
                const V sv = nw ? sNew : p;  // no new member: an empty segment (exactly 0)
                const V p2 = p * p, s2 = sv * sv;
                mo[0] = sv - p;
                mo[1] = s2 - p2;
                mo[2] = s2 * sv - p2 * p;
                mo[3] = s2 * s2 - p2 * p2;
                store(q1 + X0, sv);
            }
            if constexpr (Exact) {
                const V gv = load<V>(g + X0), f = load<V>(F + X0);
                const V fNew = half * (sNew * sNew) - gv * (half * (atanv(tc) + sNew * r));
                const V fv = nw & (tc >= gv) ? fNew : f;  // below the receiver's plane: nothing
                mo[e5] = fv - f;
                store(F + X0, fv);
            }
            // moments x radiance (lanes without a new member have zero moments;
            // the radiance read there is finite: inside the field's padding and guard)
            for (int c = 0; c < 3; ++c) {
                const V u = rwa[c] * load<V>(ra[c] + X0) + rwb[c] * load<V>(rb[c] + X0);
                for (int p = 0; p < nMo; ++p) {
                    float* acc = A + static_cast<std::size_t>(c * nMo + p) * pad + X0;
                    store(acc, load<V>(acc) + u * mo[p]);
                }
            }
        }
        nActive = kept;
    }
    // Eq. 10's closed form as a polynomial in s
    const V k0 = splat<V>(0.70710678118654752440f), k1 = splat<V>(0.61237243569579452455f);
    const V k2 = splat<V>(0.79056941504209483300f), k3 = splat<V>(0.23385358667337133659f);
    float* nlp = sc.nlp.data();
    for (int c = 0; c < 3; ++c)
        for (int X0 = 0; X0 < pad; X0 += L) {
            V Ac[nMo];
            for (int p = 0; p < nMo; ++p) Ac[p] = load<V>(A + static_cast<std::size_t>(c * nMo + p) * pad + X0);
            if constexpr (Exact) store(nlp + static_cast<std::size_t>(12 + c) * pad + X0, Ac[e5]);
            if constexpr (!Sh) continue;
            float* base = nlp + static_cast<std::size_t>(c) * 4 * pad + X0;
            store(base, k0 * Ac[0]);
            store(base + pad, k1 * Ac[1]);
            store(base + 2 * pad, k2 * (Ac[2] - Ac[0]));
            store(base + 3 * pad, k3 * (splat<V>(5.0f) * Ac[3] - splat<V>(6.0f) * Ac[1]));
        }
}

template <int Mode>
void castRowSse(const ScanStep* hTab, const ScanStep* const* rTab, const int* colSteps, int rowSteps, int Y,
                const RowInputs& in, float cosPhi, float sinPhi, IndirectScratch& sc, int pad) {
    castRowImpl<F4, Mode>(hTab, rTab, colSteps, rowSteps, Y, in, cosPhi, sinPhi, sc, pad);
}
template <int Mode>
[[gnu::target("avx2"), gnu::flatten]] void castRowAvx2(const ScanStep* hTab, const ScanStep* const* rTab, const int* colSteps,
                                         int rowSteps, int Y, const RowInputs& in, float cosPhi, float sinPhi,
                                         IndirectScratch& sc, int pad) {
    castRowImpl<F8, Mode>(hTab, rTab, colSteps, rowSteps, Y, in, cosPhi, sinPhi, sc, pad);
}

using CastRowFn = void (*)(const ScanStep*, const ScanStep* const*, const int*, int, int, const RowInputs&, float, float,
                           IndirectScratch&, int);
CastRowFn castRowFor(int mode) {
    const bool wide = simd::wideEnabled();
    if (mode == kShOnly) return wide ? castRowAvx2<kShOnly> : castRowSse<kShOnly>;
    if (mode == kShAndExact) return wide ? castRowAvx2<kShAndExact> : castRowSse<kShAndExact>;
    return wide ? castRowAvx2<kExactOnly> : castRowSse<kExactOnly>;
}

// One row and azimuth's results into the sums: the exact moments into E
// (ExactAtReceivers), and U_c += G_j u_(c, j) over the sparse pattern (Eq. 21).
struct RowSums {
    const float* nlp;  // 3 channels x 4 NLP (+ 3 exact) x pad
    int pad, nxr;
    float* exact;      // 3 channels x pad E sums of the row, or null
    int patSize;       // 0: no U (kExactOnly)
    const std::uint8_t *patRow, *patNlp;
    const float* vals;  // the operator's entries of this azimuth
    int nRows;          // SH rows of U that shading reads
    float* u[3];        // U of each channel: plane 0, row Y
    std::size_t planeR; // plane stride
};

template <class V>
[[gnu::always_inline]] inline void accumulateImpl(const RowSums& r) {
    constexpr int L = LaneTraits<V>::n;
    const int nv = r.nxr / L * L;
    auto axpy = [&](float* __restrict dst, const float* __restrict w, float gval) {
        const V g = splat<V>(gval);
        for (int X = 0; X < nv; X += L) store(dst + X, load<V>(dst + X) + g * load<V>(w + X));
        for (int X = nv; X < r.nxr; ++X) dst[X] += gval * w[X];
    };
    if (r.exact)
        for (int c = 0; c < 3; ++c) {
            float* __restrict e = r.exact + static_cast<std::size_t>(c) * r.pad;
            const float* __restrict w = r.nlp + static_cast<std::size_t>(12 + c) * r.pad;
            for (int X = 0; X < nv; X += L) store(e + X, load<V>(e + X) + load<V>(w + X));
            for (int X = nv; X < r.nxr; ++X) e[X] += w[X];
        }
    for (int e = 0; e < r.patSize; ++e) {
        const int row = r.patRow[e];
        if (row >= r.nRows) continue;
        const int l = r.patNlp[e];
        for (int c = 0; c < 3; ++c)
            axpy(r.u[c] + static_cast<std::size_t>(row) * r.planeR, r.nlp + static_cast<std::size_t>(c * 4 + l) * r.pad, r.vals[e]);
    }
}
void accumulateSse(const RowSums& r) { accumulateImpl<F4>(r); }
[[gnu::target("avx2"), gnu::flatten]] void accumulateAvx2(const RowSums& r) { accumulateImpl<F8>(r); }

// ExactAtReceivers: the shade at the receiver's normal, lam(N) . U (as
// gi/shading evaluates it there), becomes E / pi through band 0; one row.
struct ShiftRow {
    const float *gx, *gy;  // the row's receiver gradients
    const float* exact;    // 3 channels x pad E sums
    int pad, nxr;
    float eScale;          // (2 pi / m) / pi
    LambertFactors lf;
    float* u[3];           // U plane 0 of each channel at the row
    std::size_t planeR;
};

template <class T>
[[gnu::always_inline]] inline void exactShiftAt(const ShiftRow& r, T gx, T gy, const T* e, float* const* u0) {
    constexpr auto sp = splat<T>;
    const T one = sp(1.0f);
    const T inv = one / sqrtv(one + gx * gx + gy * gy);
    const T Xn = -gx * inv, Yn = -gy * inv, Z = inv;
    T lam[9];
    lambertAtNormal(r.lf, Xn, Yn, Z, lam);
    for (int c = 0; c < 3; ++c) {
        T shade = sp(0.0f);
        for (int i = 0; i < 9; ++i) shade += lam[i] * load<T>(u0[c] + static_cast<std::size_t>(i) * r.planeR);
        const T ev = sp(r.eScale) * inv * e[c];
        store(u0[c], load<T>(u0[c]) + (ev - shade) / lam[0]);
    }
}

template <class V>
[[gnu::always_inline]] inline void exactShiftImpl(const ShiftRow& r) {
    constexpr int L = LaneTraits<V>::n;
    const int nv = r.nxr / L * L;
    for (int X = 0; X < nv; X += L) {
        const V e[3] = {load<V>(r.exact + X), load<V>(r.exact + r.pad + X), load<V>(r.exact + 2 * r.pad + X)};
        float* const u0[3] = {r.u[0] + X, r.u[1] + X, r.u[2] + X};
        exactShiftAt<V>(r, load<V>(r.gx + X), load<V>(r.gy + X), e, u0);
    }
    for (int X = nv; X < r.nxr; ++X) {
        const float e[3] = {r.exact[X], r.exact[r.pad + X], r.exact[2 * r.pad + X]};
        float* const u0[3] = {r.u[0] + X, r.u[1] + X, r.u[2] + X};
        exactShiftAt<float>(r, r.gx[X], r.gy[X], e, u0);
    }
}
void exactShiftSse(const ShiftRow& r) { exactShiftImpl<F4>(r); }
[[gnu::target("avx2"), gnu::flatten]] void exactShiftAvx2(const ShiftRow& r) { exactShiftImpl<F8>(r); }

}  // namespace

void loadReceiverRow(const HeightPyramid& pyr, ConstGridView gradX, ConstGridView gradY, int Y, int pad, float* gx, float* gy,
                     float* h0, float* margin) {
    const int s = pyr.subsample, nxr = pyr.nxr;
    const float* hRow = pyr.rawPhaseRow(0, s * Y);
    for (int X = 0; X < pad; ++X) {
        const bool in = X < nxr;
        gx[X] = in ? gradX(s * X, s * Y) : 0.0f;
        gy[X] = in ? gradY(s * X, s * Y) : 0.0f;
        h0[X] = in ? hRow[X] : 0.0f;
        margin[X] = std::fabs(h0[X]) * kHeightMarginRel;
    }
}

void buildIndirectStepTable(const HeightPyramid& pyr, const std::vector<double>& phi, int pad, std::vector<ScanStep>& heightSteps,
                            std::vector<int>& stepsPerColumn, std::vector<int>& stepsPerRow, const RadianceStepFn& radiance) {
    const int m = static_cast<int>(phi.size()), nSteps = static_cast<int>(pyr.steps.size());
    const int nxr = pyr.nxr, nyr = pyr.nyr;
    parallelFor(0, m, 1, [&](int j0, int j1) {
        for (int j = j0; j < j1; ++j) {
            const double c = std::cos(phi[static_cast<std::size_t>(j)]);
            const double sn = std::sin(phi[static_cast<std::size_t>(j)]);
            const std::size_t base = static_cast<std::size_t>(j) * nSteps;
            // a receiver's sequence is its prefix of steps inside the domain
            // (for the heights and the radiance samples alike)
            ValidPrefix prefix(nxr, nyr, pad, stepsPerColumn.data() + static_cast<std::size_t>(j) * pad,
                               stepsPerRow.data() + static_cast<std::size_t>(j) * nyr);
            for (int i = 0; i < nSteps; ++i) {
                const ScanStepInfo h = scanStepInfo(pyr, i, c, sn);
                heightSteps[base + static_cast<std::size_t>(i)] = h.step;
                prefix.narrow(h);
                radiance(i, c, sn, base + static_cast<std::size_t>(i), prefix);
                prefix.commit(i);
            }
        }
    });
}

void accumulateBounce(const std::array<Grid, 3>& exit, int b, IndirectState& st) {
    double sum = 0.0;
    for (int c = 0; c < 3; ++c) {
        Grid& acc = st.indirect[static_cast<std::size_t>(c)];
        const Grid& add = exit[static_cast<std::size_t>(c)];
        for (std::size_t i = 0; i < acc.v.size(); ++i) {
            acc.v[i] += add.v[i];
            sum += add.v[i];
        }
    }
    st.bounceMean[static_cast<std::size_t>(b - 1)] = sum / (3.0 * std::max<std::size_t>(1, st.indirect[0].v.size()));
}

void sumDirectAndIndirect(const std::array<Grid, 3>& direct, IndirectState& st) {
    for (int c = 0; c < 3; ++c) {
        Grid& tot = st.total[static_cast<std::size_t>(c)];
        const Grid& ind = st.indirect[static_cast<std::size_t>(c)];
        if (tot.nx != ind.nx || tot.ny != ind.ny) tot.resize(ind.nx, ind.ny);
        const Grid& d = direct[static_cast<std::size_t>(c)];
        for (std::size_t i = 0; i < tot.v.size(); ++i) tot.v[i] = d.v[i] + ind.v[i];
    }
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

void validateIndirectSettings(const IndirectSettings& s) {
    if (s.bounces < 0 || s.bounces > 16) throw InputError("bounces must be in [0, 16]");
    if (s.radiance.levelsPerOctave < 1 || s.radiance.levelsPerOctave > 64)
        throw InputError("radiance levels per octave must be in [1, 64]");
    if (s.radiance.levelOffset < 0 || s.radiance.levelOffset > 32) throw InputError("radiance level offset must be in [0, 32]");
    if (!(s.footprintDrop >= 0.0f && s.footprintDrop <= 1.0e3f)) throw InputError("indirect footprint drop must be in [0, 1000]");
    if (!(s.footprintDropMax >= 0.0f && s.footprintDropMax <= 1.0e3f)) throw InputError("indirect footprint drop maximum must be in [0, 1000]");
    if (s.azimuths != 0 && (s.azimuths < 3 || s.azimuths > 4096)) throw InputError("indirect azimuths must be 0 or in [3, 4096]");
}

void computeIndirect(const HeightPyramid& pyr, ConstGridView gradX, ConstGridView gradY, const FoldedWedgeOperator& op,
                     const VisibilityField& envVisibility, const std::array<Grid, 3>& direct, const AlbedoMap* albedo,
                     const ShadingSettings& shading, const IndirectSettings& settings, IndirectState& st,
                     const ShadeMaps* directShade, const FootprintBox* footprint) {
    validateIndirectSettings(settings);
    // ---- glossy vector pyramid (Fig. 5 middle): its own scan, gi/indirect_glossy.cpp ----
    if (settings.glossy == GlossyIndirect::VectorPyramid && shading.brdf != Brdf::Lambert && settings.bounces > 0) {
        if (!directShade) throw InputError("glossy vector pyramid: the direct shading (incident SH) is required");
        computeGlossyIndirect(pyr, gradX, gradY, op, envVisibility, *directShade, albedo, shading, settings, st);
        return;
    }
    const auto t0 = Clock::now();
    st.timings = IndirectTimings{};
    const int nx = pyr.nx, ny = pyr.ny, s = pyr.subsample;
    const int nxr = pyr.nxr, nyr = pyr.nyr, pad = padGroup(nxr);
    const int m = op.azimuths;
    const int nSteps = static_cast<int>(pyr.steps.size());
    const std::size_t planeR = static_cast<std::size_t>(nxr) * nyr;
    const int nRows = shading.brdf == Brdf::Lambert ? 9 : kShCount;  // Lambert reads bands 0..2 only
    const bool lambertBrdf = shading.brdf == Brdf::Lambert;
    // BlockerRadiance: only E and the horizons at the receivers, no U
    const bool ratio = lambertBrdf && settings.lambert == LambertIndirect::BlockerRadiance;
    const bool exact = lambertBrdf && (settings.lambert == LambertIndirect::ExactAtReceivers || ratio);
    const int mode = !exact ? kShOnly : (s == 1 || ratio ? kExactOnly : kShAndExact);
    const FootprintBox* box = footprint;
    if (mode == kShAndExact && (!box || box->nxr != nxr || box->nyr != nyr || box->subsample != s)) {
        computeFootprintBox(gradX, gradY, s, st.footprint);
        box = &st.footprint;
    }
    // the shading footprint of a receiver (ExactAtReceivers): offsets {-s/2, 0, s/2}^2 cells

    for (int c = 0; c < 3; ++c) {
        Grid& g = st.indirect[static_cast<std::size_t>(c)];
        if (g.nx != nx || g.ny != ny) g.resize(nx, ny);
        std::fill(g.v.begin(), g.v.end(), 0.0f);
    }
    if (ratio) prepareBlockerRadiance(pyr, m, st.blocker);
    for (int c = 0; c < 3 && !ratio; ++c) {
        VisibilityField& u = st.u[static_cast<std::size_t>(c)];
        u.nxr = nxr;
        u.nyr = nyr;
        if (u.sh.size() != planeR * kShCount) st.uZeroFrom = kShCount;  // contents unknown
        u.sh.resize(planeR * kShCount);
    }
    // the planes shading does not read (Lambert: bands 0..2) stay 0; each scan
    // row clears only the planes it fills
    if (!ratio && st.uZeroFrom > nRows) {
        for (VisibilityField& u : st.u) std::fill(u.sh.begin() + static_cast<std::ptrdiff_t>(planeR) * nRows, u.sh.end(), 0.0f);
        st.uZeroFrom = nRows;
    }
    st.bounceMean.resize(static_cast<std::size_t>(settings.bounces));

    // per-block scratch: blocks of kIndirectRows receiver rows
    const int nBlocks = std::max(1, (nyr + kIndirectRows - 1) / kIndirectRows);
    const std::size_t rowFloats = static_cast<std::size_t>(kIndirectRows) * pad;
    st.blocks.resize(static_cast<std::size_t>(nBlocks));
    for (IndirectScratch& b : st.blocks) {
        b.gx.resize(rowFloats);
        b.gy.resize(rowFloats);
        b.h0.resize(rowFloats);
        b.margin.resize(rowFloats);
        if (exact) b.exact.resize(rowFloats * 3);
        if (mode == kShAndExact) {
            b.footGx.resize(rowFloats * 2);
            b.footGy.resize(rowFloats * 2);
            b.lowSlope.resize(static_cast<std::size_t>(pad));
        }
        b.nlp.resize(static_cast<std::size_t>(15) * pad);
        b.state.resize(static_cast<std::size_t>(5 + 3 * 5) * pad);
        b.groupSteps.resize(static_cast<std::size_t>(pad));
        b.active.resize(static_cast<std::size_t>(pad));
    }
    if (!ratio) setUShadingLights(st);

    // the field's highest height (the raw heights; the pyramid levels are
    // filters of it and so stay below it, up to float rounding: 1e-6 relative slack)
    float hMax = -std::numeric_limits<float>::infinity();
    for (int y = 0; y < ny; ++y)
        for (int q = 0; q < s; ++q)
            for (int x = 0; x < pyr.rawPhaseWidth; ++x) hMax = std::max(hMax, pyr.rawPhaseRow(q, y)[x]);
    hMax += std::fabs(hMax) * 1e-6f + 1e-30f;
    const std::size_t tableSize = static_cast<std::size_t>(m) * nSteps;
    st.heightSteps.resize(tableSize);
    st.radianceSteps.resize(3 * tableSize);
    st.stepsPerColumn.resize(static_cast<std::size_t>(m) * pad);
    st.stepsPerRow.resize(static_cast<std::size_t>(m) * nyr);

    const std::array<Grid, 3>* source = &direct;
    for (int b = 1; b <= settings.bounces; ++b) {
        // ---- radiance pyramid of bounce b - 1 (Section 5.3) ------------------------
        auto t = Clock::now();
        buildRadiancePyramid(*source, pyr, settings.radiance, st.radiance);
        st.timings.pyramid += msSince(t);

        // ---- step table: height and radiance steps, valid prefixes --------------------
        t = Clock::now();
        buildIndirectStepTable(pyr, op.phi, pad, st.heightSteps, st.stepsPerColumn, st.stepsPerRow,
                               [&](int i, double c, double sn, std::size_t at, ValidPrefix& prefix) {
                                   for (int ch = 0; ch < 3; ++ch) {
                                       const ScanStepInfo r = scanStepInfo(st.radiance.fields[static_cast<std::size_t>(ch)], i, c, sn);
                                       st.radianceSteps[static_cast<std::size_t>(ch) * tableSize + at] = r.step;
                                       prefix.narrow(r);
                                   }
                               });

        // ---- scan: casting sets, Eq. 12, U through the folded wedge operator ----------
        const int P = op.patternSize();
        const CastRowFn castRow = castRowFor(mode);
        const LambertFactors lambert = lambertFactors();
        void (*const accumulate)(const RowSums&) = simd::wideEnabled() ? accumulateAvx2 : accumulateSse;
        void (*const exactShift)(const ShiftRow&) = simd::wideEnabled() ? exactShiftAvx2 : exactShiftSse;
        parallelFor(0, nBlocks, 1, [&](int b0, int b1) {
            for (int block = b0; block < b1; ++block) {
                IndirectScratch& sc = st.blocks[static_cast<std::size_t>(block)];
                const int yBegin = block * kIndirectRows;
                const int rows = std::min(kIndirectRows, nyr - yBegin);
                // the rows' receiver heights, gradients (and footprints); U rows zeroed
                for (int r = 0; r < rows; ++r) {
                    const int Y = yBegin + r;
                    const std::size_t ro = static_cast<std::size_t>(r) * pad;
                    loadReceiverRow(pyr, gradX, gradY, Y, pad, sc.gx.data() + ro, sc.gy.data() + ro, sc.h0.data() + ro,
                                    sc.margin.data() + ro);
                    if (exact) {
                        // the footprint box's rows (FootprintBox), padded
                        if (mode == kShAndExact) {
                            const std::size_t at = static_cast<std::size_t>(Y) * nxr;
                            float* loX = sc.footGx.data() + 2 * ro;
                            float* loY = sc.footGy.data() + 2 * ro;
                            std::copy(box->loX.begin() + at, box->loX.begin() + at + nxr, loX);
                            std::copy(box->hiX.begin() + at, box->hiX.begin() + at + nxr, loX + pad);
                            std::copy(box->loY.begin() + at, box->loY.begin() + at + nxr, loY);
                            std::copy(box->hiY.begin() + at, box->hiY.begin() + at + nxr, loY + pad);
                            for (int X = nxr; X < pad; ++X) loX[X] = loX[pad + X] = loY[X] = loY[pad + X] = 0.0f;
                        }
                        std::fill(sc.exact.data() + 3 * ro, sc.exact.data() + 3 * ro + 3 * static_cast<std::size_t>(pad), 0.0f);
                    }
                    for (int c = 0; c < 3 && !ratio; ++c)
                        for (int i = 0; i < nRows; ++i) {
                            float* u = st.u[static_cast<std::size_t>(c)].plane(i) + static_cast<std::size_t>(Y) * nxr;
                            std::fill(u, u + nxr, 0.0f);
                        }
                }
                for (int j = 0; j < m; ++j) {
                    const std::size_t base = static_cast<std::size_t>(j) * nSteps;
                    const ScanStep* rTab[3] = {st.radianceSteps.data() + base, st.radianceSteps.data() + tableSize + base,
                                               st.radianceSteps.data() + 2 * tableSize + base};
                    const double phi = op.phi[static_cast<std::size_t>(j)];
                    const float cosPhi = static_cast<float>(std::cos(phi)), sinPhi = static_cast<float>(std::sin(phi));
                    const float* vals = op.values.data() + static_cast<std::size_t>(j) * P;
                    for (int r = 0; r < rows; ++r) {
                        const int Y = yBegin + r;
                        const std::size_t ro = static_cast<std::size_t>(r) * pad;
                        RowInputs in{sc.h0.data() + ro, sc.margin.data() + ro, sc.gx.data() + ro, sc.gy.data() + ro, nullptr, hMax};
                        if (mode == kShAndExact) {
                            // U's segments start at the footprint's lowest tangent slope, lowered
                            // (by footprintDrop x the footprint's spread of slopes, at most footprintDropMax:
                            // 0 where the footprint is one plane)
                            const F4 dropMax = splat<F4>(settings.footprintDropMax);
                            const F4 c4 = splat<F4>(cosPhi), s4 = splat<F4>(sinPhi), drop = splat<F4>(settings.footprintDrop);
                            // the box's lowest slope along (cos, sin): lo or hi per axis by the sign
                            const float* fx = sc.footGx.data() + 2 * ro + (cosPhi >= 0.0f ? 0 : pad);
                            const float* fy = sc.footGy.data() + 2 * ro + (sinPhi >= 0.0f ? 0 : pad);
                            for (int X = 0; X < pad; X += 4) {
                                const F4 lo = load<F4>(fx + X) * c4 + load<F4>(fy + X) * s4;
                                const F4 own = load<F4>(in.gx + X) * c4 + load<F4>(in.gy + X) * s4;
                                const F4 d = drop * (own - lo);
                                store(sc.lowSlope.data() + X, lo - (d < dropMax ? d : dropMax));
                            }
                            in.lowSlope = sc.lowSlope.data();
                        }
                        castRow(st.heightSteps.data() + base, rTab,
                                                                 st.stepsPerColumn.data() + static_cast<std::size_t>(j) * pad,
                                                                 st.stepsPerRow[static_cast<std::size_t>(j) * nyr + static_cast<std::size_t>(Y)], Y,
                                                                 in, cosPhi, sinPhi, sc, pad);
                        // BlockerRadiance: the receivers' horizon along this azimuth (the walk's running maximum)
                        if (ratio && b == 1 && s > 1)
                            std::copy(sc.state.data(), sc.state.data() + nxr,
                                      st.blocker.farSlope.data() + static_cast<std::size_t>(j) * planeR + static_cast<std::size_t>(Y) * nxr);
                        float* uRow[3] = {nullptr, nullptr, nullptr};  // no U with BlockerRadiance
                        for (int c = 0; c < 3 && !ratio; ++c)
                            uRow[c] = st.u[static_cast<std::size_t>(c)].plane(0) + static_cast<std::size_t>(Y) * nxr;
                        accumulate({sc.nlp.data(), pad, nxr, exact ? sc.exact.data() + 3 * ro : nullptr,
                                    mode == kExactOnly ? 0 : P, op.patternRow.data(), op.patternNlp.data(), vals, nRows,
                                    {uRow[0], uRow[1], uRow[2]}, planeR});
                    }
                }
                if (!exact) continue;
                const float eScale = 2.0f / static_cast<float>(m);  // (2 pi / m) / pi
                if (ratio) {
                    // E / pi at the receivers
                    for (int r = 0; r < rows; ++r) {
                        const std::size_t ro = static_cast<std::size_t>(r) * pad;
                        const std::size_t at = static_cast<std::size_t>(yBegin + r) * nxr;
                        const float* gx = sc.gx.data() + ro;
                        const float* gy = sc.gy.data() + ro;
                        for (int c = 0; c < 3; ++c) {
                            const float* e = sc.exact.data() + 3 * ro + static_cast<std::size_t>(c) * pad;
                            float* out = st.blocker.receiverShade[static_cast<std::size_t>(c)].data() + at;
                            for (int X = 0; X < nxr; ++X) out[X] = eScale / std::sqrt(1.0f + gx[X] * gx[X] + gy[X] * gy[X]) * e[X];
                        }
                    }
                    continue;
                }
                // ExactAtReceivers: the shade at the receiver's normal, lam(N) . U
                // (as gi/shading evaluates it there), becomes E / pi through band 0
                for (int r = 0; r < rows; ++r) {
                    const std::size_t ro = static_cast<std::size_t>(r) * pad;
                    const std::size_t at = static_cast<std::size_t>(yBegin + r) * nxr;
                    exactShift({sc.gx.data() + ro, sc.gy.data() + ro, sc.exact.data() + 3 * ro, pad, nxr, eScale,
                                lambert,
                                {st.u[0].sh.data() + at, st.u[1].sh.data() + at, st.u[2].sh.data() + at}, planeR});
                }
            }
        });
        st.timings.scan += msSince(t);

        // ---- shading of U at full-resolution normals: L_b ------------------------------
        t = Clock::now();
        ShadeMaps& out = st.bounceShade[static_cast<std::size_t>(b & 1)];
        if (ratio) {
            if (b == 1 && s > 1) computeTexelOcclusion(pyr, gradX, gradY, op.phi, st.blocker);
            shadeBlockerRadiance(st.blocker, albedo, out.rgb);
        } else {
            shadeTexels(gradX, gradY, s, envVisibility, st.lights.data(), 3, albedo, shading, out, false);
        }
        accumulateBounce(out.rgb, b, st);
        source = &out.rgb;
        st.timings.shading += msSince(t);
    }
    sumDirectAndIndirect(direct, st);
    st.timings.total = msSince(t0);
}

}  // namespace terrain::gi
