// Renderer benchmark: per-stage time per frame of the animated erosion and
// waves scenes at 256^2 and 512^2 (2x GI sub-sampling), rendered headless
// (OSMesa, llvmpipe here) at 1280 x 720, median of several frames after one
// warm-up frame. Stages: sim (the frame's ticks), pyramids (gradient + height
// pyramid), scan (environment + key-light visibility; gi/ fuses the wedge
// integration into it, so "integrate" is 0), shade (gi/ shading, the key
// light's share, packing the textures), render (upload, draw, tone map,
// read-back with glFinish semantics).
//
//   build/bench_render [--runs 5] [--out bench/results]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "bench/bench_common.h"
#include "render/context.h"
#include "render/gl.h"
#include "engine/pipeline.h"
#include "render/renderer.h"
#include "core/file_io.h"
#include "sim/scene.h"

using namespace terrain;
using terrain::bench::median;
using namespace terrain::render;
using namespace terrain::engine;

namespace {
using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }


}  // namespace

int main(int argc, char** argv) {
    int runs = 5;
    std::string out = "bench/results";
    for (int i = 1; i < argc; ++i) {
        if (!std::strcmp(argv[i], "--runs") && i + 1 < argc) runs = std::max(1, std::atoi(argv[++i]));
        else if (!std::strcmp(argv[i], "--out") && i + 1 < argc) out = argv[++i];
        else {
            std::fprintf(stderr, "usage: bench_render [--runs N] [--out DIR]\n");
            return 2;
        }
    }
    try {
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
           << "Machine: " << terrain::bench::machineDescription() << ", " << glDescription(gl) << " (software rasteriser: no GPU).\n\n"
           << "| scene | size | ticks/frame | sim | pyramids | scan | integrate | shade | render | total ms | fps |\n"
           << "|---|---|---|---|---|---|---|---|---|---|---|\n";
        std::vector<std::uint8_t> rgb;
        for (const char* scene : {"erosion", "waves"})
            for (int size : {256, 512}) {
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
                double m[7];
                for (int i = 0; i < 7; ++i) m[i] = median(t[static_cast<std::size_t>(i)]);
                csv << scene << ',' << size << ",2," << width << ',' << height << ',' << pipeline.ticksPerFrame() << ','
                    << runs;
                for (double x : m) csv << ',' << x;
                csv << '\n';
                char line[512];
                std::snprintf(line, sizeof line, "| %s | %d² | %d | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %.2f |\n",
                              scene, size, pipeline.ticksPerFrame(), m[0], m[1], m[2], m[3], m[4], m[5], m[6],
                              1000.0 / m[6]);
                md << line;
                std::printf("%s", line);
                std::fflush(stdout);
            }
        md << "\n\"integrate\" is 0 because gi/ computes the wedge integration inside the visibility scan (reported "
              "under scan). \"render\" is the OpenGL share: texture upload, the draw of the mesh (one vertex "
              "per grid point; soft-visibility mode, so no shadow-map pass) and water, tone mapping, and the read-back of the 1280 x 720 image; on llvmpipe it "
              "runs on the same 2 CPU cores as GI, so it is not small here as it would be on a GPU.\n";
        std::filesystem::create_directories(out);
        writeFileAtomic(out + "/render.csv", csv.str());
        writeFileAtomic(out + "/render.md", md.str());
        std::printf("wrote %s/render.csv and render.md\n", out.c_str());
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bench_render: error: %s\n", e.what());
        return 1;
    }
    return 0;
}
