#include "app/window_controls.h"

#include <algorithm>
#include <cmath>

#include <GLFW/glfw3.h>
#include <imgui.h>

namespace terrain::app {
namespace {

constexpr float kDeg = 0.017453292519943295f;

// Left drag orbits, the wheel zooms.
void orbitAndZoom(render::OrbitCamera& camera) {
    const ImGuiIO& io = ImGui::GetIO();
    if (io.WantCaptureMouse) return;
    if (io.MouseDown[0]) {
        camera.yawDeg -= io.MouseDelta.x * 0.3f;
        camera.pitchDeg = std::clamp(camera.pitchDeg + io.MouseDelta.y * 0.3f, -30.0f, 89.0f);
    }
    if (io.MouseWheel != 0.0f)
        camera.distance = std::clamp(camera.distance * (1.0f - 0.1f * io.MouseWheel), 0.02f, 6.0f);
}

// W/S, A/D, Q/E move the point looked at; the speed follows the zoom, so
// close views move finely. The renderer keeps the eye above the ground.
void fly(render::OrbitCamera& camera, float seconds) {
    auto axis = [](int plus, int minus) {
        return (ImGui::IsKeyDown(plus) ? 1.0f : 0.0f) - (ImGui::IsKeyDown(minus) ? 1.0f : 0.0f);
    };
    const float forward = axis(GLFW_KEY_W, GLFW_KEY_S), right = axis(GLFW_KEY_D, GLFW_KEY_A),
                up = axis(GLFW_KEY_E, GLFW_KEY_Q);
    if (forward == 0.0f && right == 0.0f && up == 0.0f) return;
    const float step = 0.3f * camera.distance * std::clamp(seconds, 0.0f, 0.25f);
    // the eye sits at target + (cos yaw, sin yaw): forward points from it to the target
    const float fx = -std::cos(camera.yawDeg * kDeg), fy = -std::sin(camera.yawDeg * kDeg);
    camera.targetX = std::clamp(camera.targetX + step * (forward * fx + right * fy), -0.5f, 1.5f);
    camera.targetY = std::clamp(camera.targetY + step * (forward * fy - right * fx), -0.5f, 1.5f);
    camera.targetZ = std::clamp(camera.targetZ + 2.0f * step * up, -1.0f, 3.0f);
}

void latchKey(GLFWwindow* window, int key, int /*scancode*/, int action, int /*mods*/) {
    if (action == GLFW_PRESS)
        if (auto* latch = static_cast<KeyLatch*>(glfwGetWindowUserPointer(window))) latch->press(key);
}

}  // namespace

KeyLatch::KeyLatch(void* glfwWindow) {
    auto* w = static_cast<GLFWwindow*>(glfwWindow);
    glfwSetWindowUserPointer(w, this);
    glfwSetKeyCallback(w, latchKey);
}

void KeyLatch::press(int key) {
    if (key >= 0 && static_cast<std::size_t>(key) < pressed_.size()) pressed_.set(static_cast<std::size_t>(key));
}

bool KeyLatch::take(int key) {
    if (key < 0 || static_cast<std::size_t>(key) >= pressed_.size() || !pressed_.test(static_cast<std::size_t>(key)))
        return false;
    pressed_.reset(static_cast<std::size_t>(key));
    return true;
}

WindowActions readWindowControls(render::OrbitCamera& camera, float seconds, KeyLatch& keys) {
    orbitAndZoom(camera);
    WindowActions a;
    if (ImGui::GetIO().WantCaptureKeyboard) {
        for (int k : {GLFW_KEY_P, GLFW_KEY_SPACE, GLFW_KEY_F12, GLFW_KEY_R, GLFW_KEY_H})
            keys.take(k);  // typed into the panel
        return a;
    }
    fly(camera, seconds);
    a.togglePause = keys.take(GLFW_KEY_P);
    a.step = keys.take(GLFW_KEY_SPACE);
    a.screenshot = keys.take(GLFW_KEY_F12);
    a.reload = keys.take(GLFW_KEY_R);
    a.togglePanel = keys.take(GLFW_KEY_H);
    return a;
}

}  // namespace terrain::app
