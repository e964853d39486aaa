// `terrain_bench render`: per-stage time per frame of the animated erosion and
// waves scenes at 256^2 and 512^2 (2x GI sub-sampling), rendered headless
// (OSMesa, llvmpipe here) at 1280 x 720, median of several frames after one
// warm-up frame. Stages: sim (the frame's ticks), pyramids (gradient + height
// pyramid), scan (environment + key-light visibility; gi/ fuses the wedge
// integration into it, so "integrate" is 0), shade (gi/ shading, the key
// light's share, packing the textures), render (upload, draw, tone map,
// read-back with glFinish semantics). Writes render.md and render.csv.
#include <chrono>
#include <cstdio>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "bench/suites.h"
#include "engine/pipeline.h"
#include "render/context.h"
#include "render/gl.h"
#include "render/renderer.h"
#include "sim/scene.h"

namespace terrain::bench {
namespace {
using namespace terrain::render;
using namespace terrain::engine;
using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

// Median per-stage times (sim, pyramids, scan, integrate, shade, render, total)
// of `runs` frames after one warm-up frame.
struct SceneTimes {
    double m[7];
    int ticksPerFrame;
};

SceneTimes measureScene(Renderer& renderer, const char* scene, int size, int runs, int width, int height) {
    std::vector<std::uint8_t> rgb;
    PipelineSettings ps;
    ps.gi.subsample = 2;
    ps.lighting = LightingMode::Global;
    ps.gi.indirect.bounces = 1;
    FramePipeline pipeline(resolveScene(scene, size, 1), ps);
    std::vector<std::vector<double>> t(7);
    for (int f = 0; f <= runs; ++f) {
        pipeline.advance();
        pipeline.light();
        const auto t0 = Clock::now();
        renderer.upload(pipeline.frame());
        renderer.drawToImage(RenderSettings{}, width, height, rgb);
        pipeline.timings().render = msSince(t0);
        if (f == 0) continue;  // warm-up
        const StageTimings& s = pipeline.timings();
        const double v[7] = {s.sim, s.pyramids, s.scan, s.integrate, s.shade, s.render, s.total()};
        for (int i = 0; i < 7; ++i) t[static_cast<std::size_t>(i)].push_back(v[i]);
    }
    SceneTimes st{};
    for (int i = 0; i < 7; ++i) st.m[i] = median(t[static_cast<std::size_t>(i)]);
    st.ticksPerFrame = pipeline.ticksPerFrame();
    return st;
}

int runRender(int runs, const BenchContext& ctx) {
    auto context = createHeadlessContext();
    Gl gl;
    loadGl(gl, context->procAddress());
    Renderer renderer(gl);
    const int width = 1280, height = 720;
    const char* stageNames[] = {"sim", "pyramids", "scan", "integrate", "shade", "render", "total"};
    std::ostringstream csv, md;
    csv << "scene,size,subsample,width,height,ticks_per_frame,runs";
    for (const char* s : stageNames) csv << ',' << s << "_ms";
    csv << '\n';
    md << "# Renderer benchmark: per-stage time per frame\n\n"
       << "Animated scenes, GI sub-sampling 2x, global lighting with one indirect bounce (sky + key light with soft "
          "visibility, no amortisation), headless OSMesa at "
       << width << " x " << height << ", median of " << runs << " frames after one warm-up frame.\n\n"
       << "Machine: " << machineDescription() << ", " << glDescription(gl) << " (software rasteriser: no GPU).\n\n"
       << "| scene | size | ticks/frame | sim | pyramids | scan | integrate | shade | render | total ms | fps |\n"
       << "|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const char* scene : {"erosion", "waves"})
        for (int size : {256, 512}) {
            const SceneTimes st = measureScene(renderer, scene, size, runs, width, height);
            const double* m = st.m;
            csv << scene << ',' << size << ",2," << width << ',' << height << ',' << st.ticksPerFrame << ',' << runs;
            for (double x : st.m) csv << ',' << x;
            csv << '\n';
            char line[512];
            std::snprintf(line, sizeof line,
                          "| %s | %d² | %d | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %.2f |\n", scene, size,
                          st.ticksPerFrame, m[0], m[1], m[2], m[3], m[4], m[5], m[6], 1000.0 / m[6]);
            md << line;
            std::printf("%s", line);
            std::fflush(stdout);
        }
    md << "\n\"integrate\" is 0 because gi/ computes the wedge integration inside the visibility scan (reported "
          "under scan). \"render\" is the OpenGL share: texture upload, the draw of the mesh (one vertex "
          "per grid point; soft-visibility mode, so no shadow-map pass) and water, tone mapping, and the read-back of "
          "the 1280 x 720 image; on llvmpipe it "
          "runs on the same 2 CPU cores as GI, so it is not small here as it would be on a GPU.\n";
    writeResult(ctx.outDir, "render.csv", csv.str());
    writeResult(ctx.outDir, "render.md", md.str());
    return 0;
}

}  // namespace

Runner addRenderSuite(CLI::App& app, const BenchContext& ctx) {
    auto runs = std::make_shared<int>(5);
    CLI::App* sub = app.add_subcommand("render", "Renderer: per-stage time per frame of two animated scenes, headless");
    addRunsOption(*sub, *runs, "Frames per figure after one warm-up (the median is reported)");
    return [runs, &ctx] { return runRender(*runs, ctx); };
}

}  // namespace terrain::bench
