#include "gi/key_light_exact.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/parallel.h"
#include "core/simd.h"
#include "gi/sh.h"

namespace terrain::gi {

namespace {

constexpr int kChunk = 256;  // texels of a row whose cosines are computed together

// N . l = (lz - gx lx - gy ly) / sqrt(1 + gx^2 + gy^2) over [0, n): 4 lanes
// at a time, then one by one (element-wise IEEE operations: the same bits).
void cosinesOfChunk(const float* gx, const float* gy, float lx, float ly, float lz, int n, float* out) {
    using simd::F4;
    const F4 vx = simd::splat<F4>(lx), vy = simd::splat<F4>(ly), vz = simd::splat<F4>(lz);
    const F4 one = simd::splat<F4>(1.0f);
    int x = 0;
    for (; x + 4 <= n; x += 4) {
        const F4 a = simd::load<F4>(gx + x), b = simd::load<F4>(gy + x);
        simd::store(out + x, (vz - a * vx - b * vy) / simd::sqrtv(one + a * a + b * b));
    }
    for (; x < n; ++x) out[x] = (lz - gx[x] * lx - gy[x] * ly) / std::sqrt(1.0f + gx[x] * gx[x] + gy[x] * gy[x]);
}

}  // namespace

void addKeyLightExactCosine(const KeyLight& light, const VisibilityField& v, int s, ConstGridView gradX,
                            ConstGridView gradY, const AlbedoMap* albedo, std::array<Grid, 3>& out,
                            const TexelRuns* runs) {
    const KeyLightExtent ext = keyLightExtent(light);
    const double solidAngle = (ext.phiEnd - ext.phiStart) * (static_cast<double>(ext.sinHigh) - ext.sinLow);
    if (!(solidAngle > 0.0)) return;
    const float toFrac = static_cast<float>(std::sqrt(4.0 * kPi) / solidAngle);
    const double az = light.azimuthDeg * kPi / 180.0, el = light.elevationDeg * kPi / 180.0;
    const float lx = static_cast<float>(std::cos(el) * std::cos(az)),
                ly = static_cast<float>(std::cos(el) * std::sin(az));
    const float lz = static_cast<float>(std::sin(el));
    const int nx = gradX.nx, ny = gradX.ny, nxr = v.nxr, nyr = v.nyr;
    const float* v0 = v.plane(0);
    const float invS = 1.0f / static_cast<float>(s);
    // each texel column's receivers and fraction, once per call
    struct Column {
        int X0, X1;
        float fx;
    };
    std::vector<Column> columns(static_cast<std::size_t>(nx));
    for (int x = 0; x < nx; ++x) {
        const int X0 = std::min(x / s, nxr - 1), X1 = std::min(X0 + 1, nxr - 1);
        columns[static_cast<std::size_t>(x)] = {X0, X1, X1 == X0 ? 0.0f : static_cast<float>(x - s * X0) * invS};
    }
    const ColumnSpan wholeRow{0, nx};
    parallelForRows(ny, nx, [&](int y0, int y1) {
        float cosine[kChunk];
        for (int y = y0; y < y1; ++y) {
            const int Y0 = std::min(y / s, nyr - 1), Y1 = std::min(Y0 + 1, nyr - 1);
            const float fy = Y1 == Y0 ? 0.0f : static_cast<float>(y - s * Y0) * invS;
            const float* r0 = v0 + static_cast<std::size_t>(Y0) * nxr;
            const float* r1 = v0 + static_cast<std::size_t>(Y1) * nxr;
            for (const ColumnSpan& run : runsOfRow(runs, y, wholeRow))
                for (int c0 = run.x0; c0 < run.x1; c0 += kChunk) {
                    const int n = std::min(kChunk, run.x1 - c0);
                    cosinesOfChunk(gradX.row(y) + c0, gradY.row(y) + c0, lx, ly, lz, n, cosine);
                    for (int k = 0; k < n; ++k) {
                        const int x = c0 + k;
                        if (!(cosine[k] > 0.0f)) continue;
                        const Column& col = columns[static_cast<std::size_t>(x)];
                        const float a = r0[col.X0] + col.fx * (r0[col.X1] - r0[col.X0]);
                        const float b = r1[col.X0] + col.fx * (r1[col.X1] - r1[col.X0]);
                        const float f = std::clamp((a + fy * (b - a)) * toFrac, 0.0f, 1.0f);
                        if (!(f > 0.0f)) continue;
                        for (std::size_t c = 0; c < 3; ++c) {
                            const float alb = albedo && !albedo->channel[c].empty() ? albedo->channel[c](x, y) : 1.0f;
                            out[c](x, y) += alb * light.rgb[c] * f * cosine[k];
                        }
                    }
                }
        }
    });
}

}  // namespace terrain::gi
