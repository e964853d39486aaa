#pragma once
// One animated frame on the CPU: simulation ticks -> GI frame (gi/frame.h) ->
// the per-texel data the renderer uploads. Shared by `terrain render`, the
// window demo, the tests and the benchmark.
//
// What the renderer receives per texel (full resolution unless noted):
//   heights    ground (bedrock + soil) and water depth, m
//   skyShade   RGB radiance the environment (sky) gives a white Lambertian
//              texel, with the engine's soft visibility (gi shade map minus
//              the key light's share)
//   keyShade   RGB radiance the key light gives it, with the engine's soft
//              visibility V_key (gi/ shading of the key light alone)
//   keyVisibility  keyShade / unshadowed key light (0..1): the key light's
//              soft visibility, which also modulates the specular term
//   ambient    gi/ ambient map (normal-weighted sky-view factor)
//   and at the receiver resolution: the sky visibility fraction (V's
//   constant term), one height-pyramid level and the mean incident indirect
//   radiance (U's constant term, or E / pi with the blocker-radiance kernel), for debug views.
#include <array>
#include <cstdint>
#include <vector>

#include "gi/frame.h"
#include "sim/scene.h"

namespace terrain::render {

/// How the lighting is computed.
enum class LightingMode {
    KeyOnly,  // the key light only (with its visibility), no sky
    Direct,   // sky + key light, each with the engine's soft visibility
    Global,   // direct + `bounces` indirect bounces (gi/indirect.h)
};

/// Lights of the demo scenes.
struct SceneLights {
    gi::ShRgb sky;      // environment radiance (SH); also the water's reflection map
    gi::KeyLight key;   // the sun
};
SceneLights defaultLights();

struct PipelineSettings {
    gi::GiSettings gi = gi::engineGiSettings();  // sub-sampling lives here (1, 2, 4)
    LightingMode lighting = LightingMode::Direct;
    int bounces = 1;         // 0..3 indirect bounces in LightingMode::Global
    bool amortise = false;   // Section 7: on static geometry alternate direct / indirect updates
    int pyramidLevel = 4;    // pyramid level exposed to the debug view
    int ticksPerFrame = 0;   // 0 = the scene's default pacing
    // Vertical exaggeration of what is lit and drawn (GI, shadow map and mesh
    // all see the same surface); 0 = automatic: relief at least 15 % of the
    // extent (the waves bay is 512 m wide and 18 m deep).
    float verticalExaggeration = 0.0f;
};

/// Milliseconds of one frame per stage.
struct StageTimings {
    double sim = 0, pyramids = 0, scan = 0, integrate = 0, shade = 0, render = 0;
    double total() const { return sim + pyramids + scan + integrate + shade + render; }
};

/// Everything the renderer uploads for one frame.
struct FrameData {
    int nx = 0, ny = 0;
    float cellSize = 1.0f;
    float zMin = 0.0f, zMax = 1.0f;       // ground range of the first frame (fixed colour ramp)
    bool hasWater = false;
    float exaggeration = 1.0f;            // vertical exaggeration (applied by the renderer to the heights)
    bool coast = false;                   // colour palette: coast (waves scenes) or mountains
    std::vector<float> heights;           // 2 per texel: ground, water depth
    std::vector<float> shade;             // 4 per texel: sky RGB, key visibility
    std::vector<float> key;               // 4 per texel: key RGB, ambient
    int nxr = 0, nyr = 0, subsample = 1;  // receiver grid
    std::vector<float> receiver;          // 4 per receiver: sky visibility fraction, pyramid level height,
                                          // mean incident indirect radiance (U's constant term, or the irradiance E / pi where the kernel keeps no U; 0 without bounces), 0
    int pyramidLevel = -1;                // level in `receiver` (-1: none built)
    SceneLights lights;
    LightingMode lighting = LightingMode::Direct;
    std::int64_t tick = 0;
    double time = 0.0;                    // s, simulated
};

class FramePipeline {
public:
    FramePipeline(const SceneSettings& scene, const PipelineSettings& settings, const SceneLights& lights = defaultLights());

    /// Advances the simulation by one frame's ticks (none for the first frame).
    void advance();
    /// Runs GI on the current terrain and fills frame().
    void light();

    PipelineSettings& settings() { return settings_; }
    const PipelineSettings& settings() const { return settings_; }
    SceneLights& lights() { return lights_; }
    const FrameData& frame() const { return frame_; }
    const Simulation& simulation() const { return sim_; }
    /// For tools and tests that set the ground themselves; call terrainReplaced() after.
    Simulation& simulation() { return sim_; }
    /// Recomputes the colour ramp range and the automatic exaggeration from the current ground.
    void terrainReplaced();
    int ticksPerFrame() const { return ticksPerFrame_; }
    /// Timings of the last advance() + light() (render is filled by the caller).
    StageTimings& timings() { return timings_; }
    const gi::GiState& giState() const { return gi_; }

private:
    Simulation sim_;
    PipelineSettings settings_;
    SceneLights lights_;
    int ticksPerFrame_ = 1;
    float autoExaggeration_ = 1.0f;
    bool first_ = true;
    float lastExaggeration_ = -1.0f;  // exaggeration of the last lit frame (a change moves the surface)
    Grid surface_;          // ground + water: what the light sees
    gi::GiState gi_;
    gi::ShadeMaps keyScratch_;           // buffers of the key light's own shading
    std::array<Grid, 3> keyOnly_;        // the key light's shade alone (white albedo)
    FrameData frame_;
    StageTimings timings_;
};

}  // namespace terrain::render
