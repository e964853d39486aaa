#include "engine/material_maps.h"

#include <algorithm>
#include <cmath>

#include "core/parallel.h"

namespace terrain::engine {
namespace {

constexpr float kRadToDeg = 57.29577951308232f;

float smoothstep(float e0, float e1, float x) {
    const float t = std::clamp((x - e0) / (e1 - e0), 0.0f, 1.0f);
    return t * t * (3.0f - 2.0f * t);
}

// A material in the form the rules blend: albedo linearly, the exponent by
// its logarithm (equal steps are equal ratios of the lobe width).
struct Blend {
    std::array<float, 3> albedo;
    float logExponent;
};
Blend blendOf(const Material& m) { return {m.albedo, std::log(m.phongExponent)}; }
void mixInto(Blend& b, const Material& m, float w) {
    if (w <= 0.0f) return;
    for (std::size_t c = 0; c < 3; ++c) b.albedo[c] += w * (m.albedo[c] - b.albedo[c]);
    b.logExponent += w * (std::log(m.phongExponent) - b.logExponent);
}

// 1 below the slope limit, fading to 0 over kSlopeFadeDeg above it.
float belowSlope(float slopeDeg, float maxSlopeDeg) {
    return 1.0f - smoothstep(maxSlopeDeg, maxSlopeDeg + kSlopeFadeDeg, slopeDeg);
}

// Slope (degrees) of the ground at (x, y): central differences, one-sided at the edges.
float slopeAt(const TerrainState& s, int x, int y) {
    const int x0 = std::max(x - 1, 0), x1 = std::min(x + 1, s.nx - 1);
    const int y0 = std::max(y - 1, 0), y1 = std::min(y + 1, s.ny - 1);
    const float gx = x1 > x0 ? (s.ground(x1, y) - s.ground(x0, y)) / (static_cast<float>(x1 - x0) * s.cellSize) : 0.0f;
    const float gy = y1 > y0 ? (s.ground(x, y1) - s.ground(x, y0)) / (static_cast<float>(y1 - y0) * s.cellSize) : 0.0f;
    return std::atan(std::sqrt(gx * gx + gy * gy)) * kRadToDeg;
}

}  // namespace

Material materialAt(const MaterialSet& m, float altitude, float slopeDeg, float soil, float water) {
    Blend b = blendOf(m.bedrock);
    mixInto(b, m.soil.material, smoothstep(0.0f, m.soil.coverDepth, soil));
    if (m.vegetation.enabled) {
        const VegetationRule& v = m.vegetation;
        const float band = smoothstep(v.minAltitude - v.altitudeFade, v.minAltitude, altitude) *
                           (1.0f - smoothstep(v.maxAltitude, v.maxAltitude + v.altitudeFade, altitude));
        mixInto(b, v.material, band * belowSlope(slopeDeg, v.maxSlopeDeg));
    }
    if (m.snow.enabled) {
        const SnowRule& v = m.snow;
        mixInto(b, v.material,
                smoothstep(v.line, v.line + v.altitudeFade, altitude) * belowSlope(slopeDeg, v.maxSlopeDeg));
    }
    if (water > 0.0f) {
        const float soaked = smoothstep(0.0f, m.wet.depth, water);
        for (float& a : b.albedo) a *= 1.0f + soaked * (m.wet.darkening - 1.0f);
        b.logExponent += soaked * (std::log(m.wet.phongExponent) - b.logExponent);
        // the bed seen through the water, down and back up
        mixInto(b, m.water.material, 1.0f - std::exp(-2.0f * water / m.water.clarity));
    }
    return {b.albedo, std::exp(b.logExponent)};
}

void deriveMaterialMaps(const TerrainState& s, const MaterialSet& m, MaterialMaps& out) {
    for (Grid& g : out.albedo.channel) g.ensureSize(s.nx, s.ny);
    out.exponent.ensureSize(s.nx, s.ny);
    parallelForRows(s.ny, s.nx, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y)
            for (int x = 0; x < s.nx; ++x) {
                const Material mat =
                    materialAt(m, s.ground(x, y), slopeAt(s, x, y), s.soil(x, y), s.hasWater() ? s.water(x, y) : 0.0f);
                for (std::size_t c = 0; c < 3; ++c) out.albedo.channel[c](x, y) = mat.albedo[c];
                out.exponent(x, y) = mat.phongExponent;
            }
    });
}

}  // namespace terrain::engine
