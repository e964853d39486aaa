#include "engine/material_maps.h"

#include <algorithm>
#include <cmath>

#include "core/parallel.h"
#include "engine/smoothstep.h"

namespace terrain::engine {
namespace {

constexpr float kDegToRad = 0.017453292519943295f;

// A material in the form the rules blend: albedo linearly, the exponent by
// its logarithm (equal steps are equal ratios of the lobe width).
struct Blend {
    std::array<float, 3> albedo;
    float logExponent;
};
Blend blendOf(const Material& m) { return {m.albedo, std::log(m.phongExponent)}; }
void mixInto(Blend& b, const Blend& m, float w) {
    if (w <= 0.0f) return;
    for (std::size_t c = 0; c < 3; ++c) b.albedo[c] += w * (m.albedo[c] - b.albedo[c]);
    b.logExponent += w * (m.logExponent - b.logExponent);
}

// A slope limit as tangents: full cover below tan(limit), none above
// tan(limit + kSlopeFadeDeg), so that a texel needs no arctangent.
struct SlopeLimit {
    float tanFull, tanNone;
    explicit SlopeLimit(float limitDeg)
        : tanFull(std::tan(std::min(limitDeg, 89.9f) * kDegToRad)),
          tanNone(std::tan(std::min(limitDeg + kSlopeFadeDeg, 89.95f) * kDegToRad)) {}
    float cover(float tanSlope) const { return 1.0f - smoothstep(tanFull, tanNone, tanSlope); }
};

// The rules with everything that does not depend on the texel worked out once.
struct Rules {
    const MaterialSet& m;
    Blend bedrock, soil, vegetation, snow, waterBody, foam;
    float logWet;
    SlopeLimit vegetationSlope, snowSlope;
    explicit Rules(const MaterialSet& set)
        : m(set),
          bedrock(blendOf(set.bedrock)),
          soil(blendOf(set.soil.material)),
          vegetation(blendOf(set.vegetation.material)),
          snow(blendOf(set.snow.material)),
          waterBody(blendOf(set.water.material)),
          foam(blendOf(set.foam.material)),
          logWet(std::log(set.wet.phongExponent)),
          vegetationSlope(set.vegetation.maxSlopeDeg),
          snowSlope(set.snow.maxSlopeDeg) {}

    Material at(float altitude, float tanSlope, float soilDepth, float water, float depthGradient) const {
        Blend b = bedrock;
        mixInto(b, soil, smoothstep(0.0f, m.soil.coverDepth, soilDepth));
        if (m.vegetation.enabled) {
            const VegetationRule& v = m.vegetation;
            const float band = smoothstep(v.minAltitude - v.altitudeFade, v.minAltitude, altitude) *
                               (1.0f - smoothstep(v.maxAltitude, v.maxAltitude + v.altitudeFade, altitude));
            mixInto(b, vegetation, band * vegetationSlope.cover(tanSlope));
        }
        if (m.snow.enabled)
            mixInto(b, snow,
                    smoothstep(m.snow.line, m.snow.line + m.snow.altitudeFade, altitude) * snowSlope.cover(tanSlope));
        if (water > 0.0f) {
            const float soaked = smoothstep(0.0f, m.wet.depth, water);
            for (float& a : b.albedo) a *= 1.0f + soaked * (m.wet.darkening - 1.0f);
            b.logExponent += soaked * (logWet - b.logExponent);
            // the bed seen through the water, down and back up
            mixInto(b, waterBody, 1.0f - std::exp(-2.0f * water / m.water.clarity));
            if (m.foam.enabled) {
                const FoamRule& f = m.foam;
                mixInto(b, foam,
                        (1.0f - smoothstep(0.5f * f.maxDepth, f.maxDepth, water)) *
                            smoothstep(f.minDepthGradient, 2.5f * f.minDepthGradient, depthGradient));
            }
        }
        return {b.albedo, std::exp(b.logExponent)};
    }
};

// Ground height (bedrock + soil) of row y of the state.
struct GroundRow {
    const float *rock, *soil;
    float operator[](int x) const { return rock[x] + soil[x]; }
};
GroundRow groundRow(const TerrainState& s, int y) {
    const std::size_t at = static_cast<std::size_t>(y) * s.nx;
    return {s.bedrock.data() + at, s.soil.data() + at};
}

// Magnitude of a field's gradient at (x, y) (the ground's: the tangent of its
// slope) from its row and the rows above and below: central differences,
// one-sided at the edges.
template <class Row>
float tanSlopeAt(const TerrainState& s, const Row& up, const Row& row, const Row& down, int rowSpan, int x) {
    const int x0 = std::max(x - 1, 0), x1 = std::min(x + 1, s.nx - 1);
    const float gx = x1 > x0 ? (row[x1] - row[x0]) / (static_cast<float>(x1 - x0) * s.cellSize) : 0.0f;
    const float gy = rowSpan > 0 ? (down[x] - up[x]) / (static_cast<float>(rowSpan) * s.cellSize) : 0.0f;
    return std::sqrt(gx * gx + gy * gy);
}

}  // namespace

Material materialAt(const MaterialSet& m, float altitude, float slopeDeg, float soil, float water,
                    float depthGradient) {
    return Rules(m).at(altitude, std::tan(slopeDeg * kDegToRad), soil, water, depthGradient);
}

void deriveMaterialMaps(const TerrainState& s, const MaterialSet& m, MaterialMaps& out) {
    for (Grid& g : out.albedo.channel) g.ensureSize(s.nx, s.ny);
    out.exponent.ensureSize(s.nx, s.ny);
    const Rules rules(m);
    parallelForRows(s.ny, s.nx, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) {
            const int ya = std::max(y - 1, 0), yb = std::min(y + 1, s.ny - 1);
            const GroundRow up = groundRow(s, ya), row = groundRow(s, y), down = groundRow(s, yb);
            const std::size_t at = static_cast<std::size_t>(y) * s.nx;
            const float* water = s.hasWater() ? s.water.data() : nullptr;
            const std::size_t nx = static_cast<std::size_t>(s.nx);
            for (int x = 0; x < s.nx; ++x) {
                const float depth = water ? water[at + x] : 0.0f;
                // the depth's gradient only where foam could form
                const float dDepth = water && m.foam.enabled && depth > 0.0f
                                         ? tanSlopeAt(s, water + ya * nx, water + at, water + yb * nx, yb - ya, x)
                                         : 0.0f;
                const Material mat =
                    rules.at(row[x], tanSlopeAt(s, up, row, down, yb - ya, x), row.soil[x], depth, dDepth);
                for (std::size_t c = 0; c < 3; ++c) out.albedo.channel[c].v[at + x] = mat.albedo[c];
                out.exponent.v[at + x] = mat.phongExponent;
            }
        }
    });
}

}  // namespace terrain::engine
