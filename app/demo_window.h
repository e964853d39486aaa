#pragma once
// The interactive demo: a GLFW window with an orbit/zoom camera and an ImGui
// panel (comparison toggles, light parameters, per-stage timings, frame rate).
#include "engine/pipeline.h"
#include "render/context.h"
#include "render/gl.h"
#include "render/renderer.h"

namespace terrain::app {

/// Runs the window until it is closed, or for maxFrames frames (> 0).
/// Returns the number of frames shown.
int runWindowDemo(render::WindowContext& window, const render::Gl& gl, engine::FramePipeline& pipeline,
                  render::RenderSettings& settings, int maxFrames);

}  // namespace terrain::app
