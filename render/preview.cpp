#include "render/preview.h"

#include <algorithm>
#include <cmath>

#include "sim/parallel.h"

namespace terrain {
namespace {
struct Rgb {
    float r, g, b;
};
Rgb lerp(Rgb a, Rgb b, float t) { return {a.r + (b.r - a.r) * t, a.g + (b.g - a.g) * t, a.b + (b.b - a.b) * t}; }
std::uint8_t toByte(float v) {
    // linear -> sRGB
    v = std::clamp(v, 0.0f, 1.0f);
    const float s = v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
    return static_cast<std::uint8_t>(std::lround(s * 255.0f));
}
}  // namespace

void shadePreview(const TerrainState& s, const PreviewSettings& p, std::vector<std::uint8_t>& rgb) {
    const int nx = s.nx, ny = s.ny;
    rgb.resize(static_cast<std::size_t>(nx) * ny * 3);
    float zMin = p.zMin, zMax = p.zMax;
    if (!(zMax > zMin)) {
        zMin = zMax = s.ground(0, 0);
        for (int y = 0; y < ny; ++y)
            for (int x = 0; x < nx; ++x) {
                zMin = std::min(zMin, s.ground(x, y));
                zMax = std::max(zMax, s.ground(x, y));
            }
        if (!(zMax > zMin)) zMax = zMin + 1.0f;
    }
    constexpr float kDeg = 0.017453292519943295f;
    const float ce = std::cos(p.sunElevationDeg * kDeg);
    const float sx = ce * std::cos(p.sunAzimuthDeg * kDeg), sy = ce * std::sin(p.sunAzimuthDeg * kDeg);
    const float sz = std::sin(p.sunElevationDeg * kDeg);
    const float inv2h = p.verticalExaggeration / (2.0f * s.cellSize);
    const bool water = !s.water.empty();
    parallelForRows(ny, nx, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y)
            for (int x = 0; x < nx; ++x) {
                auto g = [&](int xx, int yy) {
                    xx = std::clamp(xx, 0, nx - 1);
                    yy = std::clamp(yy, 0, ny - 1);
                    return s.ground(xx, yy);
                };
                const float dx = (g(x + 1, y) - g(x - 1, y)) * inv2h;
                const float dy = (g(x, y + 1) - g(x, y - 1)) * inv2h;
                const float inv = 1.0f / std::sqrt(dx * dx + dy * dy + 1.0f);
                const float nxv = -dx * inv, nyv = -dy * inv, nzv = inv;
                const float sun = std::max(0.0f, nxv * sx + nyv * sy + nzv * sz);
                const float sky = 0.5f + 0.5f * nzv;
                const float t = std::clamp((s.ground(x, y) - zMin) / (zMax - zMin), 0.0f, 1.0f);
                Rgb c = t < 0.5f ? lerp({0.20f, 0.28f, 0.10f}, {0.33f, 0.30f, 0.22f}, t * 2.0f)
                                 : lerp({0.33f, 0.30f, 0.22f}, {0.85f, 0.85f, 0.88f}, (t - 0.5f) * 2.0f);
                if (nzv < 0.75f) c = lerp(c, {0.32f, 0.29f, 0.27f}, std::min(1.0f, (0.75f - nzv) * 4.0f));
                const float light = 0.85f * sun + 0.25f * sky;
                c = {c.r * light, c.g * light, c.b * light};
                if (water) {
                    const float d = s.water(x, y);
                    if (d > 0.05f) {
                        // The water surface, lit by its own normal (exaggerated so small
                        // waves show) with a Fresnel-like sky sheen.
                        auto eta = [&](int xx, int yy) {
                            xx = std::clamp(xx, 0, nx - 1);
                            yy = std::clamp(yy, 0, ny - 1);
                            const float w = s.water(xx, yy);
                            return w > 0.05f ? s.ground(xx, yy) + w : s.ground(x, y) + d;
                        };
                        const float k = 6.0f * inv2h;
                        const float ex = (eta(x + 1, y) - eta(x - 1, y)) * k;
                        const float ey = (eta(x, y + 1) - eta(x, y - 1)) * k;
                        const float wi = 1.0f / std::sqrt(ex * ex + ey * ey + 1.0f);
                        const float ws = std::max(0.0f, (-ex * sx - ey * sy + sz) * wi);
                        const float a = 1.0f - std::exp(-d / 1.5f);
                        const Rgb deep{0.02f * (0.4f + ws), 0.10f * (0.4f + ws), 0.22f * (0.4f + ws)};
                        c = lerp(c, deep, 0.3f + 0.65f * a);
                        const float sheen = std::min(0.3f, std::pow(1.0f - wi, 2.0f) * 2.0f) + 0.25f * std::pow(ws, 40.0f);
                        c = {c.r + sheen * 0.6f, c.g + sheen * 0.7f, c.b + sheen * 0.8f};
                    } else if (d > 1e-3f) {
                        c = {c.r * 0.8f, c.g * 0.82f, c.b * 0.9f};  // wet ground
                    }
                }
                std::uint8_t* o = rgb.data() + (static_cast<std::size_t>(y) * nx + x) * 3;
                o[0] = toByte(c.r);
                o[1] = toByte(c.g);
                o[2] = toByte(c.b);
            }
    });
}

}  // namespace terrain
