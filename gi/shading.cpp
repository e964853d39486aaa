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
    out.colIndex.resize(static_cast<std::size_t>(nx));
    out.colFrac.resize(static_cast<std::size_t>(nx));

    // ---- algorithm, receivers: incident radiance I_c = sum_L T_{L,c} V_L ------
    parallelForRows(nyr, nxr * 16, [&](int y0, int y1) {
        for (int Y = y0; Y < y1; ++Y)
            for (int X = 0; X < nxr; ++X) {
                const std::size_t r = static_cast<std::size_t>(Y) * nxr + X;
                for (int ch = 0; ch < 3; ++ch)
                    for (int i = 0; i < nCoef; ++i) {
                        double acc = 0.0;
                        for (int L = 0; L < lightCount; ++L) {
                            const ShMatrix& t = lights[L].product[static_cast<std::size_t>(ch)];
                            const VisibilityField& v = *lights[L].visibility;
                            for (int k = 0; k < kShCount; ++k)
                                acc += t[static_cast<std::size_t>(i * kShCount + k)] * v.plane(k)[r];
                        }
                        out.incident[(static_cast<std::size_t>(ch) * nCoef + i) * planeR + r] = static_cast<float>(acc);
                    }
            }
    });

    // ---- interpolation tables (receiver X sits at column s X) -----------------
    for (int x = 0; x < nx; ++x) {
        int X0 = std::min(x / s, std::max(nxr - 2, 0));
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

    // ---- algorithm, texels: interpolate SH vectors, dot with the rotated BRDF --
    parallelForRows(ny, nx * 8, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) {
            const int Y0 = std::min(y / s, std::max(nyr - 2, 0));
            float fy = nyr > 1 ? static_cast<float>(y - s * Y0) / static_cast<float>(s) : 0.0f;
            if (fy > 1.0f) fy = 1.0f;
            const int Y1 = std::min(Y0 + 1, nyr - 1);
            const float* gxr = gradX.row(y);
            const float* gyr = gradY.row(y);
            for (int x = 0; x < nx; ++x) {
                const int X0 = out.colIndex[static_cast<std::size_t>(x)];
                const int X1 = std::min(X0 + 1, nxr - 1);
                const float fx = out.colFrac[static_cast<std::size_t>(x)];
                const float w00 = (1.0f - fx) * (1.0f - fy), w01 = fx * (1.0f - fy), w10 = (1.0f - fx) * fy, w11 = fx * fy;
                const std::size_t i00 = static_cast<std::size_t>(Y0) * nxr + X0, i01 = static_cast<std::size_t>(Y0) * nxr + X1;
                const std::size_t i10 = static_cast<std::size_t>(Y1) * nxr + X0, i11 = static_cast<std::size_t>(Y1) * nxr + X1;
                auto interp = [&](const float* p) { return (w00 * p[i00] + w01 * p[i01]) + (w10 * p[i10] + w11 * p[i11]); };

                // full-resolution normal
                const float gx = gxr[x], gy = gyr[x];
                const float inv = 1.0f / std::sqrt(1.0f + gx * gx + gy * gy);
                const float nxv = -gx * inv, nyv = -gy * inv, nzv = inv;
                float yn[kShCount];
                shBasisFloat(nxv, nyv, nzv, yn, 9);
                float lam[9];
                lam[0] = lam0 * yn[0];
                for (int i = 1; i < 4; ++i) lam[i] = lam1 * yn[i];
                for (int i = 4; i < 9; ++i) lam[i] = lam2 * yn[i];

                // ambient: lam(N) . V_env / pi
                float amb = 0.0f;
                for (int i = 0; i < 9; ++i) amb += lam[i] * interp(env.plane(i));
                out.ambient(x, y) = amb;

                float spec[kShCount];
                if (phong) {
                    const float nv = nxv * vx + nyv * vy + nzv * vz;
                    const float rx = 2.0f * nv * nxv - vx, ry = 2.0f * nv * nyv - vy, rz = 2.0f * nv * nzv - vz;
                    shBasisFloat(rx, ry, rz, spec, kShCount);
                    for (int i = 0; i < kShCount; ++i) spec[i] *= specWeight * ph[shBand(i)];
                }
                for (int ch = 0; ch < 3; ++ch) {
                    const float* base = out.incident.data() + static_cast<std::size_t>(ch) * nCoef * planeR;
                    float e = 0.0f, sp = 0.0f;
                    for (int i = 0; i < 9; ++i) e += lam[i] * interp(base + i * planeR);
                    if (phong)
                        for (int i = 0; i < kShCount; ++i) sp += spec[i] * interp(base + i * planeR);
                    const float a = albedo && !albedo->channel[static_cast<std::size_t>(ch)].empty()
                                        ? albedo->channel[static_cast<std::size_t>(ch)](x, y)
                                        : 1.0f;
                    float v = diffuseWeight * a * e + sp;
                    out.rgb[static_cast<std::size_t>(ch)](x, y) = std::isfinite(v) ? v : 0.0f;
                }
            }
        }
    });
}

}  // namespace terrain::gi
