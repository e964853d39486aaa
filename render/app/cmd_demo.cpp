// `terrain demo`: the animated demo. Runs a scene and writes its frames as
// images with progress; prints where they are.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "render/app/commands.h"
#include "render/app/progress.h"
#include "render/preview.h"
#include "sim/error.h"
#include "sim/io.h"
#include "sim/parallel.h"
#include "sim/scene.h"

namespace terrain::app {
namespace {

struct DemoOptions {
    std::string scene = "erosion";
    int size = 256;
    int frames = 48;
    int ticksPerFrame = 0;
    long long seed = 1;
    int threads = 0;
    std::string out = "out/demo";
};

int runDemo(const DemoOptions& o) {
    if (o.frames < 1 || o.frames > 100000) throw InputError("--frames must be 1..100000");
    if (o.ticksPerFrame < 0) throw InputError("--ticks-per-frame must be >= 0");
    ensureWritableDirectory(o.out);
    return withThreads(o.threads, [&] {
        SceneSettings settings = resolveScene(o.scene, o.size, static_cast<std::uint64_t>(o.seed));
        Simulation sim(settings);
        // Default pacing: erosion needs many ticks per frame to show change; waves ~ 0.25 s per frame.
        int perFrame = o.ticksPerFrame;
        if (perFrame == 0) {
            if (settings.waves) perFrame = std::max(1, static_cast<int>(0.25f / sim.dt()));
            else if (settings.hydraulic || settings.thermal) perFrame = 60;
            else perFrame = 1;
        }
        std::printf("demo: scene %s, %d x %d cells, %d frames of %d ticks (%.3g s each)\n", settings.name.c_str(),
                    sim.state().nx, sim.state().ny, o.frames, perFrame,
                    static_cast<double>(sim.dt()) * perFrame);
        PreviewSettings ps;
        {
            const TerrainState& s = sim.state();
            ps.zMin = ps.zMax = s.ground(0, 0);
            for (int y = 0; y < s.ny; ++y)
                for (int x = 0; x < s.nx; ++x) {
                    ps.zMin = std::min(ps.zMin, s.ground(x, y));
                    ps.zMax = std::max(ps.zMax, s.ground(x, y));
                }
        }
        std::vector<std::uint8_t> rgb;
        Progress progress("demo", o.frames, true);
        for (int f = 0; f < o.frames; ++f) {
            if (f > 0)
                for (int t = 0; t < perFrame; ++t) sim.tick();
            shadePreview(sim.state(), ps, rgb);
            char name[48];
            std::snprintf(name, sizeof name, "frame_%04d.png", f);
            writePngRgb((std::filesystem::path(o.out) / name).string(), sim.state().nx, sim.state().ny, rgb);
            progress.update(f + 1);
        }
        progress.finish();
        std::printf("demo: %d frames written to %s\n", o.frames,
                    std::filesystem::absolute(o.out).lexically_normal().string().c_str());
        return 0;
    });
}

}  // namespace

Runner addDemoCommand(CLI::App& app) {
    auto opt = std::make_shared<DemoOptions>();
    CLI::App* sub = app.add_subcommand("demo", "The animated demo: run a scene and write its frames as images");
    sub->add_option("--scene", opt->scene, "Built-in scene (erosion, waves, dem) or a .toml scene file")
        ->capture_default_str();
    sub->add_option("--size", opt->size, "Grid side in cells")->capture_default_str();
    sub->add_option("--frames", opt->frames, "Frames to write")->capture_default_str();
    sub->add_option("--ticks-per-frame", opt->ticksPerFrame, "Simulation ticks between frames (0 = scene default)");
    sub->add_option("--seed", opt->seed, "Seed for the scene generator")->capture_default_str();
    sub->add_option("--threads", opt->threads, "Worker threads (0 = all cores)")->capture_default_str();
    sub->add_option("--out", opt->out, "Output folder")->capture_default_str();
    return [opt] { return runDemo(*opt); };
}

}  // namespace terrain::app
