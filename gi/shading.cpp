#include "gi/shading.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <type_traits>
#include <utility>

#include "core/error.h"
#include "core/parallel.h"
#include "core/simd.h"

namespace terrain::gi {

LambertFactors lambertFactors() {
    double lamZh[3];
    for (int l = 0; l < 3; ++l) lamZh[l] = std::sqrt(4.0 * kPi / (2.0 * l + 1.0)) * lambertZonal()[l] / kPi;
    const float lam0 = static_cast<float>(lamZh[0]), lam1 = static_cast<float>(lamZh[1]),
                lam2 = static_cast<float>(lamZh[2]);
    return {lam0 * 0.28209479177387814f, lam1 * 0.48860251190291992f, lam2 * 1.0925484305920792f,
            lam2 * 0.31539156525252005f, lam2 * 0.54627421529603959f};
}

void phongLobeFactors(double exponent, float ph[kShOrder]) {
    double zh[kShOrder];
    phongZonal(exponent, zh);
    for (int l = 0; l < kShOrder; ++l) ph[l] = static_cast<float>(std::sqrt(4.0 * kPi / (2.0 * l + 1.0)) * zh[l]);
}

void setPhongExponentMap(AlbedoMap& map, const Grid& exponent) {
    for (std::size_t i = 0; i < exponent.v.size(); ++i)
        if (!(exponent.v[i] >= kMinPhongExponent && exponent.v[i] <= kMaxPhongExponent))
            throw InputError("Phong exponent map: value " + std::to_string(exponent.v[i]) + " at index " +
                             std::to_string(i) + " is not in [" + std::to_string(kMinPhongExponent) + ", " +
                             std::to_string(kMaxPhongExponent) + "]");
    map.phongExponent = exponent;
    for (Grid& g : map.phongLobe) g.resize(exponent.nx, exponent.ny);
    for (std::size_t i = 0; i < exponent.v.size(); ++i) {
        float ph[kShOrder];
        phongLobeFactors(exponent.v[i], ph);
        for (int l = 1; l < kShOrder; ++l) map.phongLobe[static_cast<std::size_t>(l - 1)].v[i] = ph[l];
    }
}

namespace {

// Kernels over the lane type V: F4 (SSE2) or F8 (AVX2, chosen at run time),
// core/simd.h; lane-wise IEEE operations, so each texel gets exactly the
// scalar result either way.
using namespace simd;

constexpr int kMaxShadingLights = 8;  // lights per incident pass (more are folded in several passes)

// ---- algorithm: horizontal SH interpolation (Fig. 7), L texels x .. x+L-1 ----
// Lane l of the result is lane l / S + K of a: with K = 0 the sample left of
// texel S X + l, with K = 1 the one right of it. The indices are constants
// (a shuffle, which GCC and Clang both spell __builtin_shufflevector).
template <int S, int K, class V, int... L>
[[gnu::always_inline]] inline V spreadLanes(V a, std::integer_sequence<int, L...>) {
    return __builtin_shufflevector(a, a, (L / S + K)...);
}

// Texel x = s X + k reads v[X] + (k / s) (v[X + 1] - v[X]), as the scalar code.
template <class V, int S>
[[gnu::always_inline]] inline V expandV(const float* v, int x) {
    constexpr int L = LaneTraits<V>::n;
    if constexpr (S == 1) {
        return load<V>(v + x);
    } else {
        // lane l reads X0 + l / S and X0 + l / S + 1 with the weight (l % S) / S
        V f{};
        for (int l = 0; l < L; ++l) f[l] = static_cast<float>(l % S) / static_cast<float>(S);
        const V a = load<V>(v + x / S);
        const V vlo = spreadLanes<S, 0>(a, std::make_integer_sequence<int, L>{});
        const V vhi = spreadLanes<S, 1>(a, std::make_integer_sequence<int, L>{});
        return vlo + f * (vhi - vlo);
    }
}

// ---- algorithm: Lambert shading of one full-resolution row -------------------
// vert: the row's SH planes interpolated vertically at the receivers (planes
// 0 .. 3 nCoef - 1: incident radiance per channel; then 9 planes of V_env).
// Each texel: lam(N) . I_c for the channels, lam(N) . V_env for the ambient
// map, with lam the clamped-cosine zonal vector turned to the texel's normal.
template <class V, int S>
[[gnu::always_inline]] inline void lambertRowS(const float* vert, int nxrS, int nxr, int nCoef, const float* gxr,
                                               const float* gyr, const int* colIndex, const float* colFrac,
                                               const LambertFactors& lf, float diffuseWeight, const AlbedoMap* albedo,
                                               bool ambient, int y, int nx, ColumnSpan run, ShadeMaps& out) {
    // out.ambient may hold another method's map (gi/ambient_horizon.h) of another size: written only when asked
    float* amb = ambient ? out.ambient.data() + static_cast<std::size_t>(y) * nx : nullptr;
    float* rgb[3];
    const float* alb[3];
    for (int ch = 0; ch < 3; ++ch) {
        rgb[ch] = out.rgb[static_cast<std::size_t>(ch)].data() + static_cast<std::size_t>(y) * nx;
        const Grid* a = albedo && !albedo->channel[static_cast<std::size_t>(ch)].empty()
                            ? &albedo->channel[static_cast<std::size_t>(ch)]
                            : nullptr;
        alb[ch] = a ? a->data() + static_cast<std::size_t>(y) * nx : nullptr;
    }
    // texels [0, xVec) take the vector path: all of x .. x+L-1 below s (nxr
    // - 1); of the run, the whole lane groups there, from a multiple of L
    using I = typename LaneTraits<V>::I;
    constexpr int L = LaneTraits<V>::n;
    const int interior = S * std::max(nxr - 1, 0);
    const int xVec = nxr >= 3 ? std::max(0, interior - (S == 2 ? 2 : 0)) / L * L : 0;
    const int vecBegin = std::min((run.x0 + L - 1) / L * L, xVec);
    const int vecEnd = std::max(vecBegin, std::min(run.x1 / L * L, xVec));
    const V fmax = splat<V>(3.40282347e38f);
    for (int x = vecBegin; x < vecEnd; x += L) {
        const V gx = load<V>(gxr + x), gy = load<V>(gyr + x);
        const V inv = splat<V>(1.0f) / sqrtv(splat<V>(1.0f) + gx * gx + gy * gy);
        const V X = -gx * inv, Yn = -gy * inv, Z = inv;
        V lam[9];
        lambertAtNormal(lf, X, Yn, Z, lam);
        // the four dot products interleaved: independent addition chains
        V acc = splat<V>(0.0f), oc[3] = {splat<V>(0.0f), splat<V>(0.0f), splat<V>(0.0f)};
        for (int i = 0; i < 9; ++i) {
            if (amb) acc += lam[i] * expandV<V, S>(vert + static_cast<std::size_t>(3 * nCoef + i) * nxrS, x);
            for (int ch = 0; ch < 3; ++ch)
                oc[ch] += lam[i] * expandV<V, S>(vert + static_cast<std::size_t>(ch * nCoef + i) * nxrS, x);
        }
        if (amb) store(amb + x, acc);
        for (int ch = 0; ch < 3; ++ch) {
            V o = oc[ch];
            o *= diffuseWeight * (alb[ch] ? load<V>(alb[ch] + x) : splat<V>(1.0f));
            const I finite = (o < fmax) & (o > -fmax);  // false for NaN and +-Inf
            store(rgb[ch] + x, finite ? o : splat<V>(0.0f));
        }
    }
    // the run's other texels, scalar (the same operations): those before the
    // vector groups, then those after them
    const int scalarFrom[2] = {run.x0, std::max(vecEnd, run.x0)};
    const int scalarTo[2] = {std::min(vecBegin, run.x1), run.x1};
    for (int part = 0; part < 2; ++part)
        for (int x = scalarFrom[part]; x < scalarTo[part]; ++x) {
            const int X0 = colIndex[x];
            const int X1 = std::min(X0 + 1, nxr - 1);
            const float f = colFrac[x];
            const float gx = gxr[x], gy = gyr[x];
            const float inv = 1.0f / std::sqrt(1.0f + gx * gx + gy * gy);
            const float X = -gx * inv, Yn = -gy * inv, Z = inv;
            float lam[9];
            lambertAtNormal(lf, X, Yn, Z, lam);
            auto u = [&](int plane) {
                const float* v = vert + static_cast<std::size_t>(plane) * nxrS;
                return S == 1 ? v[x] : v[X0] + f * (v[X1] - v[X0]);
            };
            if (amb) {
                float acc = 0.0f;
                for (int i = 0; i < 9; ++i) acc += lam[i] * u(3 * nCoef + i);
                amb[x] = acc;
            }
            for (int ch = 0; ch < 3; ++ch) {
                float o = 0.0f;
                for (int i = 0; i < 9; ++i) o += lam[i] * u(ch * nCoef + i);
                o *= diffuseWeight * (alb[ch] ? alb[ch][x] : 1.0f);
                rgb[ch][x] = std::isfinite(o) ? o : 0.0f;
            }
        }
}

// Where the receivers' incident SH planes live: plane c of receiver row Y at
// base + c planeStride + (Y - row0) nxr. The whole field (ShadeMaps::incident,
// row0 = 0) or a worker's window of the rows one block of texel rows reads.
struct IncidentRows {
    float* base;
    std::size_t planeStride;
    int row0;
};

// One full-resolution Lambert row: the SH planes interpolated vertically at
// the receivers (Fig. 7), then lambertRowS.
struct LambertRowJob {
    IncidentRows incident;       // 3 nCoef planes at the receivers
    const VisibilityField* env;  // V_env (ambient); null: no ambient map
    std::size_t planeR;          // of V_env
    int nxr, nyr, nxrS, s, nCoef, nx;
    const int* colIndex;
    const float* colFrac;
    LambertFactors lf;
    float diffuseWeight;
    const AlbedoMap* albedo;
    ShadeMaps* out;
};

// Plane p's receiver rows ry.i0 and ry.i1: incident radiance for p < 3 nCoef, V_env after.
struct PlaneRows {
    const float *a, *b;
};
inline PlaneRows planeRows(const LambertRowJob& j, int p, const ReceiverLerp& ry) {
    const int nIncident = 3 * j.nCoef;
    if (p < nIncident) {
        const float* plane = j.incident.base + static_cast<std::size_t>(p) * j.incident.planeStride;
        return {plane + static_cast<std::size_t>(ry.i0 - j.incident.row0) * j.nxr,
                plane + static_cast<std::size_t>(ry.i1 - j.incident.row0) * j.nxr};
    }
    const float* plane = j.env->plane(p - nIncident);
    return {plane + static_cast<std::size_t>(ry.i0) * j.nxr, plane + static_cast<std::size_t>(ry.i1) * j.nxr};
}

using Runs = std::span<const ColumnSpan>;

template <class V>
[[gnu::always_inline]] inline void lambertShadeRowImpl(const LambertRowJob& j, float* vert, const float* gxr,
                                                       const float* gyr, int y, Runs runs) {
    constexpr int L = LaneTraits<V>::n;
    const ReceiverLerp ry = receiverLerp(y, j.s, j.nyr);
    const int nPlanes = 3 * j.nCoef + (j.env ? 9 : 0);
    // the receivers the runs' texels read: [X0, X1)
    const ColumnSpan read = receiversReadBy(j.colIndex[runs.front().x0], j.colIndex[runs.back().x1 - 1], j.nxr);
    const int X0 = read.x0, X1 = read.x1;
    const int nv = X0 + (X1 - X0) / L * L;
    const V fy = splat<V>(ry.f);
    for (int p = 0; p < nPlanes; ++p) {
        const PlaneRows r = planeRows(j, p, ry);
        const float* __restrict ra = r.a;
        const float* __restrict rb = r.b;
        float* __restrict v = vert + static_cast<std::size_t>(p) * j.nxrS;
        for (int X = X0; X < nv; X += L) {
            const V a = load<V>(ra + X);
            store(v + X, a + fy * (load<V>(rb + X) - a));
        }
        for (int X = nv; X < X1; ++X) v[X] = ra[X] + ry.f * (rb[X] - ra[X]);
        for (int X = j.nxr; X < j.nxrS; ++X) v[X] = 0.0f;
    }
    auto row = [&](auto sTag) {
        constexpr int S = decltype(sTag)::value;
        for (const ColumnSpan& run : runs)
            lambertRowS<V, S>(vert, j.nxrS, j.nxr, j.nCoef, gxr, gyr, j.colIndex, j.colFrac, j.lf, j.diffuseWeight,
                              j.albedo, j.env != nullptr, y, j.nx, run, *j.out);
    };
    if (j.s == 1)
        row(std::integral_constant<int, 1>{});
    else if (j.s == 2)
        row(std::integral_constant<int, 2>{});
    else
        row(std::integral_constant<int, 4>{});
}
void lambertShadeRowSse(const LambertRowJob& j, float* vert, const float* gxr, const float* gyr, int y, Runs runs) {
    lambertShadeRowImpl<F4>(j, vert, gxr, gyr, y, runs);
}
[[gnu::target("avx2"), gnu::flatten]] void lambertShadeRowAvx2(const LambertRowJob& j, float* vert, const float* gxr,
                                                               const float* gyr, int y, Runs runs) {
    lambertShadeRowImpl<F8>(j, vert, gxr, gyr, y, runs);
}

// ---- algorithm, receivers: incident radiance I_c = sum_L T_{L,c} V_L, row Y ----
// 16 receivers at a time from `cols.x0` (a multiple of 16) to `cols.x1`: the
// lights' V vectors are read once; the output coefficients go
// kIncidentBlock at a time, their sums in registers, each input V_L,k read
// once per block and multiplied by the block's entries (buildIncidentTerms).
// Each output sums its entries in the order (light, k), lane by lane; an
// entry that is 0 for this output but not for another of its block adds
// 0 x V (V finite: +-0), which leaves a sum started at +0 as it was, so every
// output is the sum of its non-zero entries alone.
template <class V>
[[gnu::always_inline]] inline void incidentRowImpl(const ShadingLight* lights, int nl, int nCoef, int nxr,
                                                   ColumnSpan cols, const ShadeMaps& terms, IncidentRows to, int Y) {
    constexpr int L = LaneTraits<V>::n, NQ = 16 / L, B = ShadeMaps::kIncidentBlock;
    const std::size_t r0 = static_cast<std::size_t>(Y) * nxr;
    const std::size_t w0 = static_cast<std::size_t>(Y - to.row0) * nxr;
    const int outputs = 3 * nCoef, blocks = (outputs + B - 1) / B;
    for (int X = cols.x0; X < cols.x1; X += 16) {
        const int n = std::min(16, nxr - X);
        for (int g0 = 0; g0 < nl; g0 += kMaxShadingLights) {
            const int g1 = std::min(nl, g0 + kMaxShadingLights);
            V v[kMaxShadingLights * kShCount][NQ];
            for (int Li = g0; Li < g1; ++Li)
                for (int k = 0; k < kShCount; ++k) {
                    const float* p = lights[Li].visibility->plane(k) + r0 + X;
                    for (int q = 0; q < NQ; ++q) {
                        V a = splat<V>(0.0f);
                        if (L * q + L <= n)
                            a = load<V>(p + L * q);
                        else
                            for (int e = L * q; e < n; ++e) a[e - L * q] = p[e];
                        v[(Li - g0) * kShCount + k][q] = a;
                    }
                }
            for (int b = 0; b < blocks; ++b) {
                const int c0 = b * B, nOut = std::min(B, outputs - c0);
                float* o[B];
                for (int r = 0; r < nOut; ++r)
                    o[r] = to.base + static_cast<std::size_t>(c0 + r) * to.planeStride + w0 + X;
                V acc[B][NQ];
                for (int r = 0; r < B; ++r)
                    for (int q = 0; q < NQ; ++q) acc[r][q] = splat<V>(0.0f);
                if (g0 > 0)
                    for (int r = 0; r < nOut; ++r)
                        for (int e = 0; e < n; ++e) acc[r][e / L][e % L] = o[r][e];
                for (int e = terms.incidentTermStart[static_cast<std::size_t>(b)];
                     e < terms.incidentTermStart[static_cast<std::size_t>(b + 1)]; ++e) {
                    const ShadeMaps::BlockTerm& term = terms.incidentTerms[static_cast<std::size_t>(e)];
                    const int slot = term.index - g0 * kShCount;
                    if (slot < 0 || slot >= kMaxShadingLights * kShCount) continue;
                    V t[B];
                    for (int r = 0; r < B; ++r) t[r] = splat<V>(term.value[r]);
                    for (int q = 0; q < NQ; ++q)
                        for (int r = 0; r < B; ++r) acc[r][q] += t[r] * v[slot][q];
                }
                for (int r = 0; r < nOut; ++r)
                    for (int q = 0; q < NQ; ++q) {
                        if (L * q + L <= n)
                            store(o[r] + L * q, acc[r][q]);
                        else
                            for (int e = L * q; e < n; ++e) o[r][e] = acc[r][q][e - L * q];
                    }
            }
        }
    }
}
void incidentRowSse(const ShadingLight* lights, int nl, int nCoef, int nxr, ColumnSpan cols, const ShadeMaps& terms,
                    IncidentRows to, int Y) {
    incidentRowImpl<F4>(lights, nl, nCoef, nxr, cols, terms, to, Y);
}
[[gnu::target("avx2"), gnu::flatten]] void incidentRowAvx2(const ShadingLight* lights, int nl, int nCoef, int nxr,
                                                           ColumnSpan cols, const ShadeMaps& terms, IncidentRows to,
                                                           int Y) {
    incidentRowImpl<F8>(lights, nl, nCoef, nxr, cols, terms, to, Y);
}

// ---- setup ----------------------------------------------------------------------
void sizeShadeMaps(int nx, int ny, std::size_t incidentSize, bool ambient, std::size_t rowScratchSize, ShadeMaps& out) {
    out.nx = nx;
    out.ny = ny;
    for (Grid& g : out.rgb) g.ensureSize(nx, ny);
    if (ambient) out.ambient.ensureSize(nx, ny);
    out.incident.resize(incidentSize);
    out.rowScratch.resize(rowScratchSize);
    out.colIndex.resize(static_cast<std::size_t>(nx));
    out.colFrac.resize(static_cast<std::size_t>(nx));
}

// The lights' lighting matrices in float, and for each block of output
// coefficients of I_c = sum_L T_{L,c} V_L the inputs that some output of the
// block reads (a non-zero entry), with the block's entries (incidentRowImpl).
void buildIncidentTerms(const ShadingLight* lights, int nl, int nCoef, ShadeMaps& out) {
    out.lightMatrices.resize(static_cast<std::size_t>(nl) * 3 * kShCount * kShCount);
    for (int L = 0; L < nl; ++L)
        for (int ch = 0; ch < 3; ++ch)
            for (int e = 0; e < kShCount * kShCount; ++e)
                out.lightMatrices[(static_cast<std::size_t>(L) * 3 + ch) * kShCount * kShCount + e] =
                    static_cast<float>(lights[L].product[static_cast<std::size_t>(ch)][static_cast<std::size_t>(e)]);

    // the matrix entry of output coefficient c (channel c / nCoef, row c % nCoef) for input (L, k)
    const auto entry = [&](int c, int L, int k) {
        const int ch = c / nCoef, i = c % nCoef;
        return out.lightMatrices[((static_cast<std::size_t>(L) * 3 + ch) * kShCount + i) * kShCount + k];
    };
    constexpr int B = ShadeMaps::kIncidentBlock;
    const int outputs = 3 * nCoef, blocks = (outputs + B - 1) / B;
    out.incidentTerms.clear();
    out.incidentTermStart.assign(static_cast<std::size_t>(blocks + 1), 0);
    for (int b = 0; b < blocks; ++b) {
        for (int L = 0; L < nl; ++L)
            for (int k = 0; k < kShCount; ++k) {
                ShadeMaps::BlockTerm term{};
                term.index = L * kShCount + k;
                bool any = false;
                for (int r = 0; r < B && b * B + r < outputs; ++r) {
                    term.value[r] = entry(b * B + r, L, k);
                    any = any || term.value[r] != 0.0f;
                }
                if (any) out.incidentTerms.push_back(term);
            }
        out.incidentTermStart[static_cast<std::size_t>(b + 1)] = static_cast<int>(out.incidentTerms.size());
    }
}

// ---- Phong rows (Brdf::Phong, LambertPlusPhong) --------------------------------
// One full-resolution row: the SH planes interpolated to the row
// (interpolatePlanesToRow), the Lambert part at each texel's normal and the
// Phong lobe about its reflection vector (phongTexels).
struct PhongRowJob {
    LambertRowJob base;         // planes, sizes, tables, Lambert factors, diffuse weight, albedo, out
    float phUniform[kShOrder];  // the uniform lobe factors (phongLobeFactors of the settings)
    float specWeight;
    float view[3];  // unit vector towards the viewer
    bool clamp;     // GlossyPositivity::Clamp: shades below 0 become 0
};

// ---- algorithm: SH vectors interpolated to row y (Fig. 7) ----
// vert: each plane's row at the receivers (planes nxrS apart); up: the same
// at every texel of the row (planes nx apart).
void interpolatePlanesToRow(const LambertRowJob& j, int y, float* vert, float* up) {
    const int nxr = j.nxr, nxrS = j.nxrS, s = j.s, nCoef = j.nCoef, nx = j.nx;
    const int nPlanes = 3 * nCoef + (j.env ? 9 : 0);
    const ReceiverLerp ry = receiverLerp(y, s, j.nyr);
    const float fy = ry.f;
    for (int p = 0; p < nPlanes; ++p) {
        const PlaneRows r = planeRows(j, p, ry);
        const float* __restrict ra = r.a;
        const float* __restrict rb = r.b;
        float* __restrict v = vert + static_cast<std::size_t>(p) * nxrS;
        for (int X = 0; X < nxr; ++X) v[X] = ra[X] + fy * (rb[X] - ra[X]);
        for (int X = nxr; X < nxrS; ++X) v[X] = 0.0f;
        float* __restrict u = up + static_cast<std::size_t>(p) * nx;
        if (s == 1) {
            std::copy(v, v + nx, u);
        } else {
            // texels s X + k share the weights k / s
            for (int k = 0; k < s; ++k) {
                const float fx = static_cast<float>(k) / static_cast<float>(s);
                for (int X = 0; X + 1 < nxr && s * X + k < nx; ++X) u[s * X + k] = v[X] + fx * (v[X + 1] - v[X]);
            }
            for (int x = s * std::max(nxr - 1, 0); x < nx; ++x) {
                const int X0 = j.colIndex[static_cast<std::size_t>(x)];
                const int X1 = std::min(X0 + 1, nxr - 1);
                const float fx = j.colFrac[static_cast<std::size_t>(x)];
                u[x] = v[X0] + fx * (v[X1] - v[X0]);
            }
        }
    }
}

// ---- algorithm: Lambert and Phong at each texel of a run ----------------------
// Texels [x, x + lanes of V) of row y: the clamped-cosine zonal vector turned
// to the texel's normal (ambient and the diffuse part), then per channel the
// Phong lobe about its reflection vector (Section 7), dotted with the row's
// SH planes `up`; a shade that is not finite is written as 0, and below 0 as
// 0 with the clamp. V: float, F4 or F8, the same operations in every lane.
template <class V>
[[gnu::always_inline]] inline void phongTexels(const PhongRowJob& j, const float* gxr, const float* gyr,
                                               const float* up, int y, int x) {
    using simd::load;
    using simd::splat;
    const LambertRowJob& b = j.base;
    const int nx = b.nx, nCoef = b.nCoef;
    const std::size_t row = static_cast<std::size_t>(y) * nx;
    const V zero = splat<V>(0.0f), one = splat<V>(1.0f);
    const V gx = load<V>(gxr + x), gy = load<V>(gyr + x);
    const V inv = one / simd::sqrtv(one + gx * gx + gy * gy);
    const V nxv = -gx * inv, nyv = -gy * inv, nzv = inv;
    V lam[9];
    lambertAtNormal(b.lf, nxv, nyv, nzv, lam);
    if (b.env) {
        V amb = zero;
        for (int i = 0; i < 9; ++i) amb += lam[i] * load<V>(up + static_cast<std::size_t>(3 * nCoef + i) * nx + x);
        simd::store(b.out->ambient.data() + row + x, amb);
    }
    const float vx = j.view[0], vy = j.view[1], vz = j.view[2];
    const V nv = nxv * vx + nyv * vy + nzv * vz;
    V ph[kShOrder];  // the texel's exponent (AlbedoMap::phongExponent) or the uniform one
    const bool lobeMap = b.albedo && !b.albedo->phongLobe[0].empty();
    ph[0] = splat<V>(j.phUniform[0]);
    for (int l = 1; l < kShOrder; ++l)
        ph[l] = lobeMap ? load<V>(b.albedo->phongLobe[static_cast<std::size_t>(l - 1)].v.data() + row + x)
                        : splat<V>(j.phUniform[l]);
    V yb[kShCount];
    shBasisLanes<V>(2.0f * nv * nxv - vx, 2.0f * nv * nyv - vy, 2.0f * nv * nzv - vz, yb);
    const V floor = splat<V>(j.clamp ? 0.0f : -std::numeric_limits<float>::infinity());
    for (int ch = 0; ch < 3; ++ch) {
        V o = zero;
        for (int i = 0; i < 9; ++i) o += lam[i] * load<V>(up + static_cast<std::size_t>(ch * nCoef + i) * nx + x);
        const Grid* a = b.albedo && !b.albedo->channel[static_cast<std::size_t>(ch)].empty()
                            ? &b.albedo->channel[static_cast<std::size_t>(ch)]
                            : nullptr;
        o *= b.diffuseWeight * (a ? load<V>(a->v.data() + row + x) : one);
        V sp = zero;
        for (int i = 0; i < kShCount; ++i)
            sp += ph[shBand(i)] * yb[i] * load<V>(up + static_cast<std::size_t>(ch * nCoef + i) * nx + x);
        o += j.specWeight * sp;
        o = (o - o) == zero ? (o < floor ? floor : o) : zero;
        simd::store(b.out->rgb[static_cast<std::size_t>(ch)].data() + row + x, o);
    }
}

// The texels of a run: whole lane groups, then the rest one by one.
template <class V>
[[gnu::always_inline]] inline void phongShadeRunWith(const PhongRowJob& j, const float* gxr, const float* gyr,
                                                     const float* up, int y, ColumnSpan run) {
    constexpr int L = simd::kLaneCount<V>;
    int x = run.x0;
    for (; x + L <= run.x1; x += L) phongTexels<V>(j, gxr, gyr, up, y, x);
    for (; x < run.x1; ++x) phongTexels<float>(j, gxr, gyr, up, y, x);
}
void phongShadeRunSse(const PhongRowJob& j, const float* gxr, const float* gyr, const float* up, int y,
                      ColumnSpan run) {
    phongShadeRunWith<simd::F4>(j, gxr, gyr, up, y, run);
}
[[gnu::target("avx2"), gnu::flatten]] void phongShadeRunAvx2(const PhongRowJob& j, const float* gxr, const float* gyr,
                                                             const float* up, int y, ColumnSpan run) {
    phongShadeRunWith<simd::F8>(j, gxr, gyr, up, y, run);
}

}  // namespace

AlbedoMap uniformAlbedo(int nx, int ny, float albedo) {
    AlbedoMap m;
    for (Grid& c : m.channel) c.resize(nx, ny, albedo);
    return m;
}

namespace {

// Texel rows [begin, end) of fixed block b of n (the shading's schedule).
struct RowBlock {
    int begin, end;
};
RowBlock rowBlock(int ny, int n, int b) {
    return {static_cast<int>(static_cast<long long>(ny) * b / n),
            static_cast<int>(static_cast<long long>(ny) * (b + 1) / n)};
}

// The receiver rows [first, last] texel rows [y0, y1) read (Fig. 7; receiverLerp is monotone in y).
struct ReceiverSpan {
    int first, last;
};
ReceiverSpan receiverSpanOf(int y0, int y1, int s, int nyr) {
    return {receiverLerp(y0, s, nyr).i0, receiverLerp(y1 - 1, s, nyr).i1};
}

// The span of the rows with runs inside a block (all of it without runs); empty: begin == end.
RowBlock rowsWithRuns(RowBlock b, const TexelRuns* runs) {
    if (!runs) return b;
    while (b.begin < b.end && !runs->hasRow(b.begin)) ++b.begin;
    while (b.end > b.begin && !runs->hasRow(b.end - 1)) --b.end;
    return b;
}

// Every receiver row of the incident field some shaded texel row reads (all
// of them without `runs`), into ShadeMaps::incident.
void incidentField(const ShadingLight* lights, int nl, int nCoef, int s, int ny, int nxr, int nyr,
                   const TexelRuns* runs, ShadeMaps& out) {
    const std::size_t planeR = static_cast<std::size_t>(nxr) * nyr;
    std::vector<std::uint8_t>& receiverRows = out.receiverRows;
    if (runs) {
        receiverRows.assign(static_cast<std::size_t>(nyr), 0);
        for (int y = 0; y < ny; ++y)
            if (runs->hasRow(y)) {
                const ReceiverLerp r = receiverLerp(y, s, nyr);
                receiverRows[static_cast<std::size_t>(r.i0)] = receiverRows[static_cast<std::size_t>(r.i1)] = 1;
            }
    }
    const auto row = simd::wideEnabled() ? incidentRowAvx2 : incidentRowSse;
    const IncidentRows to{out.incident.data(), planeR, 0};
    parallelForRows(nyr, nxr * 16, [&](int y0, int y1) {
        for (int Y = y0; Y < y1; ++Y)
            if (!runs || receiverRows[static_cast<std::size_t>(Y)] != 0)
                row(lights, nl, nCoef, nxr, ColumnSpan{0, nxr}, out, to, Y);
    });
}

// The most receiver rows one block's texel rows read: a worker's window.
int windowRows(int ny, int nBlocks, int s, int nyr) {
    int most = 0;
    for (int b = 0; b < nBlocks; ++b) {
        const RowBlock rb = rowBlock(ny, nBlocks, b);
        if (rb.begin == rb.end) continue;
        const ReceiverSpan r = receiverSpanOf(rb.begin, rb.end, s, nyr);
        most = std::max(most, r.last - r.first + 1);
    }
    return most;
}

// Sizes the maps and each worker slot's scratch. The receivers' incident SH
// is a whole field when out.keepIncident, else a window per slot of the most
// receiver rows a block reads; returns that window's floats (0 for a field).
std::size_t sizeBuffers(int nx, int ny, int nxr, int nyr, int s, int nCoef, int nPlanes, int nxrS, int nBlocks,
                        bool ambient, ShadeMaps& out) {
    const auto slots = static_cast<std::size_t>(workerSlots());
    const bool keep = out.keepIncident;
    const std::size_t field = static_cast<std::size_t>(nxr) * nyr * 3 * nCoef;
    const std::size_t window = keep ? 0 : static_cast<std::size_t>(3 * nCoef) * windowRows(ny, nBlocks, s, nyr) * nxr;
    sizeShadeMaps(nx, ny, keep ? field : 0, ambient, slots * nPlanes * (nxrS + nx), out);
    if (!keep) std::vector<float>().swap(out.incident);
    out.incidentWindow.resize(slots * window);
    if (keep) std::vector<float>().swap(out.incidentWindow);
    return window;
}

// What every block of one shading call shares.
struct BlockSchedule {
    ConstGridView gradX, gradY;
    const ShadingLight* lights;
    int lightCount;
    const TexelRuns* runs;  // null: every texel
    int nBlocks, nPlanes;
    std::size_t window;  // floats of a slot's incident window (0: the field is kept)
    bool phong;
};

// The receiver columns the runs of rows [rows.begin, rows.end) read, from a
// multiple of 16 (incidentRowImpl's groups); every column without runs.
ColumnSpan receiverColumnsOf(const LambertRowJob& j, const TexelRuns* runs, RowBlock rows) {
    const ColumnSpan c = receiverColumnsRead(runs, rows.begin, rows.end, j.nxr, [&](int x) { return j.colIndex[x]; });
    return {c.x0 / 16 * 16, std::max(c.x0 / 16 * 16, c.x1)};
}

// One block of texel rows on a worker's slot of the scratch: the receiver
// rows it reads into the slot's incident window (unless the field is kept),
// then the runs of each of its rows.
void shadeBlock(const BlockSchedule& b, PhongRowJob job, int block, std::size_t slot) {
    LambertRowJob& base = job.base;
    ShadeMaps& out = *base.out;
    const int nx = base.nx, nxr = base.nxr, nxrS = base.nxrS;
    const RowBlock shaded = rowsWithRuns(rowBlock(b.gradX.ny, b.nBlocks, block), b.runs);
    if (shaded.begin == shaded.end) return;
    const bool wide = simd::wideEnabled();
    if (b.window > 0) {
        const ReceiverSpan r = receiverSpanOf(shaded.begin, shaded.end, base.s, base.nyr);
        base.incident = {out.incidentWindow.data() + slot * b.window,
                         static_cast<std::size_t>(r.last - r.first + 1) * nxr, r.first};
        const ColumnSpan cols = receiverColumnsOf(base, b.runs, shaded);
        for (int Y = r.first; Y <= r.last; ++Y)
            (wide ? incidentRowAvx2 : incidentRowSse)(b.lights, b.lightCount, base.nCoef, nxr, cols, out, base.incident,
                                                      Y);
    }
    float* vert = out.rowScratch.data() + slot * b.nPlanes * (nxrS + nx);
    float* up = vert + static_cast<std::size_t>(b.nPlanes) * nxrS;
    const ColumnSpan wholeRow{0, nx};
    for (int y = shaded.begin; y < shaded.end; ++y) {
        const Runs runs = runsOfRow(b.runs, y, wholeRow);
        if (runs.empty()) continue;  // keeps its last values
        if (!b.phong) {
            (wide ? lambertShadeRowAvx2 : lambertShadeRowSse)(base, vert, b.gradX.row(y), b.gradY.row(y), y, runs);
            continue;
        }
        interpolatePlanesToRow(base, y, vert, up);
        for (const ColumnSpan& run : runs)
            (wide ? phongShadeRunAvx2 : phongShadeRunSse)(job, b.gradX.row(y), b.gradY.row(y), up, y, run);
    }
}

// The lights that add something, in their order, into out.activeLights: a
// light that adds nothing (an environment lit wholly from the ambient map,
// whose V may not have been computed) has no incident terms, so leaving it
// out leaves every other light's sums as they were. Each light kept reads all
// the SH planes of its visibility (a horizons-only field has none); the
// ambient map reads V_env's bands 0..2.
void keepActiveLights(const VisibilityField& env, const ShadingLight* lights, int lightCount, bool ambient,
                      ShadeMaps& out) {
    if (ambient && env.planes < 9)
        throw InputError("shading: the ambient map needs the environment's SH visibility (bands 0..2)");
    out.activeLights.clear();
    for (int L = 0; L < lightCount; ++L) {
        if (!lightContributes(lights[L])) continue;
        if (!lights[L].visibility || lights[L].visibility->planes < kShCount)
            throw InputError("shading: a light needs the SH visibility of its receivers (all 16 planes)");
        out.activeLights.push_back(lights[L]);
    }
}

// No light adds anything and nothing else is asked for: the shade is 0 at
// the texels of the runs (what the SH shading would give, without its work).
void shadeNothing(int nx, int ny, const TexelRuns* runs, ShadeMaps& out) {
    out.nx = nx;
    out.ny = ny;
    const ColumnSpan wholeRow{0, nx};
    for (Grid& g : out.rgb) {
        g.ensureSize(nx, ny);
        for (int y = 0; y < ny; ++y)
            for (const ColumnSpan& run : runsOfRow(runs, y, wholeRow))
                std::fill(g.data() + static_cast<std::size_t>(y) * nx + run.x0,
                          g.data() + static_cast<std::size_t>(y) * nx + run.x1, 0.0f);
    }
}

}  // namespace

// The incident SH reads exactly the entries that are not 0 in float (buildIncidentTerms).
bool lightContributes(const ShadingLight& light) {
    for (const ShMatrix& m : light.product)
        for (double e : m)
            if (static_cast<float>(e) != 0.0f) return true;
    return false;
}

void shadeTexels(ConstGridView gradX, ConstGridView gradY, int s, const VisibilityField& env,
                 const ShadingLight* lights, int lightCount, const AlbedoMap* albedo, const ShadingSettings& settings,
                 ShadeMaps& out, bool ambient, const TexelRuns* runs) {
    const int nx = gradX.nx, ny = gradX.ny;
    if (runs && runs->ny != ny) throw InputError("shading: texel runs of another grid");
    keepActiveLights(env, lights, lightCount, ambient, out);
    lights = out.activeLights.data();
    lightCount = static_cast<int>(out.activeLights.size());
    if (!ambient && !out.keepIncident && lightCount == 0) return shadeNothing(nx, ny, runs, out);
    const int nxr = env.nxr, nyr = env.nyr;
    const std::size_t planeR = static_cast<std::size_t>(nxr) * nyr;
    const bool phong = settings.brdf != Brdf::Lambert;
    const int nCoef = phong ? kShCount : 9;
    const int nPlanes = 3 * nCoef + (ambient ? 9 : 0);  // incident radiance + V_env bands 0..2 (ambient)
    // Fixed blocks of at least 16 receiver rows: a block computes the one
    // receiver row it shares with the next again (windowed incident SH).
    const int nBlocks = std::clamp(ny / (16 * s), 1, 64);
    const int nxrS = nxr + 8;  // vertical scratch rows padded for 8-wide reads
    // restricted rows keep the others' incident rows only where the last call kept the field
    const bool fieldKept = out.incident.size() == planeR * 3 * nCoef;
    const std::size_t window = sizeBuffers(nx, ny, nxr, nyr, s, nCoef, nPlanes, nxrS, nBlocks, ambient, out);

    // ---- algorithm, receivers: incident radiance I_c = sum_L T_{L,c} V_L ------
    // (the whole field when a later pass reads it, else per block of texel rows)
    buildIncidentTerms(lights, lightCount, nCoef, out);
    if (out.keepIncident) incidentField(lights, lightCount, nCoef, s, ny, nxr, nyr, fieldKept ? runs : nullptr, out);

    // ---- interpolation tables (receiver X sits at column s X) -----------------
    for (int x = 0; x < nx; ++x) {
        const ReceiverLerp r = receiverLerp(x, s, nxr);
        out.colIndex[static_cast<std::size_t>(x)] = r.i0;
        out.colFrac[static_cast<std::size_t>(x)] = r.f;
    }

    const float diffuseWeight = settings.brdf == Brdf::Phong ? 0.0f : 1.0f;
    const LambertRowJob lambertJob{{out.incident.data(), planeR, 0},
                                   ambient ? &env : nullptr,
                                   planeR,
                                   nxr,
                                   nyr,
                                   nxrS,
                                   s,
                                   nCoef,
                                   nx,
                                   out.colIndex.data(),
                                   out.colFrac.data(),
                                   lambertFactors(),
                                   diffuseWeight,
                                   albedo,
                                   &out};
    PhongRowJob phongJob{lambertJob,
                         {},
                         specularWeightOf(settings),
                         {settings.viewDir[0], settings.viewDir[1], settings.viewDir[2]},
                         settings.positivity == GlossyPositivity::Clamp};
    phongLobeFactors(settings.phongExponent, phongJob.phUniform);

    // ---- schedule: fixed row blocks; a row keeps nothing in the scratch, so
    // each thread's slot of it serves every block it runs ----------------------
    const BlockSchedule schedule{gradX, gradY, lights, lightCount, runs, nBlocks, nPlanes, window, phong};
    // only the blocks with runs are handed out
    blocksWithRuns(
        runs, nBlocks,
        [&](int block) {
            const RowBlock r = rowBlock(gradX.ny, nBlocks, block);
            return RowSpan{r.begin, r.end};
        },
        out.busyBlocks);
    parallelForEach(out.busyBlocks,
                    [&](int block) { shadeBlock(schedule, phongJob, block, static_cast<std::size_t>(workerSlot())); });
}

}  // namespace terrain::gi
