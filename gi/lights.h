#pragma once
// Lights as order-4 SH (Sections 6, 7).
//
// Environment lights: uniform sky, an analytic sun-and-sky gradient, or an
// HDR equirectangular image, each projected once to 3 x 16 SH coefficients
// (RGB radiance). Equirectangular convention: column u covers azimuth
// phi = 2 pi (u + 0.5) / W from +x towards +y; row v covers elevation from
// +90 deg (row 0) to -90 deg (last row).
//
// Key lights: spherical caps (direction, angular radius, RGB). R,G,B is the
// shade an unoccluded surface of albedo 1 facing the light receives from it:
// irradiance pi * RGB at normal incidence. Each key light gets its own
// visibility from 3 azimuths over its azimuthal extent, restricted to its
// elevation interval (Section 6); the shading stage lights that region with
// the radiance that gives the same irradiance (gi/frame.cpp). keyLightSh is
// the cap as an SH light (radiance RGB / sin^2(radius)), for folding a key
// light into an environment (e.g. the reference renderer).
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "gi/sh.h"

namespace terrain::gi {

/// RGB radiance as three SH vectors.
struct ShRgb {
    std::array<ShVector, 3> c{};
};

/// Radiance `radiance` from every direction: Y00 coefficient sqrt(4 pi) * radiance.
ShRgb uniformSkyLight(float radiance = 1.0f);

struct SunSkySettings {
    float zenith[3] = {0.30f, 0.45f, 0.85f};   // sky radiance straight up
    float horizon[3] = {0.85f, 0.90f, 1.00f};  // sky radiance at the horizon
    float ground[3] = {0.10f, 0.09f, 0.08f};   // radiance below the horizon
    float sunAzimuthDeg = 135.0f;
    float sunElevationDeg = 35.0f;
    float sun[3] = {3.0f, 2.8f, 2.5f};  // peak radiance of the sun lobe
    float sunSharpness = 40.0f;         // lobe exp(k (cos - 1))
};
/// Sky gradient (horizon to zenith, linear in sin(elevation)) plus a smooth
/// sun lobe, projected by dense quadrature.
ShRgb sunSkyLight(const SunSkySettings& s = {});

/// Projects an equirectangular RGB image (3 floats per pixel, row 0 first).
/// Throws InputError on non-finite or negative pixels.
ShRgb projectEquirect(const std::vector<float>& rgb, int width, int height);

struct KeyLight {
    float azimuthDeg = 0.0f;     // from +x towards +y
    float elevationDeg = 45.0f;  // from the horizon up
    float radiusDeg = 5.0f;      // angular radius of the cap (> 0, < 90)
    float rgb[3] = {1.0f, 1.0f, 1.0f};
};

/// SH radiance of the cap (zonal cap turned to the light direction).
ShRgb keyLightSh(const KeyLight& k);

/// Azimuthal extent and elevation interval of a key light (Section 6).
struct KeyLightExtent {
    double phiStart = 0.0, phiEnd = 0.0;   // radians
    float sinLow = -1.0f, sinHigh = 1.0f;  // sines of the elevation interval
};
KeyLightExtent keyLightExtent(const KeyLight& k);

/// Throws InputError when a key light's parameters are out of range.
void validateKeyLight(const KeyLight& k);

/// Evaluates an SH RGB radiance in direction d.
void evaluateShRgb(const ShRgb& l, double x, double y, double z, double out[3]);

/// True when a and b cover the same region of the sky (direction and size):
/// a key light's visibility depends on that alone, not on its radiance.
inline bool sameSkyRegion(const KeyLight& a, const KeyLight& b) {
    return a.azimuthDeg == b.azimuthDeg && a.elevationDeg == b.elevationDeg && a.radiusDeg == b.radiusDeg;
}

/// The analytic sky as a function of direction (sunSkyLight's gradient,
/// without its sun lobe): radiance horizon + (zenith - horizon) sin(elevation)
/// above the horizontal, `ground` below it.
struct SkyGradient {
    std::array<float, 3> zenith{}, horizon{}, ground{};
    bool operator==(const SkyGradient&) const = default;
};

/// The lights of a GI frame: an environment and any number of key lights.
struct GiLighting {
    ShRgb environment = uniformSkyLight(1.0f);
    std::vector<KeyLight> keys;
    // When the environment is the analytic sky: its function, of which
    // `environment` is the SH projection (engine::LightRig sets both). A
    // Lambert shade with the exact ambient (AmbientMethod::Horizons) then
    // integrates the function itself above each azimuth's horizon
    // (gi/ambient_horizon.h) instead of its order-4 SH; everything else
    // reads `environment`.
    std::optional<SkyGradient> gradient;
};

}  // namespace terrain::gi
