// `terrain sim`: run a scene headless, print state hashes, write frames.
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "app/commands.h"
#include "app/option_ranges.h"
#include "app/progress.h"
#include "core/error.h"
#include "core/geotiff_io.h"
#include "core/image_io.h"
#include "core/parallel.h"
#include "core/png_io.h"
#include "sim/frame_layers.h"
#include "sim/scene.h"
#include "sim/scene_ranges.h"
#include "sim/vdb_io.h"

namespace terrain::app {
namespace {

struct SimOptions {
    std::string scene = "erosion";
    // given on the command line: over the scene's own (a built-in's default
    // otherwise: 256 cells, seed 1, the CFL step)
    std::optional<int> size;
    std::optional<std::int64_t> seed;
    std::optional<double> dt;
    std::int64_t ticks = 100;
    int threads = 0;
    std::int64_t hashEvery = 0;
    std::string out;
    std::int64_t outEvery = 0;
    std::string format = "vdb";
    bool quiet = false;
};

// Everything about the options that can be wrong, before any input is read.
void checkOptions(const SimOptions& o) {
    namespace r = option_ranges;
    checkRange(r::kTicks, o.ticks);
    checkRange(r::kHashEvery, o.hashEvery);
    checkRange(r::kOutEvery, o.outEvery);
    checkRange(r::kThreads, o.threads);
    if (o.format != "vdb" && o.format != "png" && o.format != "tif" && o.format != "exr" && o.format != "both")
        throw InputError("--format must be vdb, png, tif, exr or both (got '" + o.format + "')");
    if (o.size) checkRange(scene_ranges::kSize, *o.size, "--size");
    if (o.seed) checkRange(scene_ranges::kSeed, *o.seed, "--seed");
    if (o.dt) checkRange(widened(scene_ranges::kDt), *o.dt, "--dt");
}

SceneOverrides overridesOf(const SimOptions& o) {
    SceneOverrides over;
    over.size = o.size;
    if (o.seed) over.seed = static_cast<std::uint64_t>(*o.seed);
    if (o.dt) over.dt = static_cast<float>(*o.dt);
    return over;
}

// No NaN or Inf leaves the simulation: checked before a state is hashed or
// written, so a diverging scene fails at the tick it diverged.
void checkDiverged(const TerrainState& s) {
    try {
        checkFinite(s);
    } catch (const InputError& e) {
        throw InputError("the simulation diverged by tick " + std::to_string(s.tick) + ": " + e.what());
    }
}

// The frame's layers (sim/frame_layers.h) as a GeoTIFF's float32 bands,
// named by their descriptions, with the place and CRS of a GeoTIFF DEM the
// scene started from.
void writeTifFrame(const std::string& file, FrameLayers frame, const GeoReference& geo) {
    const std::vector<std::string> names = frame.names();
    std::vector<Grid> bands;
    bands.reserve(frame.layers.size());
    for (FrameLayer& layer : frame.layers) bands.push_back(std::move(layer.grid));
    writeGeoTiff(file, bands, geo, names);
}

// vdb, exr and tif frames carry every layer; png the ground height alone.
void writeFrame(const std::string& dir, const Simulation& sim, const std::string& format, float zScale, float zOffset) {
    const TerrainState& s = sim.state();
    checkDiverged(s);
    char name[64];
    std::snprintf(name, sizeof name, "frame_%06lld", static_cast<long long>(s.tick));
    const std::string base = (std::filesystem::path(dir) / name).string();
    if (format == "png" || format == "both") {
        Grid h;
        s.groundHeight(h);
        writePngHeightmap(base + ".png", h, zScale, zOffset);
    }
    if (format == "png") return;
    FrameLayers frame = frameLayers(sim);
    if (format == "vdb" || format == "both") writeVdbLayers(base + ".vdb", frame);
    if (format == "exr") writeExrChannels(base + ".exr", frame.names(), frame.grids(), frame.cellSize);
    if (format == "tif") writeTifFrame(base + ".tif", std::move(frame), sim.geoReference());
}

// The scene's summary and any notice, on stdout: stderr carries errors only.
void printSummary(const SimOptions& o, const Simulation& sim) {
    const SceneSettings& settings = sim.settings();
    if (sim.dtClamped())
        std::printf("terrain sim: requested dt %.6g s is above the stability limit %.6g s; clamped\n",
                    static_cast<double>(settings.dt), static_cast<double>(sim.dtLimit()));
    const TerrainState& s = sim.state();
    if (!o.quiet)
        std::printf("scene %s: %d x %d cells of %.4g m, dt %.4g s, stages:%s%s%s\n", settings.name.c_str(), s.nx, s.ny,
                    static_cast<double>(s.cellSize), static_cast<double>(sim.dt()),
                    settings.hydraulic ? " hydraulic" : "", settings.thermal ? " thermal" : "",
                    settings.waves ? " waves" : "");
    std::fflush(stdout);
}

// PNG frames share one height range (from the first frame, with margin).
void pngRange(const TerrainState& s, float& zScale, float& zOffset) {
    Grid h;
    s.groundHeight(h);
    pngRangeFor(h, zScale, zOffset);
    const float span = zScale * 65535.0f;
    zOffset -= 0.1f * span;
    zScale *= 1.2f;
}

int runSim(const SimOptions& o) {
    checkOptions(o);
    return withThreads(o.threads, [&] {
        // the scene and its inputs (a DEM) are read and checked before any output is made
        Simulation sim(resolveScene(o.scene, overridesOf(o)));
        if (!o.out.empty()) ensureWritableDirectory(o.out);
        printSummary(o, sim);
        const TerrainState& s = sim.state();
        float zScale = 1.0f, zOffset = 0.0f;
        pngRange(s, zScale, zOffset);
        const std::int64_t outEvery = o.outEvery > 0 ? o.outEvery : (o.hashEvery > 0 ? o.hashEvery : o.ticks);
        if (!o.out.empty()) writeFrame(o.out, sim, o.format, zScale, zOffset);
        Progress progress("sim", o.ticks, !o.quiet);
        for (std::int64_t t = 1; t <= o.ticks; ++t) {
            sim.tick();
            if (o.hashEvery > 0 && t % o.hashEvery == 0) {
                checkDiverged(s);
                progress.clear();
                std::printf("tick %lld hash %s\n", static_cast<long long>(t), hashHex(hashState(s)).c_str());
                std::fflush(stdout);
            }
            if (!o.out.empty() && outEvery > 0 && t % outEvery == 0) writeFrame(o.out, sim, o.format, zScale, zOffset);
            progress.update(t);
        }
        progress.finish();
        checkDiverged(s);
        if (!o.out.empty() && !o.quiet) std::printf("frames written to %s\n", o.out.c_str());
        return 0;
    });
}

}  // namespace

Runner addSimCommand(CLI::App& app) {
    auto opt = std::make_shared<SimOptions>();
    namespace r = option_ranges;
    namespace sr = scene_ranges;
    CLI::App* sub = app.add_subcommand("sim", "Run a scene's simulation headless; print state hashes, write frames");
    sub->add_option("--scene", opt->scene, "Built-in scene (erosion, waves, dem) or a .toml scene file")
        ->capture_default_str();
    sub->add_option("--size", opt->size,
                    describe(sr::kSize) + " (default: the scene file's size, which keeps its extent; else 256)");
    sub->add_option("--ticks", opt->ticks, describe(r::kTicks))->capture_default_str();
    sub->add_option("--seed", opt->seed, describe(sr::kSeed) + " (default: the scene file's, else 1)");
    sub->add_option("--threads", opt->threads, describe(r::kThreads))->capture_default_str();
    sub->add_option("--hash-every", opt->hashEvery, describe(r::kHashEvery))->capture_default_str();
    sub->add_option("--out", opt->out, "Write frames to this folder (created if missing)");
    sub->add_option("--out-every", opt->outEvery, describe(r::kOutEvery));
    sub->add_option(
           "--format", opt->format,
           "Frame format: vdb (all layers as grids), exr (all layers as float32 channels), tif (all layers as float32 "
           "GeoTIFF bands), png (16-bit height) or both (vdb and png)")
        ->capture_default_str();
    sub->add_option("--dt", opt->dt, describe(sr::kDt) + " (default: the scene file's, else 0)");
    sub->add_flag("--quiet", opt->quiet, "No progress or summary");
    return [opt] { return runSim(*opt); };
}

}  // namespace terrain::app
