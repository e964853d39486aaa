#pragma once
// The options of `terrain gi` that say how a height field is lit and what is
// written, shared by the command line and the Python module (python/): both
// register the same CLI11 flags, check them the same way and build the
// frame's settings from them with the same functions, so a frame run from
// either is the same frame.
#include <string>

#include <CLI/CLI.hpp>

#include "app/light_options.h"
#include "gi/settings.h"

namespace terrain::app {

struct GiOptions {
    std::string heightmap;  // the input's name (a file, or what the caller calls it) in messages
    double cellSize = 0.0;
    double zScale = 1.0;
    double zOffset = 0.0;
    LightOptions lights;  // over a uniform sky of radiance 1 and no key light
    // The numeric settings bind straight into the engine's settings: their
    // defaults and ranges are the engine's own (gi/settings.h).
    gi::GiSettings settings = gi::GiSettings{};
    std::string indirectKernel;
    std::string interp;
    int threads = 0;
    bool reference = false;
    bool progress = true;  // the reference's progress line on stderr (no flag: the Python module turns it off)
    std::string outShade, outAmbient;
    float exposure = 1.0f;  // of the .png shade map
    int frames = 1;
    bool time = false;
    // indirect light
    std::string brdf = "lambert";
    std::string albedo;
    std::string outIndirect;
    std::string outExr;             // every map as channels of one float32 EXR
    std::string outSvf;             // a sky-view factor (gi/sky_view.h, gi/ambient_horizon.h)
    std::string svfKind = "plain";  // which one --out-svf writes: plain | normal
    std::string outHorizons;        // horizon elevation angles per azimuth (gi/horizon_angles.h)
    int referenceDirections = 2048;
    int referenceLobeRings = 12;    // glossy reference: lobe quadrature rings (ReferenceGiSettings::lobeRings)
    std::string glossy;             // vector | scalar | lobe (glossy indirect light)
    std::string glossyLobeMembers;  // windowed | sh (what the lobe gather's first-bounce members send)
    std::string glossyPositivity;   // clamp | off (negative Phong radiance clamped, or the paper's linear values)
    std::string phongExponent;      // VALUE or a 16-bit PNG
    std::string phongExponentRange = "1,1000";
};

/// Which sky-view factor --out-svf writes.
enum class SvfKind {
    Plain,   // 1 - mean sin(max(0, horizon)): the open fraction of the hemisphere over the horizontal (gi/sky_view.h)
    Normal,  // the cosine-weighted visible sky at the texel's normal / pi: the ambient map (gi/ambient_horizon.h)
};

/// The --svf-kind the options name. InputError when it is neither.
SvfKind svfKindOf(const GiOptions& o);

/// Registers every flag of `terrain gi` but those naming the input
/// (--heightmap, --cell-size, --z-scale, --z-offset) on `sub`, bound to `o`.
void addGiOptions(CLI::App* sub, GiOptions& o);

/// Everything about the options that can be wrong, before any input is
/// read. Throws InputError naming the flag.
void checkGiOptions(const GiOptions& o);

/// Where the Phong exponent comes from: a constant (in the settings), or a
/// 16-bit PNG mapped to [lo, hi].
struct ExponentSource {
    bool fromFile = false;
    float lo = 1.0f, hi = 1000.0f;
};

/// The frame's settings from the options: the modes named by strings, then
/// one range check of everything (gi/settings.h). Throws InputError.
gi::GiSettings giSettingsFrom(const GiOptions& o, ExponentSource& exponent);

}  // namespace terrain::app
