#include "gi/reference_gi.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <vector>

#include "core/error.h"
#include "core/parallel.h"
#include "gi/frame.h"

namespace terrain::gi {
namespace {

inline float bilinearF(const float* v, int nx, int ny, float px, float py) {
    int x0 = static_cast<int>(px), y0 = static_cast<int>(py);
    x0 = std::clamp(x0, 0, std::max(nx - 2, 0));
    y0 = std::clamp(y0, 0, std::max(ny - 2, 0));
    const int x1 = std::min(x0 + 1, nx - 1), y1 = std::min(y0 + 1, ny - 1);
    const float fx = std::clamp(px - static_cast<float>(x0), 0.0f, 1.0f);
    const float fy = std::clamp(py - static_cast<float>(y0), 0.0f, 1.0f);
    const float* r0 = v + static_cast<std::size_t>(y0) * nx;
    const float* r1 = v + static_cast<std::size_t>(y1) * nx;
    const float a = r0[x0] + fx * (r0[x1] - r0[x0]);
    const float b = r1[x0] + fx * (r1[x1] - r1[x0]);
    return a + fy * (b - a);
}

}  // namespace

bool referenceFirstHit(const float* h, int nx, int ny, float hMax, float cellSize, int x, int y,
                       const std::array<float, 3>& d, float step, float& hx, float& hy) {
    const float horiz = std::sqrt(d[0] * d[0] + d[1] * d[1]);
    if (horiz < 1e-6f) return d[2] < 0.0f ? (hx = static_cast<float>(x), hy = static_cast<float>(y), true) : false;
    const float dx = d[0] / horiz, dy = d[1] / horiz;
    const float rise = d[2] / horiz * cellSize;  // metres of ray height per cell travelled
    const float h0 = h[static_cast<std::size_t>(y) * nx + x];
    float prevGap = 0.0f;  // ray height - terrain height at the previous sample (0 at the start)
    float prevT = 0.0f;
    for (float t = step;; t += step) {
        const float px = static_cast<float>(x) + t * dx, py = static_cast<float>(y) + t * dy;
        if (px < 0.0f || py < 0.0f || px > static_cast<float>(nx - 1) || py > static_cast<float>(ny - 1)) return false;
        const float rayZ = h0 + rise * t;
        if (rise >= 0.0f && rayZ > hMax) return false;
        const float gap = rayZ - bilinearF(h, nx, ny, px, py);
        if (gap < 0.0f) {
            // linear refinement between the last sample above and this one below
            const float f = prevGap / (prevGap - gap);
            const float th = prevT + f * (t - prevT);
            hx = static_cast<float>(x) + th * dx;
            hy = static_cast<float>(y) + th * dy;
            return true;
        }
        prevGap = gap;
        prevT = t;
    }
}

void addReferenceKeyLight(ConstGridView heights, float cellSize, const KeyLight& key, const AlbedoMap* albedo,
                          int azimuths, std::array<Grid, 3>& rgb) {
    validateKeyLight(key);
    const int nx = heights.nx, ny = heights.ny;
    for (Grid& g : rgb) g.ensureSize(nx, ny);
    const int A = std::max(azimuths, 1);
    const KeyLightExtent ext = keyLightExtent(key);
    const double r = key.radiusDeg * kPi / 180.0, el = key.elevationDeg * kPi / 180.0,
                 az = key.azimuthDeg * kPi / 180.0;
    const double cosR = std::cos(r), sr = std::sin(r);
    const double radianceScale =
        1.0 / (sr * sr);  // cap radiance = RGB / sin^2(r): irradiance ~ pi RGB at normal incidence
    // per azimuth: the cap's elevation chord [lo, hi] (A sin w + B cos w >= cos r)
    struct Az {
        double c, s, lo, hi;
        bool any;
    };
    std::vector<Az> az_(static_cast<std::size_t>(A));
    const double dphi = (ext.phiEnd - ext.phiStart) / A;
    for (int a = 0; a < A; ++a) {
        const double phi = ext.phiStart + (a + 0.5) * dphi;
        const double pa = std::sin(el), pb = std::cos(el) * std::cos(phi - az);
        const double R = std::sqrt(pa * pa + pb * pb);
        Az& z = az_[static_cast<std::size_t>(a)];
        z.c = std::cos(phi);
        z.s = std::sin(phi);
        z.any = R > cosR;
        if (!z.any) continue;
        const double centre = std::atan2(pa, pb), half = std::acos(std::min(1.0, cosR / R));
        z.lo = std::max(-0.5 * kPi, centre - half);
        z.hi = std::min(0.5 * kPi, centre + half);
        z.any = z.hi > z.lo;
    }
    Grid gx, gy;
    computeGradient(heights, cellSize, gx, gy);
    double heightMax = -1e300;
    for (int y = 0; y < ny; ++y)
        for (int x = 0; x < nx; ++x) heightMax = std::max(heightMax, static_cast<double>(heights(x, y)));
    parallelFor(0, ny, 1, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y)
            for (int x = 0; x < nx; ++x) {
                const double gxv = gx(x, y), gyv = gy(x, y);
                const double inv = 1.0 / std::sqrt(1.0 + gxv * gxv + gyv * gyv);
                double e = 0.0;  // int over the visible cap of (N . d) d(solid angle)
                for (const Az& z : az_) {
                    if (!z.any) continue;
                    const double slope = referenceMaxSlope(heights, cellSize, x, y, z.c, z.s, heightMax);
                    const double lo = std::max(z.lo, std::atan(std::max(slope, gxv * z.c + gyv * z.s)));
                    if (lo >= z.hi) continue;
                    // (N . d) cos w = (horiz cos w + nz sin w) cos w
                    const double horiz = -(gxv * z.c + gyv * z.s) * inv;
                    const double c2 = 0.5 * (z.hi - lo) + 0.25 * (std::sin(2.0 * z.hi) - std::sin(2.0 * lo));
                    const double sc = 0.5 * (std::sin(z.hi) * std::sin(z.hi) - std::sin(lo) * std::sin(lo));
                    e += horiz * c2 + inv * sc;
                }
                e *= dphi * radianceScale / kPi;
                for (int c = 0; c < 3; ++c) {
                    const float alb = albedo && !albedo->channel[static_cast<std::size_t>(c)].empty()
                                          ? albedo->channel[static_cast<std::size_t>(c)](x, y)
                                          : 1.0f;
                    rgb[static_cast<std::size_t>(c)](x, y) += static_cast<float>(alb * key.rgb[c] * e);
                }
            }
    });
}

void referenceDirections(int count, std::vector<std::array<float, 3>>& out) {
    out.resize(static_cast<std::size_t>(count));
    const double golden = kPi * (3.0 - std::sqrt(5.0));
    for (int k = 0; k < count; ++k) {
        const double z = 1.0 - (2.0 * k + 1.0) / count;
        const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
        const double phi = golden * k;
        out[static_cast<std::size_t>(k)] = {static_cast<float>(r * std::cos(phi)),
                                            static_cast<float>(r * std::sin(phi)), static_cast<float>(z)};
    }
}

void gatherReferenceBounce(ConstGridView heights, float cellSize, const std::array<Grid, 3>& prev,
                           const AlbedoMap* albedo, const ReferenceGiSettings& s, std::array<Grid, 3>& next) {
    const int nx = heights.nx, ny = heights.ny;
    for (int c = 0; c < 3; ++c) next[c].resize(nx, ny, 0.0f);
    if (nx < 2 || ny < 2) return;  // a line or a point sees nothing but sky
    Grid hCopy(nx, ny);
    for (int y = 0; y < ny; ++y)
        for (int x = 0; x < nx; ++x) hCopy(x, y) = heights(x, y);
    const float hMax = *std::max_element(hCopy.v.begin(), hCopy.v.end());
    Grid gx, gy;
    computeGradient(heights, cellSize, gx, gy);
    std::vector<std::array<float, 3>> dirs;
    referenceDirections(s.directions, dirs);
    const float weight = static_cast<float>(4.0 * kPi / s.directions);
    std::atomic<int> rowsDone{0};
    parallelFor(0, ny, 1, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) {
            for (int x = 0; x < nx; ++x) {
                // unit normal from the same central differences as the fast path
                const float ddx = gx(x, y), ddy = gy(x, y);
                const float inv = 1.0f / std::sqrt(ddx * ddx + ddy * ddy + 1.0f);
                const float n0 = -ddx * inv, n1 = -ddy * inv, n2 = inv;
                float e[3] = {0.0f, 0.0f, 0.0f};
                for (const auto& dir : dirs) {
                    const float cosine = n0 * dir[0] + n1 * dir[1] + n2 * dir[2];
                    if (cosine <= 0.0f) continue;
                    float qx, qy;
                    if (!referenceFirstHit(hCopy.data(), nx, ny, hMax, cellSize, x, y, dir, s.marchStep, qx, qy))
                        continue;
                    const float k =
                        s.shLambert ? 0.25f + 0.5f * cosine + 0.15625f * (3.0f * cosine * cosine - 1.0f) : cosine;
                    for (int c = 0; c < 3; ++c) e[c] += k * bilinearF(prev[c].data(), nx, ny, qx, qy);
                }
                for (int c = 0; c < 3; ++c) {
                    const float a = albedo && !albedo->channel[c].empty() ? albedo->channel[c](x, y) : 1.0f;
                    next[c](x, y) = a / static_cast<float>(kPi) * weight * e[c];
                }
            }
            const int done = ++rowsDone;
            if (s.progress && (done % 16 == 0 || done == ny))
                std::printf("\rreference indirect: %3d%%%s", 100 * done / ny, done == ny ? "\n" : "");
        }
    });
}

void renderDirectReference(ConstGridView heights, float cellSize, const ShRgb& lighting, const AlbedoMap* albedo,
                           const ReferenceGiSettings& settings, ReferenceResult& out) {
    ReferenceSettings direct;
    direct.azimuths = settings.azimuths;
    direct.progress = settings.progress;
    renderReference(heights, cellSize, &lighting, albedo, direct, out);
}

void renderReferenceGi(ConstGridView heights, float cellSize, const ShRgb& lighting, const AlbedoMap* albedo,
                       const ReferenceGiSettings& s, ReferenceGiResult& out) {
    if (s.directions < 16 || s.directions > 1 << 20) throw InputError("reference: directions must be 16 .. 2^20");
    if (s.bounces < 0 || s.bounces > 16) throw InputError("reference: bounces must be 0 .. 16");
    if (!(s.marchStep > 0.0f && s.marchStep <= 2.0f)) throw InputError("reference: march step must be in (0, 2] cells");
    checkHeightsFinite(heights);
    if (s.shading.brdf != Brdf::Lambert) {  // glossy surfaces: SH incident radiance per texel (gi/reference_glossy.cpp)
        renderReferenceGlossy(heights, cellSize, lighting, albedo, s, out);
        return;
    }
    const int nx = heights.nx, ny = heights.ny;
    // Bounce 0: the exact direct reference.
    ReferenceResult d;
    renderDirectReference(heights, cellSize, lighting, albedo, s, d);
    out.ambient = d.ambient;
    for (const KeyLight& k : s.keys) addReferenceKeyLight(heights, cellSize, k, albedo, s.keyAzimuths, d.rgb);
    for (int c = 0; c < 3; ++c) {
        out.direct[c] = d.rgb[c];
        out.indirect[c].resize(nx, ny, 0.0f);
    }
    std::array<Grid, 3> prev = out.direct, next;
    for (int b = 1; b <= s.bounces; ++b) {
        if (s.progress) std::printf("reference: bounce %d of %d\n", b, s.bounces);
        gatherReferenceBounce(heights, cellSize, prev, albedo, s, next);
        for (int c = 0; c < 3; ++c) {
            for (std::size_t i = 0; i < next[c].v.size(); ++i) out.indirect[c].v[i] += next[c].v[i];
            std::swap(prev[c], next[c]);
        }
    }
    for (int c = 0; c < 3; ++c) {
        out.total[c].resize(nx, ny);
        for (std::size_t i = 0; i < out.total[c].v.size(); ++i)
            out.total[c].v[i] = out.direct[c].v[i] + out.indirect[c].v[i];
    }
}

}  // namespace terrain::gi
