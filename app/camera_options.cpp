#include "app/camera_options.h"

#include "core/error.h"
#include "core/parse.h"

namespace terrain::app {
namespace {

CameraKey parseKey(const std::string& text) {
    const std::vector<float> v = parseNumberList(text, "--camera-key");
    if (v.size() != 4 && v.size() != 6 && v.size() != 7)
        throw InputError("--camera-key '" + text +
                         "': expected FRAME,YAW_DEG,PITCH_DEG,DISTANCE[,TARGET_X,TARGET_Y[,TARGET_Z]]");
    CameraKey k;
    k.frame = v[0];
    k.yawDeg = v[1];
    k.pitchDeg = v[2];
    k.distance = v[3];
    for (std::size_t j = 4; j < v.size(); ++j) k.target[j - 4] = v[j];
    return k;
}

}  // namespace

void addCameraOptions(CLI::App* sub, CameraOptions& o) {
    sub->add_option("--yaw", o.yaw, "Still camera: azimuth of the eye around the terrain, degrees (default 235)");
    sub->add_option("--pitch", o.pitch, "Still camera: elevation of the eye, degrees (default 34)");
    sub->add_option("--distance", o.distance, "Still camera: distance in terrain extents (default 1.35)");
    sub->add_option("--camera-key", o.keys,
                    "Camera keyframe FRAME,YAW_DEG,PITCH_DEG,DISTANCE[,TARGET_X,TARGET_Y[,TARGET_Z]] (the point looked "
                    "at: fractions of the extent, z of the relief; default 0.5,0.5,0.5); repeatable, frames "
                    "increasing, interpolated smoothly; replaces the scene's [camera] path");
    sub->add_option("--fov", o.fov, "Vertical field of view, degrees (default: the scene's, else 40)");
}

void applyCameraOptions(const CameraOptions& o, CameraPath& path) {
    if (!o.keys.empty()) {
        path.keys.clear();
        for (const std::string& k : o.keys) path.keys.push_back(parseKey(k));
    } else if (o.yaw || o.pitch || o.distance) {
        CameraKey still = path.keys.empty() ? CameraKey{} : path.keys.front();
        still.frame = 0.0f;
        if (o.yaw) still.yawDeg = *o.yaw;
        if (o.pitch) still.pitchDeg = *o.pitch;
        if (o.distance) still.distance = *o.distance;
        path.keys = {still};
    }
    if (o.fov) path.fovYDeg = *o.fov;
    try {
        validateCameraPath(path);
    } catch (const InputError& e) {
        throw InputError(std::string(e.what()) +
                         " (--yaw, --pitch, --distance, --fov, --camera-key or the scene's [camera])");
    }
}

void checkCameraOptions(const CameraOptions& o) {
    CameraPath none;
    applyCameraOptions(o, none);
}

render::OrbitCamera cameraOfFrame(const CameraPath& path, int frame) {
    render::OrbitCamera c;
    c.fovYDeg = path.fovYDeg;
    if (path.keys.empty()) return c;
    const CameraKey k = cameraAt(path, frame);
    c.yawDeg = k.yawDeg;
    c.pitchDeg = k.pitchDeg;
    c.distance = k.distance;
    c.targetX = k.target[0];
    c.targetY = k.target[1];
    c.targetZ = k.target[2];
    return c;
}

}  // namespace terrain::app
