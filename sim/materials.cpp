#include "sim/materials.h"

#include <cmath>

#include "core/error.h"
#include "core/parse.h"

namespace terrain {
namespace {

void requireIn(const std::string& what, float v, float lo, float hi) {
    if (!(v >= lo && v <= hi))
        throw InputError("material " + what + " = " + formatNumber(v) + " is out of range [" + formatNumber(lo) + ", " +
                         formatNumber(hi) + "]");
}

void requirePositive(const std::string& what, float v) {
    if (!(v > 0.0f) || !std::isfinite(v))
        throw InputError("material " + what + " = " + formatNumber(v) + " must be a positive number");
}

void validateMaterial(const std::string& name, const Material& m) {
    for (int c = 0; c < 3; ++c) requireIn(name + ".albedo", m.albedo[static_cast<std::size_t>(c)], 0.0f, 1.0f);
    requireIn(name + ".exponent", m.phongExponent, 1.0f, 10000.0f);
}

void validateBand(const std::string& name, float lo, float hi) {
    if (!std::isfinite(lo) || !std::isfinite(hi) || !(lo < hi))
        throw InputError("material " + name + ": min_altitude must be below max_altitude");
}

// Linear reflectance of an sRGB-looking colour picked to match a measured
// broadband albedo: each channel scaled so that the luminance is `albedo`.
Material withLuminance(std::array<float, 3> tint, float albedo, float exponent) {
    const float lum = 0.2126f * tint[0] + 0.7152f * tint[1] + 0.0722f * tint[2];
    for (float& c : tint) c *= albedo / lum;
    return {tint, exponent};
}

}  // namespace

void validateMaterials(const MaterialSet& m) {
    validateMaterial("bedrock", m.bedrock);
    validateMaterial("soil", m.soil.material);
    requirePositive("soil.cover_depth", m.soil.coverDepth);
    validateMaterial("vegetation", m.vegetation.material);
    validateBand("vegetation", m.vegetation.minAltitude, m.vegetation.maxAltitude);
    requirePositive("vegetation.altitude_fade", m.vegetation.altitudeFade);
    requireIn("vegetation.max_slope", m.vegetation.maxSlopeDeg, 0.0f, 90.0f);
    validateMaterial("snow", m.snow.material);
    if (!std::isfinite(m.snow.line)) throw InputError("material snow.line must be a finite altitude");
    requirePositive("snow.altitude_fade", m.snow.altitudeFade);
    requireIn("snow.max_slope", m.snow.maxSlopeDeg, 0.0f, 90.0f);
    requireIn("wet.darkening", m.wet.darkening, 0.0f, 1.0f);
    requirePositive("wet.depth", m.wet.depth);
    requireIn("wet.exponent", m.wet.phongExponent, 1.0f, 10000.0f);
    validateMaterial("water", m.water.material);
    requirePositive("water.clarity", m.water.clarity);
    validateMaterial("foam", m.foam.material);
    requirePositive("foam.max_depth", m.foam.maxDepth);
    requirePositive("foam.min_gradient", m.foam.minDepthGradient);
}

// Albedos: typical broadband values (Oke 1987, "Boundary Layer Climates",
// Table 1.1: dry sand 0.35-0.45, soils 0.05-0.40 (darker when wet), grass
// 0.16-0.26, fresh snow 0.75-0.95, water 0.03-0.10 mostly as specular
// reflection) set as the luminance of a plausible tint; vegetation at its
// visible-band reflectance (chlorophyll absorbs the red and the blue, a
// green peak near 0.1), which is what a camera sees. Phong exponents: rough
// diffuse materials low, snow and wet ground glossier, water sharp.
MaterialSet builtinMaterials(const std::string& scene) {
    MaterialSet m;
    m.bedrock = withLuminance({0.30f, 0.29f, 0.28f}, 0.25f, 10.0f);        // granite / gneiss
    m.soil.material = withLuminance({0.36f, 0.27f, 0.18f}, 0.22f, 6.0f);   // dry brown soil
    m.vegetation.material = {{0.045f, 0.095f, 0.030f}, 4.0f};              // meadow and forest
    m.snow.material = withLuminance({0.93f, 0.95f, 1.00f}, 0.85f, 30.0f);  // old to fresh snow
    m.water.material = {{0.012f, 0.035f, 0.045f}, 400.0f};                 // the body's own scattering
    if (scene == "erosion") {
        // 90-490 m noise mountains: meadows in the valleys, snow on the tops
        m.vegetation.maxAltitude = 330.0f;
        m.vegetation.altitudeFade = 40.0f;
        m.vegetation.maxSlopeDeg = 28.0f;
        m.snow.line = 400.0f;
        m.snow.altitudeFade = 30.0f;
        m.snow.maxSlopeDeg = 35.0f;
        m.water.clarity = 0.5f;  // rain water carrying sediment
    } else if (scene == "waves") {
        // a bay: sand under and beside the water, grass above the beach
        m.bedrock = withLuminance({0.80f, 0.70f, 0.52f}, 0.40f, 8.0f);  // dry sand
        m.soil.material = m.bedrock;
        m.vegetation.minAltitude = 1.2f;
        m.vegetation.altitudeFade = 0.8f;
        m.vegetation.maxSlopeDeg = 30.0f;
        m.wet.darkening = 0.55f;  // wet sand 0.20-0.25 against 0.35-0.45 dry
        m.water.clarity = 3.0f;
        m.foam.enabled = true;  // sea foam: a broadband albedo of about 0.5-0.8 when dense
    } else if (scene == "dem") {
        // the Mont Blanc massif: forest and alpine meadows up to about
        // 2500 m, bare granite above, glaciers and firn above about 2900 m
        m.vegetation.maxAltitude = 2400.0f;
        m.vegetation.altitudeFade = 250.0f;
        m.vegetation.maxSlopeDeg = 35.0f;
        m.snow.line = 2900.0f;
        m.snow.altitudeFade = 250.0f;
        m.snow.maxSlopeDeg = 45.0f;
    } else {
        return MaterialSet{};
    }
    m.vegetation.enabled = true;
    m.snow.enabled = scene != "waves";
    return m;
}

}  // namespace terrain
