#include "gi/glossy_exit_radiance.h"

#include <algorithm>
#include <cmath>

#include "core/bfloat16.h"
#include "core/parallel.h"
#include "core/simd.h"

namespace terrain::gi {

namespace {

constexpr int kMaxBlocks = 64;

// ---- the reflection Rot_N(pi) in SH, per band -------------------------------
// Band l of h(w) = f(R_N w) is fixed by its values at 2l+1 directions d_j:
// E_l = B_l^-1 h_l(d), B_l[j][m] = Y_lm(d_j), d_0..d_(2l) the first 2l+1 of
// 7 fixed directions. Symmetric sets are singular (a 7-point Fibonacci set
// is, for band 3); these 7 came from a random search (200000 draws)
// minimising the largest Frobenius norm of the three inverses: 4.7, 4.5, 4.8,
// so float rounding of h costs ~1e-6 relative. The inverses are computed once
// in double (Gauss-Jordan, partial pivoting).
struct MirrorTables {
    static constexpr float kDirs[7][3] = {
        {-0.784515631f, -0.552553248f, 0.281460715f}, {-0.971931924f, -0.041938494f, -0.231494056f},
        {0.054143289f, -0.730243560f, -0.681038066f}, {0.772798188f, -0.028211642f, -0.634024498f},
        {0.081702522f, -0.036083780f, -0.996003343f}, {0.005037122f, 0.998826450f, 0.048170015f},
        {0.631249704f, 0.383672776f, -0.674031908f}};
    float dir[7][3];
    float inv[83];  // band l: (2l+1) x (2l+1) block at offset(l)
    static int offset(int l) { return l == 1 ? 0 : (l == 2 ? 9 : 34); }
    MirrorTables() {
        for (int k = 0; k < 7; ++k) {
            const double len = std::sqrt(static_cast<double>(kDirs[k][0]) * kDirs[k][0] +
                                         static_cast<double>(kDirs[k][1]) * kDirs[k][1] +
                                         static_cast<double>(kDirs[k][2]) * kDirs[k][2]);
            for (int a = 0; a < 3; ++a) dir[k][a] = static_cast<float>(kDirs[k][a] / len);
        }
        for (int l = 1; l < kShOrder; ++l) {
            const int n = 2 * l + 1;
            double a[7][14];
            for (int j = 0; j < n; ++j) {
                double y[kShCount];
                shEvaluate(static_cast<double>(dir[j][0]), static_cast<double>(dir[j][1]),
                           static_cast<double>(dir[j][2]), y);
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

// E for the three channels of one texel per lane (V: float, F4 or F8, the
// same operations in every lane); I: 3 x 16 interpolated incident SH.
template <class V>
[[gnu::always_inline]] inline void exitVectors(const MirrorTables& mt, const V (*I)[kShCount], V nx, V ny, V nz,
                                               const V ph[kShOrder], float ws, const V diffuse[3], V (*E)[kShCount]) {
    V yr[7][kShCount];
    for (int j = 0; j < 7; ++j) {
        const float* d = mt.dir[j];
        const V dn = 2.0f * (nx * d[0] + ny * d[1] + nz * d[2]);
        shBasisLanes<V>(dn * nx - d[0], dn * ny - d[1], dn * nz - d[2], yr[j]);
    }
    const float sqrt4pi = 3.5449077018110318f;
    for (int c = 0; c < 3; ++c) {
        // band 0 is invariant under rotation; the diffuse scalar joins it
        E[c][0] = ws * ph[0] * I[c][0] + sqrt4pi * diffuse[c];
        for (int l = 1; l < kShOrder; ++l) {
            const int n = 2 * l + 1, b = l * l;
            V cl[7], h[7];
            for (int m = 0; m < n; ++m) cl[m] = ws * ph[l] * I[c][b + m];
            for (int j = 0; j < n; ++j) {
                V sum = simd::splat<V>(0.0f);
                for (int m = 0; m < n; ++m) sum += cl[m] * yr[j][b + m];
                h[j] = sum;
            }
            const float* inv = mt.inv + MirrorTables::offset(l);
            for (int m = 0; m < n; ++m) {
                V sum = simd::splat<V>(0.0f);
                for (int j = 0; j < n; ++j) sum += inv[m * n + j] * h[j];
                E[c][b + m] = sum;
            }
        }
    }
}

// What one row's texels read: the incident SH interpolated to every texel
// column (48 rows of the worker's scratch) and the row's inputs.
struct ExitRow {
    const float* incident;  // 48 planes of nxPad: I at the texels
    std::size_t nxPad;
    const float *gx, *gy;
    const float* shade[3];
    const float* lobe[kShOrder - 1];  // per-texel lobe factors of bands 1..3 (null: uniform)
    const float* uniformLobe;         // phongLobeFactors of the settings
    float ws, view[3];
    float* planes;          // E plane 0 at the row's first texel (null: none)
    std::size_t plane;      // the planes' stride
    std::uint16_t* texels;  // E of the row's first texel, texel by texel (null: none)
    float* diffuse;         // D of the row's first texel, RGB texel by texel (null: none)
    std::size_t diffuseStride;
};

// E of the texels [x, x + lanes of V) of a row: the normal, the lobe, the
// diffuse part (the shade less the lobe towards the viewer), then E; a
// value that is not finite is written as 0.
template <class V>
[[gnu::always_inline]] inline void exitTexels(const MirrorTables& mt, const ExitRow& r, int x) {
    using simd::load;
    using simd::splat;
    V I[3][kShCount];
    for (int c = 0; c < 3; ++c)
        for (int i = 0; i < kShCount; ++i) I[c][i] = load<V>(r.incident + (c * kShCount + i) * r.nxPad + x);
    const V gx = load<V>(r.gx + x), gy = load<V>(r.gy + x), one = splat<V>(1.0f), zero = splat<V>(0.0f);
    const V inv = one / simd::sqrtv(one + gx * gx + gy * gy);
    const V nx = -gx * inv, ny = -gy * inv, nz = inv;
    V ph[kShOrder];
    ph[0] = splat<V>(r.uniformLobe[0]);
    for (int l = 1; l < kShOrder; ++l) ph[l] = r.lobe[l - 1] ? load<V>(r.lobe[l - 1] + x) : splat<V>(r.uniformLobe[l]);
    // what the shade holds beside the lobe towards the viewer: the diffuse part
    const V nv = nx * r.view[0] + ny * r.view[1] + nz * r.view[2];
    V yv[kShCount];
    shBasisLanes<V>(2.0f * nv * nx - r.view[0], 2.0f * nv * ny - r.view[1], 2.0f * nv * nz - r.view[2], yv);
    V diffuse[3];
    for (int c = 0; c < 3; ++c) {
        V sp = zero;
        for (int i = 0; i < kShCount; ++i) sp += ph[shBand(i)] * yv[i] * I[c][i];
        diffuse[c] = load<V>(r.shade[c] + x) - r.ws * sp;
    }
    constexpr int L = simd::kLaneCount<V>;
    if (r.diffuse) {
        alignas(32) float lanes[3][L];
        for (int c = 0; c < 3; ++c) simd::store(lanes[c], (diffuse[c] - diffuse[c]) == zero ? diffuse[c] : zero);
        for (int l = 0; l < L; ++l)
            for (int c = 0; c < 3; ++c)
                r.diffuse[static_cast<std::size_t>(x + l) * r.diffuseStride + static_cast<std::size_t>(c)] =
                    lanes[c][l];
    }
    if (!r.planes && !r.texels) return;
    V E[3][kShCount];
    exitVectors<V>(mt, I, nx, ny, nz, ph, r.ws, diffuse, E);
    alignas(32) float lanes[kGlossyFields][L];  // E of the lanes' texels, field by field
    for (int c = 0; c < 3; ++c)
        for (int i = 0; i < kShCount; ++i) {
            const int f = c * kShCount + i;
            const V e = E[c][i], finite = (e - e) == zero ? e : zero;
            if (r.planes) simd::store(r.planes + static_cast<std::size_t>(f) * r.plane + x, finite);
            if (r.texels) simd::store(lanes[f], finite);
        }
    if (r.texels)
        for (int l = 0; l < L; ++l)
            for (int f = 0; f < kGlossyFields; ++f)
                r.texels[static_cast<std::size_t>(x + l) * kGlossyFields + f] = toBfloat16(lanes[f][l]);
}

// A row's texels: whole lane groups, then the rest one by one (the same
// operations per texel).
template <class V>
[[gnu::always_inline]] inline void exitRowWith(const MirrorTables& mt, const ExitRow& r, int nx) {
    constexpr int L = simd::kLaneCount<V>;
    int x = 0;
    for (; x + L <= nx; x += L) exitTexels<V>(mt, r, x);
    for (; x < nx; ++x) exitTexels<float>(mt, r, x);
}
void exitRowSse(const MirrorTables& mt, const ExitRow& r, int nx) { exitRowWith<simd::F4>(mt, r, nx); }
[[gnu::target("avx2"), gnu::flatten]] void exitRowAvx2(const MirrorTables& mt, const ExitRow& r, int nx) {
    exitRowWith<simd::F8>(mt, r, nx);
}

}  // namespace

void glossyExitVector(const float incident[kShCount], float nx, float ny, float nz, const float ph[kShOrder], float ws,
                      float diffuse, float out[kShCount]) {
    float I[3][kShCount] = {}, E[3][kShCount];
    const float d[3] = {diffuse, 0.0f, 0.0f};
    for (int i = 0; i < kShCount; ++i) I[0][i] = incident[i];
    exitVectors<float>(mirrorTables(), I, nx, ny, nz, ph, ws, d, E);
    for (int i = 0; i < kShCount; ++i) out[i] = E[0][i];
}

void glossyExitRadiance(ConstGridView gradX, ConstGridView gradY, int s, int nxr, int nyr, const float* incident,
                        const std::array<Grid, 3>& shade, const AlbedoMap* surface, const ShadingSettings& shading,
                        GlossyExitScratch& scratch, const GlossyExitOutputs& out) {
    const int nx = gradX.nx, ny = gradX.ny;
    const std::size_t planeR = static_cast<std::size_t>(nxr) * nyr, plane = static_cast<std::size_t>(nx) * ny;
    const MirrorTables& mt = mirrorTables();
    float phUniform[kShOrder];
    phongLobeFactors(shading.phongExponent, phUniform);
    const bool lobeMap = surface && !surface->phongLobe[0].empty();
    std::vector<ReceiverLerp>& columns = scratch.columns;
    receiverLerps(nx, s, nxr, columns);
    const int nBlocks = std::max(1, std::min(ny, kMaxBlocks));
    // per worker slot: the receivers' rows mixed vertically (48 x nxr), then
    // along the row (48 x nx); a row keeps nothing in it
    const std::size_t nxPad = static_cast<std::size_t>(nx), slot = kGlossyFields * (std::max(nxr, 1) + nxPad);
    scratch.rows.resize(static_cast<std::size_t>(workerSlots()) * slot);
    void (*const exitRow)(const MirrorTables&, const ExitRow&, int) = simd::wideEnabled() ? exitRowAvx2 : exitRowSse;
    parallelFor(0, nBlocks, 1, [&](int b0, int b1) {
        float* vert = scratch.rows.data() + static_cast<std::size_t>(workerSlot()) * slot;
        float* rowIncident = vert + kGlossyFields * static_cast<std::size_t>(nxr);
        for (int block = b0; block < b1; ++block) {
            const int yBegin = static_cast<int>(static_cast<long long>(ny) * block / nBlocks);
            const int yEnd = static_cast<int>(static_cast<long long>(ny) * (block + 1) / nBlocks);
            for (int y = yBegin; y < yEnd; ++y) {
                // the incident SH vectors of this row, interpolated as gi/shading does (Fig. 7)
                const ReceiverLerp ry = receiverLerp(y, s, nyr);
                for (int p = 0; p < kGlossyFields; ++p) {
                    const float* ra = incident + p * planeR + static_cast<std::size_t>(ry.i0) * nxr;
                    const float* rb = incident + p * planeR + static_cast<std::size_t>(ry.i1) * nxr;
                    float* v = vert + static_cast<std::size_t>(p) * nxr;
                    for (int X = 0; X < nxr; ++X) v[X] = ra[X] + ry.f * (rb[X] - ra[X]);
                    lerpReceiverRow(v, nxr, s, columns.data(), nx, rowIncident + p * nxPad);
                }
                const std::size_t row = static_cast<std::size_t>(y) * nx;
                ExitRow r{rowIncident,
                          nxPad,
                          gradX.row(y),
                          gradY.row(y),
                          {},
                          {},
                          phUniform,
                          specularWeightOf(shading),
                          {shading.viewDir[0], shading.viewDir[1], shading.viewDir[2]},
                          out.planes ? out.planes + row : nullptr,
                          plane,
                          out.texels ? out.texels + row * kGlossyFields : nullptr,
                          out.diffuse ? out.diffuse + row * static_cast<std::size_t>(out.diffuseStride) : nullptr,
                          static_cast<std::size_t>(out.diffuseStride)};
                for (std::size_t c = 0; c < 3; ++c) r.shade[c] = shade[c].v.data() + row;
                for (int l = 1; l < kShOrder; ++l)
                    r.lobe[l - 1] =
                        lobeMap ? surface->phongLobe[static_cast<std::size_t>(l - 1)].v.data() + row : nullptr;
                exitRow(mt, r, nx);
            }
        }
    });
}

}  // namespace terrain::gi
