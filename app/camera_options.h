#pragma once
// The camera options of `terrain render` (and the demo's headless
// fallback): a still camera (--yaw, --pitch, --distance) or keyframes
// (--camera-key), over the scene's [camera] path (sim/scene_camera.h).
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "render/renderer.h"
#include "sim/scene_camera.h"

namespace terrain::app {

struct CameraOptions {
    std::optional<float> yaw, pitch, distance;  // a still camera
    std::vector<std::string> keys;              // --camera-key FRAME,YAW,PITCH,DISTANCE[,TARGET_X,TARGET_Y[,TARGET_Z]]
    std::optional<float> fov;
};

void addCameraOptions(CLI::App* sub, CameraOptions& o);

/// Sets the path the options give over `path`: --camera-key replaces its
/// keys; else --yaw / --pitch / --distance make one still key (the rest from
/// the path's first key). Validates; throws InputError naming the option.
void applyCameraOptions(const CameraOptions& o, CameraPath& path);

/// The options on their own, before a scene is read: applied to an empty
/// path, they must give a valid one. Throws InputError naming the option.
void checkCameraOptions(const CameraOptions& o);

/// The renderer's camera at `frame` of the path (its default camera when the
/// path has no keys).
render::OrbitCamera cameraOfFrame(const CameraPath& path, int frame);

}  // namespace terrain::app
