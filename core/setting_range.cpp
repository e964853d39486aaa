#include "core/setting_range.h"

#include <sstream>

#include "core/error.h"

namespace terrain {
namespace {

template <class T>
std::string bounds(const SettingRange<T>& r) {
    std::ostringstream s;
    if (r.zeroMeansDefault) s << "0 or ";
    s << "[" << r.lo << ", " << r.hi << "]";
    return s.str();
}

template <class T>
void check(const SettingRange<T>& r, T v, const std::string& label) {
    if (r.contains(v)) return;
    std::ostringstream s;
    s << (label.empty() ? std::string(r.name) : label) << " must be " << (r.zeroMeansDefault ? "" : "in ") << bounds(r)
      << " (got " << v << ")";
    throw InputError(s.str());
}

}  // namespace

std::string describe(const SettingRange<int>& r) { return std::string(r.what) + ", " + bounds(r); }
std::string describe(const SettingRange<std::int64_t>& r) { return std::string(r.what) + ", " + bounds(r); }
std::string describe(const SettingRange<float>& r) { return std::string(r.what) + ", " + bounds(r); }
std::string describe(const SettingRange<double>& r) { return std::string(r.what) + ", " + bounds(r); }

void checkRange(const SettingRange<int>& r, int v, const std::string& label) { check(r, v, label); }
void checkRange(const SettingRange<std::int64_t>& r, std::int64_t v, const std::string& label) { check(r, v, label); }
void checkRange(const SettingRange<float>& r, float v, const std::string& label) { check(r, v, label); }
void checkRange(const SettingRange<double>& r, double v, const std::string& label) { check(r, v, label); }

}  // namespace terrain
