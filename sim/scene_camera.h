#pragma once
// Where an animation looks from: keyframes of an orbit camera (yaw, pitch
// and distance around a target point of the terrain), interpolated between
// frames. An orbit is keys with growing yaw (0 to 360 is one turn); a
// fly-through moves the target across the terrain at a short distance.
// Plain data: scene files ([[camera.key]]) and `terrain render
// --camera-key` set it; the renderer's camera takes cameraAt(frame), and
// never dips under the terrain (render/renderer.h).
#include <array>
#include <vector>

namespace terrain {

struct CameraKey {
    float frame = 0.0f;
    float yawDeg = 235.0f;   // azimuth of the eye around the target, from +x towards +y
    float pitchDeg = 34.0f;  // elevation of the eye above the target
    float distance = 1.35f;  // in terrain extents
    // the point looked at: fractions of the extent along x and y, and of the
    // relief (lowest to highest ground of the first frame) along z
    std::array<float, 3> target{0.5f, 0.5f, 0.5f};
};

struct CameraPath {
    std::vector<CameraKey> keys;  // frames strictly increasing; none: the renderer's default view
    float fovYDeg = 40.0f;
};

/// The camera at `frame`: Catmull-Rom between the keys around it (the end
/// keys repeated), so the motion has no corner at a key; held before the
/// first key and after the last. Requires at least one key.
CameraKey cameraAt(const CameraPath& path, double frame);

/// Throws InputError naming the first value outside its range
/// (sim/scene_ranges.h: pitch in [-89, 89], distance up to 100 extents, a
/// field of view in [1, 170], every value finite) or frames not increasing.
void validateCameraPath(const CameraPath& path);

}  // namespace terrain
