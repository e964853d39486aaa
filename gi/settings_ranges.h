#pragma once
// The range of every numeric GI setting, declared once (core/setting_range.h:
// name, bounds and meaning together). validateGiSettings (gi/settings.h)
// checks them, the command line prints them in its help, and the benchmark
// tables can name them; nothing else writes a bound down.
#include "core/setting_range.h"

namespace terrain::gi {

using terrain::checkRange;
using terrain::describe;
using terrain::SettingRange;

namespace ranges {

// Sub-sampling is further restricted to 1, 2 or 4 (validateGiSettings).
inline constexpr SettingRange<int> kSubsample{"subsample", 1, 4, "Receivers every s cells (1, 2 or 4)"};
inline constexpr SettingRange<int> kAzimuths{"azimuths", 3, 4096, "Azimuths m of the visibility scan"};
inline constexpr SettingRange<int> kLevelsPerOctave{"levels per octave", 1, 64, "Height pyramid levels per octave k_v"};
inline constexpr SettingRange<int> kLevelOffset{"level offset", 0, 32, "Height pyramid level offset o_v, octaves"};
inline constexpr SettingRange<float> kPeakBlend{"peak blend", 0.0f, 1.0f,
                                                "Share of max-decimated octaves in the height pyramid"};
inline constexpr SettingRange<int> kKeyLightAzimuths{"key light azimuths", 2, 256,
                                                     "Azimuths over a key light's extent"};
inline constexpr SettingRange<float> kPhongExponent{"Phong exponent", 0.01f, 10000.0f, "Phong exponent S"};
inline constexpr SettingRange<float> kSpecularWeight{"specular weight", 0.0f, 1.0f,
                                                     "Weight of the Phong lobe in the Lambert + Phong mixture"};
inline constexpr SettingRange<float> kTolerance{
    "GI tolerance", 0.0f, 1.0f,
    "Largest change in shade units a cached GI result may be behind by: the ambient map's for the visibility, the "
    "gathered radiance's for the indirect light (0: exact)"};
inline constexpr SettingRange<int> kRefreshEvery{"GI refresh interval", 0, 1000000,
                                                 "With incremental GI, recompute everything every N frames (0: never)"};
inline constexpr SettingRange<int> kBounces{"bounces", 0, 16, "Indirect light bounces (0: direct light only)"};
inline constexpr SettingRange<int> kRadianceLevelsPerOctave{"radiance levels per octave", 1, 64,
                                                            "Radiance pyramid levels per octave k_u"};
inline constexpr SettingRange<int> kRadianceLevelOffset{"radiance level offset", 0, 32,
                                                        "Radiance pyramid level offset o_u, octaves"};
inline constexpr SettingRange<int> kLobeAzimuths{"glossy lobe azimuths", 4, 4096,
                                                 "Global azimuths of the glossy lobe gather"};
// At most 16 rings of up to 16 x 64 directions: 8704 directions per lobe.
inline constexpr SettingRange<int> kLobeRings{
    "glossy lobe rings", 0, 16, "Rings of the glossy lobe quadrature (0: 3 below exponent 16, 2 from it up)"};
inline constexpr SettingRange<int> kLobeInnerDirections{
    "glossy lobe inner directions", 3, 64,
    "Directions of the glossy lobe quadrature's ring nearest the lobe's axis (each ring outwards has as many more)"};
inline constexpr SettingRange<int> kLobeNearStepsPerOctave{
    "glossy lobe near steps per octave", 1, 64, "Raw height steps per octave of the glossy lobe gather's walks"};
inline constexpr SettingRange<int> kLobeNearOctaves{"glossy lobe near octaves", 0, 16,
                                                    "The glossy lobe gather's raw height steps reach 2^this cells"};
inline constexpr SettingRange<int> kIndirectAzimuths{"indirect azimuths", 3, 4096,
                                                     "Azimuths of the indirect scan (0: the visibility's)", true};

}  // namespace ranges
}  // namespace terrain::gi
