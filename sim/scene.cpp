#include "sim/scene.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>

#include "core/error.h"
#include "core/parallel.h"
#include "sim/heightmap_io.h"
#include "sim/scene_ranges.h"

#ifndef TERRAIN_DATA_DIR
#define TERRAIN_DATA_DIR "../shared/data"
#endif

namespace terrain {
namespace {

std::string defaultDemFile() {
    if (const char* env = std::getenv("TERRAIN_DATA")) return std::string(env) + "/alps-montblanc.png";
    return std::string(TERRAIN_DATA_DIR) + "/alps-montblanc.png";
}

// Bilinear resample keeping the extent: corner samples stay on the corners.
Grid resampleBilinear(const Grid& in, int nx, int ny) {
    Grid out(nx, ny);
    const float sx = nx > 1 ? static_cast<float>(in.nx - 1) / static_cast<float>(nx - 1) : 0.0f;
    const float sy = ny > 1 ? static_cast<float>(in.ny - 1) / static_cast<float>(ny - 1) : 0.0f;
    parallelForRows(ny, nx, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) {
            const float fy = static_cast<float>(y) * sy;
            const int iy = std::min(static_cast<int>(fy), in.ny - 1);
            const int iy1 = std::min(iy + 1, in.ny - 1);
            const float ty = fy - static_cast<float>(iy);
            for (int x = 0; x < nx; ++x) {
                const float fx = static_cast<float>(x) * sx;
                const int ix = std::min(static_cast<int>(fx), in.nx - 1);
                const int ix1 = std::min(ix + 1, in.nx - 1);
                const float tx = fx - static_cast<float>(ix);
                const float a = in(ix, iy) + tx * (in(ix1, iy) - in(ix, iy));
                const float b = in(ix, iy1) + tx * (in(ix1, iy1) - in(ix, iy1));
                out(x, y) = a + ty * (b - a);
            }
        }
    });
    return out;
}

// Tiles of `tile` cells covering `cells`, the last one partial; in 64 bits,
// so that no tile size can overflow the sum.
int tilesAlong(int cells, int tile) { return static_cast<int>((static_cast<std::int64_t>(cells) + tile - 1) / tile); }

// Noise terrain `extent` metres across at any resolution.
void noiseTerrain(SceneSettings& s, float extent, const NoiseSettings& noise) {
    s.cellSize = extent / static_cast<float>(s.nx);
    s.terrain.kind = TerrainSource::Kind::Noise;
    s.terrain.noise = noise;
}

}  // namespace

std::vector<std::string> builtinSceneNames() { return {"erosion", "waves", "dem"}; }

SceneSettings builtinScene(const std::string& name, int size, std::uint64_t seed) {
    checkRange(scene_ranges::kSize, size, "scene size");
    SceneSettings s;
    s.name = name;
    s.nx = s.ny = size;
    s.seed = seed;
    if (name == "erosion") {
        // Noise mountains, 4 km across at any resolution, under rain:
        // hydraulic + thermal erosion carve valleys and fill basins.
        noiseTerrain(s, 4000.0f, {.amplitude = 500.0f, .wavelength = 3000.0f, .octaves = 9, .ridged = true});
        s.soilDepth = 2.0f;
        s.hydraulic = true;
        s.thermal = true;
        // A heavy, steady rain (0.72 m/h) so valleys show within a few
        // thousand ticks; capacity and rates tuned down from the model's
        // defaults so the carving stays gradual at 4-16 m cells.
        s.hydraulicSettings.rainRate = 2.0e-4f;
        s.hydraulicSettings.capacity = 0.2f;
        s.hydraulicSettings.dissolve = 0.3f;
        s.hydraulicSettings.deposit = 0.3f;
        s.thermalSettings.talusAngleDeg = 38.0f;
    } else if (name == "waves") {
        // A 512 m bay: the bottom rises from 8 m deep at -x to a beach and
        // rocky islands at +x; a swell rolls in through the -x edge and drops
        // fall into the bay.
        const float extent = 512.0f;
        noiseTerrain(s, extent, {.amplitude = 6.0f, .wavelength = 140.0f, .octaves = 5, .offset = -3.0f});
        s.terrain.rampStart = -8.0f;
        s.terrain.rampEnd = 4.0f;
        s.hasWaterLevel = true;
        s.waterLevel = 0.0f;
        s.waves = true;
        s.waveSettings.swell.enabled = true;
        s.waveSettings.swell.edge = 0;
        s.waveSettings.swell.amplitude = 0.25f;
        s.waveSettings.swell.period = 6.0f;
        s.waveSettings.swell.seaLevel = s.waterLevel;
        // the swell crosses the bay (at sqrt(g h), about 9 m/s) before the
        // first frame; the drops fall from 2 s into the animation on
        s.spinUp = 40.0f;
        for (int i = 0; i < 4; ++i) {
            WaveDrop d;
            d.time = s.spinUp + 2.0 + 5.0 * i;
            d.x = extent * (0.3f + 0.12f * static_cast<float>(i));
            d.y = extent * (0.25f + 0.17f * static_cast<float>((i * 3) % 4));
            d.radius = 6.0f;
            d.height = 0.6f;
            s.waveSettings.drops.push_back(d);
        }
    } else if (name == "dem") {
        // The Mont Blanc massif (SRTM-3, 60 km across, 454..4810 m) at its true
        // scale, resampled to the requested size; no simulation by default
        // (enable erosion in a scene file with base = "dem").
        s.terrain.kind = TerrainSource::Kind::Dem;
        s.terrain.demFile = defaultDemFile();
        s.terrain.demZScale = (4810.0f - 454.0f) / 65535.0f;
        s.terrain.demZOffset = 454.0f;
        s.terrain.demCellSize = 60000.0f / 647.0f;
        s.cellSize = 60000.0f / static_cast<float>(size);
    } else {
        throw InputError("unknown scene '" + name + "' (built-in scenes: erosion, waves, dem; or a .toml file)");
    }
    s.materials = builtinMaterials(name);
    s.lights = builtinLights(name);
    return s;
}

SceneSettings resolveScene(const std::string& nameOrFile, const SceneOverrides& over) {
    const auto names = builtinSceneNames();
    const bool isFile = std::find(names.begin(), names.end(), nameOrFile) == names.end() && nameOrFile.size() > 5 &&
                        nameOrFile.substr(nameOrFile.size() - 5) == ".toml";
    if (!isFile) {  // a built-in, or an error with the list of names
        SceneSettings s = builtinScene(nameOrFile, over.size.value_or(256), over.seed.value_or(1));
        if (over.dt) s.dt = *over.dt;
        return s;
    }
    SceneSettings s = loadSceneFile(nameOrFile);
    if (over.size && (s.nx != *over.size || s.ny != *over.size)) {
        checkRange(scene_ranges::kSize, *over.size, "scene size");
        // the grid changes, the extent stays
        const float extent = s.cellSize * static_cast<float>(std::max(s.nx, s.ny));
        s.nx = s.ny = *over.size;
        s.cellSize = extent / static_cast<float>(*over.size);
    }
    if (over.seed) s.seed = *over.seed;
    if (over.dt) s.dt = *over.dt;
    return s;
}

SceneSettings resolveScene(const std::string& nameOrFile, int size, std::uint64_t seed) {
    return resolveScene(nameOrFile, SceneOverrides{.size = size, .seed = seed});
}

void buildInitialTerrain(const SceneSettings& s, TerrainState& state, GeoReference* geoOut) {
    LayerSet layers;
    layers.water = s.hydraulic || s.waves || s.hasWaterLevel;
    layers.sediment = s.hydraulic;
    layers.pipes = s.hydraulic;
    layers.faceVelocity = s.waves;
    Grid ground;
    float cellSize = s.cellSize;
    int nx = s.nx, ny = s.ny;
    switch (s.terrain.kind) {
        case TerrainSource::Kind::Noise:
            generateNoise(ground, nx, ny, cellSize, s.seed, s.terrain.noise);
            break;
        case TerrainSource::Kind::Shape:
            generateShape(ground, nx, ny, cellSize, s.terrain.shape);
            break;
        case TerrainSource::Kind::Dem: {
            float fileCell = s.terrain.demCellSize;
            // a cell_size in [terrain] overrides the file's own (a .tif's geotransform, a .vdb's voxels)
            GeoReference geo;
            Grid dem = readHeightmap(s.terrain.demFile, s.terrain.demZScale, s.terrain.demZOffset,
                                     fileCell > 0.0f ? nullptr : &fileCell, &geo);
            if (!(fileCell > 0.0f))
                throw InputError("DEM " + s.terrain.demFile + " needs a cell size (set cell_size in [terrain])");
            if (s.terrain.demResample && (dem.nx != nx || dem.ny != ny)) {
                const float extentX = fileCell * static_cast<float>(dem.nx);
                ground = resampleBilinear(dem, nx, ny);
                cellSize = extentX / static_cast<float>(nx);
            } else {
                ground = std::move(dem);
                nx = ground.nx;
                ny = ground.ny;
                cellSize = fileCell;
            }
            if (geoOut && geo.georeferenced()) *geoOut = geo.withCellSize(cellSize);
            break;
        }
    }
    if (s.terrain.rampStart != 0.0f || s.terrain.rampEnd != 0.0f) {
        const float denom = nx > 1 ? static_cast<float>(nx - 1) : 1.0f;
        for (int y = 0; y < ny; ++y)
            for (int x = 0; x < nx; ++x)
                ground(x, y) +=
                    s.terrain.rampStart + (s.terrain.rampEnd - s.terrain.rampStart) * static_cast<float>(x) / denom;
    }
    state.allocate(nx, ny, cellSize, layers);
    state.bedrock.v = ground.v;
    if (s.soilDepth > 0.0f) std::fill(state.soil.v.begin(), state.soil.v.end(), s.soilDepth);
    if (s.hasWaterLevel && !state.water.empty())
        for (std::size_t i = 0; i < state.water.v.size(); ++i)
            state.water.v[i] = std::max(0.0f, s.waterLevel - (state.bedrock.v[i] + state.soil.v[i]));
    checkFinite(state);
}

Simulation::Simulation(const SceneSettings& settings) : settings_(settings) {
    checkRange(scene_ranges::kChangeTile, settings_.changeTile, "change-tracking tile size");
    checkRange(scene_ranges::kDt, settings_.dt, "time step");
    buildInitialTerrain(settings_, state_, &geo_);
    settings_.nx = state_.nx;
    settings_.ny = state_.ny;
    settings_.cellSize = state_.cellSize;
    dtLimit_ = stableDt();
    if (settings_.dt > 0.0f) {
        dt_ = std::min(settings_.dt, dtLimit_);
        dtClamped_ = settings_.dt > dtLimit_;
    } else {
        dt_ = dtLimit_;
    }
    changes_.tileSize = settings_.changeTile;
    changes_.tilesX = tilesAlong(state_.nx, settings_.changeTile);
    changes_.tilesY = tilesAlong(state_.ny, settings_.changeTile);
    changes_.dirty.assign(static_cast<std::size_t>(changes_.tilesX) * changes_.tilesY, 1);
    changes_.dirtyCount = changes_.tilesX * changes_.tilesY;
    // Ground and water as of the last tick: updateChanges compares against
    // them and writes the new values back in the same pass.
    state_.groundHeight(prevGround_);
    if (!state_.water.empty()) prevWater_ = state_.water;
    hydrology_.start(state_, settings_.hydraulic || settings_.thermal, settings_.hydraulic || settings_.waves);
}

float Simulation::stableDt() const {
    // A scene without simulators still ticks (time advances) at 1 s.
    float limit = 1.0f;
    if (settings_.hydraulic) limit = std::min(limit, hydraulicMaxDt(state_, settings_.hydraulicSettings));
    if (settings_.waves) limit = std::min(limit, waveMaxDt(state_, settings_.waveSettings));
    return limit;
}

void Simulation::tick() {
    const bool simulates = settings_.hydraulic || settings_.thermal || settings_.waves;
    // The tick is fixed. The pipe model's limit does not depend on the state
    // (hydraulic.h), and waveStep cuts a step internally when the current flow
    // exceeds its hard Courant limit (waves.h), so no check is needed here.
    if (settings_.waves) waveStep(state_, settings_.waveSettings, dt_, waveScratch_);
    if (settings_.hydraulic) hydraulicStep(state_, settings_.hydraulicSettings, dt_, hydraulicScratch_);
    if (settings_.thermal) thermalStep(state_, settings_.thermalSettings, dt_, thermalScratch_);
    state_.time += static_cast<double>(dt_);
    lastSubsteps_ = settings_.waves ? waveScratch_.lastSubsteps : 1;
    state_.tick += 1;
    hydrology_.countTick();
    if (simulates)
        updateChanges();
    else {
        std::fill(changes_.dirty.begin(), changes_.dirty.end(), 0);
        changes_.dirtyCount = 0;
        changes_.maxGroundChange = changes_.maxWaterChange = 0.0f;
    }
}

void Simulation::updateChanges() {
    const int ts = changes_.tileSize;
    const int nx = state_.nx, ny = state_.ny;
    std::vector<float>& tileGround = tileGround_;
    std::vector<float>& tileWater = tileWater_;
    tileGround.assign(changes_.dirty.size(), 0.0f);  // capacity kept: no allocation after the first tick
    tileWater.assign(changes_.dirty.size(), 0.0f);
    // One task per row of tiles: each writes only its own tiles.
    parallelFor(0, changes_.tilesY, 1, [&](int t0, int t1) {
        for (int ty = t0; ty < t1; ++ty)
            for (int y = ty * ts; y < std::min(ny, (ty + 1) * ts); ++y) {
                const float* b = state_.bedrock.data() + static_cast<std::size_t>(y) * nx;
                const float* so = state_.soil.data() + static_cast<std::size_t>(y) * nx;
                float* p = prevGround_.data() + static_cast<std::size_t>(y) * nx;
                const float* w = prevWater_.empty() ? nullptr : state_.water.data() + static_cast<std::size_t>(y) * nx;
                float* pw = prevWater_.empty() ? nullptr : prevWater_.data() + static_cast<std::size_t>(y) * nx;
                hydrology_.accumulateRow(y, b, so, p, w);  // before p moves on to this tick's ground
                for (int tx = 0; tx < changes_.tilesX; ++tx) {
                    float mg = 0.0f, mw = 0.0f;
                    const int x1 = std::min(nx, (tx + 1) * ts);
                    for (int x = tx * ts; x < x1; ++x) {
                        const float g = b[x] + so[x];
                        mg = std::max(mg, std::fabs(g - p[x]));
                        p[x] = g;
                    }
                    if (w)
                        for (int x = tx * ts; x < x1; ++x) {
                            mw = std::max(mw, std::fabs(w[x] - pw[x]));
                            pw[x] = w[x];
                        }
                    const std::size_t t = static_cast<std::size_t>(ty) * changes_.tilesX + tx;
                    tileGround[t] = std::max(tileGround[t], mg);
                    tileWater[t] = std::max(tileWater[t], mw);
                }
            }
    });
    changes_.maxGroundChange = 0.0f;
    changes_.maxWaterChange = 0.0f;
    changes_.dirtyCount = 0;
    for (std::size_t t = 0; t < changes_.dirty.size(); ++t) {
        changes_.dirty[t] = tileGround[t] > 0.0f ? 1 : 0;
        changes_.dirtyCount += changes_.dirty[t];
        changes_.maxGroundChange = std::max(changes_.maxGroundChange, tileGround[t]);
        changes_.maxWaterChange = std::max(changes_.maxWaterChange, tileWater[t]);
    }
}

}  // namespace terrain
