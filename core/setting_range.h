#pragma once
// The range of a numeric setting, declared once with its name and meaning.
// Each library declares the ranges of its own values beside them
// (gi/settings_ranges.h, sim/scene_ranges.h, app/option_ranges.h); the
// checks, the help texts and the error messages read them, and nothing else
// writes a bound down.
#include <cstdint>
#include <string>

namespace terrain {

/// A numeric setting: its name in messages, its closed range [lo, hi] and
/// what it means. `zeroMeansDefault`: 0 is also accepted and stands for "the
/// value derived from another setting" (say which in `what`).
template <class T>
struct SettingRange {
    const char* name;
    T lo, hi;
    const char* what;
    bool zeroMeansDefault = false;

    /// NaN is never contained.
    bool contains(T v) const { return (zeroMeansDefault && v == T(0)) || (v >= lo && v <= hi); }
};

/// "what, [lo, hi]" (or "what, 0 or [lo, hi]"), for command-line help.
std::string describe(const SettingRange<int>& r);
std::string describe(const SettingRange<std::int64_t>& r);
std::string describe(const SettingRange<float>& r);
std::string describe(const SettingRange<double>& r);

/// Throws InputError "<label> must be in [lo, hi] (got v)" unless
/// r.contains(v); the label is the range's name unless one is given (a
/// command-line flag, or a scene file's key with its table).
void checkRange(const SettingRange<int>& r, int v, const std::string& label = "");
void checkRange(const SettingRange<std::int64_t>& r, std::int64_t v, const std::string& label = "");
void checkRange(const SettingRange<float>& r, float v, const std::string& label = "");
void checkRange(const SettingRange<double>& r, double v, const std::string& label = "");

/// The same range over a wider type, to check a value before it is narrowed
/// (a scene file's 64-bit integers and doubles).
inline SettingRange<std::int64_t> widened(const SettingRange<int>& r) {
    return {r.name, r.lo, r.hi, r.what, r.zeroMeansDefault};
}
inline SettingRange<double> widened(const SettingRange<float>& r) {
    return {r.name, r.lo, r.hi, r.what, r.zeroMeansDefault};
}

}  // namespace terrain
