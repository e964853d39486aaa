#pragma once
// What a scene's surface is made of: the materials it declares and the rules
// that say where each one lies. Plain data: the frame pipeline derives
// per-texel albedo and Phong exponent maps from these rules and the terrain
// state every frame (engine/material_maps.h), and the GI bounces and the
// renderer's base colour both read those maps.
//
// The rules, applied in this order at every texel (altitude = ground height,
// bedrock + soil, in metres; slope from the ground's central differences):
//   1. bedrock, covered by soil as the soil layer thickens
//      (smoothstep from 0 to soil.coverDepth);
//   2. vegetation where the altitude lies in its band and the slope is below
//      its limit (faded over altitudeFade metres, and from the limit to
//      kSlopeFadeDeg degrees above it, smoothly in the slope's tangent);
//   3. snow above the snow line on slopes below its limit (faded likewise);
//   4. wet ground where water stands: albedo times wet.darkening, reached at
//      wet.depth metres of water;
//   5. water: the ground seen through the water body, a two-layer diffuse
//      mix, ground weight exp(-2 depth / water.clarity) (down and back up);
//   6. foam (when enabled) in the swash zone: shallow water whose depth
//      changes fast across the ground (the sea thinning out over a beach,
//      the fronts of waves running up it); a film flowing down a slope keeps
//      its depth and stays clear.
// Albedos blend linearly, Phong exponents geometrically (lobe widths).
#include <array>
#include <string>

namespace terrain {

/// A surface material: linear (not sRGB) diffuse albedo and a Phong exponent
/// S (the glossy lobe, gi/ Section 7; the renderer's specular roughness).
struct Material {
    std::array<float, 3> albedo{0.3f, 0.3f, 0.3f};
    float phongExponent = 10.0f;
};

struct SoilRule {
    Material material;
    float coverDepth = 0.5f;  // m of soil that hides the bedrock entirely
};

struct VegetationRule {
    Material material;
    bool enabled = false;
    float minAltitude = -1.0e9f, maxAltitude = 1.0e9f;  // m
    float altitudeFade = 100.0f;                        // m over which the cover fades at each end
    float maxSlopeDeg = 35.0f;                          // steeper ground is bare
};

struct SnowRule {
    Material material;
    bool enabled = false;
    float line = 1.0e9f;          // m: snow above this altitude
    float altitudeFade = 100.0f;  // m over which it thickens above the line
    float maxSlopeDeg = 45.0f;    // steeper rock holds no snow
};

struct WetRule {
    float darkening = 0.6f;       // albedo factor of soaked ground
    float depth = 0.01f;          // m of water at which the ground is soaked
    float phongExponent = 40.0f;  // a wet surface is glossier
};

struct WaterRule {
    Material material;     // the water body's own diffuse reflectance
    float clarity = 1.5f;  // m: depth scale of the light that reaches the bed
};

struct FoamRule {
    Material material{{0.75f, 0.77f, 0.78f}, 20.0f};
    bool enabled = false;
    float maxDepth = 0.5f;           // m: none in deeper water (fading from half this depth)
    float minDepthGradient = 0.02f;  // m per m: full foam from 2.5 times this
};

struct MaterialSet {
    Material bedrock{{0.26f, 0.25f, 0.24f}, 10.0f};
    SoilRule soil;
    VegetationRule vegetation;
    SnowRule snow;
    WetRule wet;
    WaterRule water;
    FoamRule foam;
};

/// Degrees over which the slope limits fade in.
inline constexpr float kSlopeFadeDeg = 5.0f;

/// Throws InputError naming the first value out of range (albedo in [0, 1],
/// exponents in [1, 10000], depths and fades positive, slopes in [0, 90],
/// altitude bands ordered, darkening in [0, 1]).
void validateMaterials(const MaterialSet& m);

/// Materials of the built-in scenes ("erosion", "waves", "dem"); for any
/// other name the defaults: bedrock and soil, no vegetation, no snow.
MaterialSet builtinMaterials(const std::string& scene);

}  // namespace terrain
