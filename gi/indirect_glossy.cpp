#include "gi/indirect_glossy.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>

#include "gi/indirect.h"
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
typedef int I4 __attribute__((vector_size(16)));
using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

constexpr int kMaxBlocks = 64;
constexpr int kGroup = 8;   // receivers per kernel call (2 x 4 lanes)
constexpr int kNV = kGroup / 4;

inline int padGroup(int n) { return (n + kGroup - 1) / kGroup * kGroup; }
inline bool anyLane(I4 m) { return (m[0] | m[1] | m[2] | m[3]) != 0; }

// ---- the reflection Rot_N(pi) in SH, per band -------------------------------
// Band l of h(w) = f(R_N w) is fixed by its values at 2l+1 directions d_j:
// E_l = B_l^-1 h_l(d), B_l[j][m] = Y_lm(d_j), d_0..d_(2l) the first 2l+1 of
// 7 fixed directions. Symmetric sets are singular (a 7-point Fibonacci set
// is, for band 3); these 7 came from a random search (200000 draws)
// minimising the largest Frobenius norm of the three inverses: 4.7, 4.5, 4.8,
// so float rounding of h costs ~1e-6 relative. The inverses are computed once
// in double (Gauss-Jordan, partial pivoting).
struct MirrorTables {
    static constexpr float kDirs[7][3] = {{-0.784515631f, -0.552553248f, 0.281460715f},
                                          {-0.971931924f, -0.041938494f, -0.231494056f},
                                          {0.054143289f, -0.730243560f, -0.681038066f},
                                          {0.772798188f, -0.028211642f, -0.634024498f},
                                          {0.081702522f, -0.036083780f, -0.996003343f},
                                          {0.005037122f, 0.998826450f, 0.048170015f},
                                          {0.631249704f, 0.383672776f, -0.674031908f}};
    float dir[7][3];
    float inv[83];  // band l: (2l+1) x (2l+1) block at offset(l)
    static int offset(int l) { return l == 1 ? 0 : (l == 2 ? 9 : 34); }
    MirrorTables() {
        for (int k = 0; k < 7; ++k) {
            const double len = std::sqrt(static_cast<double>(kDirs[k][0]) * kDirs[k][0] + static_cast<double>(kDirs[k][1]) * kDirs[k][1] +
                                         static_cast<double>(kDirs[k][2]) * kDirs[k][2]);
            for (int a = 0; a < 3; ++a) dir[k][a] = static_cast<float>(kDirs[k][a] / len);
        }
        for (int l = 1; l < kShOrder; ++l) {
            const int n = 2 * l + 1;
            double a[7][14];
            for (int j = 0; j < n; ++j) {
                double y[kShCount];
                shEvaluate(static_cast<double>(dir[j][0]), static_cast<double>(dir[j][1]), static_cast<double>(dir[j][2]), y);
                for (int m = 0; m < n; ++m) {
                    a[j][m] = y[l * l + m];
                    a[j][n + m] = j == m ? 1.0 : 0.0;
                }
            }
            for (int c = 0; c < n; ++c) {
                int p = c;
                for (int r = c + 1; r < n; ++r)
                    if (std::fabs(a[r][c]) > std::fabs(a[p][c])) p = r;
                for (int k = 0; k < 2 * n; ++k) std::swap(a[c][k], a[p][k]);
                const double piv = a[c][c];
                for (int k = 0; k < 2 * n; ++k) a[c][k] /= piv;
                for (int r = 0; r < n; ++r) {
                    if (r == c) continue;
                    const double f = a[r][c];
                    for (int k = 0; k < 2 * n; ++k) a[r][k] -= f * a[c][k];
                }
            }
            // inv[m][j]: E_lm = sum_j inv[m][j] h(d_j)
            for (int m = 0; m < n; ++m)
                for (int j = 0; j < n; ++j) inv[offset(l) + m * n + j] = static_cast<float>(a[m][n + j]);
        }
    }
};

const MirrorTables& mirrorTables() {
    static const MirrorTables t;
    return t;
}

// E for the three channels of one texel; I: 3 x 16 interpolated incident SH.
void exitVectors(const MirrorTables& mt, const float (*I)[kShCount], float nx, float ny, float nz, const float ph[kShOrder],
                 float ws, const float diffuse[3], float (*E)[kShCount]) {
    float yr[7][kShCount];
    for (int j = 0; j < 7; ++j) {
        const float* d = mt.dir[j];
        const float dn = 2.0f * (nx * d[0] + ny * d[1] + nz * d[2]);
        shBasisLanes<float>(dn * nx - d[0], dn * ny - d[1], dn * nz - d[2], yr[j]);
    }
    const float sqrt4pi = 3.5449077018110318f;
    for (int c = 0; c < 3; ++c) {
        // band 0 is invariant under rotation; the diffuse scalar joins it
        E[c][0] = ws * ph[0] * I[c][0] + sqrt4pi * diffuse[c];
        for (int l = 1; l < kShOrder; ++l) {
            const int n = 2 * l + 1, b = l * l;
            float cl[7], h[7];
            for (int m = 0; m < n; ++m) cl[m] = ws * ph[l] * I[c][b + m];
            for (int j = 0; j < n; ++j) {
                float s = 0.0f;
                for (int m = 0; m < n; ++m) s += cl[m] * yr[j][b + m];
                h[j] = s;
            }
            const float* inv = mt.inv + MirrorTables::offset(l);
            for (int m = 0; m < n; ++m) {
                float s = 0.0f;
                for (int j = 0; j < n; ++j) s += inv[m * n + j] * h[j];
                E[c][b + m] = s;
            }
        }
    }
}

// ---- algorithm: casting set, direction-dependent u, Eq. 12 ------------------
// Pass 1 (as gi/indirect): the height steps (Eq. 17); at each step with a new
// member in some lane, the clamped segment's moments Delta(s^p), p = 1..4,
// and the SH basis at the direction from the member back to the receiver,
// -d = -(cos phi c, sin phi c, s), s = t / sqrt(1 + t^2), c = 1 / sqrt(1 + t^2)
// for the member's slope t (0 in lanes without a new member).
// Pass 2, per channel: u = Ebar . Y(-d) from the 16 planes' bilinear samples,
// accumulated with the moments; then Eq. 10's closed form in s.
// Out: nlp[(c * 4 + l) * pad + X].
void castGroupGlossy(const ScanStep* hTab, const ScanStep* rGeo, const float* const* rFields, const I4* steps, int nAny,
                     int Y, int X0, const float* h0, const float* margin, const float* gx, const float* gy, float cosPhi,
                     float sinPhi, F4* moments, F4* basis, int* list, float* nlp, int pad) {
    F4 M[kNV], g[kNV], q1[kNV];
    const F4 one = splat<F4>(1.0f), lim = splat<F4>(1e6f), nlim = splat<F4>(-1e6f), zero = splat<F4>(0.0f);
    const F4 cp = splat<F4>(-cosPhi), sp = splat<F4>(-sinPhi);
    for (int k = 0; k < kNV; ++k) {
        M[k] = splat<F4>(kNoBlocker);
        g[k] = load<F4>(gx + X0 + 4 * k) * splat<F4>(cosPhi) + load<F4>(gy + X0 + 4 * k) * splat<F4>(sinPhi);  // omega_min (Section 3)
        const F4 t = g[k] < nlim ? nlim : (g[k] > lim ? lim : g[k]);
        q1[k] = t / simd::sqrtv(one + t * t);
    }
    int n = 0;
    for (int i = 0; i < nAny; ++i) {
        const ScanStep& st = hTab[i];
        const std::ptrdiff_t o = Y * st.rowStep + X0;
        const float* a = st.field + (o + st.offA);
        const float* b = st.field + (o + st.offB);
        const F4 wa = load<F4>(st.w[0]), wb = load<F4>(st.w[1]), inv = load<F4>(st.w[2]);
        const I4 iv = {i, i, i, i};
        F4 t[kNV];
        I4 nw[kNV];
        I4 any = {0, 0, 0, 0};
        for (int k = 0; k < kNV; ++k) {
            t[k] = (((wa * load<F4>(a + 4 * k) + wb * load<F4>(b + 4 * k)) - load<F4>(h0 + X0 + 4 * k)) - load<F4>(margin + X0 + 4 * k)) * inv;
            nw[k] = (iv < steps[k]) & (t[k] > M[k]);  // Eq. 17
            any |= nw[k];
        }
        if (!anyLane(any)) continue;
        F4* mo = moments + static_cast<std::size_t>(n) * kNV * 4;
        F4* ba = basis + static_cast<std::size_t>(n) * kNV * kShCount;
        list[n++] = i;
        for (int k = 0; k < kNV; ++k) {
            M[k] = nw[k] ? t[k] : M[k];
            F4 tc = t[k] < g[k] ? g[k] : t[k];
            tc = tc < nlim ? nlim : (tc > lim ? lim : tc);
            const F4 sNew = tc / simd::sqrtv(one + tc * tc);
            const F4 sv = nw[k] ? sNew : q1[k];  // no new member: an empty segment
            const F4 p = q1[k], p2 = p * p, s2 = sv * sv;
            mo[4 * k + 0] = sv - p;
            mo[4 * k + 1] = s2 - p2;
            mo[4 * k + 2] = s2 * sv - p2 * p;
            mo[4 * k + 3] = s2 * s2 - p2 * p2;
            q1[k] = sv;
            // the member's own direction (its unclamped elevation), reversed
            F4 tm = t[k] < nlim ? nlim : (t[k] > lim ? lim : t[k]);
            tm = nw[k] ? tm : zero;
            const F4 ic = one / simd::sqrtv(one + tm * tm);
            F4 y[kShCount];
            shBasisLanes<F4>(cp * ic, sp * ic, -(tm * ic), y);
            for (int f = 0; f < kShCount; ++f) ba[kShCount * k + f] = nw[k] ? y[f] : zero;
        }
    }
    const F4 k0 = splat<F4>(0.70710678118654752440f), k1 = splat<F4>(0.61237243569579452455f);
    const F4 k2 = splat<F4>(0.79056941504209483300f), k3 = splat<F4>(0.23385358667337133659f);
    for (int c = 0; c < 3; ++c) {
        F4 A[kNV][4];
        for (int k = 0; k < kNV; ++k)
            for (int p = 0; p < 4; ++p) A[k][p] = zero;
        for (int e = 0; e < n; ++e) {
            const int i = list[e];
            const ScanStep& rs = rGeo[i];
            const std::ptrdiff_t ro = Y * rs.rowStep + X0, dB = rs.offB - rs.offA;
            const F4 rwa = load<F4>(rs.w[0]), rwb = load<F4>(rs.w[1]);
            const float* const* fp = rFields + static_cast<std::size_t>(i) * kGlossyFields + c * kShCount;
            const F4* mo = moments + static_cast<std::size_t>(e) * kNV * 4;
            const F4* ba = basis + static_cast<std::size_t>(e) * kNV * kShCount;
            F4 u[kNV];
            for (int k = 0; k < kNV; ++k) u[k] = zero;
            for (int f = 0; f < kShCount; ++f) {
                const float* pa = fp[f] + ro;
                for (int k = 0; k < kNV; ++k) {
                    // lanes without a new member have a zero basis; their samples are finite
                    const F4 v = rwa * load<F4>(pa + 4 * k) + rwb * load<F4>(pa + dB + 4 * k);
                    u[k] += v * ba[kShCount * k + f];
                }
            }
            for (int k = 0; k < kNV; ++k)
                for (int p = 0; p < 4; ++p) A[k][p] += u[k] * mo[4 * k + p];
        }
        for (int k = 0; k < kNV; ++k) {
            float* base = nlp + static_cast<std::size_t>(c) * 4 * pad + X0 + 4 * k;
            simd::store(base, k0 * A[k][0]);
            simd::store(base + pad, k1 * A[k][1]);
            simd::store(base + 2 * pad, k2 * (A[k][2] - A[k][0]));
            simd::store(base + 3 * pad, k3 * (splat<F4>(5.0f) * A[k][3] - splat<F4>(6.0f) * A[k][1]));
        }
    }
}

// Scratch layout of one row block (floats; every part a multiple of 4).
struct BlockLayout {
    std::size_t gx, gy, h0, margin, nlp, moments, basis, total;
    BlockLayout(int pad, int nSteps) {
        const std::size_t p = static_cast<std::size_t>(pad), s = static_cast<std::size_t>(std::max(nSteps, 1));
        gx = 0;
        gy = gx + p;
        h0 = gy + p;
        margin = h0 + p;
        nlp = margin + p;
        moments = nlp + 12 * p;
        basis = moments + s * kNV * 4 * 4;
        total = basis + s * kNV * kShCount * 4 + 4;
    }
};

}  // namespace

void glossyExitVector(const float incident[kShCount], float nx, float ny, float nz, const float ph[kShOrder], float ws,
                      float diffuse, float out[kShCount]) {
    float I[3][kShCount] = {}, E[3][kShCount];
    const float d[3] = {diffuse, 0.0f, 0.0f};
    for (int i = 0; i < kShCount; ++i) I[0][i] = incident[i];
    exitVectors(mirrorTables(), I, nx, ny, nz, ph, ws, d, E);
    for (int i = 0; i < kShCount; ++i) out[i] = E[0][i];
}

void glossyExitRadiance(ConstGridView gradX, ConstGridView gradY, int s, int nxr, int nyr, const float* incident,
                        const std::array<Grid, 3>& shade, const AlbedoMap* surface, const ShadingSettings& shading,
                        GlossyIndirectState& st, float* out) {
    const int nx = gradX.nx, ny = gradX.ny;
    const std::size_t planeR = static_cast<std::size_t>(nxr) * nyr, plane = static_cast<std::size_t>(nx) * ny;
    const MirrorTables& mt = mirrorTables();
    float phUniform[kShOrder];
    phongLobeFactors(shading.phongExponent, phUniform);
    const float ws = specularWeightOf(shading);
    const float vx = shading.viewDir[0], vy = shading.viewDir[1], vz = shading.viewDir[2];
    const int nBlocks = std::max(1, std::min(ny, kMaxBlocks));
    st.rowScratch.resize(static_cast<std::size_t>(nBlocks) * kGlossyFields * std::max(nxr, 1));
    parallelFor(0, nBlocks, 1, [&](int b0, int b1) {
        for (int block = b0; block < b1; ++block) {
            float* vert = st.rowScratch.data() + static_cast<std::size_t>(block) * kGlossyFields * nxr;
            const int yBegin = static_cast<int>(static_cast<long long>(ny) * block / nBlocks);
            const int yEnd = static_cast<int>(static_cast<long long>(ny) * (block + 1) / nBlocks);
            for (int y = yBegin; y < yEnd; ++y) {
                // ---- the incident SH vectors of this row, interpolated as gi/shading does (Fig. 7)
                const ReceiverLerp ry = receiverLerp(y, s, nyr);
                const int Y0 = ry.i0, Y1 = ry.i1;
                const float fy = ry.f;
                for (int p = 0; p < kGlossyFields; ++p) {
                    const float* ra = incident + p * planeR + static_cast<std::size_t>(Y0) * nxr;
                    const float* rb = incident + p * planeR + static_cast<std::size_t>(Y1) * nxr;
                    float* v = vert + static_cast<std::size_t>(p) * nxr;
                    for (int X = 0; X < nxr; ++X) v[X] = ra[X] + fy * (rb[X] - ra[X]);
                }
                for (int x = 0; x < nx; ++x) {
                    const ReceiverLerp rx = receiverLerp(x, s, nxr);
                    const int X0 = rx.i0, X1 = rx.i1;
                    const float fx = rx.f;
                    float I[3][kShCount];
                    for (int c = 0; c < 3; ++c)
                        for (int i = 0; i < kShCount; ++i) {
                            const float* v = vert + static_cast<std::size_t>(c * kShCount + i) * nxr;
                            I[c][i] = v[X0] + fx * (v[X1] - v[X0]);
                        }
                    const float gxv = gradX(x, y), gyv = gradY(x, y);
                    const float inv = 1.0f / std::sqrt(1.0f + gxv * gxv + gyv * gyv);
                    const float nxv = -gxv * inv, nyv = -gyv * inv, nzv = inv;
                    const std::size_t idx = static_cast<std::size_t>(y) * nx + x;
                    float ph[kShOrder];
                    texelPhongLobe(surface, idx, phUniform, ph);
                    // what the shade holds beside the lobe towards the viewer: the diffuse part
                    const float nv = nxv * vx + nyv * vy + nzv * vz;
                    float yv[kShCount];
                    shBasisLanes<float>(2.0f * nv * nxv - vx, 2.0f * nv * nyv - vy, 2.0f * nv * nzv - vz, yv);
                    float diffuse[3];
                    for (int c = 0; c < 3; ++c) {
                        float sp = 0.0f;
                        for (int i = 0; i < kShCount; ++i) sp += ph[shBand(i)] * yv[i] * I[c][i];
                        diffuse[c] = shade[static_cast<std::size_t>(c)].v[idx] - ws * sp;
                    }
                    float E[3][kShCount];
                    exitVectors(mt, I, nxv, nyv, nzv, ph, ws, diffuse, E);
                    for (int c = 0; c < 3; ++c)
                        for (int i = 0; i < kShCount; ++i) {
                            const float e = E[c][i];
                            out[static_cast<std::size_t>(c * kShCount + i) * plane + idx] = std::isfinite(e) ? e : 0.0f;
                        }
                }
            }
        }
    });
}

void computeGlossyIndirect(const HeightPyramid& pyr, ConstGridView gradX, ConstGridView gradY, const FoldedWedgeOperator& op,
                           const VisibilityField& envVisibility, const ShadeMaps& directShade, const AlbedoMap* surface,
                           const ShadingSettings& shading, const IndirectSettings& settings, IndirectState& st) {
    const auto t0 = Clock::now();
    st.timings = IndirectTimings{};
    GlossyIndirectState& gs = st.glossy;
    const int nx = pyr.nx, ny = pyr.ny, s = pyr.subsample;
    const int nxr = pyr.nxr, nyr = pyr.nyr, pad = padGroup(nxr);
    const int m = op.azimuths;
    const int nSteps = static_cast<int>(pyr.steps.size());
    const std::size_t planeR = static_cast<std::size_t>(nxr) * nyr, plane = static_cast<std::size_t>(nx) * ny;
    if (directShade.incident.size() != planeR * kGlossyFields || directShade.nx != nx || directShade.ny != ny)
        throw InputError("glossy vector pyramid: the direct shading is not a Phong shading of this field");

    for (int c = 0; c < 3; ++c) {
        Grid& g = st.indirect[static_cast<std::size_t>(c)];
        if (g.nx != nx || g.ny != ny) g.resize(nx, ny);
        std::fill(g.v.begin(), g.v.end(), 0.0f);
        VisibilityField& u = st.u[static_cast<std::size_t>(c)];
        u.nxr = nxr;
        u.nyr = nyr;
        u.sh.resize(planeR * kShCount);
        st.uZeroFrom = kShCount;  // every plane is written here
    }
    st.bounceMean.resize(static_cast<std::size_t>(settings.bounces));
    setUShadingLights(st);
    const int nBlocks = std::max(1, std::min(nyr, kMaxBlocks));
    const BlockLayout lay(pad, nSteps);
    gs.blockScratch.resize(static_cast<std::size_t>(nBlocks) * lay.total);
    gs.blockList.resize(static_cast<std::size_t>(nBlocks) * std::max(nSteps, 1));
    gs.exitSh.resize(plane * kGlossyFields);
    const std::size_t tableSize = static_cast<std::size_t>(m) * nSteps;
    st.heightSteps.resize(tableSize);
    gs.steps.resize(tableSize);
    gs.fields.resize(tableSize * kGlossyFields);
    st.stepsPerColumn.resize(static_cast<std::size_t>(m) * pad);
    st.stepsPerRow.resize(static_cast<std::size_t>(m) * nyr);

    const ShadeMaps* prev = &directShade;
    for (int b = 1; b <= settings.bounces; ++b) {
        // ---- E of bounce b - 1 at full resolution, and its pyramid (Section 5.3) --------
        auto t = Clock::now();
        glossyExitRadiance(gradX, gradY, s, nxr, nyr, prev->incident.data(), prev->rgb, surface, shading, gs, gs.exitSh.data());
        buildScalarPyramids(gs.exitSh.data(), kGlossyFields, pyr, settings.radiance, gs.pyramid);
        st.timings.pyramid += msSince(t);

        // ---- step table: heights, E geometry (identical for the 48 planes), valid prefixes
        t = Clock::now();
        buildIndirectStepTable(pyr, op.phi, pad, st.heightSteps, st.stepsPerColumn, st.stepsPerRow,
                               [&](int i, double c, double sn, std::size_t at, ValidPrefix& prefix) {
                                   const ScanStepInfo r = scanStepInfo(gs.pyramid.fields[0], i, c, sn);
                                   gs.steps[at] = r.step;
                                   const float** fp = gs.fields.data() + at * kGlossyFields;
                                   for (int f = 0; f < kGlossyFields; ++f) {
                                       // same layout in every plane's pyramid: only the base pointer differs
                                       const ScanStep rf =
                                           f == 0 ? r.step : scanStepInfo(gs.pyramid.fields[static_cast<std::size_t>(f)], i, c, sn).step;
                                       fp[f] = rf.field + rf.offA;
                                   }
                                   prefix.narrow(r);
                               });

        // ---- scan: casting sets, u = Ebar . Y(-d), Eq. 12, U through the folded wedge operator
        const int P = op.patternSize();
        parallelFor(0, nBlocks, 1, [&](int b0, int b1) {
            for (int block = b0; block < b1; ++block) {
                float* scr = gs.blockScratch.data() + static_cast<std::size_t>(block) * lay.total;
                float* gxs = scr + lay.gx;
                float* gys = scr + lay.gy;
                float* h0s = scr + lay.h0;
                float* mgs = scr + lay.margin;
                float* nlp = scr + lay.nlp;
                F4* moments = reinterpret_cast<F4*>(scr + lay.moments);
                F4* basis = reinterpret_cast<F4*>(scr + lay.basis);
                int* list = gs.blockList.data() + static_cast<std::size_t>(block) * std::max(nSteps, 1);
                const int yBegin = static_cast<int>(static_cast<long long>(nyr) * block / nBlocks);
                const int yEnd = static_cast<int>(static_cast<long long>(nyr) * (block + 1) / nBlocks);
                for (int Y = yBegin; Y < yEnd; ++Y) {
                    loadReceiverRow(pyr, gradX, gradY, Y, pad, gxs, gys, h0s, mgs);  // the margin as gi/indirect
                    float* uRows[3][kShCount];
                    for (int c = 0; c < 3; ++c)
                        for (int i = 0; i < kShCount; ++i) {
                            uRows[c][i] = st.u[static_cast<std::size_t>(c)].plane(i) + static_cast<std::size_t>(Y) * nxr;
                            std::fill(uRows[c][i], uRows[c][i] + nxr, 0.0f);
                        }
                    for (int j = 0; j < m; ++j) {
                        const std::size_t base = static_cast<std::size_t>(j) * nSteps;
                        const double phi = op.phi[static_cast<std::size_t>(j)];
                        const float cosPhi = static_cast<float>(std::cos(phi)), sinPhi = static_cast<float>(std::sin(phi));
                        const int* colSteps = st.stepsPerColumn.data() + static_cast<std::size_t>(j) * pad;
                        const int rowSteps = st.stepsPerRow[static_cast<std::size_t>(j) * nyr + static_cast<std::size_t>(Y)];
                        const I4 rowLimit = {rowSteps, rowSteps, rowSteps, rowSteps};
                        for (int X0 = 0; X0 < pad; X0 += kGroup) {
                            I4 steps[kNV];
                            int nAny = 0;
                            for (int k = 0; k < kNV; ++k) {
                                I4 cs;
                                std::memcpy(&cs, colSteps + X0 + 4 * k, sizeof cs);
                                steps[k] = cs < rowLimit ? cs : rowLimit;
                                for (int l = 0; l < 4; ++l) nAny = std::max(nAny, steps[k][l]);
                            }
                            castGroupGlossy(st.heightSteps.data() + base, gs.steps.data() + base,
                                            gs.fields.data() + base * kGlossyFields, steps, nAny, Y, X0, h0s, mgs, gxs, gys,
                                            cosPhi, sinPhi, moments, basis, list, nlp, pad);
                        }
                        // U_c += G_j u_(c, j) over the sparse pattern (Eq. 21), all 16 rows
                        const float* vals = op.values.data() + static_cast<std::size_t>(j) * P;
                        for (int e = 0; e < P; ++e) {
                            const int r = op.patternRow[static_cast<std::size_t>(e)];
                            const float gval = vals[e];
                            const int l = op.patternNlp[static_cast<std::size_t>(e)];
                            for (int c = 0; c < 3; ++c) {
                                float* __restrict dst = uRows[c][r];
                                const float* __restrict w = nlp + static_cast<std::size_t>(c * 4 + l) * pad;
                                for (int X = 0; X < nxr; ++X) dst[X] += gval * w[X];
                            }
                        }
                    }
                }
            }
        });
        st.timings.scan += msSince(t);

        // ---- shading of U at full-resolution normals: L_b; its incident SH feeds bounce b + 1
        t = Clock::now();
        ShadeMaps& out = st.bounceShade[static_cast<std::size_t>(b & 1)];
        shadeTexels(gradX, gradY, s, envVisibility, st.lights.data(), 3, surface, shading, out, false);
        accumulateBounce(out.rgb, b, st);
        prev = &out;
        st.timings.shading += msSince(t);
    }
    sumDirectAndIndirect(directShade.rgb, st);
    st.timings.total = msSince(t0);
}

}  // namespace terrain::gi
