// `terrain sim`: run a scene headless, print state hashes, write frames.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>

#include "app/commands.h"
#include "app/progress.h"
#include "core/error.h"
#include "core/parallel.h"
#include "core/png_io.h"
#include "sim/scene.h"
#include "sim/vdb_io.h"

namespace terrain::app {
namespace {

struct SimOptions {
    std::string scene = "erosion";
    int size = 256;
    long long ticks = 100;
    long long seed = 1;
    int threads = 0;
    long long hashEvery = 0;
    std::string out;
    long long outEvery = 0;
    std::string format = "vdb";
    double dt = 0.0;
    bool quiet = false;
};

void writeFrame(const std::string& dir, const TerrainState& s, const std::string& format, float zScale, float zOffset) {
    char name[64];
    std::snprintf(name, sizeof name, "frame_%06lld", static_cast<long long>(s.tick));
    const std::filesystem::path base = std::filesystem::path(dir) / name;
    if (format == "vdb" || format == "both") writeVdb(base.string() + ".vdb", s);
    if (format == "png" || format == "both") {
        Grid h;
        s.groundHeight(h);
        writePngHeightmap(base.string() + ".png", h, zScale, zOffset);
    }
}

int runSim(const SimOptions& o) {
    if (o.ticks < 0) throw InputError("--ticks must be >= 0");
    if (o.hashEvery < 0 || o.outEvery < 0) throw InputError("--hash-every and --out-every must be >= 0");
    if (o.format != "vdb" && o.format != "png" && o.format != "both")
        throw InputError("--format must be vdb, png or both (got '" + o.format + "')");
    if (o.threads < 0 || o.threads > 256) throw InputError("--threads must be 0 (all) .. 256");
    if (!o.out.empty()) ensureWritableDirectory(o.out);
    return withThreads(o.threads, [&] {
        SceneSettings settings = resolveScene(o.scene, o.size, static_cast<std::uint64_t>(o.seed));
        settings.dt = static_cast<float>(o.dt);
        Simulation sim(settings);
        if (sim.dtClamped())
            std::fprintf(stderr, "terrain sim: requested dt %.6g s is above the stability limit %.6g s; clamped\n",
                         o.dt, static_cast<double>(sim.dtLimit()));
        const TerrainState& s = sim.state();
        if (!o.quiet)
            std::fprintf(stderr, "scene %s: %d x %d cells of %.4g m, dt %.4g s, stages:%s%s%s\n", settings.name.c_str(),
                         s.nx, s.ny, static_cast<double>(s.cellSize), static_cast<double>(sim.dt()),
                         settings.hydraulic ? " hydraulic" : "", settings.thermal ? " thermal" : "",
                         settings.waves ? " waves" : "");
        // PNG frames share one height range (from the first frame, with margin)
        float zScale = 1.0f, zOffset = 0.0f;
        {
            Grid h;
            s.groundHeight(h);
            pngRangeFor(h, zScale, zOffset);
            const float span = zScale * 65535.0f;
            zOffset -= 0.1f * span;
            zScale *= 1.2f;
        }
        const long long outEvery = o.outEvery > 0 ? o.outEvery : (o.hashEvery > 0 ? o.hashEvery : o.ticks);
        if (!o.out.empty()) writeFrame(o.out, s, o.format, zScale, zOffset);
        Progress progress("sim", o.ticks, !o.quiet);
        for (long long t = 1; t <= o.ticks; ++t) {
            sim.tick();
            if (o.hashEvery > 0 && t % o.hashEvery == 0) {
                progress.clear();
                std::printf("tick %lld hash %s\n", t, hashHex(hashState(s)).c_str());
                std::fflush(stdout);
            }
            if (!o.out.empty() && outEvery > 0 && t % outEvery == 0) writeFrame(o.out, s, o.format, zScale, zOffset);
            progress.update(t);
        }
        progress.finish();
        checkFinite(s);
        if (!o.out.empty() && !o.quiet) std::fprintf(stderr, "frames written to %s\n", o.out.c_str());
        return 0;
    });
}

}  // namespace

Runner addSimCommand(CLI::App& app) {
    auto opt = std::make_shared<SimOptions>();
    CLI::App* sub = app.add_subcommand("sim", "Run a scene's simulation headless; print state hashes, write frames");
    sub->add_option("--scene", opt->scene, "Built-in scene (erosion, waves, dem) or a .toml scene file")
        ->capture_default_str();
    sub->add_option("--size", opt->size, "Grid side in cells (the scene keeps its extent)")->capture_default_str();
    sub->add_option("--ticks", opt->ticks, "Number of fixed time steps")->capture_default_str();
    sub->add_option("--seed", opt->seed, "Seed for the scene generator")->capture_default_str();
    sub->add_option("--threads", opt->threads, "Worker threads (0 = all cores)")->capture_default_str();
    sub->add_option("--hash-every", opt->hashEvery,
                    "Print 'tick <t> hash <16 hex digits>' every E ticks (hash over the whole state; 0 = never)")
        ->capture_default_str();
    sub->add_option("--out", opt->out, "Write frames to this folder (created if missing)");
    sub->add_option("--out-every", opt->outEvery, "Write a frame every F ticks (default: --hash-every, else the last)");
    sub->add_option("--format", opt->format, "Frame format: vdb (all layers), png (16-bit height) or both")
        ->capture_default_str();
    sub->add_option("--dt", opt->dt, "Time step in s (default: derived from the CFL limits; larger is clamped)");
    sub->add_flag("--quiet", opt->quiet, "No progress or summary on stderr");
    return [opt] { return runSim(*opt); };
}

}  // namespace terrain::app
