#pragma once
// The range of every numeric GI setting, declared once (in the manner of
// Halide's GeneratorParam: name, bounds and meaning together). validateGiSettings
// (gi/settings.h) checks them, the command line prints them in its help, and
// the benchmark tables can name them; nothing else writes a bound down.
#include <string>

namespace terrain::gi {

/// A numeric setting: its name in messages, its closed range [lo, hi] and
/// what it means. `zeroMeansDefault`: 0 is also accepted and stands for "the
/// value derived from another setting" (say which in `what`).
template <class T>
struct SettingRange {
    const char* name;
    T lo, hi;
    const char* what;
    bool zeroMeansDefault = false;

    bool contains(T v) const { return (zeroMeansDefault && v == T(0)) || (v >= lo && v <= hi); }
};

/// "what [lo, hi]" (or "what: 0 or [lo, hi]"), for command-line help.
std::string describe(const SettingRange<int>& r);
std::string describe(const SettingRange<float>& r);

/// Throws InputError "<name> must be in [lo, hi] (got v)" unless r.contains(v)
/// (NaN is never contained).
void checkRange(const SettingRange<int>& r, int v);
void checkRange(const SettingRange<float>& r, float v);

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
inline constexpr SettingRange<int> kIndirectAzimuths{"indirect azimuths", 3, 4096,
                                                     "Azimuths of the indirect scan (0: the visibility's)", true};

}  // namespace ranges
}  // namespace terrain::gi
