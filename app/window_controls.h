#pragma once
// The window's mouse and keys: left drag orbits, the wheel zooms, W/S and
// A/D fly the point looked at forward, back and sideways, Q/E lower and
// raise it; P pauses, space steps one frame (paused), F12 writes a
// screenshot, R reloads the scene, H hides the panel. Nothing reaches the
// camera while the panel has the mouse or the keyboard.
#include <bitset>

#include "render/renderer.h"

namespace terrain::app {

/// Presses of keys since they were last taken, latched by a GLFW key
/// callback: a key pressed and released between two frames still counts
/// (ImGui's key state would only show it released at a low frame rate).
/// Construct it before ImGui's GLFW backend, which calls it from its own
/// callback; it lives as long as the window's user pointer points to it.
class KeyLatch {
public:
    explicit KeyLatch(void* glfwWindow);
    KeyLatch(const KeyLatch&) = delete;
    KeyLatch& operator=(const KeyLatch&) = delete;
    /// Whether `key` (a GLFW key code) was pressed since the last take.
    bool take(int key);
    void press(int key);

private:
    std::bitset<512> pressed_;
};

/// What the keys asked for this frame.
struct WindowActions {
    bool togglePause = false, step = false, screenshot = false, reload = false, togglePanel = false;
};

/// Reads this frame's input into the camera (ImGui's view of the mouse and
/// of the held flight keys) and the latched action keys; `seconds` since the
/// last frame scales the flight.
WindowActions readWindowControls(render::OrbitCamera& camera, float seconds, KeyLatch& keys);

}  // namespace terrain::app
