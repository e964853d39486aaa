#pragma once
// Where OpenGL comes from: one interface, two small platform files
// (context_osmesa.cpp: headless OSMesa; context_glfw.cpp: a GLFW window).
// Both hand the renderer a get-proc-address callback, from which it loads the
// one function table of render/gl.h.
#include <memory>
#include <string>

#include "core/error.h"

namespace terrain::render {

/// No OpenGL context could be made (no OSMesa, no display, too old a version).
class ContextError : public Error {
public:
    using Error::Error;
};

using GlProc = void (*)();
using GlGetProcAddress = GlProc (*)(const char* name);

class GlContext {
public:
    virtual ~GlContext() = default;
    virtual void makeCurrent() = 0;
    virtual GlGetProcAddress procAddress() const = 0;
    /// Framebuffer a frame is presented to (0 for a window; the renderer's own
    /// target for a headless context).
    virtual bool isWindow() const { return false; }
};

/// An OpenGL core context without a display (OSMesa: 4.5 core on llvmpipe,
/// else 3.3 core). Throws ContextError when none can be made.
std::unique_ptr<GlContext> createHeadlessContext();

/// A GLFW window with an OpenGL 3.3+ core context.
class WindowContext : public GlContext {
public:
    virtual bool shouldClose() const = 0;
    virtual void swapBuffers() = 0;
    virtual void pollEvents() = 0;
    /// Waits for input for at most `seconds`, then handles it like pollEvents.
    virtual void waitEvents(double seconds) = 0;
    virtual void framebufferSize(int& w, int& h) const = 0;
    /// The GLFWwindow*, for input callbacks and ImGui.
    virtual void* nativeHandle() const = 0;
    bool isWindow() const override { return true; }
};

/// Why there is no display, or "" when one seems to exist (DISPLAY or
/// WAYLAND_DISPLAY set).
std::string noDisplayReason();

/// Opens a window. Throws ContextError when there is no display or no
/// suitable context.
std::unique_ptr<WindowContext> createWindowContext(int width, int height, const std::string& title);

}  // namespace terrain::render
