// `terrain render`: the animated scene rendered headless (OSMesa) to PNG
// frames, optionally an mp4 through ffmpeg, with a per-stage timing summary.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <system_error>
#include <vector>

#include <unistd.h>

#include "app/commands.h"
#include "app/named_choice.h"
#include "app/option_ranges.h"
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
#include "sim/scene_ranges.h"

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
    SceneOverrides over;
    over.size = o.size;
    if (o.seed) over.seed = static_cast<std::uint64_t>(*o.seed);
    SceneSettings scene = resolveScene(o.scene, over);
    applyLightOptions(o.lights, scene.lights);
    applyCameraOptions(o.camera, scene.camera);
    return scene;
}

void addRenderOptions(CLI::App* sub, RenderOptions& o, bool withSize) {
    namespace r = option_ranges;
    namespace sr = scene_ranges;
    if (withSize)
        sub->add_option("--size", o.size,
                        describe(sr::kSize) + " (default: the scene file's size, which keeps its extent; else 256)");
    sub->add_option("--frames", o.frames, describe(r::kFrames))->capture_default_str();
    sub->add_option("--width", o.width, describe(r::kImageSide))->capture_default_str();
    sub->add_option("--height", o.height, describe(r::kImageSide))->capture_default_str();
    sub->add_option("--ticks-per-frame", o.ticksPerFrame, describe(r::kTicksPerFrame));
    sub->add_option("--seed", o.seed, describe(sr::kSeed) + " (default: the scene file's, else 1)");
    sub->add_option("--threads", o.threads, describe(r::kThreads))->capture_default_str();
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
           "Debug view: none | ambient | v | u (with --lighting global) | key | normals | pyramid | shade | albedo | "
           "discharge | velocity | net-erosion | wetness (the hydrology maps, each over its largest value)")
        ->capture_default_str();
    sub->add_option("--pyramid-level", o.pyramidLevel, describe(r::kPyramidLevel))->capture_default_str();
    sub->add_option("--exposure", o.exposure, describe(r::kExposure))->capture_default_str();
    sub->add_option("--lod", o.lodPixelError, describe(kLodRange) + " (0: the full grid, one vertex per grid point)")
        ->capture_default_str();
    sub->add_option("--exaggeration", o.exaggeration, describe(r::kExaggeration))->capture_default_str();
    addCameraOptions(sub, o.camera);
    sub->add_flag("--quiet", o.quiet, "Print only errors");
}

namespace {

// The numbers among the options, each in its range.
void checkRenderRanges(const RenderOptions& o) {
    namespace r = option_ranges;
    checkRange(r::kFrames, o.frames);
    checkRange(r::kImageSide, o.width, "--width");
    checkRange(r::kImageSide, o.height, "--height");
    checkRange(r::kThreads, o.threads);
    checkRange(r::kTicksPerFrame, o.ticksPerFrame);
    checkRange(r::kPyramidLevel, o.pyramidLevel);
    checkRange(r::kExposure, o.exposure);
    checkRange(r::kExaggeration, o.exaggeration);
    checkRange(kLodRange, o.lodPixelError);
    if (o.size) checkRange(scene_ranges::kSize, *o.size, "--size");
    if (o.seed) checkRange(scene_ranges::kSeed, *o.seed, "--seed");
    checkRange(gi::ranges::kSubsample, o.subsample, "--subsample");
    checkRange(gi::ranges::kBounces, o.bounces, "--bounces");
    if (o.giTolerance) checkRange(gi::ranges::kTolerance, *o.giTolerance, "--gi-tolerance");
    if (o.giRefresh) checkRange(gi::ranges::kRefreshEvery, *o.giRefresh, "--gi-refresh");
    if (!o.video.empty() && std::filesystem::path(o.video).extension() != ".mp4")
        throw InputError("--video must name an .mp4 file (got '" + o.video + "')");
}

engine::LightingMode lightingOf(const std::string& text) {
    using engine::LightingMode;
    return namedChoice<LightingMode>(
        "--lighting", text,
        {{"key", LightingMode::KeyOnly}, {"direct", LightingMode::Direct}, {"global", LightingMode::Global}});
}

render::ShadowMode shadowOf(const std::string& text) {
    using render::ShadowMode;
    return namedChoice<ShadowMode>(
        "--shadow", text,
        {{"soft", ShadowMode::SoftVisibility}, {"map", ShadowMode::ShadowMap}, {"none", ShadowMode::None}});
}

render::DebugView debugOf(const std::string& text) {
    using render::DebugView;
    return namedChoice<DebugView>("--debug", text,
                                  {{"none", DebugView::None},
                                   {"ambient", DebugView::Ambient},
                                   {"v", DebugView::SkyVisibility},
                                   {"u", DebugView::IndirectRadiance},
                                   {"key", DebugView::KeyVisibility},
                                   {"normals", DebugView::Normals},
                                   {"pyramid", DebugView::PyramidLevel},
                                   {"shade", DebugView::ShadeMap},
                                   {"albedo", DebugView::Albedo},
                                   {"discharge", DebugView::Discharge},
                                   {"velocity", DebugView::Velocity},
                                   {"net-erosion", DebugView::NetErosion},
                                   {"wetness", DebugView::Wetness}});
}

}  // namespace

void toSettings(const RenderOptions& o, engine::PipelineSettings& p, render::RenderSettings& r) {
    checkRenderRanges(o);
    p.gi = engine::defaultPipelineGi();
    p.gi.subsample = o.subsample;
    p.gi.indirect.bounces = o.bounces;
    p.gi.indirect.amortise = o.amortise;
    if (o.giIncremental) p.gi.incremental = *o.giIncremental;
    if (o.giTolerance) p.gi.tolerance = *o.giTolerance;
    if (o.giRefresh) p.gi.refreshEvery = *o.giRefresh;
    gi::validateGiSettings(p.gi);
    p.ticksPerFrame = o.ticksPerFrame;
    p.pyramidLevel = o.pyramidLevel;
    p.lighting = lightingOf(o.lighting);
    r.shadow = shadowOf(o.shadow);
    r.debug = debugOf(o.debug);
    // the hydrology maps are packed only for their views (a pass per tick drawn)
    p.hydrologyMaps = r.debug == render::DebugView::Discharge || r.debug == render::DebugView::Velocity ||
                      r.debug == render::DebugView::NetErosion || r.debug == render::DebugView::Wetness;
    if (r.debug == render::DebugView::IndirectRadiance && p.lighting != engine::LightingMode::Global)
        throw InputError("--debug u needs --lighting global (U is the indirect light)");
    r.exposure = o.exposure;
    p.verticalExaggeration = o.exaggeration;
    r.lodPixelError = o.lodPixelError;
    // the options on their own, before any scene is read: a bad --key, --sun
    // or camera key fails here
    checkLightOptions(o.lights);
    checkCameraOptions(o.camera);
}

void applyScene(const RenderOptions& o, const SceneSettings& scene, engine::PipelineSettings& p,
                render::RenderSettings& r) {
    if (!o.giIncremental && scene.gi.incremental) p.gi.incremental = *scene.gi.incremental;
    if (!o.giTolerance && scene.gi.tolerance) {
        checkRange(gi::ranges::kTolerance, *scene.gi.tolerance, o.scene + ": 'gi.tolerance'");
        p.gi.tolerance = *scene.gi.tolerance;
    }
    if (!o.giRefresh && scene.gi.refreshEvery) {
        checkRange(widened(gi::ranges::kRefreshEvery), *scene.gi.refreshEvery, o.scene + ": 'gi.refresh'");
        p.gi.refreshEvery = static_cast<int>(*scene.gi.refreshEvery);
    }
    r.camera = cameraOfFrame(scene.camera, 0);
}

namespace {

// No NaN or Inf reaches an image: the arrays a frame uploads are checked
// whenever they change, so a run fails at the frame where they went wrong.
class FrameGuard {
public:
    void check(const engine::FrameData& f, int frame) {
        if (f.heightsVersion != heights_) require(f.heights, "the terrain", frame);
        if (f.shadeVersion != shade_) {
            require(f.shade, "the lighting", frame);
            require(f.key, "the lighting", frame);
            require(f.receiver, "the lighting", frame);
        }
        heights_ = f.heightsVersion;
        shade_ = f.shadeVersion;
    }

private:
    static void require(const std::vector<float>& v, const char* what, int frame) {
        for (float x : v)
            if (!std::isfinite(x))
                throw InputError("frame " + std::to_string(frame) + ": " + what +
                                 " is not finite (NaN or Inf); the scene's values are out of their physical range");
    }
    std::int64_t heights_ = -1, shade_ = -1;
};

// What the frames took, stage by stage (printSummary's columns).
struct FrameStats {
    std::vector<std::vector<double>> stage = std::vector<std::vector<double>>(7);
    double recomputed = 0.0;          // receivers whose visibility the frames recomputed, summed over frames
    double indirectRecomputed = 0.0;  // the same for the indirect light
};

FrameStats renderFrames(const RenderOptions& o, const char* label, const SceneSettings& scene,
                        engine::FramePipeline& pipeline, render::Renderer& renderer, render::RenderSettings& rs) {
    FrameStats stats;
    FrameGuard guard;
    std::vector<std::uint8_t> rgb;
    Progress progress(label, o.frames, !o.quiet);
    for (int f = 0; f < o.frames; ++f) {
        pipeline.advance();
        pipeline.light();
        guard.check(pipeline.frame(), f);
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
        stats.recomputed += pipeline.giState().receiversRecomputed;
        stats.indirectRecomputed += pipeline.giState().indirectRecomputed;
        const double values[7] = {tm.sim, tm.pyramids, tm.scan, tm.integrate, tm.shade, renderMs, writeMs};
        for (int i = 0; i < 7; ++i) stats.stage[static_cast<std::size_t>(i)].push_back(values[i]);
        progress.update(f + 1);
    }
    progress.finish();
    return stats;
}

}  // namespace

int runHeadlessRender(const RenderOptions& o, const char* label) {
    engine::PipelineSettings ps;
    render::RenderSettings rs;
    // Every option, then the scene, fails on bad input before any file is read or written.
    toSettings(o, ps, rs);
    const SceneSettings scene = resolveRenderScene(o);
    applyScene(o, scene, ps, rs);
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
        const FrameStats stats = renderFrames(o, label, scene, pipeline, renderer, rs);
        const std::string dir = std::filesystem::absolute(o.out).lexically_normal().string();
        if (!o.quiet) {
            printSummary(label, o, ps, stats.stage, stats.recomputed, stats.indirectRecomputed);
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
