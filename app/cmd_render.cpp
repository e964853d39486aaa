// `terrain render`: the animated scene rendered headless (OSMesa) to PNG
// frames, optionally an mp4 through ffmpeg, with a per-stage timing summary.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <system_error>
#include <vector>

#include <unistd.h>

#include "app/commands.h"
#include "app/progress.h"
#include "app/render_options.h"
#include "core/error.h"
#include "core/file_io.h"
#include "core/parallel.h"
#include "core/parse.h"
#include "core/png_io.h"
#include "engine/pipeline.h"
#include "render/context.h"
#include "render/gl.h"
#include "render/renderer.h"
#include "sim/scene.h"

namespace terrain::app {
namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

std::string findOnPath(const std::string& program) {
    const char* path = std::getenv("PATH");
    if (!path) return "";
    std::string p(path);
    std::size_t start = 0;
    while (start <= p.size()) {
        const std::size_t end = std::min(p.find(':', start), p.size());
        const std::filesystem::path candidate = std::filesystem::path(p.substr(start, end - start)) / program;
        std::error_code ec;
        if (std::filesystem::is_regular_file(candidate, ec) && access(candidate.c_str(), X_OK) == 0)
            return candidate.string();
        start = end + 1;
    }
    return "";
}

double median(std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    const std::size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::string shellQuote(const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

// The per-stage medians and the share of GI receivers recomputed.
void printSummary(const char* label, const RenderOptions& o, const engine::PipelineSettings& ps,
                  const std::vector<std::vector<double>>& stage, double recomputed, double indirectRecomputed) {
    static const char* names[7] = {"sim", "pyramids", "scan", "integrate", "shade", "render", "png write"};
    std::printf("%s: per-stage time per frame (median of %d frames, ms):", label, o.frames);
    double sum = 0.0;
    for (int i = 0; i < 7; ++i) {
        const double m = median(stage[static_cast<std::size_t>(i)]);
        sum += m;
        std::printf(" %s %.1f%s", names[i], m, i == 6 ? "" : ",");
    }
    std::printf(" (total %.1f; integrate is fused into scan in gi/)\n", sum);
    std::printf(
        "%s: GI receivers recomputed per frame on average: visibility %.1f %%, indirect light %.1f %% (incremental "
        "GI %s, tolerance %g)\n",
        label, 100.0 * recomputed / o.frames, 100.0 * indirectRecomputed / o.frames, ps.gi.incremental ? "on" : "off",
        static_cast<double>(ps.gi.tolerance));
}

// --video: the frames as an mp4 through ffmpeg (atomic), or a message that
// ffmpeg is missing.
void encodeVideo(const RenderOptions& o, const std::string& dir, const char* label) {
    const std::string ffmpeg = findOnPath("ffmpeg");
    if (ffmpeg.empty()) {
        std::printf(
            "%s: ffmpeg is not installed, so no %s was made (the PNG frames are in %s; "
            "install ffmpeg, e.g. apt-get install ffmpeg, for video)\n",
            label, o.video.c_str(), dir.c_str());
    } else {
        const std::string tmp = temporaryNameFor(o.video) + ".mp4";
        const std::string cmd = shellQuote(ffmpeg) + " -loglevel error -y -framerate 24 -i " +
                                shellQuote((std::filesystem::path(o.out) / "frame_%04d.png").string()) +
                                " -c:v libx264 -pix_fmt yuv420p -vf 'pad=ceil(iw/2)*2:ceil(ih/2)*2' " + shellQuote(tmp);
        if (std::system(cmd.c_str()) != 0) {
            std::error_code ec;
            std::filesystem::remove(tmp, ec);
            throw IoError(o.video, "ffmpeg failed to encode the frames");
        }
        commitTemporary(tmp, o.video);
        if (!o.quiet) std::printf("%s: video written to %s\n", label, o.video.c_str());
    }
}

}  // namespace

SceneSettings resolveRenderScene(const RenderOptions& o) {
    SceneSettings scene = resolveScene(o.scene, o.size, static_cast<std::uint64_t>(o.seed));
    applyLightOptions(o.lights, scene.lights);
    applyCameraOptions(o.camera, scene.camera);
    return scene;
}

void addRenderOptions(CLI::App* sub, RenderOptions& o, bool withSize) {
    if (withSize) sub->add_option("--size", o.size, "Grid side in cells")->capture_default_str();
    sub->add_option("--frames", o.frames, "Frames to render")->capture_default_str();
    sub->add_option("--width", o.width, "Image width in pixels")->capture_default_str();
    sub->add_option("--height", o.height, "Image height in pixels")->capture_default_str();
    sub->add_option("--ticks-per-frame", o.ticksPerFrame, "Simulation ticks between frames (0 = scene default)");
    sub->add_option("--seed", o.seed, "Seed for the scene generator")->capture_default_str();
    sub->add_option("--threads", o.threads, "Worker threads (0 = all cores)")->capture_default_str();
    sub->add_option("--subsample", o.subsample, gi::describe(gi::ranges::kSubsample))->capture_default_str();
    addLightOptions(sub, o.lights, "the scene");
    sub->add_option("--lighting", o.lighting, "key (key light only) | direct (sky + key) | global (direct + bounces)")
        ->capture_default_str();
    sub->add_option("--bounces", o.bounces, gi::describe(gi::ranges::kBounces) + ", with --lighting global")
        ->capture_default_str();
    sub->add_option("--gi-incremental", o.giIncremental,
                    "on: GI reruns only the stages whose inputs changed since the last frame; off: every frame "
                    "recomputes everything (default: the scene file's [gi] incremental, else on)");
    sub->add_option("--gi-tolerance", o.giTolerance,
                    gi::describe(gi::ranges::kTolerance) + " (default: the scene file's [gi] tolerance, else " +
                        formatNumber(engine::defaultPipelineGi().tolerance) + ")");
    sub->add_option("--gi-refresh", o.giRefresh,
                    gi::describe(gi::ranges::kRefreshEvery) + " (default: the scene file's [gi] refresh, else 0)");
    sub->add_flag("--amortise", o.amortise,
                  "Shading amortisation: on static geometry update direct and indirect light on alternate frames");
    sub->add_option("--shadow", o.shadow, "Key light shadow: soft (engine visibility) | map (shadow map) | none")
        ->capture_default_str();
    sub->add_option(
           "--debug", o.debug,
           "Debug view: none | ambient | v | u (with --lighting global) | key | normals | pyramid | shade | albedo")
        ->capture_default_str();
    sub->add_option("--pyramid-level", o.pyramidLevel, "Height-pyramid level for --debug pyramid")
        ->capture_default_str();
    sub->add_option("--exposure", o.exposure, "Exposure before tone mapping")->capture_default_str();
    sub->add_option("--lod", o.lodPixelError,
                    "Level of detail: the mesh's largest screen-space error in pixels (0 = the full grid, one vertex "
                    "per grid point)")
        ->capture_default_str();
    sub->add_option("--exaggeration", o.exaggeration,
                    "Vertical exaggeration (0 = automatic: relief >= 15% of the extent)")
        ->capture_default_str();
    addCameraOptions(sub, o.camera);
    sub->add_flag("--quiet", o.quiet, "Print only errors");
}

void toSettings(const RenderOptions& o, const SceneSettings& scene, engine::PipelineSettings& p,
                render::RenderSettings& r) {
    using namespace render;
    using namespace engine;
    if (o.frames < 1 || o.frames > 100000) throw InputError("--frames must be 1..100000");
    if (o.width < 16 || o.height < 16 || o.width > 8192 || o.height > 8192)
        throw InputError("--width and --height must be 16..8192 pixels");
    if (o.threads < 0 || o.threads > 256) throw InputError("--threads must be 0 (all) .. 256");
    if (o.ticksPerFrame < 0) throw InputError("--ticks-per-frame must be >= 0");
    if (!(o.exposure > 0.0f && o.exposure < 1000.0f)) throw InputError("--exposure must be > 0");
    if (!(o.exaggeration >= 0.0f && o.exaggeration <= 100.0f)) throw InputError("--exaggeration must be in [0, 100]");
    if (!(o.lodPixelError >= 0.0f && o.lodPixelError <= render::kMaxLodPixelError))
        throw InputError("--lod must be in [0, " + formatNumber(render::kMaxLodPixelError) + "] pixels");
    p.gi = engine::defaultPipelineGi();
    p.gi.subsample = o.subsample;
    p.gi.indirect.bounces = o.bounces;
    p.gi.indirect.amortise = o.amortise;
    p.gi.incremental = o.giIncremental.value_or(scene.gi.incremental.value_or(p.gi.incremental));
    p.gi.tolerance = o.giTolerance.value_or(scene.gi.tolerance.value_or(p.gi.tolerance));
    p.gi.refreshEvery = o.giRefresh.value_or(scene.gi.refreshEvery.value_or(p.gi.refreshEvery));
    gi::validateGiSettings(p.gi);
    p.ticksPerFrame = o.ticksPerFrame;
    p.pyramidLevel = o.pyramidLevel;
    if (o.lighting == "key")
        p.lighting = LightingMode::KeyOnly;
    else if (o.lighting == "direct")
        p.lighting = LightingMode::Direct;
    else if (o.lighting == "global")
        p.lighting = LightingMode::Global;
    else
        throw InputError("--lighting must be key, direct or global (got '" + o.lighting + "')");
    if (o.shadow == "soft")
        r.shadow = ShadowMode::SoftVisibility;
    else if (o.shadow == "map")
        r.shadow = ShadowMode::ShadowMap;
    else if (o.shadow == "none")
        r.shadow = ShadowMode::None;
    else
        throw InputError("--shadow must be soft, map or none (got '" + o.shadow + "')");
    if (o.debug == "none")
        r.debug = DebugView::None;
    else if (o.debug == "ambient")
        r.debug = DebugView::Ambient;
    else if (o.debug == "v")
        r.debug = DebugView::SkyVisibility;
    else if (o.debug == "key")
        r.debug = DebugView::KeyVisibility;
    else if (o.debug == "normals")
        r.debug = DebugView::Normals;
    else if (o.debug == "pyramid")
        r.debug = DebugView::PyramidLevel;
    else if (o.debug == "shade")
        r.debug = DebugView::ShadeMap;
    else if (o.debug == "albedo")
        r.debug = DebugView::Albedo;
    else if (o.debug == "u") {
        r.debug = DebugView::IndirectRadiance;
        if (p.lighting != LightingMode::Global)
            throw InputError("--debug u needs --lighting global (U is the indirect light)");
    } else
        throw InputError("--debug must be none, ambient, v, u, key, normals, pyramid, shade or albedo (got '" +
                         o.debug + "')");
    r.exposure = o.exposure;
    p.verticalExaggeration = o.exaggeration;
    r.lodPixelError = o.lodPixelError;
    r.camera = cameraOfFrame(scene.camera, 0);
}

int runHeadlessRender(const RenderOptions& o, const char* label) {
    engine::PipelineSettings ps;
    render::RenderSettings rs;
    // Everything that can fail on bad input fails before any file is written.
    const SceneSettings scene = resolveRenderScene(o);
    toSettings(o, scene, ps, rs);
    if (!o.video.empty() && std::filesystem::path(o.video).extension() != ".mp4")
        throw InputError("--video must name an .mp4 file (got '" + o.video + "')");
    std::unique_ptr<render::GlContext> context = render::createHeadlessContext();
    return withThreads(o.threads, [&] {
        render::Gl gl;
        render::loadGl(gl, context->procAddress());
        render::Renderer renderer(gl);
        engine::FramePipeline pipeline(scene, ps);  // reads an image environment
        ensureWritableDirectory(o.out);
        const TerrainState& st = pipeline.simulation().state();
        if (!o.quiet) {
            std::printf(
                "%s: scene %s, %d x %d cells of %.3g m, ground %.0f..%.0f m, %d frames of %d ticks, %d x %d pixels, "
                "%s\n",
                label, scene.name.c_str(), st.nx, st.ny, static_cast<double>(st.cellSize),
                static_cast<double>(pipeline.frame().zMin), static_cast<double>(pipeline.frame().zMax), o.frames,
                pipeline.ticksPerFrame(), o.width, o.height, render::glDescription(gl).c_str());
        }
        std::vector<std::vector<double>> stage(7);
        double recomputed = 0.0;          // receivers whose visibility the frames recomputed, summed over frames
        double indirectRecomputed = 0.0;  // the same for the indirect light
        std::vector<std::uint8_t> rgb;
        Progress progress(label, o.frames, !o.quiet);
        for (int f = 0; f < o.frames; ++f) {
            pipeline.advance();
            pipeline.light();
            auto t = Clock::now();
            rs.camera = cameraOfFrame(scene.camera, f);
            renderer.upload(pipeline.frame());
            renderer.drawToImage(rs, o.width, o.height, rgb);
            const double renderMs = msSince(t);
            t = Clock::now();
            char name[48];
            std::snprintf(name, sizeof name, "frame_%04d.png", f);
            writePngRgb((std::filesystem::path(o.out) / name).string(), o.width, o.height, rgb);
            const double writeMs = msSince(t);
            const engine::StageTimings& tm = pipeline.timings();
            recomputed += pipeline.giState().receiversRecomputed;
            indirectRecomputed += pipeline.giState().indirectRecomputed;
            const double values[7] = {tm.sim, tm.pyramids, tm.scan, tm.integrate, tm.shade, renderMs, writeMs};
            for (int i = 0; i < 7; ++i) stage[static_cast<std::size_t>(i)].push_back(values[i]);
            progress.update(f + 1);
        }
        progress.finish();
        const std::string dir = std::filesystem::absolute(o.out).lexically_normal().string();
        if (!o.quiet) {
            printSummary(label, o, ps, stage, recomputed, indirectRecomputed);
            std::printf("%s: %d frames written to %s\n", label, o.frames, dir.c_str());
        }
        if (!o.video.empty()) encodeVideo(o, dir, label);
        return 0;
    });
}

Runner addRenderCommand(CLI::App& app) {
    auto o = std::make_shared<RenderOptions>();
    CLI::App* sub =
        app.add_subcommand("render", "Render an animated scene headless (OSMesa) to PNG frames, optionally an mp4");
    sub->add_option("--scene", o->scene, "Built-in scene (erosion, waves, dem) or a .toml scene file")
        ->capture_default_str();
    sub->add_option("--out", o->out, "Output folder for frame_NNNN.png")->capture_default_str();
    sub->add_option("--video", o->video, "Also encode the frames to this .mp4 (needs ffmpeg)");
    addRenderOptions(sub, *o, true);
    return [o] { return runHeadlessRender(*o, "render"); };
}

}  // namespace terrain::app
