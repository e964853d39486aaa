#include "sim/scene_lights.h"

#include <cmath>

#include "core/error.h"
#include "core/parse.h"

namespace terrain {
namespace {

void requireRadiance(const std::string& what, const std::array<float, 3>& rgb) {
    for (float v : rgb)
        if (!(v >= 0.0f) || !std::isfinite(v))
            throw InputError("lights: " + what + " must be finite and >= 0 (R, G, B)");
}

void requireIn(const std::string& what, float v, float lo, float hi) {
    if (!(v >= lo && v <= hi))
        throw InputError("lights: " + what + " = " + formatNumber(v) + " is out of range [" + formatNumber(lo) + ", " +
                         formatNumber(hi) + "]");
}

void validateKey(const std::string& what, float azimuth, float elevation, float radius,
                 const std::array<float, 3>& rgb) {
    if (!std::isfinite(azimuth)) throw InputError("lights: " + what + " azimuth must be finite");
    requireIn(what + " elevation", elevation, -90.0f, 90.0f);
    if (!(radius > 0.0f && radius < 90.0f)) throw InputError("lights: " + what + " radius must be in (0, 90) degrees");
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
    if (!(e.intensity >= 0.0f) || !std::isfinite(e.intensity))
        throw InputError("lights: environment intensity must be finite and >= 0");
    requireRadiance("sky zenith", e.zenith);
    requireRadiance("sky horizon", e.horizon);
    requireRadiance("sky ground", e.ground);
    if (!(e.visibility >= 0.0f) || !std::isfinite(e.visibility))
        throw InputError("lights: visibility must be finite and >= 0 m (0: no haze)");
    if (e.kind == EnvironmentSpec::Kind::Image && e.file.empty())
        throw InputError("lights: an image environment needs a file (.exr or .hdr)");
    for (std::size_t k = 0; k < l.keys.size(); ++k) {
        const KeyLightSpec& key = l.keys[k];
        validateKey("key light " + std::to_string(k + 1), key.azimuthDeg, key.elevationDeg, key.radiusDeg, key.rgb);
    }
    const SunSpec& s = l.sun;
    if (!s.enabled) return;
    requireIn("sun latitude", s.latitudeDeg, -90.0f, 90.0f);
    if (s.dayOfYear < 1 || s.dayOfYear > 366) throw InputError("lights: sun day of the year must be in 1..366");
    requireIn("sun hour", s.hour, 0.0f, 24.0f);
    requireIn("sun hours per frame", s.hoursPerFrame, -24.0f, 24.0f);
    validateKey("sun", s.northAzimuthDeg, 0.0f, s.radiusDeg, s.rgb);
}

}  // namespace terrain
