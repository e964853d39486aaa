#include "gi/settings_ranges.h"

#include <cmath>
#include <sstream>

#include "core/error.h"

namespace terrain::gi {
namespace {

template <class T>
std::string bounds(const SettingRange<T>& r) {
    std::ostringstream s;
    if (r.zeroMeansDefault) s << "0 or ";
    s << "[" << r.lo << ", " << r.hi << "]";
    return s.str();
}

template <class T>
void check(const SettingRange<T>& r, T v) {
    if (r.contains(v)) return;
    std::ostringstream s;
    s << r.name << " must be " << (r.zeroMeansDefault ? "" : "in ") << bounds(r) << " (got " << v << ")";
    throw InputError(s.str());
}

}  // namespace

std::string describe(const SettingRange<int>& r) { return std::string(r.what) + ", " + bounds(r); }
std::string describe(const SettingRange<float>& r) { return std::string(r.what) + ", " + bounds(r); }
void checkRange(const SettingRange<int>& r, int v) { check(r, v); }
void checkRange(const SettingRange<float>& r, float v) { check(r, v); }

}  // namespace terrain::gi
