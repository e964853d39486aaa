#include "app/demo_window.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>

#include "app/progress.h"
#include "app/window_controls.h"
#include "core/error.h"
#include "core/png_io.h"

namespace terrain::app {
using namespace render;
using namespace engine;
namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

// Exponential moving average, so the panel's numbers are readable.
void smooth(double& avg, double v) { avg = avg == 0.0 ? v : 0.9 * avg + 0.1 * v; }

struct ImGuiSession {
    explicit ImGuiSession(void* window) {
        IMGUI_CHECKVERSION();
        ImGui::CreateContext();
        ImGui::GetIO().IniFilename = nullptr;
        ImGui::StyleColorsDark();
        ImGui_ImplGlfw_InitForOpenGL(static_cast<GLFWwindow*>(window), true);
        ImGui_ImplOpenGL3_Init("#version 330 core");
    }
    ~ImGuiSession() {
        ImGui_ImplOpenGL3_Shutdown();
        ImGui_ImplGlfw_Shutdown();
        ImGui::DestroyContext();
    }
    ImGuiSession(const ImGuiSession&) = delete;
    ImGuiSession& operator=(const ImGuiSession&) = delete;
};

// The panel's light controls: they edit a copy of the declared lights and
// hand it back when something changed (the sky is re-projected then).
void drawLightControls(FramePipeline& pipeline) {
    LightSet l = pipeline.lightSpec();
    bool changed = false;
    EnvironmentSpec& e = l.environment;
    if (e.kind != EnvironmentSpec::Kind::Image) {
        int kind = e.kind == EnvironmentSpec::Kind::SunSky ? 1 : 0;
        const char* kinds[] = {"uniform sky", "sun and sky"};
        if (ImGui::Combo("environment", &kind, kinds, 2)) {
            e.kind = kind == 1 ? EnvironmentSpec::Kind::SunSky : EnvironmentSpec::Kind::Uniform;
            changed = true;
        }
    }
    changed |= ImGui::SliderFloat("sky intensity", &e.intensity, 0.0f, 4.0f);
    SunSpec& sun = l.sun;
    changed |= ImGui::Checkbox("sun follows the time of day", &sun.enabled);
    if (sun.enabled) {
        changed |= ImGui::SliderFloat("hour", &sun.hour, 0.0f, 24.0f, "%.2f h");
        changed |= ImGui::SliderFloat("hours per frame", &sun.hoursPerFrame, 0.0f, 0.5f, "%.3f");
        changed |= ImGui::SliderFloat("latitude", &sun.latitudeDeg, -90.0f, 90.0f);
        changed |= ImGui::SliderInt("day of year", &sun.dayOfYear, 1, 366);
    }
    for (std::size_t k = 0; k < l.keys.size(); ++k) {
        KeyLightSpec& key = l.keys[k];
        ImGui::PushID(static_cast<int>(k));
        ImGui::Text("key light %zu", k + 1);
        changed |= ImGui::SliderFloat("azimuth", &key.azimuthDeg, 0.0f, 359.0f);
        changed |= ImGui::SliderFloat("elevation", &key.elevationDeg, 1.0f, 89.0f);
        changed |= ImGui::SliderFloat("radius", &key.radiusDeg, 0.5f, 15.0f);
        changed |= ImGui::ColorEdit3("colour", key.rgb.data(), ImGuiColorEditFlags_Float | ImGuiColorEditFlags_HDR);
        ImGui::PopID();
    }
    if (changed) pipeline.setLights(l);
}

// The panel's material controls: albedos and where vegetation and snow lie;
// a change re-derives the maps (and so re-lights the GI) on the next frame.
void drawMaterialControls(FramePipeline& pipeline) {
    if (!ImGui::CollapsingHeader("materials")) return;
    MaterialSet m = pipeline.materials();
    bool changed = false;
    const auto colour = [&](const char* name, Material& mat) {
        changed |= ImGui::ColorEdit3(name, mat.albedo.data(), ImGuiColorEditFlags_Float);
    };
    colour("bedrock", m.bedrock);
    colour("soil", m.soil.material);
    colour("vegetation", m.vegetation.material);
    colour("snow", m.snow.material);
    colour("water body", m.water.material);
    if (m.vegetation.enabled)
        changed |= ImGui::DragFloat("vegetation up to (m)", &m.vegetation.maxAltitude, 10.0f,
                                    m.vegetation.minAltitude + 1.0f, 1.0e5f);
    if (m.snow.enabled) changed |= ImGui::DragFloat("snow line (m)", &m.snow.line, 10.0f, -1.0e4f, 1.0e5f);
    if (changed) pipeline.setMaterials(m);
}

// The control panel: what is shown, the frame's timings, and the settings it edits.
void drawPanel(FramePipeline& pipeline, RenderSettings& rs, bool& paused, const StageTimings& avg, double fpsAvg) {
    const char* lightingNames[] = {"key light only", "direct (sky + key)", "global (direct + bounces)"};
    const char* shadowNames[] = {"engine soft visibility", "shadow map", "none"};
    const char* debugNames[] = {"none",
                                "ambient",
                                "V (sky visibility)",
                                "key visibility",
                                "normals",
                                "pyramid level",
                                "GI shade map",
                                "U (indirect, global)",
                                "albedo (materials)",
                                "discharge",
                                "velocity",
                                "net erosion",
                                "wetness"};
    PipelineSettings& ps = pipeline.settings();
    ImGui::SetNextWindowPos(ImVec2(10, 10), ImGuiCond_FirstUseEver);
    ImGui::Begin("terrain");
    ImGui::Text("%s  %d x %d  tick %lld", pipeline.simulation().settings().name.c_str(), pipeline.frame().nx,
                pipeline.frame().ny, static_cast<long long>(pipeline.frame().tick));
    ImGui::Text("%.1f fps", fpsAvg > 0.0 ? 1000.0 / fpsAvg : 0.0);
    ImGui::Text("ms: sim %.1f  pyramids %.1f  scan %.1f", avg.sim, avg.pyramids, avg.scan);
    ImGui::Text("    integrate %.1f  shade %.1f  render %.1f", avg.integrate, avg.shade, avg.render);
    // incremental GI: a paused or static scene recomputes nothing
    ImGui::Text("GI recomputed: visibility %.0f %%, indirect %.0f %%", 100.0 * pipeline.giState().receiversRecomputed,
                100.0 * pipeline.giState().indirectRecomputed);
    ImGui::Separator();
    ImGui::Checkbox("pause simulation", &paused);
    int lighting = static_cast<int>(ps.lighting);
    if (ImGui::Combo("lighting", &lighting, lightingNames, 3)) ps.lighting = static_cast<LightingMode>(lighting);
    ImGui::SliderInt("bounces", &ps.gi.indirect.bounces, 0, 3);
    ImGui::Checkbox("amortise shading", &ps.gi.indirect.amortise);
    ImGui::Checkbox("incremental GI", &ps.gi.incremental);
    ImGui::SliderFloat("GI tolerance", &ps.gi.tolerance, 0.0f, 0.1f, "%.3f");
    int sub = ps.gi.subsample == 1 ? 0 : (ps.gi.subsample == 2 ? 1 : 2);
    ImGui::Text("sub-sampling");
    ImGui::SameLine();
    ImGui::RadioButton("1", &sub, 0);
    ImGui::SameLine();
    ImGui::RadioButton("2", &sub, 1);
    ImGui::SameLine();
    ImGui::RadioButton("4", &sub, 2);
    ps.gi.subsample = sub == 0 ? 1 : (sub == 1 ? 2 : 4);
    int shadow = static_cast<int>(rs.shadow);
    if (ImGui::Combo("key shadow", &shadow, shadowNames, 3)) rs.shadow = static_cast<ShadowMode>(shadow);
    int debug = static_cast<int>(rs.debug);
    if (ImGui::Combo("view", &debug, debugNames, 13)) rs.debug = static_cast<DebugView>(debug);
    // the hydrology maps are packed only while one of their views shows
    ps.hydrologyMaps = rs.debug >= DebugView::Discharge;
    ImGui::SliderInt("pyramid level", &ps.pyramidLevel, 0, 16);
    ImGui::Checkbox("water", &rs.water);
    ImGui::SameLine();
    ImGui::Checkbox("specular", &rs.specular);
    ImGui::SliderFloat("exposure", &rs.exposure, 0.1f, 4.0f);
    ImGui::SliderFloat("exaggeration (0 = auto)", &ps.verticalExaggeration, 0.0f, 10.0f);
    ImGui::Separator();
    drawLightControls(pipeline);
    ImGui::Separator();
    drawMaterialControls(pipeline);
    ImGui::TextDisabled("drag: orbit, wheel: zoom, WASD/QE: fly");
    ImGui::TextDisabled("P: pause, space: step, F12: screenshot, R: reload, H: hide");
    ImGui::End();
}

// R: the scene anew from its file (or the built-in); a bad file keeps the
// scene running and says why.
void reloadScene(const WindowDemoSetup& setup, std::unique_ptr<FramePipeline>& pipeline) {
    try {
        pipeline = setup.loadScene();
        std::printf("demo: reloaded scene %s\n", pipeline->simulation().settings().name.c_str());
    } catch (const Error& e) {
        std::fprintf(stderr, "demo: reload failed, the scene keeps running: %s\n", e.what());
    }
}

// F12: the frame as the window shows it (without the panel) to a PNG.
void writeScreenshot(Renderer& renderer, const RenderSettings& rs, int w, int h, const std::string& dir, int n) {
    try {
        ensureWritableDirectory(dir);
        std::vector<std::uint8_t> rgb;
        renderer.drawToImage(rs, w, h, rgb);
        char name[40];
        std::snprintf(name, sizeof name, "screenshot_%04d.png", n);
        const std::string file = (std::filesystem::path(dir) / name).string();
        writePngRgb(file, w, h, rgb);
        std::printf("demo: screenshot %s\n", file.c_str());
    } catch (const Error& e) {
        std::fprintf(stderr, "demo: no screenshot: %s\n", e.what());
    }
}

void smoothTimings(StageTimings& avg, const StageTimings& tm) {
    smooth(avg.sim, tm.sim);
    smooth(avg.pyramids, tm.pyramids);
    smooth(avg.scan, tm.scan);
    smooth(avg.integrate, tm.integrate);
    smooth(avg.shade, tm.shade);
    smooth(avg.render, tm.render);
}

}  // namespace

int runWindowDemo(WindowContext& window, const Gl& gl, const WindowDemoSetup& setup, RenderSettings& rs) {
    Renderer renderer(gl);
    KeyLatch latch(window.nativeHandle());  // before ImGui's backend, which chains to its callback
    ImGuiSession imgui(window.nativeHandle());
    std::unique_ptr<FramePipeline> pipeline = setup.loadScene();
    bool paused = false, panel = true;
    int frames = 0, screenshots = 0;
    StageTimings avg;
    double fpsAvg = 0.0;
    auto last = Clock::now();
    while (!window.shouldClose() && (setup.maxFrames <= 0 || frames < setup.maxFrames)) {
        // Paused, a frame changes only with input: wait for it (a 60 Hz redraw
        // at most), rather than redraw as fast as a display without vsync lets.
        if (paused)
            window.waitEvents(1.0 / 60.0);
        else
            window.pollEvents();
        ImGui_ImplOpenGL3_NewFrame();
        ImGui_ImplGlfw_NewFrame();
        ImGui::NewFrame();
        const WindowActions keys = readWindowControls(rs.camera, static_cast<float>(fpsAvg / 1000.0), latch);
        if (keys.reload) reloadScene(setup, pipeline);
        if (keys.togglePause) {
            paused = !paused;
            std::printf("demo: %s at tick %lld\n", paused ? "paused" : "running",
                        static_cast<long long>(pipeline->frame().tick));
        }
        panel ^= keys.togglePanel;
        // ---- simulation + GI (a paused window does no GI work: nothing changed) ------
        if (!paused || keys.step) {
            pipeline->advance();
            if (paused)
                std::printf("demo: stepped to tick %lld\n",
                            static_cast<long long>(pipeline->simulation().state().tick));
        } else {
            pipeline->timings().sim = 0.0;
        }
        pipeline->light();
        if (panel) drawPanel(*pipeline, rs, paused, avg, fpsAvg);
        ImGui::Render();
        // ---- draw ------------------------------------------------------------------------
        int w = 0, h = 0;
        window.framebufferSize(w, h);
        const auto t = Clock::now();
        if (w > 0 && h > 0) {
            renderer.upload(pipeline->frame());
            renderer.draw(rs, w, h, 0);
            if (keys.screenshot) writeScreenshot(renderer, rs, w, h, setup.screenshotDir, ++screenshots);
        }
        ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
        gl.Finish();
        pipeline->timings().render = msSince(t);
        window.swapBuffers();
        smoothTimings(avg, pipeline->timings());
        smooth(fpsAvg, msSince(last));
        last = Clock::now();
        ++frames;
    }
    return frames;
}

}  // namespace terrain::app
