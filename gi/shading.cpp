#include "gi/shading.h"

#include <algorithm>
#include <cmath>

#include "sim/parallel.h"

namespace terrain::gi {

namespace {

// SH basis in float at a unit direction (bands 0..3; only `count` filled).
inline void shBasisFloat(float x, float y, float z, float* o, int count) {
    o[0] = 0.28209479177387814f;
    o[1] = 0.48860251190291992f * y;
    o[2] = 0.48860251190291992f * z;
    o[3] = 0.48860251190291992f * x;
    o[4] = 1.0925484305920792f * x * y;
    o[5] = 1.0925484305920792f * y * z;
    o[6] = 0.31539156525252005f * (3.0f * z * z - 1.0f);
    o[7] = 1.0925484305920792f * x * z;
    o[8] = 0.54627421529603959f * (x * x - y * y);
    if (count <= 9) return;
    o[9] = 0.59004358992664352f * y * (3.0f * x * x - y * y);
    o[10] = 2.8906114426405538f * x * y * z;
    o[11] = 0.45704579946446572f * y * (5.0f * z * z - 1.0f);
    o[12] = 0.37317633259011546f * (5.0f * z * z * z - 3.0f * z);
    o[13] = 0.45704579946446572f * x * (5.0f * z * z - 1.0f);
    o[14] = 1.4453057213202769f * z * (x * x - y * y);
    o[15] = 0.59004358992664352f * x * (x * x - 3.0f * y * y);
}

}  // namespace

void shadeTexels(ConstGridView gradX, ConstGridView gradY, int s, const VisibilityField& env,
                 const ShadingLight* lights, int lightCount, const AlbedoMap* albedo, const ShadingSettings& settings,
                 ShadeMaps& out) {
    const int nx = gradX.nx, ny = gradX.ny;
    const int nxr = env.nxr, nyr = env.nyr;
    const std::size_t planeR = static_cast<std::size_t>(nxr) * nyr;
    const bool phong = settings.brdf != Brdf::Lambert;
    const int nCoef = phong ? kShCount : 9;
    out.nx = nx;
    out.ny = ny;
    for (Grid& g : out.rgb)
        if (g.nx != nx || g.ny != ny) g.resize(nx, ny);
    if (out.ambient.nx != nx || out.ambient.ny != ny) out.ambient.resize(nx, ny);
    out.incident.resize(planeR * 3 * nCoef);
    const int nPlanes = 3 * nCoef + 9;  // incident radiance + V_env bands 0..2 (ambient)
    const int nBlocks = std::max(1, std::min(ny, 64));
    out.rowScratch.resize(static_cast<std::size_t>(nBlocks) * nPlanes * (nxr + nx));
    out.basisScratch.resize(static_cast<std::size_t>(nBlocks) * 24 * nx);

    out.colIndex.resize(static_cast<std::size_t>(nx));
    out.colFrac.resize(static_cast<std::size_t>(nx));

    // lighting matrices in float
    const int nl = lightCount;
    out.lightMatrices.resize(static_cast<std::size_t>(nl) * 3 * kShCount * kShCount);
    for (int L = 0; L < nl; ++L)
        for (int ch = 0; ch < 3; ++ch)
            for (int e = 0; e < kShCount * kShCount; ++e)
                out.lightMatrices[(static_cast<std::size_t>(L) * 3 + ch) * kShCount * kShCount + e] =
                    static_cast<float>(lights[L].product[static_cast<std::size_t>(ch)][static_cast<std::size_t>(e)]);

    // ---- algorithm, receivers: incident radiance I_c = sum_L T_{L,c} V_L ------
    // (vectorised along receiver rows; zero matrix entries skipped)
    parallelForRows(nyr, nxr * 16, [&](int y0, int y1) {
        for (int Y = y0; Y < y1; ++Y) {
            const std::size_t r0 = static_cast<std::size_t>(Y) * nxr;
            for (int ch = 0; ch < 3; ++ch)
                for (int i = 0; i < nCoef; ++i) {
                    float* __restrict o = out.incident.data() + (static_cast<std::size_t>(ch) * nCoef + i) * planeR + r0;
                    std::fill(o, o + nxr, 0.0f);
                    for (int L = 0; L < nl; ++L)
                        for (int k = 0; k < kShCount; ++k) {
                            const float t = out.lightMatrices[((static_cast<std::size_t>(L) * 3 + ch) * kShCount + i) * kShCount + k];
                            if (t == 0.0f) continue;
                            const float* __restrict v = lights[L].visibility->plane(k) + r0;
                            for (int X = 0; X < nxr; ++X) o[X] += t * v[X];
                        }
                }
        }
    });

    // ---- interpolation tables (receiver X sits at column s X) -----------------
    for (int x = 0; x < nx; ++x) {
        const int X0 = std::min(x / s, std::max(nxr - 2, 0));
        float f = nxr > 1 ? static_cast<float>(x - s * X0) / static_cast<float>(s) : 0.0f;
        if (f > 1.0f) f = 1.0f;  // texels beyond the last receiver: clamp
        out.colIndex[static_cast<std::size_t>(x)] = X0;
        out.colFrac[static_cast<std::size_t>(x)] = f;
    }

    double lamZh[kShOrder];
    for (int l = 0; l < kShOrder; ++l) lamZh[l] = std::sqrt(4.0 * kPi / (2.0 * l + 1.0)) * lambertZonal()[l] / kPi;
    const float lam0 = static_cast<float>(lamZh[0]), lam1 = static_cast<float>(lamZh[1]), lam2 = static_cast<float>(lamZh[2]);
    double phZh[kShOrder];
    phongZonal(settings.phongExponent, phZh);
    float ph[kShOrder];
    for (int l = 0; l < kShOrder; ++l) ph[l] = static_cast<float>(std::sqrt(4.0 * kPi / (2.0 * l + 1.0)) * phZh[l]);
    const float diffuseWeight = settings.brdf == Brdf::Phong ? 0.0f : 1.0f;
    const float specWeight = settings.brdf == Brdf::Phong ? 1.0f : (settings.brdf == Brdf::LambertPlusPhong ? settings.specularWeight : 0.0f);
    const float vx = settings.viewDir[0], vy = settings.viewDir[1], vz = settings.viewDir[2];

    // ---- schedule: fixed row blocks, each with its own scratch ---------------
    parallelFor(0, nBlocks, 1, [&](int b0, int b1) {
        for (int block = b0; block < b1; ++block) {
            float* vert = out.rowScratch.data() + static_cast<std::size_t>(block) * nPlanes * (nxr + nx);
            float* up = vert + static_cast<std::size_t>(nPlanes) * nxr;
            float* basis = out.basisScratch.data() + static_cast<std::size_t>(block) * 24 * nx;
            const int yBegin = static_cast<int>(static_cast<long long>(ny) * block / nBlocks);
            const int yEnd = static_cast<int>(static_cast<long long>(ny) * (block + 1) / nBlocks);
            for (int y = yBegin; y < yEnd; ++y) {
                // ---- algorithm: SH vectors interpolated to this row (Fig. 7) ----
                const int Y0 = std::min(y / s, std::max(nyr - 2, 0));
                float fy = nyr > 1 ? static_cast<float>(y - s * Y0) / static_cast<float>(s) : 0.0f;
                if (fy > 1.0f) fy = 1.0f;
                const int Y1 = std::min(Y0 + 1, nyr - 1);
                for (int p = 0; p < nPlanes; ++p) {
                    const float* plane = p < 3 * nCoef ? out.incident.data() + static_cast<std::size_t>(p) * planeR
                                                       : env.plane(p - 3 * nCoef);
                    const float* __restrict ra = plane + static_cast<std::size_t>(Y0) * nxr;
                    const float* __restrict rb = plane + static_cast<std::size_t>(Y1) * nxr;
                    float* __restrict v = vert + static_cast<std::size_t>(p) * nxr;
                    for (int X = 0; X < nxr; ++X) v[X] = ra[X] + fy * (rb[X] - ra[X]);
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
                            const int X0 = out.colIndex[static_cast<std::size_t>(x)];
                            const int X1 = std::min(X0 + 1, nxr - 1);
                            const float fx = out.colFrac[static_cast<std::size_t>(x)];
                            u[x] = v[X0] + fx * (v[X1] - v[X0]);
                        }
                    }
                }
                // ---- algorithm: rotated BRDF at each full-resolution normal -----
                const float* __restrict gxr = gradX.row(y);
                const float* __restrict gyr = gradY.row(y);
                float* __restrict lamRow = basis;  // 9 x nx
                for (int x = 0; x < nx; ++x) {
                    const float gx = gxr[x], gy = gyr[x];
                    const float inv = 1.0f / std::sqrt(1.0f + gx * gx + gy * gy);
                    const float X = -gx * inv, Yn = -gy * inv, Z = inv;
                    lamRow[0 * nx + x] = lam0 * 0.28209479177387814f;
                    lamRow[1 * nx + x] = lam1 * 0.48860251190291992f * Yn;
                    lamRow[2 * nx + x] = lam1 * 0.48860251190291992f * Z;
                    lamRow[3 * nx + x] = lam1 * 0.48860251190291992f * X;
                    lamRow[4 * nx + x] = lam2 * 1.0925484305920792f * X * Yn;
                    lamRow[5 * nx + x] = lam2 * 1.0925484305920792f * Yn * Z;
                    lamRow[6 * nx + x] = lam2 * 0.31539156525252005f * (3.0f * Z * Z - 1.0f);
                    lamRow[7 * nx + x] = lam2 * 1.0925484305920792f * X * Z;
                    lamRow[8 * nx + x] = lam2 * 0.54627421529603959f * (X * X - Yn * Yn);
                }
                float* __restrict amb = out.ambient.data() + static_cast<std::size_t>(y) * nx;
                for (int x = 0; x < nx; ++x) amb[x] = 0.0f;
                for (int i = 0; i < 9; ++i) {
                    const float* __restrict l = lamRow + static_cast<std::size_t>(i) * nx;
                    const float* __restrict u = up + static_cast<std::size_t>(3 * nCoef + i) * nx;
                    for (int x = 0; x < nx; ++x) amb[x] += l[x] * u[x];
                }
                for (int ch = 0; ch < 3; ++ch) {
                    float* __restrict o = out.rgb[static_cast<std::size_t>(ch)].data() + static_cast<std::size_t>(y) * nx;
                    for (int x = 0; x < nx; ++x) o[x] = 0.0f;
                    for (int i = 0; i < 9; ++i) {
                        const float* __restrict l = lamRow + static_cast<std::size_t>(i) * nx;
                        const float* __restrict u = up + static_cast<std::size_t>(ch * nCoef + i) * nx;
                        for (int x = 0; x < nx; ++x) o[x] += l[x] * u[x];
                    }
                    const Grid* a = albedo && !albedo->channel[static_cast<std::size_t>(ch)].empty()
                                        ? &albedo->channel[static_cast<std::size_t>(ch)]
                                        : nullptr;
                    for (int x = 0; x < nx; ++x) o[x] *= diffuseWeight * (a ? (*a)(x, y) : 1.0f);
                    if (phong) {
                        // Phong lobe about the reflection vector (Section 7)
                        for (int x = 0; x < nx; ++x) {
                            const float gx = gxr[x], gy = gyr[x];
                            const float inv = 1.0f / std::sqrt(1.0f + gx * gx + gy * gy);
                            const float nxv = -gx * inv, nyv = -gy * inv, nzv = inv;
                            const float nv = nxv * vx + nyv * vy + nzv * vz;
                            float yb[kShCount];
                            shBasisFloat(2.0f * nv * nxv - vx, 2.0f * nv * nyv - vy, 2.0f * nv * nzv - vz, yb, kShCount);
                            float sp = 0.0f;
                            for (int i = 0; i < kShCount; ++i) sp += ph[shBand(i)] * yb[i] * up[static_cast<std::size_t>(ch * nCoef + i) * nx + x];
                            o[x] += specWeight * sp;
                        }
                    }
                    for (int x = 0; x < nx; ++x) o[x] = std::isfinite(o[x]) ? o[x] : 0.0f;
                }
            }
        }
    });
}

}  // namespace terrain::gi
