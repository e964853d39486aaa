#pragma once
// What the renderer uploads for one frame: plain per-texel arrays filled by
// the frame pipeline (engine/pipeline.h). The OpenGL code sees only this.
//
// Per texel (full resolution unless noted):
//   heights    ground (bedrock + soil) and water depth, m
//   albedo     linear RGB albedo and Phong exponent of the surface (the
//              scene's materials, engine/material_maps.h): the GI's albedo
//              map and the renderer's base colour
//   skyShade   RGB radiance the texel reflects of the environment and of the
//              indirect light (the GI's result with the albedo, minus the
//              key light's share)
//   keyShade   RGB radiance the key light gives a white texel, with the
//              engine's soft visibility V_key (gi/ shading of the key light
//              alone; times the albedo it is the key light's share)
//   keyVisibility  keyShade / unshadowed key light (0..1): the key light's
//              soft visibility, which also modulates the specular term
//   ambient    gi/ ambient map (normal-weighted sky-view factor)
//   and at the receiver resolution: the sky visibility fraction (V's
//   constant term), one height-pyramid level and the mean incident indirect
//   radiance (U's constant term, or E / pi with the blocker-radiance kernel), for debug views.
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "gi/lights.h"

namespace terrain::engine {

/// How the lighting is computed.
enum class LightingMode {
    KeyOnly,  // the key light only (with its visibility), no sky
    Direct,   // sky + key light, each with the engine's soft visibility
    Global,   // direct + `bounces` indirect bounces (gi/indirect.h)
};

/// An equirectangular RGB radiance image (gi/lights.h's convention: column
/// 0 starts at azimuth 0, row 0 is the zenith), 3 floats per pixel.
struct EnvironmentImage {
    int width = 0, height = 0;
    std::vector<float> rgb;
};

/// What the sky behind the terrain looks like.
enum class SkyKind {
    Sh,        // the environment's SH (a uniform sky is exact in SH)
    Gradient,  // the analytic sky: horizon to zenith, linear in sin(elevation); `ground` below
    Image,     // an HDR image (`image`, times `imageScale`)
};

/// The lights of one frame, resolved (engine/light_rig.h).
struct SceneLights {
    gi::ShRgb sky;                   // environment radiance (SH); also the water's reflection map
    std::vector<gi::KeyLight> keys;  // the first is the sun: specular highlights and the shadow map
    SkyKind skyKind = SkyKind::Sh;
    std::array<float, 3> zenith{}, horizon{}, ground{};  // SkyKind::Gradient, radiance
    std::shared_ptr<const EnvironmentImage> image;       // SkyKind::Image
    float imageScale = 1.0f;
    float hazeExtinction = 0.0f;  // per metre of view distance (0: clear air)
};

/// Everything the renderer uploads for one frame.
struct FrameData {
    int nx = 0, ny = 0;
    float cellSize = 1.0f;
    float zMin = 0.0f, zMax = 1.0f;  // ground range of the first frame (camera framing, debug views)
    bool hasWater = false;
    float exaggeration = 1.0f;   // vertical exaggeration (applied by the renderer to the heights)
    std::vector<float> heights;  // 2 per texel: ground, water depth
    std::vector<float> albedo;   // 4 per texel: linear RGB albedo, Phong exponent
    // New, unique in the process, whenever the arrays they name change (a
    // renderer uploads only what changed, and never takes one pipeline's
    // arrays for another's): heights; albedo; shade, key and receiver.
    std::int64_t heightsVersion = 0, albedoVersion = 0, shadeVersion = 0;
    std::vector<float> shade;             // 4 per texel: sky RGB, key visibility
    std::vector<float> key;               // 4 per texel: key RGB, ambient
    int nxr = 0, nyr = 0, subsample = 1;  // receiver grid
    // 4 per texel when PipelineSettings::hydrologyMaps is on (else empty):
    // discharge (m^3/s), velocity (m/s), net erosion (m), wetness
    // (sim/hydrology.h), each 0 where the scene has no such map; and each
    // map's largest magnitude, which the debug views scale by.
    std::vector<float> hydrology;
    std::array<float, 4> hydrologyMax{};
    std::int64_t hydrologyVersion = 0;
    std::vector<float> receiver;  // 4 per receiver: sky visibility fraction, pyramid level height,
        // mean incident indirect radiance (U's constant term, or the irradiance E / pi where the kernel keeps no U; 0 without bounces), 0
    int pyramidLevel = -1;  // level in `receiver` (-1: none built)
    SceneLights lights;
    LightingMode lighting = LightingMode::Direct;
    std::int64_t tick = 0;
    double time = 0.0;  // s, simulated
};

}  // namespace terrain::engine
