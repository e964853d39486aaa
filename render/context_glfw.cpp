// A window with an OpenGL core context through GLFW.
#include <cstdlib>
#include <string>

#include <GLFW/glfw3.h>

#include "render/context.h"

namespace terrain::render {
namespace {

std::string lastGlfwError() {
    const char* d = nullptr;
    glfwGetError(&d);
    return d ? std::string(d) : std::string("unknown GLFW error");
}

class GlfwWindow final : public WindowContext {
public:
    GlfwWindow(int width, int height, const std::string& title) {
        if (!glfwInit()) throw ContextError("GLFW: cannot initialise (" + lastGlfwError() + ")");
        glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
        glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
        glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
        glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
        window_ = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
        if (!window_) {
            const std::string why = lastGlfwError();
            glfwTerminate();
            throw ContextError("GLFW: cannot open an OpenGL 3.3 core window (" + why + ")");
        }
        glfwMakeContextCurrent(window_);
        glfwSwapInterval(1);
    }
    ~GlfwWindow() override {
        glfwDestroyWindow(window_);
        glfwTerminate();
    }
    GlfwWindow(const GlfwWindow&) = delete;
    GlfwWindow& operator=(const GlfwWindow&) = delete;

    void makeCurrent() override { glfwMakeContextCurrent(window_); }
    GlGetProcAddress procAddress() const override {
        return [](const char* name) -> GlProc { return reinterpret_cast<GlProc>(glfwGetProcAddress(name)); };
    }
    bool shouldClose() const override { return glfwWindowShouldClose(window_); }
    void swapBuffers() override { glfwSwapBuffers(window_); }
    void pollEvents() override { glfwPollEvents(); }
    void waitEvents(double seconds) override { glfwWaitEventsTimeout(seconds); }
    void framebufferSize(int& w, int& h) const override { glfwGetFramebufferSize(window_, &w, &h); }
    void* nativeHandle() const override { return window_; }

private:
    GLFWwindow* window_ = nullptr;
};

}  // namespace

std::string noDisplayReason() {
    const char* x = std::getenv("DISPLAY");
    const char* w = std::getenv("WAYLAND_DISPLAY");
    if ((x && *x) || (w && *w)) return "";
    return "no display (DISPLAY and WAYLAND_DISPLAY are not set)";
}

std::unique_ptr<WindowContext> createWindowContext(int width, int height, const std::string& title) {
    const std::string why = noDisplayReason();
    if (!why.empty()) throw ContextError(why);
    return std::make_unique<GlfwWindow>(width, height, title);
}

}  // namespace terrain::render
