#include "gi/lights.h"

#include <array>
#include <cmath>
#include <string>

#include "core/error.h"

namespace terrain::gi {

namespace {
constexpr double kDeg = kPi / 180.0;

// SH projection of the radiance of every direction by the midpoint rule over
// an nTheta x nPhi equirectangular grid (theta from +z, phi from +x towards
// +y): radiance(a, b, x, y, z) is the RGB radiance of cell (a, b), direction
// (x, y, z).
template <class Radiance>
ShRgb projectMidpoints(int nTheta, int nPhi, Radiance radiance) {
    ShRgb l;
    for (int a = 0; a < nTheta; ++a) {
        const double theta = kPi * (a + 0.5) / nTheta;
        const double z = std::cos(theta), r = std::sin(theta);
        const double dA = (kPi / nTheta) * (2.0 * kPi / nPhi) * r;
        for (int b = 0; b < nPhi; ++b) {
            const double phi = 2.0 * kPi * (b + 0.5) / nPhi;
            const double x = r * std::cos(phi), y = r * std::sin(phi);
            double yv[kShCount];
            shEvaluate(x, y, z, yv);
            const std::array<double, 3> rgb = radiance(a, b, x, y, z);
            for (int ch = 0; ch < 3; ++ch)
                for (int i = 0; i < kShCount; ++i)
                    l.c[static_cast<std::size_t>(ch)][static_cast<std::size_t>(i)] +=
                        rgb[static_cast<std::size_t>(ch)] * yv[i] * dA;
        }
    }
    return l;
}

}  // namespace

ShRgb uniformSkyLight(float radiance) {
    ShRgb l;
    for (auto& c : l.c) c[0] = std::sqrt(4.0 * kPi) * radiance;
    return l;
}

ShRgb sunSkyLight(const SunSkySettings& s) {
    const double sa = s.sunAzimuthDeg * kDeg, se = s.sunElevationDeg * kDeg;
    const double sx = std::cos(se) * std::cos(sa), sy = std::cos(se) * std::sin(sa), sz = std::sin(se);
    return projectMidpoints(256, 512, [&](int, int, double x, double y, double z) {
        const double lobe = std::exp(s.sunSharpness * (x * sx + y * sy + z * sz - 1.0));
        std::array<double, 3> rgb;
        for (int ch = 0; ch < 3; ++ch) {
            double rad = z >= 0.0 ? s.horizon[ch] + (s.zenith[ch] - s.horizon[ch]) * z : s.ground[ch];
            rad += s.sun[ch] * lobe;
            rgb[static_cast<std::size_t>(ch)] = rad;
        }
        return rgb;
    });
}

ShRgb projectEquirect(const std::vector<float>& rgb, int width, int height) {
    if (width <= 0 || height <= 0 || rgb.size() != static_cast<std::size_t>(width) * height * 3)
        throw InputError("environment map: bad size");
    return projectMidpoints(height, width, [&](int v, int u, double, double, double) {
        std::array<double, 3> pixel;
        for (int ch = 0; ch < 3; ++ch) {
            const float p = rgb[(static_cast<std::size_t>(v) * width + u) * 3 + ch];
            if (!std::isfinite(p) || p < 0.0f)
                throw InputError("environment map: pixel (" + std::to_string(u) + ", " + std::to_string(v) +
                                 ") is negative, NaN or Inf");
            pixel[static_cast<std::size_t>(ch)] = p;
        }
        return pixel;
    });
}

void validateKeyLight(const KeyLight& k) {
    auto bad = [](float v) { return !std::isfinite(v); };
    if (bad(k.azimuthDeg) || bad(k.elevationDeg) || bad(k.radiusDeg) || bad(k.rgb[0]) || bad(k.rgb[1]) || bad(k.rgb[2]))
        throw InputError("key light: values must be finite");
    if (k.elevationDeg < -90.0f || k.elevationDeg > 90.0f)
        throw InputError("key light: elevation must be in [-90, 90] degrees");
    if (k.radiusDeg <= 0.0f || k.radiusDeg >= 90.0f) throw InputError("key light: radius must be in (0, 90) degrees");
    if (k.rgb[0] < 0.0f || k.rgb[1] < 0.0f || k.rgb[2] < 0.0f) throw InputError("key light: R,G,B must be >= 0");
}

ShRgb keyLightSh(const KeyLight& k) {
    // ZH of a unit-radiance cap of half-angle r about +z:
    // z_l = 2 pi int_{cos r}^{1} Y_l0(z) dz (Gauss-Legendre, exact: polynomial).
    const double r = k.radiusDeg * kDeg;
    const double c = std::cos(r);
    double x[16], w[16];
    gaussLegendre(16, x, w);
    double zh[kShOrder] = {};
    for (int q = 0; q < 16; ++q) {
        const double z = c + (1.0 - c) * 0.5 * (x[q] + 1.0);
        const double wt = 0.5 * (1.0 - c) * w[q] * 2.0 * kPi;
        const double s = std::sqrt(std::max(0.0, 1.0 - z * z));
        double y[kShCount];
        shEvaluate(s, 0.0, z, y);
        for (int l = 0; l < kShOrder; ++l) zh[l] += wt * y[shIndex(l, 0)];
    }
    const double az = k.azimuthDeg * kDeg, el = k.elevationDeg * kDeg;
    double rot[kShCount];
    shRotateZonal(zh, std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el), rot);
    const double sr = std::sin(r);
    ShRgb l;
    for (int ch = 0; ch < 3; ++ch)
        for (int i = 0; i < kShCount; ++i)
            l.c[static_cast<std::size_t>(ch)][static_cast<std::size_t>(i)] = rot[i] * k.rgb[ch] / (sr * sr);
    return l;
}

KeyLightExtent keyLightExtent(const KeyLight& k) {
    const double az = k.azimuthDeg * kDeg, el = k.elevationDeg * kDeg, r = k.radiusDeg * kDeg;
    KeyLightExtent e;
    double half = kPi;
    if (std::abs(el) + r < 0.5 * kPi) half = std::asin(std::min(1.0, std::sin(r) / std::cos(el)));
    e.phiStart = az - half;
    e.phiEnd = az + half;
    e.sinLow = static_cast<float>(std::sin(std::max(-0.5 * kPi, el - r)));
    e.sinHigh = static_cast<float>(std::sin(std::min(0.5 * kPi, el + r)));
    return e;
}

void evaluateShRgb(const ShRgb& l, double x, double y, double z, double out[3]) {
    double yv[kShCount];
    shEvaluate(x, y, z, yv);
    for (int ch = 0; ch < 3; ++ch) {
        double s = 0.0;
        for (int i = 0; i < kShCount; ++i) s += l.c[static_cast<std::size_t>(ch)][static_cast<std::size_t>(i)] * yv[i];
        out[ch] = s;
    }
}

}  // namespace terrain::gi
