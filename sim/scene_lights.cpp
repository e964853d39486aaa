#include "sim/scene_lights.h"

#include <cmath>

#include "core/error.h"
#include "sim/scene_ranges.h"

namespace terrain {
namespace {

namespace r = scene_ranges;

void requireRadiance(const std::string& what, const std::array<float, 3>& rgb) {
    for (float v : rgb) checkRange(r::kRadiance, v, "lights: " + what);
}

void validateKey(const std::string& what, float azimuth, float elevation, float radius,
                 const std::array<float, 3>& rgb) {
    checkRange(r::kAngle, azimuth, "lights: " + what + " azimuth");
    checkRange(r::kElevation, elevation, "lights: " + what + " elevation");
    checkRange(r::kLightRadius, radius, "lights: " + what + " radius");
    requireRadiance(what + " rgb", rgb);
}

}  // namespace

LightSet builtinLights(const std::string& scene) {
    LightSet l;
    l.environment.kind = EnvironmentSpec::Kind::SunSky;
    KeyLightSpec sun;
    sun.azimuthDeg = 300.0f;
    sun.elevationDeg = 22.0f;
    sun.radiusDeg = 3.0f;
    sun.rgb = {1.9f, 1.75f, 1.5f};
    l.keys.push_back(sun);
    if (scene == "dem") l.environment.visibility = 400000.0f;
    return l;
}

void validateLights(const LightSet& l) {
    const EnvironmentSpec& e = l.environment;
    checkRange(r::kRadiance, e.intensity, "lights: environment intensity");
    requireRadiance("sky zenith", e.zenith);
    requireRadiance("sky horizon", e.horizon);
    requireRadiance("sky ground", e.ground);
    checkRange(r::kVisibility, e.visibility, "lights: visibility");
    if (e.kind == EnvironmentSpec::Kind::Image && e.file.empty())
        throw InputError("lights: an image environment needs a file (.exr or .hdr)");
    for (std::size_t k = 0; k < l.keys.size(); ++k) {
        const KeyLightSpec& key = l.keys[k];
        validateKey("key light " + std::to_string(k + 1), key.azimuthDeg, key.elevationDeg, key.radiusDeg, key.rgb);
    }
    const SunSpec& s = l.sun;
    if (!s.enabled) return;
    checkRange(r::kLatitude, s.latitudeDeg, "lights: sun latitude");
    checkRange(r::kDayOfYear, s.dayOfYear, "lights: sun day of the year");
    checkRange(r::kHour, s.hour, "lights: sun hour");
    checkRange(r::kHoursPerFrame, s.hoursPerFrame, "lights: sun hours per frame");
    validateKey("sun", s.northAzimuthDeg, 0.0f, s.radiusDeg, s.rgb);
}

}  // namespace terrain
