// Camera paths: the interpolation passes through every key without a
// corner, holds before the first and after the last, scene files declare
// paths, and bad keys are one clear error.
#include <cmath>
#include <filesystem>
#include <fstream>

#include <doctest/doctest.h>

#include "core/error.h"
#include "sim/scene.h"
#include "sim/scene_camera.h"

using namespace terrain;

namespace {

CameraPath orbit() {
    CameraPath p;
    for (int i = 0; i < 4; ++i) {
        CameraKey k;
        k.frame = 10.0f * static_cast<float>(i);
        k.yawDeg = 90.0f * static_cast<float>(i);  // one quarter turn per 10 frames
        k.pitchDeg = 30.0f + 5.0f * static_cast<float>(i % 2);
        k.distance = 1.0f + 0.1f * static_cast<float>(i);
        k.target = {0.5f, 0.5f - 0.1f * static_cast<float>(i), 0.5f};
        p.keys.push_back(k);
    }
    return p;
}

}  // namespace

TEST_CASE("camera: the path passes through its keys smoothly and holds at its ends") {
    const CameraPath p = orbit();
    CHECK_NOTHROW(validateCameraPath(p));
    for (const CameraKey& k : p.keys) {
        const CameraKey at = cameraAt(p, k.frame);
        CHECK(at.yawDeg == doctest::Approx(k.yawDeg));
        CHECK(at.pitchDeg == doctest::Approx(k.pitchDeg));
        CHECK(at.distance == doctest::Approx(k.distance));
        CHECK(at.target[1] == doctest::Approx(k.target[1]));
    }
    CHECK(cameraAt(p, -5.0).yawDeg == 0.0f);
    CHECK(cameraAt(p, 99.0).yawDeg == 270.0f);
    // an evenly turning orbit turns evenly between its keys too (Catmull-Rom reproduces linear motion)
    CHECK(cameraAt(p, 15.0).yawDeg == doctest::Approx(135.0));
    // no corner at a key: the yaw's rate just before and just after frame 10 agree
    const double h = 1e-2;
    const double before = (cameraAt(p, 10.0).yawDeg - cameraAt(p, 10.0 - h).yawDeg) / h;
    const double after = (cameraAt(p, 10.0 + h).yawDeg - cameraAt(p, 10.0).yawDeg) / h;
    CHECK(before == doctest::Approx(after).epsilon(0.01));
}

TEST_CASE("camera: bad paths are one clear error") {
    CameraPath p = orbit();
    p.keys[2].frame = p.keys[1].frame;
    CHECK_THROWS_WITH_AS(validateCameraPath(p), doctest::Contains("frames must increase"), InputError);
    p = orbit();
    p.keys[0].pitchDeg = 95.0f;
    CHECK_THROWS_WITH_AS(validateCameraPath(p), doctest::Contains("pitch"), InputError);
    p = orbit();
    p.keys[3].distance = 0.0f;
    CHECK_THROWS_WITH_AS(validateCameraPath(p), doctest::Contains("distance"), InputError);
    p = orbit();
    p.fovYDeg = 0.0f;
    CHECK_THROWS_WITH_AS(validateCameraPath(p), doctest::Contains("field of view"), InputError);
    CHECK_THROWS_AS(cameraAt(CameraPath{}, 0.0), InputError);
}

TEST_CASE("camera: scene files declare the path") {
    const std::filesystem::path dir = std::filesystem::temp_directory_path() / "terrain_test_camera";
    std::filesystem::create_directories(dir);
    auto write = [&](const char* name, const char* text) {
        std::ofstream(dir / name) << text;
        return (dir / name).string();
    };
    const SceneSettings s = loadSceneFile(write("fly.toml", R"(
base = "dem"
[camera]
fov = 50.0
[[camera.key]]
frame = 0
yaw = 200.0
pitch = 20.0
distance = 0.3
target = [0.2, 0.3]
[[camera.key]]
frame = 48
yaw = 260.0
pitch = 15.0
distance = 0.2
target = [0.7, 0.6, 0.8]
)"));
    CHECK(s.camera.fovYDeg == 50.0f);
    REQUIRE(s.camera.keys.size() == 2);
    CHECK(s.camera.keys[0].target[0] == 0.2f);
    CHECK(s.camera.keys[0].target[2] == 0.5f);  // the relief's middle unless given
    CHECK(s.camera.keys[1].target[2] == 0.8f);
    CHECK(cameraAt(s.camera, 24.0).target[0] == doctest::Approx(0.45));
    CHECK_THROWS_WITH_AS(loadSceneFile(write("b1.toml", "[[camera.key]]\nframe = 5\n[[camera.key]]\nframe = 2\n")),
                         doctest::Contains("frames must increase"), IoError);
    CHECK_THROWS_WITH_AS(loadSceneFile(write("b2.toml", "[[camera.key]]\ntarget = [0.5]\n")),
                         doctest::Contains("camera.key.target"), IoError);
    CHECK_THROWS_WITH_AS(loadSceneFile(write("b3.toml", "[camera]\nzoom = 2.0\n")), doctest::Contains("camera.zoom"),
                         IoError);
    std::filesystem::remove_all(dir);
}
