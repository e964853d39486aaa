#include "engine/pipeline.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>

#include "core/error.h"
#include "core/parallel.h"
#include "sim/hydrology.h"

namespace terrain::engine {
namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

constexpr float kDeg = 0.017453292519943295f;

// The light sees the surface: ground, and water where there is water.
void exaggeratedSurface(const TerrainState& s, float exag, Grid& surface) {
    const int nx = s.nx, ny = s.ny;
    surface.ensureSize(nx, ny);
    parallelForRows(ny, nx, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y)
            for (int x = 0; x < nx; ++x)
                surface(x, y) = exag * (s.ground(x, y) + (s.hasWater() ? s.water(x, y) : 0.0f));
    });
}

// A version number for FrameData, unique in the process.
std::int64_t nextVersion() {
    static std::atomic<std::int64_t> versions{0};
    return ++versions;
}

// The hydrology maps of the debug views, 4 per texel (engine/frame_data.h),
// and each map's largest magnitude; a map the scene lacks stays 0.
void packHydrology(const Simulation& sim, FrameData& f) {
    const TerrainState& s = sim.state();
    const HydrologyAccumulator& h = sim.hydrology();
    std::array<Grid, 4> maps;
    for (Grid& g : maps) g.resize(s.nx, s.ny);
    if (hasWaterFlow(s)) {
        dischargeMap(s, maps[0]);
        velocityMap(s, maps[1]);
    }
    if (h.tracksGround()) h.netErosionMap(maps[2]);
    if (h.tracksWater()) h.wetnessMap(maps[3]);
    f.hydrology.resize(4 * maps[0].size());
    f.hydrologyMax = {};
    for (std::size_t i = 0; i < maps[0].size(); ++i)
        for (std::size_t m = 0; m < 4; ++m) {
            f.hydrology[4 * i + m] = maps[m].v[i];
            f.hydrologyMax[m] = std::max(f.hydrologyMax[m], std::fabs(maps[m].v[i]));
        }
    f.hydrologyVersion = nextVersion();
}

// Ground and water depth of every texel (they may move apart while their
// sum, the lit surface, stays: packed whenever the terrain ticked).
void packHeights(const TerrainState& s, FrameData& f) {
    const int nx = s.nx, ny = s.ny;
    f.heights.resize(2 * static_cast<std::size_t>(nx) * ny);
    parallelForRows(ny, nx, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y)
            for (int x = 0; x < nx; ++x) {
                const std::size_t i = static_cast<std::size_t>(y) * nx + x;
                f.heights[2 * i] = s.ground(x, y);
                f.heights[2 * i + 1] = s.hasWater() ? s.water(x, y) : 0.0f;
            }
    });
}

// Per texel: the shade without the key light's share and the key light's
// own shade of a white texel; its soft visibility and the ambient map.
// `total` is the GI's result with the albedo, so the key light's share of it
// is the albedo times keyRgb.
void packTexels(const gi::GiState& gi, const std::array<Grid, 3>& total, const std::array<Grid, 3>& keyRgb,
                const gi::AlbedoMap& albedo, const gi::KeyLight* key, FrameData& f) {
    const int nx = total[0].nx, ny = total[0].ny;
    const std::size_t n = static_cast<std::size_t>(nx) * ny;
    f.shade.resize(4 * n);
    f.key.resize(4 * n);
    const gi::KeyLight k = key ? *key : gi::KeyLight{};
    const float ce = std::cos(k.elevationDeg * kDeg);
    const float lx = ce * std::cos(k.azimuthDeg * kDeg), ly = ce * std::sin(k.azimuthDeg * kDeg);
    const float lz = std::sin(k.elevationDeg * kDeg);
    const float keyLum = key ? 0.2126f * k.rgb[0] + 0.7152f * k.rgb[1] + 0.0722f * k.rgb[2] : 0.0f;
    parallelForRows(ny, nx, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y)
            for (int x = 0; x < nx; ++x) {
                const std::size_t i = static_cast<std::size_t>(y) * nx + x;
                float keyC[3];
                for (std::size_t c = 0; c < 3; ++c) {
                    keyC[c] = std::max(0.0f, keyRgb[c].v[i]);
                    f.shade[4 * i + c] = std::max(0.0f, total[c].v[i] - albedo.channel[c].v[i] * keyRgb[c].v[i]);
                    f.key[4 * i + c] = keyC[c];
                }
                // Soft visibility of the key light: its shade over the unshadowed N.L shade.
                const float gx = gi.gradX.v[i], gy = gi.gradY.v[i];
                const float nl = (-gx * lx - gy * ly + lz) / std::sqrt(gx * gx + gy * gy + 1.0f);
                const float lum = 0.2126f * keyC[0] + 0.7152f * keyC[1] + 0.0722f * keyC[2];
                const float vis = nl > 0.02f && keyLum > 0.0f ? std::clamp(lum / (keyLum * nl), 0.0f, 1.0f) : 0.0f;
                f.shade[4 * i + 3] = vis;
                f.key[4 * i + 3] = gi.shade.ambient.v[i];
            }
    });
}

// Albedo and Phong exponent of every texel.
void packAlbedo(const MaterialMaps& maps, FrameData& f) {
    const std::size_t n = maps.exponent.v.size();
    f.albedo.resize(4 * n);
    parallelFor(0, static_cast<int>(maps.exponent.ny), 1, [&](int y0, int y1) {
        const std::size_t a = static_cast<std::size_t>(y0) * maps.exponent.nx;
        const std::size_t e = static_cast<std::size_t>(y1) * maps.exponent.nx;
        for (std::size_t i = a; i < e; ++i) {
            for (std::size_t c = 0; c < 3; ++c) f.albedo[4 * i + c] = maps.albedo.channel[c].v[i];
            f.albedo[4 * i + 3] = maps.exponent.v[i];
        }
    });
    f.albedoVersion = nextVersion();
}

// Receiver grid: sky visibility fraction (V_00 sqrt(4 pi) / 2 pi), one
// pyramid level and the mean incident indirect radiance.
void packReceivers(const gi::GiState& gi, const Grid& surface, const PipelineSettings& settings, float exag,
                   bool indirect, FrameData& f) {
    const int nx = surface.nx, ny = surface.ny;
    const gi::VisibilityField& v = gi.envVisibility;
    f.nxr = v.nxr;
    f.nyr = v.nyr;
    f.subsample = settings.gi.subsample;
    f.receiver.resize(4 * static_cast<std::size_t>(v.nxr) * v.nyr);
    const int levels = static_cast<int>(gi.pyramid.levels.size());
    f.pyramidLevel = levels > 0 ? std::clamp(settings.pyramidLevel, 0, levels - 1) : -1;
    const float vScale = static_cast<float>(std::sqrt(4.0 * gi::kPi) / (2.0 * gi::kPi));
    // U's constant term: the mean incident indirect radiance U_00 / sqrt(4 pi) (luminance)
    const float uScale = static_cast<float>(1.0 / std::sqrt(4.0 * gi::kPi));
    const auto& u = gi.indirect.u;
    const bool hasU = indirect && u[0].nxr == v.nxr && u[0].nyr == v.nyr && !u[0].sh.empty();
    // LambertIndirect::BlockerRadiance keeps no U: its receivers' irradiance / pi instead
    const auto& eRecv = gi.indirect.blocker.receiverShade;
    const bool hasE = indirect && !hasU && eRecv[0].size() == static_cast<std::size_t>(v.nxr) * v.nyr;
    for (int y = 0; y < v.nyr; ++y)
        for (int x = 0; x < v.nxr; ++x) {
            const std::size_t i = static_cast<std::size_t>(y) * v.nxr + x;
            f.receiver[4 * i] = v.plane(0)[i] * vScale;
            float level = surface(std::min(x * f.subsample, nx - 1), std::min(y * f.subsample, ny - 1)) / exag;
            if (f.pyramidLevel >= 0) {
                const gi::PaddedField& p = gi.pyramid.levels[static_cast<std::size_t>(f.pyramidLevel)];
                if (x < p.nx && y < p.ny) level = p.row(y)[x] / exag;
            }
            f.receiver[4 * i + 1] = level;
            f.receiver[4 * i + 2] =
                hasU   ? uScale * (0.2126f * u[0].plane(0)[i] + 0.7152f * u[1].plane(0)[i] + 0.0722f * u[2].plane(0)[i])
                : hasE ? 0.2126f * eRecv[0][i] + 0.7152f * eRecv[1][i] + 0.0722f * eRecv[2][i]
                       : 0.0f;
            f.receiver[4 * i + 3] = 0.0f;
        }
}

// gi/'s timings of the frame in the pipeline's stages (sim and render are not gi/'s).
void recordGiTimings(const gi::GiState& gi, const gi::GiSettings& gs, double surfaceMs, double packMs,
                     StageTimings& timings) {
    const gi::GiTimings& g = gi.timings;
    // Indirect light's own radiance pyramids, casting-set scans and shading go
    // into the matching stages (zero on frames that did not update it).
    const gi::IndirectTimings& ind = gi.indirect.timings;
    const bool indirectRan = gs.indirect.bounces > 0 && g.indirect > 0.0;
    timings.pyramids = g.gradient + g.pyramid + (indirectRan ? ind.pyramid : 0.0);
    timings.scan = g.visibility + g.keyVisibility + (indirectRan ? ind.scan : 0.0);
    timings.integrate = 0.0;  // gi/ fuses the wedge integration into the scan
    timings.shade = g.shading + (indirectRan ? ind.shading : 0.0) + packMs + (surfaceMs - g.total);
    timings.render = 0.0;
}

}  // namespace

gi::GiSettings defaultPipelineGi() {
    gi::GiSettings s = gi::GiSettings{};
    s.indirect.bounces = 1;
    return s;
}

FramePipeline::FramePipeline(const SceneSettings& scene, const PipelineSettings& settings)
    : sim_(scene), settings_(settings), rig_(scene.lights), materials_(scene.materials) {
    gi::validateGiSettings(settings_.gi);
    validateMaterials(materials_);
    if (settings_.ticksPerFrame < 0) throw InputError("ticks per frame must be >= 0");
    ticksPerFrame_ = settings_.ticksPerFrame;
    if (ticksPerFrame_ == 0) {
        // Erosion needs many ticks per frame to show change; waves ~0.25 s of water per frame.
        if (scene.waves)
            ticksPerFrame_ = std::max(1, static_cast<int>(0.25f / sim_.dt()));
        else if (scene.hydraulic || scene.thermal)
            ticksPerFrame_ = 60;
        else
            ticksPerFrame_ = 1;
    }
    terrainReplaced();
}

void FramePipeline::terrainReplaced() {
    const TerrainState& s = sim_.state();
    frame_.nx = s.nx;
    frame_.ny = s.ny;
    frame_.cellSize = s.cellSize;
    frame_.hasWater = s.hasWater();
    float lo = s.ground(0, 0), hi = lo;
    for (int y = 0; y < s.ny; ++y)
        for (int x = 0; x < s.nx; ++x) {
            lo = std::min(lo, s.ground(x, y));
            hi = std::max(hi, s.ground(x, y));
        }
    frame_.zMin = lo;
    frame_.zMax = hi > lo ? hi : lo + 1.0f;
    const float extent = static_cast<float>(std::max(s.nx, s.ny) - 1) * s.cellSize;
    autoExaggeration_ = std::clamp(0.15f * extent / (frame_.zMax - frame_.zMin), 1.0f, 10.0f);
    mapsTick_ = -1;
    heightsTick_ = -1;
    hydrologyTick_ = -1;
}

void FramePipeline::setLights(const LightSet& lights) { rig_ = LightRig(lights, &rig_); }

void FramePipeline::setMaterials(const MaterialSet& materials) {
    validateMaterials(materials);
    materials_ = materials;
    mapsTick_ = -1;
}

void FramePipeline::advance() {
    const auto t0 = Clock::now();
    if (!first_) {
        for (int t = 0; t < ticksPerFrame_; ++t) sim_.tick();
        ++frameIndex_;
    } else {
        // the scene's spin-up: the first frame shows it already running
        const double spinUp = sim_.settings().spinUp;
        while (sim_.state().time < spinUp) sim_.tick();
    }
    first_ = false;
    timings_.sim = msSince(t0);
}

// The materials follow the terrain: derived again only when it ticked (or
// was replaced, or the materials changed). Returns whether they were.
bool FramePipeline::updateMaterialMaps() {
    const TerrainState& s = sim_.state();
    if (mapsTick_ == s.tick) return false;
    deriveMaterialMaps(s, materials_, maps_);
    mapsTick_ = s.tick;
    return true;
}

// The first key light's share of the shade map, of a white texel: gi/
// shading with that light alone (the renderer adds its specular and can swap
// its shadows); zero without key lights. Returns that light, or none.
const gi::KeyLight* FramePipeline::shadeFirstKey(const gi::GiSettings& gs, const gi::GiLighting& lighting) {
    if (!lighting.keys.empty()) {
        gi::shadeKeyLight(gi_, gs, lighting, 0, keyScratch_, keyOnly_);
        return &lighting.keys[0];
    }
    for (Grid& g : keyOnly_) {
        g.ensureSize(sim_.state().nx, sim_.state().ny);
        std::fill(g.v.begin(), g.v.end(), 0.0f);
    }
    return nullptr;
}

void FramePipeline::light() {
    if (!(settings_.verticalExaggeration >= 0.0f && settings_.verticalExaggeration <= 100.0f))
        throw InputError("vertical exaggeration must be in [0, 100] (0 = automatic)");
    const float exag = settings_.verticalExaggeration > 0.0f ? settings_.verticalExaggeration : autoExaggeration_;
    const TerrainState& s = sim_.state();
    auto t = Clock::now();
    exaggeratedSurface(s, exag, surface_);
    const bool newMaps = updateMaterialMaps();
    lights_ = rig_.at(frameIndex_);
    const gi::GiLighting lighting = giLighting(lights_);
    // Global lighting adds gi.indirect.bounces indirect bounces (gi/indirect.h);
    // the other modes none. The simulator's change report says whether the
    // lit surface moved, which drives the shading amortisation
    // (Nowrouzezahrai & Snyder 2009, Section 7) when it is on.
    gi::GiSettings gs = settings_.gi;
    gs.minEnvironmentShRows = 1;  // the receivers' sky fraction dims the water's mirrored sky (packReceivers)
    if (settings_.lighting != LightingMode::Global) gs.indirect.bounces = 0;
    // Incremental GI frames see for themselves what changed since the cached
    // results (gi/frame_change.h); without them the simulator's report of the
    // last tick says whether the surface moved.
    const ChangeReport& ch = sim_.changes();
    gi_.geometryChanged = exag != lastExaggeration_ || ch.maxGroundChange > 0.0f || ch.maxWaterChange > 0.0f;
    lastExaggeration_ = exag;
    gi::runGiFrame(surface_.cview(), s.cellSize, lighting, gs, gi_, &maps_.albedo);
    const double surfaceMs = msSince(t);

    t = Clock::now();
    FrameData& f = frame_;
    if (heightsTick_ != s.tick) {
        packHeights(s, f);
        f.heightsVersion = nextVersion();
        heightsTick_ = s.tick;
    }
    // also when the views were just asked for, on a paused scene
    if (settings_.hydrologyMaps && hydrologyTick_ != s.tick) {
        packHydrology(sim_, f);
        hydrologyTick_ = s.tick;
    }
    if (newMaps) packAlbedo(maps_, f);
    const bool giUpdated = gi_.directUpdated || gi_.indirectUpdated;
    if (!giUpdated && f.lighting == settings_.lighting && packedPyramidLevel_ == settings_.pyramidLevel) {
        // nothing the light sees changed: the packed shade is this frame's
        f.tick = s.tick;
        f.time = s.time;
        recordGiTimings(gi_, gs, surfaceMs, msSince(t), timings_);
        return;
    }
    packedPyramidLevel_ = settings_.pyramidLevel;
    const gi::KeyLight* key = shadeFirstKey(gs, lighting);

    // ---- pack what the renderer uploads -----------------------------------------
    f.lighting = settings_.lighting;
    f.exaggeration = exag;
    f.lights = lights_;
    f.tick = s.tick;
    f.time = s.time;
    const bool indirect = gs.indirect.bounces > 0;
    packTexels(gi_, indirect ? gi_.indirect.total : gi_.shade.rgb, keyOnly_, maps_.albedo, key, f);
    packReceivers(gi_, surface_, settings_, exag, indirect, f);
    f.shadeVersion = nextVersion();
    const double packMs = msSince(t);
    recordGiTimings(gi_, gs, surfaceMs, packMs, timings_);
}

}  // namespace terrain::engine
