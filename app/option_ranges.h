#pragma once
// The range of every numeric command-line option that is the command line's
// own (core/setting_range.h); the options that set a scene value or a GI
// setting check that value's range (sim/scene_ranges.h, gi/settings_ranges.h).
// Each command checks its options against these before it reads any input.
#include <cstdint>

#include "core/setting_range.h"

namespace terrain::app::option_ranges {

inline constexpr SettingRange<int> kThreads{"--threads", 0, 256, "Worker threads (0: all cores)"};
// a billion steps: years of simulated time at the usual steps
inline constexpr SettingRange<std::int64_t> kTicks{"--ticks", 0, 1000000000, "Number of fixed time steps"};
inline constexpr SettingRange<std::int64_t> kHashEvery{
    "--hash-every", 0, 1000000000,
    "Print 'tick <t> hash <16 hex digits>' every E ticks (hash over the whole state; 0: never)"};
inline constexpr SettingRange<std::int64_t> kOutEvery{
    "--out-every", 0, 1000000000, "Write a frame every F ticks (0: every --hash-every ticks, else the last)"};
inline constexpr SettingRange<int> kFrames{"--frames", 1, 100000, "Frames"};
inline constexpr SettingRange<int> kImageSide{"--width and --height", 16, 8192, "Image side in pixels"};
inline constexpr SettingRange<int> kTicksPerFrame{"--ticks-per-frame", 0, 1000000,
                                                  "Simulation ticks between frames (0: the scene's pacing)"};
// clamped to the pyramid's last level
inline constexpr SettingRange<int> kPyramidLevel{"--pyramid-level", 0, 1024,
                                                 "Height-pyramid level for --debug pyramid"};
// exposure times the largest radiance (sim/scene_ranges.h) stays finite
inline constexpr SettingRange<float> kExposure{"--exposure", 1.0e-6f, 1000.0f, "Exposure before tone mapping"};
inline constexpr SettingRange<float> kExaggeration{"--exaggeration", 0.0f, 100.0f,
                                                   "Vertical exaggeration (0: automatic, relief >= 15% of the extent)"};
inline constexpr SettingRange<int> kReferenceDirections{"--reference-directions", 16, 1 << 20,
                                                        "Directions of the indirect reference"};
inline constexpr SettingRange<int> kReferenceLobeRings{
    "--reference-lobe-rings", 1, 256, "Glossy reference: rings of each Phong lobe's quadrature (2x as many azimuths)"};

}  // namespace terrain::app::option_ranges
