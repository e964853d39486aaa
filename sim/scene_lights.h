#pragma once
// How a scene is lit, as plain data: an environment (uniform, an analytic
// sky, or an HDR image), any number of fixed key lights, and optionally a sun
// that follows the time of day over the animation. The frame pipeline turns
// this into the GI's lights every frame (engine/light_rig.h); scene files
// ([lights]) and the command line (--light, --key, --sun) set it.
//
// Directions: azimuth in degrees from the grid's +x axis towards +y,
// elevation from the horizon up. The sun's compass needs to know where north
// lies on the grid: sun.northAzimuthDeg (default -90: north is -y, image
// rows running north to south as in a DEM).
#include <array>
#include <string>
#include <vector>

namespace terrain {

struct EnvironmentSpec {
    enum class Kind { Uniform, SunSky, Image };
    Kind kind = Kind::Uniform;
    std::string file;        // Image: an equirectangular .exr or .hdr
    float intensity = 1.0f;  // radiance scale (Uniform: the radiance itself)
    // SunSky: radiance straight up, at the horizon and below it (RGB)
    std::array<float, 3> zenith{0.135f, 0.2025f, 0.3825f};
    std::array<float, 3> horizon{0.279f, 0.342f, 0.45f};
    std::array<float, 3> ground{0.10f, 0.09f, 0.08f};
    // Haze: the distance at which a dark object fades into the horizon sky
    // (meteorological visibility; extinction 3.912 / visibility, Koschmieder
    // 1924). 0: a perfectly clear atmosphere.
    float visibility = 0.0f;  // m
};

/// A spherical cap light: R,G,B is the shade it gives an unoccluded white
/// surface facing it (gi/lights.h, KeyLight).
struct KeyLightSpec {
    float azimuthDeg = 0.0f;
    float elevationDeg = 45.0f;
    float radiusDeg = 3.0f;
    std::array<float, 3> rgb{1.0f, 1.0f, 1.0f};
};

/// The sun at a place and time: its position from the latitude, the day of
/// the year and the local solar time, advancing hoursPerFrame each frame; its
/// colour the light above the atmosphere dimmed along the air mass.
struct SunSpec {
    bool enabled = false;
    float latitudeDeg = 45.8f;  // Chamonix
    int dayOfYear = 172;        // 1..366 (172: the June solstice)
    float hour = 10.0f;         // local solar time of the first frame, 0..24
    float hoursPerFrame = 0.0f;
    float northAzimuthDeg = -90.0f;
    float radiusDeg = 3.0f;                      // wider than the real 0.27 deg: soft shadows from a hazy sun
    std::array<float, 3> rgb{2.6f, 2.6f, 2.6f};  // above the atmosphere
};

struct LightSet {
    EnvironmentSpec environment;
    std::vector<KeyLightSpec> keys;
    SunSpec sun;  // when enabled, the first key light, ahead of `keys`
};

/// The lights of the built-in scenes: a clear sky and a low sun from the
/// north-west as a fixed key light; the 60 km "dem" scene adds the haze of a
/// clear alpine day.
LightSet builtinLights(const std::string& scene);

/// Throws InputError naming the first value outside its range
/// (sim/scene_ranges.h: radiance and intensity finite, >= 0 and bounded, a key
/// light's elevation in [-90, 90], its radius, the sun's latitude, day and
/// hour) or an image environment without a file.
void validateLights(const LightSet& lights);

}  // namespace terrain
