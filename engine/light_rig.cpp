#include "engine/light_rig.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/image_io.h"
#include "engine/smoothstep.h"

namespace terrain::engine {
namespace {

constexpr double kDeg = 0.017453292519943295;

// The analytic sky (gi::sunSkyLight without its sun lobe) is linear in its
// three colours: project each term once at radiance 1 and mix per frame.
std::array<gi::ShRgb, 3> projectSkyBasis() {
    std::array<gi::ShRgb, 3> basis;
    for (int term = 0; term < 3; ++term) {
        gi::SunSkySettings s;
        for (int c = 0; c < 3; ++c) {
            s.zenith[c] = term == 0 ? 1.0f : 0.0f;
            s.horizon[c] = term == 1 ? 1.0f : 0.0f;
            s.ground[c] = term == 2 ? 1.0f : 0.0f;
            s.sun[c] = 0.0f;
        }
        basis[static_cast<std::size_t>(term)] = gi::sunSkyLight(s);
    }
    return basis;
}

gi::ShRgb scaled(const gi::ShRgb& sh, float k) {
    gi::ShRgb out = sh;
    for (gi::ShVector& v : out.c)
        for (auto& x : v) x *= k;
    return out;
}

gi::KeyLight keyLight(float azimuthDeg, float elevationDeg, float radiusDeg, const std::array<float, 3>& rgb) {
    gi::KeyLight k;
    k.azimuthDeg = azimuthDeg;
    k.elevationDeg = elevationDeg;
    k.radiusDeg = radiusDeg;
    for (std::size_t c = 0; c < 3; ++c) k.rgb[c] = rgb[c];
    return k;
}

// How much daylight the sky keeps with the sun at this elevation: full from
// 15 deg up, fading through twilight to a faint night sky.
float daylight(float elevationDeg) { return std::max(0.02f, smoothstep(-6.0f, 15.0f, elevationDeg)); }

}  // namespace

SunPosition sunPosition(const SunSpec& spec, double hour) {
    const double decl = -23.44 * kDeg * std::cos(2.0 * 3.141592653589793 / 365.0 * (spec.dayOfYear + 10));
    const double h = 15.0 * kDeg * (hour - 12.0);
    const double lat = spec.latitudeDeg * kDeg;
    // the sun's direction in local east, north, up
    const double east = -std::cos(decl) * std::sin(h);
    const double north = std::sin(decl) * std::cos(lat) - std::cos(decl) * std::sin(lat) * std::cos(h);
    const double up = std::sin(lat) * std::sin(decl) + std::cos(lat) * std::cos(decl) * std::cos(h);
    const double compass = std::atan2(east, north) / kDeg;  // from north towards east
    SunPosition p;
    p.azimuthDeg = static_cast<float>(std::remainder(spec.northAzimuthDeg + compass, 360.0));
    p.elevationDeg = static_cast<float>(std::asin(std::clamp(up, -1.0, 1.0)) / kDeg);
    return p;
}

std::array<float, 3> sunTransmittance(float elevationDeg) {
    if (elevationDeg <= -6.0f) return {0.0f, 0.0f, 0.0f};
    const double h = elevationDeg;
    const double airMass = 1.0 / (std::sin(h * kDeg) + 0.50572 * std::pow(h + 6.07995, -1.6364));
    const double rayleigh[3] = {0.045, 0.097, 0.236};
    const double aerosol = 0.08;
    std::array<float, 3> t;
    for (int c = 0; c < 3; ++c)
        t[static_cast<std::size_t>(c)] = static_cast<float>(std::exp(-(rayleigh[c] + aerosol) * airMass));
    return t;
}

LightRig::LightRig(const LightSet& spec, const LightRig* previous) : spec_(spec) {
    validateLights(spec_);
    const EnvironmentSpec& e = spec_.environment;
    const EnvironmentSpec* was = previous ? &previous->spec_.environment : nullptr;
    if (e.kind == EnvironmentSpec::Kind::SunSky) {
        if (was && was->kind == e.kind)
            skyBasis_ = previous->skyBasis_;
        else
            skyBasis_ = projectSkyBasis();
    }
    if (e.kind == EnvironmentSpec::Kind::Image && was && was->kind == e.kind && was->file == e.file) {
        imageSh_ = previous->imageSh_;
        image_ = previous->image_;
    } else if (e.kind == EnvironmentSpec::Kind::Image) {
        auto image = std::make_shared<EnvironmentImage>();
        image->rgb = readEquirect(e.file, image->width, image->height);
        try {
            imageSh_ = gi::projectEquirect(image->rgb, image->width, image->height);
        } catch (const InputError& err) {
            throw IoError(e.file, err.what());
        }
        image_ = std::move(image);
    }
}

SunState sunState(const SunSpec& sun, int frame) {
    SunState s;
    if (!sun.enabled) return s;
    const SunPosition p = sunPosition(sun, sun.hour + static_cast<double>(sun.hoursPerFrame) * frame);
    const std::array<float, 3> t = sunTransmittance(p.elevationDeg);
    // a sun wholly below the horizon lights nothing
    if (p.elevationDeg > -sun.radiusDeg)
        s.key = keyLight(p.azimuthDeg, p.elevationDeg, sun.radiusDeg,
                         {sun.rgb[0] * t[0], sun.rgb[1] * t[1], sun.rgb[2] * t[2]});
    s.daylight = daylight(p.elevationDeg);
    // the horizon takes on the low sun's colour (its light's hue, brightest
    // channel 1) as it sets: not at all from 20 deg up, 60 % at 0 deg
    const std::array<float, 3> low = sunTransmittance(std::max(p.elevationDeg, 0.0f));
    const float k = 0.6f * (1.0f - smoothstep(0.0f, 20.0f, p.elevationDeg));
    for (std::size_t c = 0; c < 3; ++c) s.horizonTint[c] = 1.0f + k * (low[c] / low[0] - 1.0f);
    return s;
}

SceneLights LightRig::at(int frame) const {
    SceneLights l;
    const EnvironmentSpec& e = spec_.environment;
    l.hazeExtinction = e.visibility > 0.0f ? 3.912f / e.visibility : 0.0f;
    const SunState sun = sunState(spec_.sun, frame);
    if (sun.key) l.keys.push_back(*sun.key);
    const float skyScale = e.intensity * sun.daylight;
    for (const KeyLightSpec& k : spec_.keys)
        l.keys.push_back(keyLight(k.azimuthDeg, k.elevationDeg, k.radiusDeg, k.rgb));
    switch (e.kind) {
        case EnvironmentSpec::Kind::Uniform:
            l.sky = gi::uniformSkyLight(skyScale);
            l.skyKind = SkyKind::Sh;
            break;
        case EnvironmentSpec::Kind::SunSky:
            for (std::size_t c = 0; c < 3; ++c) {
                l.zenith[c] = skyScale * e.zenith[c];
                l.horizon[c] = skyScale * e.horizon[c] * sun.horizonTint[c];
                l.ground[c] = skyScale * e.ground[c];
                const std::array<float, 3> w{l.zenith[c], l.horizon[c], l.ground[c]};
                for (std::size_t i = 0; i < l.sky.c[c].size(); ++i)
                    l.sky.c[c][i] =
                        w[0] * skyBasis_[0].c[c][i] + w[1] * skyBasis_[1].c[c][i] + w[2] * skyBasis_[2].c[c][i];
            }
            l.skyKind = SkyKind::Gradient;
            break;
        case EnvironmentSpec::Kind::Image:
            l.sky = scaled(imageSh_, skyScale);
            l.skyKind = SkyKind::Image;
            l.image = image_;
            l.imageScale = skyScale;
            break;
    }
    return l;
}

gi::GiLighting giLighting(const SceneLights& lights) {
    gi::GiLighting g;
    g.environment = lights.sky;
    g.keys = lights.keys;
    if (lights.skyKind == SkyKind::Gradient) g.gradient = gi::SkyGradient{lights.zenith, lights.horizon, lights.ground};
    return g;
}

}  // namespace terrain::engine
