#pragma once
// The interactive demo: a GLFW window with an orbit/zoom camera and an ImGui
// panel (comparison toggles, light parameters, per-stage timings, frame rate).
#include "render/context.h"
#include "render/gl.h"
#include "render/pipeline.h"
#include "render/renderer.h"

namespace terrain::render {

/// Runs the window until it is closed, or for maxFrames frames (> 0).
/// Returns the number of frames shown.
int runWindowDemo(WindowContext& window, const Gl& gl, FramePipeline& pipeline, RenderSettings& settings, int maxFrames);

}  // namespace terrain::render
