#pragma once
// Options shared by `terrain render` and `terrain demo` (its headless
// fallback), and the headless render both run.
#include <cstdint>
#include <optional>
#include <string>

#include <CLI/CLI.hpp>

#include "app/camera_options.h"
#include "app/light_options.h"
#include "core/setting_range.h"
#include "engine/pipeline.h"
#include "render/renderer.h"
#include "render/terrain_lod.h"

namespace terrain::app {

/// --lod's range: up to the renderer's largest screen-space error.
inline constexpr SettingRange<float> kLodRange{"--lod", 0.0f, render::kMaxLodPixelError,
                                               "Level of detail: the mesh's largest screen-space error in pixels"};

/// Options shared by `terrain render` and the demo (its headless fallback).
struct RenderOptions {
    std::string scene = "erosion";
    // given on the command line: over the scene's own (a built-in's default
    // otherwise: 256 cells, seed 1)
    std::optional<int> size;
    std::optional<std::int64_t> seed;
    int frames = 24;
    int width = 1280, height = 720;
    std::string out = "out/render";
    std::string video;  // .mp4 through ffmpeg, when installed
    int threads = 0;
    int ticksPerFrame = 0;            // 0 = the scene's pacing
    int subsample = 2;                // GI receivers every 1, 2 or 4 cells
    std::string lighting = "global";  // key | direct | global (direct + `bounces` indirect bounces)
    int bounces = 1;
    bool amortise = false;
    std::optional<bool> giIncremental;  // given on the command line: over the scene's [gi] table
    std::optional<float> giTolerance;
    std::optional<int> giRefresh;
    std::string shadow = "soft";  // soft | map | none
    std::string debug =
        "none";  // none | ambient | v | key | normals | pyramid | shade | u | albedo | discharge | velocity | net-erosion | wetness
    int pyramidLevel = 4;
    float exposure = 1.0f;
    float exaggeration = 0.0f;   // 0 = automatic
    float lodPixelError = 1.0f;  // render/terrain_lod.h; 0 = the full grid
    bool quiet = false;
    LightOptions lights;   // over the scene's [lights]
    CameraOptions camera;  // over the scene's [camera]
};

/// Adds the options above (except the scene) to a subcommand.
void addRenderOptions(CLI::App* sub, RenderOptions& o, bool withSize);

/// Checks every option on its own (ranges, modes and their combinations)
/// and turns them into pipeline and renderer settings; reads no file, so a
/// bad option fails before any input is read. Throws InputError naming it.
void toSettings(const RenderOptions& o, engine::PipelineSettings& pipeline, render::RenderSettings& renderer);

/// The scene the options name (a scene file is read here), with the size,
/// seed, light and camera options over its own.
SceneSettings resolveRenderScene(const RenderOptions& o);

/// The scene's GI hints where the command line is silent (checked against
/// the GI's ranges, naming the key), and the camera of the first frame.
void applyScene(const RenderOptions& o, const SceneSettings& scene, engine::PipelineSettings& pipeline,
                render::RenderSettings& renderer);

/// The headless render: PNG frames in o.out (atomic writes), a progress bar,
/// the per-stage timing summary and, when asked, an mp4. Returns the exit code.
int runHeadlessRender(const RenderOptions& o, const char* label);

}  // namespace terrain::app
