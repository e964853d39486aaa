#pragma once
// The range of every numeric scene value, declared once (core/setting_range.h).
// The scene file reader checks each value against its range as it reads it
// (the message names the key with its table), and the command-line flags that
// set the same values (--size, --seed, --dt, `terrain gi`'s --cell-size,
// --z-scale, --z-offset) check the same ranges naming the flag. The limits
// are physical: wide enough for any terrain on any planet, narrow enough
// that the simulation and the GI stay finite in single precision.
#include <cstdint>
#include <limits>

#include "core/setting_range.h"
#include "core/size_limits.h"

namespace terrain::scene_ranges {

// The physical limits the ranges below are built from, each stated once.
// Heights, depths and levels: ten times the Earth's relief (Everest 8.8 km
// above the sea, the Mariana Trench 11 km below it).
inline constexpr float kMaxAltitude = 1.0e5f;  // m
// Horizontal lengths and positions: beyond the Earth's circumference (40 000 km).
inline constexpr float kMaxLength = 1.0e8f;  // m
// The finest length a height field resolves: a millimetre. Finer cells turn
// height differences into slopes beyond what the GI's single-precision
// gradients can hold.
inline constexpr float kMinLength = 1.0e-3f;  // m
// Grid side: the engine's largest (core/size_limits.h); the grid's cell at most 1000 km.
inline constexpr int kMaxSide = kMaxGridSide;
inline constexpr float kMaxCellSize = 1.0e6f;  // m
// Gravity: from a dwarf planet's (Ceres 0.28 m/s^2) to four times Jupiter's (24.8 m/s^2).
inline constexpr float kMinGravity = 0.1f, kMaxGravity = 100.0f;  // m/s^2
// Rates (1/s): the models take rate * dt as the fraction moved in a step and
// clamp it to 1; the bound keeps the product finite.
inline constexpr float kMaxRate = 1000.0f;  // 1/s
// Radiance, in units of the shade an unoccluded white surface gets from it:
// a million times a bright sky, the sun's disc included, and after any number
// of bounces and exposures still far from the largest float.
inline constexpr float kMaxRadiance = 1.0e6f;
// Angles wrap around; beyond a million degrees a float no longer resolves a
// tenth of one.
inline constexpr float kMaxAngle = 1.0e6f;  // degrees

// Sizes, seed and time
inline constexpr SettingRange<int> kSize{"size", 1, kMaxSide, "Grid side in cells"};
inline constexpr SettingRange<float> kCellSize{"cell_size", kMinLength, kMaxCellSize, "Metres between grid points"};
inline constexpr SettingRange<std::int64_t> kSeed{"seed", 0, std::numeric_limits<std::int64_t>::max(),
                                                  "Seed of the scene generator"};
// Any step above the stability limit (at most 1 s) is clamped to it.
inline constexpr SettingRange<float> kDt{"dt", 0.0f, 3600.0f,
                                         "Time step in s (0: from the CFL limits; larger steps are clamped to them)"};
inline constexpr SettingRange<float> kSpinUp{"spin_up", 0.0f, 1.0e6f,
                                             "Simulated time before an animation's first frame, s"};
inline constexpr SettingRange<int> kChangeTile{"change_tile", 1, kMaxSide, "Cells per side of a change-tracking tile"};

// Heights and lengths shared by many keys
inline constexpr SettingRange<float> kAltitude{"altitude", -kMaxAltitude, kMaxAltitude, "A height or level, m"};
inline constexpr SettingRange<float> kDepth{"depth", 0.0f, kMaxAltitude, "A thickness or depth, m"};
inline constexpr SettingRange<float> kLength{"length", kMinLength, kMaxLength, "A horizontal length, m"};
inline constexpr SettingRange<float> kPosition{"position", -kMaxLength, kMaxLength, "A horizontal position, m"};
inline constexpr SettingRange<float> kAngle{"angle", -kMaxAngle, kMaxAngle, "An angle, degrees"};
inline constexpr SettingRange<float> kFraction{"fraction", 0.0f, 1.0f, "A fraction"};
inline constexpr SettingRange<float> kRate{"rate", 0.0f, kMaxRate, "A rate, 1/s"};
inline constexpr SettingRange<float> kGravity{"gravity", kMinGravity, kMaxGravity, "Gravity, m/s^2"};

// [terrain]
inline constexpr SettingRange<int> kOctaves{"octaves", 1, 24, "Noise octaves"};
inline constexpr SettingRange<float> kLacunarity{"lacunarity", 1.01f, 16.0f, "Wavelength divisor per octave"};
// 16 bits of a PNG DEM span at most the altitude range
inline constexpr SettingRange<float> kDemZScale{"z_scale", 1.0e-6f, 2.0f * kMaxAltitude / 65535.0f,
                                                "Metres per 16-bit step of a PNG DEM"};
inline constexpr SettingRange<float> kDemCellSize{"cell_size", kMinLength, kMaxCellSize,
                                                  "Metres between the DEM's samples (0: from the .vdb)", true};

// [hydraulic], [thermal], [waves]
inline constexpr SettingRange<float> kPipeArea{"pipe_area", 1.0e-3f, 1.0e3f, "Pipe cross-section, cell areas"};
// twenty times the heaviest rain measured (31 mm in a minute, 5e-4 m/s)
inline constexpr SettingRange<float> kRainRate{"rain_rate", 0.0f, 1.0e-2f, "Rain, m/s"};
inline constexpr SettingRange<float> kCapacity{"capacity", 0.0f, 1000.0f, "Sediment capacity constant"};
inline constexpr SettingRange<float> kTalus{"talus_deg", 0.0f, 89.0f, "Talus angle, degrees"};
inline constexpr SettingRange<float> kCourant{"courant", 1.0e-3f, 1.0f, "Courant number of the default step"};
inline constexpr SettingRange<float> kMaxCourant{"max_courant", 0.05f, 1.0f, "Courant number that forces sub-steps"};
inline constexpr SettingRange<float> kDryDepth{"dry_depth", 1.0e-6f, 1.0f,
                                               "Depth below which a face carries no flow, m"};
inline constexpr SettingRange<float> kManning{"friction", 0.0f, 1.0f, "Manning n, s/m^(1/3)"};
// five times the highest ocean wave measured (about 20 m)
inline constexpr SettingRange<float> kSwellAmplitude{"amplitude", 0.0f, 100.0f, "Swell amplitude, m"};
inline constexpr SettingRange<float> kSwellPeriod{"period", 0.1f, 3600.0f, "Swell period, s"};
inline constexpr SettingRange<float> kRampPeriods{"ramp_periods", 0.0f, 1.0e6f, "Swell ramp-up, periods"};
inline constexpr SettingRange<double> kDropTime{"time", 0.0, 1.0e9, "Time of a drop, s"};

// [lights]
inline constexpr SettingRange<float> kRadiance{"radiance", 0.0f, kMaxRadiance, "Radiance (R, G, B)"};
inline constexpr SettingRange<float> kVisibility{"visibility", 0.0f, kMaxLength,
                                                 "Haze: metres at which the distance fades into the sky (0: clear)"};
inline constexpr SettingRange<float> kElevation{"elevation", -90.0f, 90.0f, "Elevation above the horizon, degrees"};
inline constexpr SettingRange<float> kLightRadius{"radius", 1.0e-3f, 89.9f, "Angular radius of a key light, degrees"};
inline constexpr SettingRange<float> kLatitude{"latitude", -90.0f, 90.0f, "Latitude, degrees"};
inline constexpr SettingRange<int> kDayOfYear{"day", 1, 366, "Day of the year"};
inline constexpr SettingRange<float> kHour{"hour", 0.0f, 24.0f, "Local solar time, hours"};
inline constexpr SettingRange<float> kHoursPerFrame{"hours_per_frame", -24.0f, 24.0f, "Hours the sun moves per frame"};

// [camera]
inline constexpr SettingRange<float> kFieldOfView{"fov", 1.0f, 170.0f, "Vertical field of view, degrees"};
// frame numbers a float holds exactly, either side of the first frame
inline constexpr SettingRange<float> kCameraFrame{"frame", -1.0e6f, 1.0e6f, "Frame of a camera key"};
inline constexpr SettingRange<float> kPitch{"pitch", -89.0f, 89.0f, "Elevation of the eye above the target, degrees"};
inline constexpr SettingRange<float> kDistance{"distance", 1.0e-3f, 100.0f, "Distance of the eye, terrain extents"};
inline constexpr SettingRange<float> kTarget{"target", -100.0f, 100.0f,
                                             "Point looked at, fractions of the extent (z: of the relief)"};

}  // namespace terrain::scene_ranges
