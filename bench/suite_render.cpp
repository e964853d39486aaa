// `terrain_bench render`: per-stage time per frame of the animated erosion and
// waves scenes at 256^2 ... 2048^2 (2x GI sub-sampling), rendered headless
// (OSMesa, llvmpipe here) at 1280 x 720 with the terrain mesh's level of detail
// off (the full grid) and on (render/terrain_lod.h), median of several frames
// after one warm-up frame. Each frame is simulated and lit once, uploaded once
// and drawn once per LOD setting, so the settings see the same frames. Stages:
// sim (the frame's ticks), pyramids (gradient + height pyramid), scan
// (environment + key-light visibility; gi/ fuses the wedge integration into
// it, so "integrate" is 0), shade (gi/ shading, the key light's share, packing
// the textures), upload (textures and the LOD chunk errors), draw (the passes
// and the read-back with glFinish semantics); render = upload + draw. Each
// setting's image is compared with the full grid's of the same frame. Writes
// render.md and render.csv.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
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

struct RenderOptions {
    int runs = 5;
    std::vector<int> sizes{256, 512, 1024, 2048};
    std::vector<float> lod{0.0f, 1.0f, 2.0f, 4.0f};  // RenderSettings::lodPixelError; 0: the full grid
};

// Medians over the measured frames of one scene and size.
struct SceneTimes {
    double sim = 0, pyramids = 0, scan = 0, integrate = 0, shade = 0, upload = 0;
    std::vector<double> draw;      // per LOD setting
    std::vector<double> totalIqr;  // per LOD setting: interquartile range of the frames' whole time
    std::vector<DrawStats> stats;
    // per LOD setting, against the full grid's image (-1: no full grid drawn):
    std::vector<double> meanDifference;  // mean over pixels of the largest |difference| over R, G, B (levels)
    std::vector<double> above8;          // fraction of pixels differing by more than 8 levels
    int ticksPerFrame = 0;
};

SceneTimes measureScene(Renderer& renderer, const char* scene, int size, const RenderOptions& o, int width,
                        int height) {
    PipelineSettings ps;
    ps.gi.subsample = 2;
    ps.lighting = LightingMode::Global;
    ps.gi.indirect.bounces = 1;
    FramePipeline pipeline(resolveScene(scene, size, 1), ps);
    const std::size_t modes = o.lod.size();
    const auto fullGrid = std::find(o.lod.begin(), o.lod.end(), 0.0f);
    const std::size_t reference = static_cast<std::size_t>(fullGrid - o.lod.begin());  // == modes: none
    std::vector<std::vector<std::uint8_t>> images(modes);
    std::vector<std::vector<double>> stage(6), draw(modes), total(modes), meanDifference(modes), above8(modes);
    SceneTimes st;
    st.stats.resize(modes);
    for (int f = 0; f <= o.runs; ++f) {
        pipeline.advance();
        pipeline.light();
        const auto t0 = Clock::now();
        renderer.upload(pipeline.frame());
        const double upload = msSince(t0);
        for (std::size_t m = 0; m < modes; ++m) {
            RenderSettings rs;
            rs.lodPixelError = o.lod[m];
            const auto t1 = Clock::now();
            renderer.drawToImage(rs, width, height, images[m]);
            if (f > 0) draw[m].push_back(msSince(t1));
            st.stats[m] = renderer.lastDrawStats();
        }
        if (f == 0) continue;  // warm-up
        for (std::size_t m = 0; m < modes && reference < modes; ++m) {
            const render::ImageDifference d = render::compareImages(images[reference], images[m], 8);
            meanDifference[m].push_back(d.mean);
            above8[m].push_back(d.fractionAbove);
        }
        const StageTimings& s = pipeline.timings();
        const double v[6] = {s.sim, s.pyramids, s.scan, s.integrate, s.shade, upload};
        for (std::size_t i = 0; i < 6; ++i) stage[i].push_back(v[i]);
        const double shared = v[0] + v[1] + v[2] + v[3] + v[4] + v[5];
        for (std::size_t m = 0; m < modes; ++m) total[m].push_back(shared + draw[m].back());
    }
    double* fields[6] = {&st.sim, &st.pyramids, &st.scan, &st.integrate, &st.shade, &st.upload};
    for (std::size_t i = 0; i < 6; ++i) *fields[i] = median(stage[i]);
    for (std::size_t m = 0; m < modes; ++m) {
        st.draw.push_back(median(draw[m]));
        st.totalIqr.push_back(spreadOf(total[m]).iqr());
        st.meanDifference.push_back(reference < modes ? median(meanDifference[m]) : -1.0);
        st.above8.push_back(reference < modes ? median(above8[m]) : -1.0);
    }
    st.ticksPerFrame = pipeline.ticksPerFrame();
    return st;
}

std::string lodName(float px) {
    char s[32];
    if (px <= 0.0f) return "off";
    std::snprintf(s, sizeof s, "%g px", static_cast<double>(px));
    return s;
}

int runRender(const RenderOptions& o, const BenchContext& ctx) {
    auto context = createHeadlessContext();
    Gl gl;
    loadGl(gl, context->procAddress());
    Renderer renderer(gl);
    const int width = 1280, height = 720;
    const unsigned threads = std::thread::hardware_concurrency();
    std::ostringstream csv, md;
    csv << "scene,size,lod_px,subsample,width,height,threads,ticks_per_frame,runs,sim_ms,pyramids_ms,scan_ms,"
           "integrate_ms,shade_ms,upload_ms,draw_ms,render_ms,total_ms,triangles,terrain_triangles,terrain_chunks,"
           "mean_abs_difference,fraction_above_8,total_iqr_ms\n";
    md << "# Renderer benchmark: per-stage time per frame, terrain level of detail off and on\n\n"
       << "Animated scenes, GI sub-sampling 2x, global lighting with one indirect bounce (sky + key light with soft "
          "visibility, no amortisation), headless OSMesa at "
       << width << " x " << height << ", median of " << o.runs
       << " frames after one warm-up frame (IQR: the interquartile range of the frames' whole time). Each frame is "
          "simulated, lit and uploaded once and drawn once per LOD "
          "setting: \"off\" is the full grid (`RenderSettings::lodPixelError` 0, one vertex per grid point), \"1 "
          "px\" the default (render/terrain_lod.h). The simulation, GI and upload columns are the same frames for "
          "every setting. \"Δ mean\" and \"Δ > 8\" compare each setting's image with the full grid's of the same "
          "frame: the mean over pixels of the largest difference over R, G, B (8-bit levels), and the share of "
          "pixels where it is above 8 levels (medians over the frames).\n\n"
       << "Machine: " << machineDescription() << ", " << glDescription(gl)
       << " (software rasteriser: no GPU). Threads: the engine's TBB stages use all " << threads
       << " hardware threads; llvmpipe rasterises on its own threads, as many, on the same cores.\n\n"
       << "Command: `" << ctx.command << "`.\n\n"
       << "| scene | size | LOD | ticks/frame | sim | pyramids | scan | shade | upload | draw | render | total ms | "
          "IQR | fps | terrain triangles | chunks | all triangles | Δ mean | Δ > 8 |\n"
       << "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const char* scene : {"erosion", "waves"})
        for (int size : o.sizes) {
            const SceneTimes st = measureScene(renderer, scene, size, o, width, height);
            for (std::size_t m = 0; m < o.lod.size(); ++m) {
                const double render = st.upload + st.draw[m];
                const double total = st.sim + st.pyramids + st.scan + st.integrate + st.shade + render;
                const DrawStats& ds = st.stats[m];
                csv << scene << ',' << size << ',' << o.lod[m] << ",2," << width << ',' << height << ',' << threads
                    << ',' << st.ticksPerFrame << ',' << o.runs << ',' << st.sim << ',' << st.pyramids << ',' << st.scan
                    << ',' << st.integrate << ',' << st.shade << ',' << st.upload << ',' << st.draw[m] << ',' << render
                    << ',' << total << ',' << ds.triangles << ',' << ds.terrainTriangles << ',' << ds.terrainChunks
                    << ',' << st.meanDifference[m] << ',' << st.above8[m] << ',' << st.totalIqr[m] << '\n';
                char line[512];
                std::snprintf(line, sizeof line,
                              "| %s | %d² | %s | %d | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | "
                              "%.2f | %lld | %d | %lld | %.2f | %.2f %% |\n",
                              scene, size, lodName(o.lod[m]).c_str(), st.ticksPerFrame, st.sim, st.pyramids, st.scan,
                              st.shade, st.upload, st.draw[m], render, total, st.totalIqr[m], 1000.0 / total,
                              static_cast<long long>(ds.terrainTriangles), ds.terrainChunks,
                              static_cast<long long>(ds.triangles), st.meanDifference[m], 100.0 * st.above8[m]);
                md << line;
                std::printf("%s", line);
                std::fflush(stdout);
            }
        }
    md << "\n\"integrate\" (not shown) is 0: gi/ computes the wedge integration inside the visibility scan. "
          "\"upload\" streams the heights and GI textures and computes the LOD chunk errors (every grid point once "
          "per chunk level; done for every setting). \"draw\" is the OpenGL share: the terrain mesh, the water "
          "surface (the same chunks, those with water), tone mapping and the read-back of the image; on llvmpipe it "
          "runs on the same CPU cores as the engine. \"terrain triangles\" are those of the terrain pass, \"chunks\" "
          "its draws (0: the full grid in one draw), \"all triangles\" every mesh pass (terrain and water; no "
          "shadow-map pass in soft-visibility mode).\n";
    writeResult(ctx.outDir, "render.csv", csv.str());
    writeResult(ctx.outDir, "render.md", md.str());
    return 0;
}

}  // namespace

Runner addRenderSuite(CLI::App& app, const BenchContext& ctx) {
    auto o = std::make_shared<RenderOptions>();
    CLI::App* sub = app.add_subcommand("render",
                                       "Renderer: per-stage time per frame of two animated scenes, headless, "
                                       "with the terrain's level of detail off and on");
    addRunsOption(*sub, o->runs, "Frames per figure after one warm-up (the median is reported)");
    sub->add_option("--sizes", o->sizes, "Grid sizes (n for n x n)")->capture_default_str();
    sub->add_option("--lod", o->lod, "LOD pixel errors to draw each frame with (0: the full grid)")
        ->check(CLI::Range(0.0f, kMaxLodPixelError))
        ->capture_default_str();
    return [o, &ctx] { return runRender(*o, ctx); };
}

}  // namespace terrain::bench
