#pragma once
// The interactive demo: a GLFW window with an orbit, zoom and fly camera and
// keys (app/window_controls.h), and an ImGui panel (comparison toggles,
// lights, per-stage timings, frame rate).
#include <functional>
#include <memory>
#include <string>

#include "engine/pipeline.h"
#include "render/context.h"
#include "render/gl.h"
#include "render/renderer.h"

namespace terrain::app {

struct WindowDemoSetup {
    /// Builds the scene's pipeline: at the start, and again on R (re-reading a scene file).
    std::function<std::unique_ptr<engine::FramePipeline>()> loadScene;
    std::string screenshotDir;  // F12 writes screenshot_NNNN.png here
    int maxFrames = 0;          // > 0: close after that many frames
};

/// Runs the window until it is closed, or for setup.maxFrames frames.
/// Returns the number of frames shown.
int runWindowDemo(render::WindowContext& window, const render::Gl& gl, const WindowDemoSetup& setup,
                  render::RenderSettings& settings);

}  // namespace terrain::app
