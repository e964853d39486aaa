#include "app/light_options.h"

#include <cmath>
#include <filesystem>

#include "core/error.h"
#include "core/parse.h"
#include "sim/scene_ranges.h"

namespace terrain::app {
namespace {

bool isImageFile(const std::string& f) {
    std::string e = std::filesystem::path(f).extension().string();
    for (char& c : e) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return e == ".exr" || e == ".hdr";
}

void applyEnvironment(const std::string& text, EnvironmentSpec& e) {
    if (text == "uniform") {
        e.kind = EnvironmentSpec::Kind::Uniform;
    } else if (text == "sunsky") {
        e.kind = EnvironmentSpec::Kind::SunSky;
    } else {
        const std::string file = text.rfind("env:", 0) == 0 ? text.substr(4) : text;
        if (!isImageFile(file))
            throw InputError("--light must be uniform, sunsky, env:FILE or an .exr / .hdr file (got '" + text + "')");
        e.kind = EnvironmentSpec::Kind::Image;
        e.file = file;
    }
}

KeyLightSpec parseKey(const std::string& text) {
    const std::vector<float> v = parseNumberList(text, "--key");
    if (v.size() != 6) throw InputError("--key '" + text + "': expected AZ_DEG,EL_DEG,RADIUS_DEG,R,G,B");
    KeyLightSpec k;
    k.azimuthDeg = v[0];
    k.elevationDeg = v[1];
    k.radiusDeg = v[2];
    k.rgb = {v[3], v[4], v[5]};
    return k;
}

void applySun(const std::string& text, SunSpec& sun) {
    if (text == "off") {
        sun.enabled = false;
        return;
    }
    const std::vector<float> v = parseNumberList(text, "--sun");
    if (v.empty() || v.size() > 4)
        throw InputError("--sun '" + text + "': expected HOUR[,HOURS_PER_FRAME[,LATITUDE_DEG[,DAY_OF_YEAR]]] or off");
    sun.enabled = true;
    sun.hour = v[0];
    if (v.size() > 1) sun.hoursPerFrame = v[1];
    if (v.size() > 2) sun.latitudeDeg = v[2];
    if (v.size() > 3) {
        // in its range before it is converted to an integer
        const SettingRange<int>& days = scene_ranges::kDayOfYear;
        checkRange(
            SettingRange<double>{days.name, static_cast<double>(days.lo), static_cast<double>(days.hi), days.what},
            static_cast<double>(v[3]), "--sun: the day of the year");
        if (v[3] != std::floor(v[3])) throw InputError("--sun: the day of the year is a whole number");
        sun.dayOfYear = static_cast<int>(v[3]);
    }
}

}  // namespace

void addLightOptions(CLI::App* sub, LightOptions& o, const std::string& defaults) {
    sub->add_option("--light", o.environment,
                    "Environment: uniform | sunsky (sky gradient) | env:FILE or FILE (.exr/.hdr equirectangular) "
                    "(default: " +
                        defaults + ")");
    sub->add_option("--light-intensity", o.intensity, "Environment radiance scale (default: " + defaults + ")");
    sub->add_option(
        "--visibility", o.visibility,
        "Haze: metres at which the distance fades into the horizon sky, 0 = clear air (default: " + defaults + ")");
    sub->add_option("--key", o.keys,
                    "Key light AZ_DEG,EL_DEG,RADIUS_DEG,R,G,B (repeatable; replaces the default key lights; "
                    "'none' for none)");
    sub->add_option("--sun", o.sun,
                    "A sun at the time of day HOUR (local solar time), moving HOURS_PER_FRAME each frame, at "
                    "LATITUDE_DEG on DAY_OF_YEAR: HOUR[,HOURS_PER_FRAME[,LATITUDE_DEG[,DAY_OF_YEAR]]], or off "
                    "(default: " +
                        defaults + ")");
}

void applyLightOptions(const LightOptions& o, LightSet& lights) {
    if (o.environment) applyEnvironment(*o.environment, lights.environment);
    if (o.intensity) lights.environment.intensity = *o.intensity;
    if (o.visibility) lights.environment.visibility = *o.visibility;
    if (!o.keys.empty()) {
        lights.keys.clear();
        if (!(o.keys.size() == 1 && o.keys[0] == "none"))
            for (const std::string& k : o.keys) lights.keys.push_back(parseKey(k));
    }
    if (o.sun) applySun(*o.sun, lights.sun);
    try {
        validateLights(lights);
    } catch (const InputError& e) {
        throw InputError(std::string(e.what()) + " (--light, --key, --sun or the scene's [lights])");
    }
}

void checkLightOptions(const LightOptions& o) {
    LightSet none;
    applyLightOptions(o, none);
}

}  // namespace terrain::app
