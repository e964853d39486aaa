#include "sim/scene_camera.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.h"
#include "sim/scene_ranges.h"

namespace terrain {
namespace {

// Catmull-Rom through p1 (t = 0) and p2 (t = 1).
float catmullRom(float p0, float p1, float p2, float p3, float t) {
    return 0.5f * (2.0f * p1 + (p2 - p0) * t + (2.0f * p0 - 5.0f * p1 + 4.0f * p2 - p3) * t * t +
                   (3.0f * p1 - p0 - 3.0f * p2 + p3) * t * t * t);
}

template <class Field>
float spline(const CameraKey& a, const CameraKey& b, const CameraKey& c, const CameraKey& d, float t, Field f) {
    return catmullRom(f(a), f(b), f(c), f(d), t);
}

}  // namespace

CameraKey cameraAt(const CameraPath& path, double frame) {
    const std::vector<CameraKey>& k = path.keys;
    if (k.empty()) throw InputError("camera path: no keyframes");
    if (frame <= k.front().frame) return k.front();
    if (frame >= k.back().frame) return k.back();
    std::size_t i = 0;
    while (k[i + 1].frame <= frame) ++i;
    const CameraKey& a = k[i > 0 ? i - 1 : i];
    const CameraKey& b = k[i];
    const CameraKey& c = k[i + 1];
    const CameraKey& d = k[std::min(i + 2, k.size() - 1)];
    const float t = static_cast<float>((frame - b.frame) / (c.frame - b.frame));
    CameraKey out;
    out.frame = static_cast<float>(frame);
    out.yawDeg = spline(a, b, c, d, t, [](const CameraKey& q) { return q.yawDeg; });
    out.pitchDeg = spline(a, b, c, d, t, [](const CameraKey& q) { return q.pitchDeg; });
    out.distance = spline(a, b, c, d, t, [](const CameraKey& q) { return q.distance; });
    for (std::size_t j = 0; j < 3; ++j)
        out.target[j] = spline(a, b, c, d, t, [j](const CameraKey& q) { return q.target[j]; });
    // the spline may overshoot between keys: keep the eye where the keys allow it
    out.pitchDeg = std::clamp(out.pitchDeg, -89.0f, 89.0f);
    out.distance = std::max(out.distance, std::min(b.distance, c.distance) * 0.5f);
    return out;
}

void validateCameraPath(const CameraPath& path) {
    namespace r = scene_ranges;
    checkRange(r::kFieldOfView, path.fovYDeg, "camera: field of view");
    for (std::size_t i = 0; i < path.keys.size(); ++i) {
        const CameraKey& k = path.keys[i];
        const std::string which = "camera key " + std::to_string(i + 1) + ": ";
        checkRange(r::kCameraFrame, k.frame, which + "frame");
        if (i > 0 && !(k.frame > path.keys[i - 1].frame))
            throw InputError(which + "frames must increase from key to key");
        checkRange(r::kAngle, k.yawDeg, which + "yaw");
        checkRange(r::kPitch, k.pitchDeg, which + "pitch");
        checkRange(r::kDistance, k.distance, which + "distance");
        for (float t : k.target) checkRange(r::kTarget, t, which + "target");
    }
}

}  // namespace terrain
