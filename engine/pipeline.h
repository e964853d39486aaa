#pragma once
// One animated frame on the CPU: simulation ticks -> GI frame (gi/frame.h) ->
// the per-texel data the renderer uploads (engine/frame_data.h). Shared by
// `terrain render`, the window demo, the tests and the benchmark.
#include <array>
#include <cstdint>
#include <vector>

#include "engine/frame_data.h"
#include "engine/light_rig.h"
#include "engine/material_maps.h"
#include "gi/frame.h"
#include "sim/scene.h"

namespace terrain::engine {

/// The engine's GI settings with one indirect bounce.
gi::GiSettings defaultPipelineGi();

struct PipelineSettings {
    // Sub-sampling, bounces (used by LightingMode::Global only) and shading
    // amortisation live here; one indirect bounce by default.
    gi::GiSettings gi = defaultPipelineGi();
    LightingMode lighting = LightingMode::Direct;
    int pyramidLevel = 4;   // pyramid level exposed to the debug view
    int ticksPerFrame = 0;  // 0 = the scene's default pacing
    // Vertical exaggeration of what is lit and drawn (GI, shadow map and mesh
    // all see the same surface); 0 = automatic: relief at least 15 % of the
    // extent (the waves bay is 512 m wide and 18 m deep).
    float verticalExaggeration = 0.0f;
    // Pack the hydrology maps for the debug views (FrameData::hydrology);
    // off by default: it costs a pass over the grid per tick drawn.
    bool hydrologyMaps = false;
};

/// Milliseconds of one frame per stage.
struct StageTimings {
    double sim = 0, pyramids = 0, scan = 0, integrate = 0, shade = 0, render = 0;
    double total() const { return sim + pyramids + scan + integrate + shade + render; }
};

class FramePipeline {
public:
    /// Lights and materials come from the scene (its `lights` and `materials`).
    FramePipeline(const SceneSettings& scene, const PipelineSettings& settings);

    /// Advances the simulation by one frame's ticks and the time of day by
    /// one frame; the first call runs the scene's spin-up instead.
    void advance();
    /// Runs GI on the current terrain and fills frame().
    void light();

    PipelineSettings& settings() { return settings_; }
    const PipelineSettings& settings() const { return settings_; }
    /// The lights as declared, and this frame's (the sun moved to its time of day).
    const LightSet& lightSpec() const { return rig_.spec(); }
    const SceneLights& lights() const { return lights_; }
    /// Replaces the declared lights (validated; an image environment is read
    /// here); the next light() uses them.
    void setLights(const LightSet& lights);
    /// Frames advanced since the first (the sun's clock).
    int frameIndex() const { return frameIndex_; }
    /// The materials the maps are derived from (the scene's at start).
    const MaterialSet& materials() const { return materials_; }
    /// Replaces them (validated); the next light() derives the maps anew.
    void setMaterials(const MaterialSet& materials);
    /// The per-texel maps of the last light() (the GI's albedo and the renderer's base colour).
    const MaterialMaps& materialMaps() const { return maps_; }
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
    bool updateMaterialMaps();
    const gi::KeyLight* shadeFirstKey(const gi::GiSettings& gs, const gi::GiLighting& lighting);

    Simulation sim_;
    PipelineSettings settings_;
    LightRig rig_;
    SceneLights lights_;
    int frameIndex_ = 0;
    int ticksPerFrame_ = 1;
    float autoExaggeration_ = 1.0f;
    bool first_ = true;
    float lastExaggeration_ = -1.0f;  // exaggeration of the last lit frame (a change moves the surface)
    int packedPyramidLevel_ = -2;     // the debug level in the packed receiver data (-2: none packed yet)
    Grid surface_;                    // ground + water: what the light sees
    MaterialSet materials_;
    MaterialMaps maps_;
    std::int64_t mapsTick_ = -1;       // the tick the maps were derived at (-1: to derive)
    std::int64_t heightsTick_ = -1;    // the tick frame_.heights holds (-1: to pack)
    std::int64_t hydrologyTick_ = -1;  // the tick frame_.hydrology holds (-1: to pack)
    gi::GiState gi_;
    gi::ShadeMaps keyScratch_;     // buffers of the key light's own shading
    std::array<Grid, 3> keyOnly_;  // the key light's shade alone (white albedo)
    FrameData frame_;
    StageTimings timings_;
};

}  // namespace terrain::engine
