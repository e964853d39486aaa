#pragma once
// A scene's lights (sim/scene_lights.h) made ready for the frames: the image
// environment read and projected once, the analytic sky's SH basis projected
// once, and per frame the sun's position, colour and the daylight it leaves
// in the sky.
#include <array>
#include <memory>
#include <optional>

#include "engine/frame_data.h"
#include "sim/scene_lights.h"

namespace terrain::engine {

/// Where the sun stands: grid azimuth (from +x towards +y) and elevation, degrees.
struct SunPosition {
    float azimuthDeg = 0.0f, elevationDeg = 0.0f;
};

/// The sun's position at local solar time `hour` on spec's day and latitude
/// (declination from the day of the year, Cooper 1969; the hour angle 15 deg
/// per hour from solar noon), turned to the grid by spec.northAzimuthDeg.
SunPosition sunPosition(const SunSpec& spec, double hour);

/// Fraction of the sunlight above the atmosphere that reaches the ground at
/// this elevation, per channel (about 680, 550 and 440 nm): Beer-Lambert
/// along the relative air mass of Kasten & Young 1989 with Rayleigh optical
/// depths (Bucholtz 1995) plus a light aerosol load. 0 below the horizon.
std::array<float, 3> sunTransmittance(float elevationDeg);

/// What the sun does to a frame's lights: its key light (none once it is
/// below the horizon), the daylight it leaves in the sky (1 at full day) and
/// the tint it gives the horizon as it sets (1 by day).
struct SunState {
    std::optional<gi::KeyLight> key;
    float daylight = 1.0f;
    std::array<float, 3> horizonTint{1.0f, 1.0f, 1.0f};
};
SunState sunState(const SunSpec& sun, int frame);

class LightRig {
public:
    /// Validates the lights; reads and projects an image environment (throws
    /// IoError when it cannot be read, InputError on a bad value). What
    /// `previous` already holds for the same environment (the image, the sky's
    /// SH basis) is taken over instead of being read and projected again.
    explicit LightRig(const LightSet& spec, const LightRig* previous = nullptr);

    /// The lights of frame `frame` (0 = the first): with a sun, its position
    /// and colour at that frame's time of day, and a sky dimmed as it sets.
    SceneLights at(int frame) const;

    const LightSet& spec() const { return spec_; }

private:
    LightSet spec_;
    gi::ShRgb imageSh_;  // the image's SH, unscaled
    std::shared_ptr<const EnvironmentImage> image_;
    std::array<gi::ShRgb, 3> skyBasis_;  // SH of the analytic sky's zenith, horizon and ground terms at radiance 1
};

/// The GI's lights for these scene lights.
gi::GiLighting giLighting(const SceneLights& lights);

}  // namespace terrain::engine
