#pragma once
// Scenes: what a terrain is made of, which simulators run on it, and the
// fixed time step. A scene runs only the stages it declares (model only what
// a scene needs): no water layers without water, no erosion without erosion.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/geotiff_io.h"
#include "sim/generators.h"
#include "sim/hydraulic.h"
#include "sim/hydrology.h"
#include "sim/materials.h"
#include "sim/scene_camera.h"
#include "sim/scene_lights.h"
#include "sim/terrain.h"
#include "sim/thermal.h"
#include "sim/waves.h"

namespace terrain {

/// Where the initial ground comes from.
struct TerrainSource {
    enum class Kind { Noise, Shape, Dem };
    Kind kind = Kind::Noise;
    NoiseSettings noise;
    ShapeSettings shape;
    std::string demFile;       // .png (16-bit greyscale) or .vdb
    float demZScale = 1.0f;    // m per 16-bit step (PNG only)
    float demZOffset = 0.0f;   // m (PNG only)
    float demCellSize = 0.0f;  // m; 0 = from the .vdb, required for a .png
    bool demResample = true;   // resample the DEM to the scene size keeping its extent
    float rampStart = 0.0f;    // m added at x = 0, going linearly to
    float rampEnd = 0.0f;      // m added at the last column (a tilted coast)
};

/// How a scene asks to be lit by the GI (a scene file's [gi] table). Unset
/// values leave the engine's defaults; command-line options override both.
/// Plain values: the GI checks their ranges when it applies them (the
/// refresh interval as read, before it is narrowed).
struct SceneGiHints {
    std::optional<bool> incremental;           // change-driven GI frames (GiSettings::incremental)
    std::optional<float> tolerance;            // GiSettings::tolerance, shade units
    std::optional<std::int64_t> refreshEvery;  // GiSettings::refreshEvery, frames
};

struct SceneSettings {
    std::string name = "erosion";
    int nx = 256;
    int ny = 256;
    float cellSize = 10.0f;  // m
    std::uint64_t seed = 1;
    TerrainSource terrain;
    float soilDepth = 0.0f;  // m of loose material laid on the generated ground
    bool hasWaterLevel = false;
    float waterLevel = 0.0f;  // m: fill water up to this surface level at start

    bool hydraulic = false;
    bool thermal = false;
    bool waves = false;
    HydraulicSettings hydraulicSettings;
    ThermalSettings thermalSettings;
    WaveSettings waveSettings;

    float dt = 0.0f;  // s; 0 = the default, derived from the CFL limits
    // s of simulated time an animation runs before its first frame (a sea
    // whose swell has already reached the shore); `terrain sim` starts at 0.
    float spinUp = 0.0f;
    int changeTile = 32;  // cells per side of a change-tracking tile
    SceneGiHints gi;
    MaterialSet materials;                // what the surface is made of, where (sim/materials.h)
    LightSet lights = builtinLights("");  // how it is lit (sim/scene_lights.h)
    CameraPath camera;                    // where an animation looks from (sim/scene_camera.h)
};

/// The built-in scenes: "erosion", "waves", "dem". size is the grid side
/// (nx = ny = size). dem uses demFile, or the Mont Blanc DEM in shared/data.
SceneSettings builtinScene(const std::string& name, int size, std::uint64_t seed);

/// Names of the built-in scenes.
std::vector<std::string> builtinSceneNames();

/// Reads a TOML scene file; it may start from a built-in (`base = "erosion"`)
/// and set anything a built-in sets. Unknown keys are errors.
SceneSettings loadSceneFile(const std::string& file);

/// What the command line sets over a scene: only the values it was given,
/// so a scene file keeps every value no flag names.
struct SceneOverrides {
    std::optional<int> size;  // grid side (nx = ny); a file's scene keeps its extent
    std::optional<std::uint64_t> seed;
    std::optional<float> dt;  // s; 0 = from the CFL limits
};

/// A built-in name (size 256 and seed 1 unless overridden), or a path to a
/// .toml scene file, with the overrides over it.
SceneSettings resolveScene(const std::string& nameOrFile, const SceneOverrides& overrides);

/// The same with the size and the seed given.
SceneSettings resolveScene(const std::string& nameOrFile, int size, std::uint64_t seed);

/// What changed in the last tick: per change tile whether the ground moved,
/// and the largest ground and water change. The frame pipeline reads only
/// the maxima today (engine/pipeline.cpp: "did anything move?").
struct ChangeReport {
    int tileSize = 32;
    int tilesX = 0;
    int tilesY = 0;
    std::vector<std::uint8_t> dirty;  // tilesX * tilesY, 1 = the ground changed in the tile
    float maxGroundChange = 0.0f;     // m, largest |d(bedrock + soil)| this tick
    float maxWaterChange = 0.0f;      // m, largest |d water| this tick (0 without water)
    int dirtyCount = 0;
};

/// A running simulation: the terrain state and the fixed-step tick.
class Simulation {
public:
    explicit Simulation(const SceneSettings& settings);

    /// Advances one fixed time step and updates the change report.
    void tick();

    const TerrainState& state() const { return state_; }
    TerrainState& state() { return state_; }
    const SceneSettings& settings() const { return settings_; }
    const ChangeReport& changes() const { return changes_; }
    /// Erosion, deposition and wetness accumulated since the first tick
    /// (sim/hydrology.h): ground maps when the scene erodes (hydraulic or
    /// thermal), wetness when it moves water (hydraulic or waves).
    const HydrologyAccumulator& hydrology() const { return hydrology_; }
    /// Where the terrain lies when it came from a GeoTIFF DEM (else unreferenced).
    const GeoReference& geoReference() const { return geo_; }
    float dt() const { return dt_; }
    /// The CFL-derived limit at start, and whether the requested dt was clamped to it.
    float dtLimit() const { return dtLimit_; }
    bool dtClamped() const { return dtClamped_; }
    /// Internal sub-steps the last tick needed (waves only; 1 normally).
    int lastSubsteps() const { return lastSubsteps_; }

private:
    float stableDt() const;
    void updateChanges();

    SceneSettings settings_;
    TerrainState state_;
    GeoReference geo_;
    HydraulicScratch hydraulicScratch_;
    ThermalScratch thermalScratch_;
    WaveScratch waveScratch_;
    Grid prevGround_, prevWater_;
    std::vector<float> tileGround_, tileWater_;  // per-tile max |dh| of the last tick
    ChangeReport changes_;
    HydrologyAccumulator hydrology_;
    float dt_ = 0.0f;
    float dtLimit_ = 0.0f;
    bool dtClamped_ = false;
    int lastSubsteps_ = 1;
};

/// Builds the initial ground for a scene (exposed for tests and tools). A
/// DEM read from a GeoTIFF gives its place and CRS through geoOut (its
/// pixel size the scene's cell size, after any resampling); any other
/// terrain leaves geoOut unreferenced.
void buildInitialTerrain(const SceneSettings& s, TerrainState& state, GeoReference* geoOut = nullptr);

}  // namespace terrain
