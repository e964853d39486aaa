#include "gi/indirect.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>

#include "gi/nlp.h"
#include "gi/sh.h"
#include "sim/error.h"
#include "sim/parallel.h"
#include "sim/simd.h"

namespace terrain::gi {

namespace {

using simd::F4;
typedef int I4 __attribute__((vector_size(16)));
using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

constexpr int kMaxBlocks = 64;
constexpr int kGroup = 8;  // receivers per kernel call (2 x 4 lanes); rows are padded to it
constexpr float kMarginRel = 1.0f / 1048576.0f;  // 2^-20 |h0|: height differences below it are rounding

inline int padGroup(int n) { return (n + kGroup - 1) / kGroup * kGroup; }
inline F4 ld(const float* p) { return simd::load<F4>(p); }
inline F4 spl(float x) { return simd::splat<F4>(x); }
inline bool anyLane(I4 m) { return (m[0] | m[1] | m[2] | m[3]) != 0; }

// Deterministic float atan (Cephes atanf: range reduction to |x| <= tan(pi/8),
// then a degree-9 odd minimax polynomial; ~1e-7 relative): a pure function of
// its argument, so bit-identical for any thread count.
inline F4 atan4(F4 t) {
    const F4 zero = spl(0.0f), one = spl(1.0f);
    const F4 x = t < zero ? -t : t;
    const auto big = x > spl(2.414213562373095f);
    const auto mid = (x > spl(0.4142135623730950f)) & ~big;
    const F4 dBig = big ? x : one;
    const F4 xr = big ? -one / dBig : (mid ? (x - one) / (x + one) : x);
    const F4 y0 = big ? spl(1.5707963267948966f) : (mid ? spl(0.7853981633974483f) : zero);
    const F4 z = xr * xr;
    const F4 p = ((((spl(8.05374449538e-2f) * z - spl(1.38776856032e-1f)) * z + spl(1.99777106478e-1f)) * z -
                   spl(3.33329491539e-1f)) * z) * xr + xr;
    const F4 r = y0 + p;
    return t < zero ? -r : r;
}

// Exact clamped-cosine antiderivatives at elevation w = atan(t):
// f1 = (w + sin w cos w) / 2 = int cos^2, f2 = sin^2 w / 2 = int sin cos.
inline void cosineAntiderivatives(F4 t, F4& f1, F4& f2) {
    const F4 one = spl(1.0f), half = spl(0.5f);
    const F4 inv = one / (one + t * t);
    f1 = half * (atan4(t) + t * inv);
    f2 = half * (t * t * inv);
}

// ---- algorithm: the casting set and Eq. 12 for 4 NV receivers of row Y ------
// Pass 1 walks the height steps (Eq. 17) and, at each step where some lane
// has a new casting-set member, stores the clamped segment's moments
// Delta(s^p), p = 1..4 (0 in the other lanes) and the step index. Pass 2
// multiplies them with the radiance samples at those steps, one channel at a
// time (few live registers; each lane's sums run in step order).
// hTab: the height steps of this azimuth; rTab[c]: channel c's radiance steps;
// moments: scratch of nSteps x NV x 4 vectors; list: nSteps ints.
// Out: 3 channels x 4 NLP coefficients, written at nlp[(c * 4 + l) * pad + X].
// Exact (IndirectSettings::exactCosine): the moments are Delta f1, Delta f2
// of each clamped segment instead; out: nlp[(c * 4 + 0 / 1) * pad + X] =
// sum u Delta f1 / sum u Delta f2.
template <int NV, bool Exact>
void castGroup(const ScanStep* hTab, const ScanStep* const* rTab, const I4* steps, int nAny, int Y, int X0,
               const float* h0, const float* margin, const float* gx, const float* gy, float cosPhi, float sinPhi,
               F4* moments, int* list, float* nlp, int pad) {
    F4 M[NV], g[NV], q1[NV], f1[NV], f2[NV];
    const F4 one = spl(1.0f), lim = spl(1e6f), nlim = spl(-1e6f), zero = spl(0.0f);
    for (int k = 0; k < NV; ++k) {
        M[k] = spl(kNoBlocker);
        // omega_min: the tangent plane's slope along the azimuth (Section 3)
        g[k] = ld(gx + X0 + 4 * k) * spl(cosPhi) + ld(gy + X0 + 4 * k) * spl(sinPhi);
        const F4 t = g[k] < nlim ? nlim : (g[k] > lim ? lim : g[k]);
        q1[k] = t / simd::vsqrt(one + t * t);
        if constexpr (Exact) cosineAntiderivatives(t, f1[k], f2[k]);
    }
    int n = 0;
    for (int i = 0; i < nAny; ++i) {
        const ScanStep& st = hTab[i];
        const std::ptrdiff_t o = Y * st.rowStep + X0;
        const float* a = st.field + (o + st.offA);
        const float* b = st.field + (o + st.offB);
        const F4 wa = ld(st.w[0]), wb = ld(st.w[1]), inv = ld(st.w[2]);
        const I4 iv = {i, i, i, i};
        F4 t[NV];
        I4 nw[NV];
        I4 any = {0, 0, 0, 0};
        for (int k = 0; k < NV; ++k) {
            t[k] = (((wa * ld(a + 4 * k) + wb * ld(b + 4 * k)) - ld(h0 + X0 + 4 * k)) - ld(margin + X0 + 4 * k)) * inv;
            nw[k] = (iv < steps[k]) & (t[k] > M[k]);  // Eq. 17: above every earlier sample
            any |= nw[k];
        }
        if (!anyLane(any)) continue;
        F4* mo = moments + static_cast<std::size_t>(n) * NV * 4;
        list[n++] = i;
        for (int k = 0; k < NV; ++k) {
            M[k] = nw[k] ? t[k] : M[k];
            // the segment [c_(i-1), c_i] clamped to [omega_min, pi/2]
            F4 tc = t[k] < g[k] ? g[k] : t[k];
            tc = tc < nlim ? nlim : (tc > lim ? lim : tc);
            if constexpr (Exact) {
                F4 a1, a2;
                cosineAntiderivatives(tc, a1, a2);
                a1 = nw[k] ? a1 : f1[k];  // no new member: an empty segment (exactly 0)
                a2 = nw[k] ? a2 : f2[k];
                mo[4 * k + 0] = a1 - f1[k];
                mo[4 * k + 1] = a2 - f2[k];
                f1[k] = a1;
                f2[k] = a2;
                continue;
            }
            const F4 sNew = tc / simd::vsqrt(one + tc * tc);
            const F4 sv = nw[k] ? sNew : q1[k];  // no new member: an empty segment
            const F4 p = q1[k], p2 = p * p, s2 = sv * sv;
            mo[4 * k + 0] = sv - p;
            mo[4 * k + 1] = s2 - p2;
            mo[4 * k + 2] = s2 * sv - p2 * p;
            mo[4 * k + 3] = s2 * s2 - p2 * p2;
            q1[k] = sv;
        }
    }
    // pass 2: moments x radiance, then Eq. 10's closed form as a polynomial in s
    const F4 k0 = spl(0.70710678118654752440f), k1 = spl(0.61237243569579452455f);
    const F4 k2 = spl(0.79056941504209483300f), k3 = spl(0.23385358667337133659f);
    for (int c = 0; c < 3; ++c) {
        F4 A[NV][4];
        for (int k = 0; k < NV; ++k)
            for (int p = 0; p < 4; ++p) A[k][p] = zero;
        const ScanStep* tab = rTab[c];
        for (int e = 0; e < n; ++e) {
            const ScanStep& rs = tab[list[e]];
            const std::ptrdiff_t ro = Y * rs.rowStep + X0;
            const float* ra = rs.field + (ro + rs.offA);
            const float* rb = rs.field + (ro + rs.offB);
            const F4 rwa = ld(rs.w[0]), rwb = ld(rs.w[1]);
            const F4* mo = moments + static_cast<std::size_t>(e) * NV * 4;
            for (int k = 0; k < NV; ++k) {
                // lanes without a new member have zero moments; the radiance
                // read there is finite (inside the field's padding and guard)
                const F4 u = rwa * ld(ra + 4 * k) + rwb * ld(rb + 4 * k);
                for (int p = 0; p < (Exact ? 2 : 4); ++p) A[k][p] += u * mo[4 * k + p];
            }
        }
        if constexpr (Exact) {
            for (int k = 0; k < NV; ++k) {
                float* base = nlp + static_cast<std::size_t>(c) * 4 * pad + X0 + 4 * k;
                simd::store(base, A[k][0]);
                simd::store(base + pad, A[k][1]);
            }
            continue;
        }
        for (int k = 0; k < NV; ++k) {
            float* base = nlp + static_cast<std::size_t>(c) * 4 * pad + X0 + 4 * k;
            simd::store(base, k0 * A[k][0]);
            simd::store(base + pad, k1 * A[k][1]);
            simd::store(base + 2 * pad, k2 * (A[k][2] - A[k][0]));
            simd::store(base + 3 * pad, k3 * (spl(5.0f) * A[k][3] - spl(6.0f) * A[k][1]));
        }
    }
}

// Row of receivers for one azimuth.
template <bool Exact>
void castRow(const ScanStep* hTab, const ScanStep* const* rTab, const int* colSteps, int rowSteps, int Y,
             IndirectScratch& sc, float cosPhi, float sinPhi, float* nlp, int pad) {
    const I4 rowLimit = {rowSteps, rowSteps, rowSteps, rowSteps};
    for (int X0 = 0; X0 < pad; X0 += kGroup) {
        I4 steps[kGroup / 4];
        int nAny = 0;
        for (int k = 0; k < kGroup / 4; ++k) {
            I4 c;
            std::memcpy(&c, colSteps + X0 + 4 * k, sizeof c);
            steps[k] = c < rowLimit ? c : rowLimit;
            for (int l = 0; l < 4; ++l) nAny = std::max(nAny, steps[k][l]);
        }
        castGroup<kGroup / 4, Exact>(hTab, rTab, steps, nAny, Y, X0, sc.h0.data(), sc.margin.data(), sc.gx.data(), sc.gy.data(), cosPhi,
                     sinPhi, reinterpret_cast<F4*>(sc.moments.data()), sc.list.data(), nlp, pad);
    }
}

}  // namespace

void validateIndirectSettings(const IndirectSettings& s) {
    if (s.bounces < 0 || s.bounces > 16) throw InputError("bounces must be in [0, 16]");
    if (s.radiance.levelsPerOctave < 1 || s.radiance.levelsPerOctave > 64)
        throw InputError("radiance levels per octave must be in [1, 64]");
    if (s.radiance.levelOffset < 0 || s.radiance.levelOffset > 32) throw InputError("radiance level offset must be in [0, 32]");
}

void computeIndirect(const HeightPyramid& pyr, ConstGridView gradX, ConstGridView gradY, const FoldedWedgeOperator& op,
                     const VisibilityField& envVisibility, const std::array<Grid, 3>& direct, const AlbedoMap* albedo,
                     const ShadingSettings& shading, const IndirectSettings& settings, IndirectState& st,
                     const ShadeMaps* directShade) {
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
    const bool exact = settings.exactCosine && shading.brdf == Brdf::Lambert;
    // dphi / (pi lam1 c1), lam1 = sqrt(4 pi / 3) z_1 / pi as in gi/shading
    const double lam1 = std::sqrt(4.0 * kPi / 3.0) * lambertZonal()[1] / kPi;
    const bool scalarE = exact && settings.exactCosineReceiverNormal;
    const float scalarScale = static_cast<float>(lam1 * 0.48860251190291992 / (std::sqrt(4.0 * kPi) * lambertZonal()[0] / kPi * 0.28209479177387814));
    const double exactScale = (2.0 * kPi / m) / (kPi * lam1 * 0.48860251190291992);

    for (int c = 0; c < 3; ++c) {
        Grid& g = st.indirect[static_cast<std::size_t>(c)];
        if (g.nx != nx || g.ny != ny) g.resize(nx, ny);
        std::fill(g.v.begin(), g.v.end(), 0.0f);
        VisibilityField& u = st.u[static_cast<std::size_t>(c)];
        u.nxr = nxr;
        u.nyr = nyr;
        u.sh.resize(planeR * kShCount);
    }
    st.bounceMean.resize(static_cast<std::size_t>(settings.bounces));

    // per-block scratch
    const int nBlocks = std::max(1, std::min(nyr, kMaxBlocks));
    st.blocks.resize(static_cast<std::size_t>(nBlocks));
    for (IndirectScratch& b : st.blocks) {
        b.gx.resize(static_cast<std::size_t>(pad));
        b.gy.resize(static_cast<std::size_t>(pad));
        b.h0.resize(static_cast<std::size_t>(pad));
        b.margin.resize(static_cast<std::size_t>(pad));
        b.nlp.resize(static_cast<std::size_t>(12) * pad);
        b.moments.resize(static_cast<std::size_t>(std::max(nSteps, 1)) * 2 * 4 * 4 + 4);  // nSteps x 2 vectors x 4 moments x 4 lanes
        b.list.resize(static_cast<std::size_t>(std::max(nSteps, 1)));
    }
    // shading: U of channel c lights channel c only (identity product matrix)
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
        parallelFor(0, m, 1, [&](int j0, int j1) {
            for (int j = j0; j < j1; ++j) {
                const double c = std::cos(op.phi[static_cast<std::size_t>(j)]);
                const double sn = std::sin(op.phi[static_cast<std::size_t>(j)]);
                const std::size_t base = static_cast<std::size_t>(j) * nSteps;
                int* colSteps = st.stepsPerColumn.data() + static_cast<std::size_t>(j) * pad;
                int* rowSteps = st.stepsPerRow.data() + static_cast<std::size_t>(j) * nyr;
                std::fill(colSteps, colSteps + pad, 0);
                std::fill(rowSteps, rowSteps + nyr, 0);
                // a receiver's sequence is its prefix of steps inside the domain
                // (for the heights and the radiance sample alike)
                int xLo = 0, xHi = nxr - 1, yLo = 0, yHi = nyr - 1;
                for (int i = 0; i < nSteps; ++i) {
                    const ScanStepInfo h = scanStepInfo(pyr, i, c, sn);
                    st.heightSteps[base + static_cast<std::size_t>(i)] = h.step;
                    int xf = h.xFirst, xl = h.xLast, yf = h.yFirst, yl = h.yLast;
                    for (int ch = 0; ch < 3; ++ch) {
                        const ScanStepInfo r = scanStepInfo(st.radiance.fields[static_cast<std::size_t>(ch)], i, c, sn);
                        st.radianceSteps[static_cast<std::size_t>(ch) * tableSize + base + static_cast<std::size_t>(i)] = r.step;
                        xf = std::max(xf, r.xFirst);
                        xl = std::min(xl, r.xLast);
                        yf = std::max(yf, r.yFirst);
                        yl = std::min(yl, r.yLast);
                    }
                    // receivers still inside at step i: those inside at every step so far
                    xLo = std::max(xLo, xf);
                    xHi = std::min(xHi, xl);
                    yLo = std::max(yLo, yf);
                    yHi = std::min(yHi, yl);
                    for (int X = xLo; X <= xHi; ++X) colSteps[X] = i + 1;
                    for (int Y = yLo; Y <= yHi; ++Y) rowSteps[Y] = i + 1;
                }
            }
        });

        // ---- scan: casting sets, Eq. 12, U through the folded wedge operator ----------
        const int P = op.patternSize();
        parallelFor(0, nBlocks, 1, [&](int b0, int b1) {
            for (int block = b0; block < b1; ++block) {
                IndirectScratch& sc = st.blocks[static_cast<std::size_t>(block)];
                const int yBegin = static_cast<int>(static_cast<long long>(nyr) * block / nBlocks);
                const int yEnd = static_cast<int>(static_cast<long long>(nyr) * (block + 1) / nBlocks);
                for (int Y = yBegin; Y < yEnd; ++Y) {
                    const float* hRow = pyr.rawPhaseRow(0, s * Y);
                    for (int X = 0; X < pad; ++X) {
                        const bool in = X < nxr;
                        const std::size_t xi = static_cast<std::size_t>(X);
                        sc.gx[xi] = in ? gradX(s * X, s * Y) : 0.0f;
                        sc.gy[xi] = in ? gradY(s * X, s * Y) : 0.0f;
                        sc.h0[xi] = in ? hRow[X] : 0.0f;
                        sc.margin[xi] = std::fabs(sc.h0[xi]) * kMarginRel;
                    }
                    float* uRows[3][kShCount];
                    for (int c = 0; c < 3; ++c)
                        for (int i = 0; i < kShCount; ++i) {
                            uRows[c][i] = st.u[static_cast<std::size_t>(c)].plane(i) + static_cast<std::size_t>(Y) * nxr;
                            std::fill(uRows[c][i], uRows[c][i] + nxr, 0.0f);
                        }
                    for (int j = 0; j < m; ++j) {
                        const std::size_t base = static_cast<std::size_t>(j) * nSteps;
                        const ScanStep* rTab[3] = {st.radianceSteps.data() + base, st.radianceSteps.data() + tableSize + base,
                                                   st.radianceSteps.data() + 2 * tableSize + base};
                        const double phi = op.phi[static_cast<std::size_t>(j)];
                        (exact ? castRow<true> : castRow<false>)(st.heightSteps.data() + base, rTab, st.stepsPerColumn.data() + static_cast<std::size_t>(j) * pad,
                                st.stepsPerRow[static_cast<std::size_t>(j) * nyr + static_cast<std::size_t>(Y)], Y, sc,
                                static_cast<float>(std::cos(phi)), static_cast<float>(std::sin(phi)), sc.nlp.data(), pad);
                        if (exact) {
                            // A and B (box weight dphi) into U's band-1 planes, scaled so
                            // that the Lambert shade lam1 c1 (Yn U1 + Z U2 + X U3) = E / pi
                            const float ax = static_cast<float>(exactScale * std::cos(phi));
                            const float ay = static_cast<float>(exactScale * std::sin(phi));
                            const float bz = static_cast<float>(exactScale);
                            for (int c = 0; c < 3; ++c) {
                                const float* __restrict w1 = sc.nlp.data() + static_cast<std::size_t>(c * 4) * pad;
                                const float* __restrict w2 = w1 + pad;
                                float* __restrict u1 = uRows[c][1];
                                float* __restrict u2 = uRows[c][2];
                                float* __restrict u3 = uRows[c][3];
                                for (int X = 0; X < nxr; ++X) {
                                    u1[X] += ay * w1[X];
                                    u2[X] += bz * w2[X];
                                    u3[X] += ax * w1[X];
                                }
                            }
                            continue;
                        }
                        // U_c += G_j u_(c, j) over the sparse pattern (Eq. 21)
                        const float* vals = op.values.data() + static_cast<std::size_t>(j) * P;
                        for (int e = 0; e < P; ++e) {
                            const int r = op.patternRow[static_cast<std::size_t>(e)];
                            if (r >= nRows) continue;
                            const float gval = vals[e];
                            const int l = op.patternNlp[static_cast<std::size_t>(e)];
                            for (int c = 0; c < 3; ++c) {
                                float* __restrict dst = uRows[c][r];
                                const float* __restrict w = sc.nlp.data() + static_cast<std::size_t>(c * 4 + l) * pad;
                                for (int X = 0; X < nxr; ++X) dst[X] += gval * w[X];
                            }
                        }
                    }
                    if (scalarE) {
                        // E at the receiver's own normal, interpolated as a scalar (band 0)
                        for (int c = 0; c < 3; ++c)
                            for (int X = 0; X < nxr; ++X) {
                                const float gx = sc.gx[static_cast<std::size_t>(X)], gy = sc.gy[static_cast<std::size_t>(X)];
                                const float inv = 1.0f / std::sqrt(1.0f + gx * gx + gy * gy);
                                const float e = (-gx * inv) * uRows[c][3][X] + (-gy * inv) * uRows[c][1][X] + inv * uRows[c][2][X];
                                uRows[c][0][X] = scalarScale * e;
                                uRows[c][1][X] = uRows[c][2][X] = uRows[c][3][X] = 0.0f;
                            }
                    }
                }
            }
        });
        st.timings.scan += msSince(t);

        // ---- shading of U at full-resolution normals: L_b ------------------------------
        t = Clock::now();
        ShadeMaps& out = st.bounceShade[static_cast<std::size_t>(b & 1)];
        shadeTexels(gradX, gradY, s, envVisibility, st.lights.data(), 3, albedo, shading, out);
        double sum = 0.0;
        for (int c = 0; c < 3; ++c) {
            Grid& acc = st.indirect[static_cast<std::size_t>(c)];
            const Grid& add = out.rgb[static_cast<std::size_t>(c)];
            for (std::size_t i = 0; i < acc.v.size(); ++i) {
                acc.v[i] += add.v[i];
                sum += add.v[i];
            }
        }
        st.bounceMean[static_cast<std::size_t>(b - 1)] = sum / (3.0 * std::max<std::size_t>(1, static_cast<std::size_t>(nx) * ny));
        source = &out.rgb;
        st.timings.shading += msSince(t);
    }
    for (int c = 0; c < 3; ++c) {
        Grid& tot = st.total[static_cast<std::size_t>(c)];
        if (tot.nx != nx || tot.ny != ny) tot.resize(nx, ny);
        const Grid& d = direct[static_cast<std::size_t>(c)];
        const Grid& ind = st.indirect[static_cast<std::size_t>(c)];
        for (std::size_t i = 0; i < tot.v.size(); ++i) tot.v[i] = d.v[i] + ind.v[i];
    }
    st.timings.total = msSince(t0);
}

}  // namespace terrain::gi
