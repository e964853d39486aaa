// `terrain demo`: the animated demo. With a display: a window (orbit/zoom
// camera, ImGui panel). Without one: says so in one line and renders a short
// headless animation to a folder, printing its path.
#include <cstdio>
#include <memory>
#include <string>

#include "app/commands.h"
#include "app/demo_window.h"
#include "app/render_options.h"
#include "core/error.h"
#include "core/parallel.h"
#include "engine/pipeline.h"
#include "render/context.h"
#include "render/gl.h"
#include "sim/scene.h"

namespace terrain::app {
namespace {

struct DemoOptions {
    RenderOptions render;
    bool headless = false;
    CLI::Option* frames = nullptr;  // given explicitly: the window closes after that many frames
};

int runDemo(DemoOptions& d) {
    RenderOptions& o = d.render;
    engine::PipelineSettings ps;
    render::RenderSettings rs;
    toSettings(o, ps, rs);
    const SceneSettings scene = resolveRenderScene(o);
    applyScene(o, scene, ps, rs);
    std::string why = d.headless ? "headless requested" : render::noDisplayReason();
    std::unique_ptr<render::WindowContext> window;
    if (why.empty()) {
        try {
            window = render::createWindowContext(o.width, o.height, "terrain demo: " + scene.name);
        } catch (const render::ContextError& e) {
            why = e.what();
        }
    }
    if (!window) {
        std::printf("demo: %s: rendering a headless animation to %s instead\n", why.c_str(), o.out.c_str());
        o.quiet = false;
        return runHeadlessRender(o, "demo");
    }
    return withThreads(o.threads, [&] {
        render::Gl gl;
        render::loadGl(gl, window->procAddress());
        WindowDemoSetup setup;
        // R reloads: the scene file read again, with the same options over it
        setup.loadScene = [&o, &ps] { return std::make_unique<engine::FramePipeline>(resolveRenderScene(o), ps); };
        setup.screenshotDir = o.out;
        setup.maxFrames = d.frames->count() > 0 ? o.frames : 0;
        std::printf(
            "demo: scene %s in a window (%s); drag to orbit, wheel to zoom, WASD/QE to fly, P pause, space step, F12 "
            "screenshot, R reload, H hide the panel\n",
            scene.name.c_str(), render::glDescription(gl).c_str());
        const int shown = runWindowDemo(*window, gl, setup, rs);
        std::printf("demo: %d frames shown\n", shown);
        return 0;
    });
}

}  // namespace

Runner addDemoCommand(CLI::App& app) {
    auto d = std::make_shared<DemoOptions>();
    d->render.out = "out/demo";
    d->render.frames = 48;
    d->render.width = 960;
    d->render.height = 540;
    CLI::App* sub = app.add_subcommand(
        "demo", "The animated demo: a window when there is a display, else a headless animation written to --out");
    sub->add_option("--scene", d->render.scene, "Built-in scene (erosion, waves, dem) or a .toml scene file")
        ->capture_default_str();
    sub->add_option("--out", d->render.out, "Output folder of the headless fallback")->capture_default_str();
    sub->add_flag("--headless", d->headless, "Render headless even when there is a display");
    addRenderOptions(sub, d->render, true);
    d->frames = sub->get_option("--frames");
    d->frames->description("Frames of the headless animation; given with a window: close it after that many frames");
    return [d] { return runDemo(*d); };
}

}  // namespace terrain::app
