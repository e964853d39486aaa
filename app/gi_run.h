#pragma once
// Running `terrain gi` on heights already read: the lights and albedo the
// options give, the fast path (o.frames times) or the ground truth, and the
// maps it writes. Shared by the command line and the Python module.
#include <array>
#include <memory>

#include "app/gi_options.h"
#include "core/geotiff_io.h"
#include "core/grid.h"
#include "engine/light_rig.h"
#include "gi/albedo_io.h"
#include "gi/horizon_angles.h"
#include "gi/lights.h"

namespace terrain::app {

/// What a frame lights: the heights, their cell size and the albedo maps.
struct GiInputs {
    Grid heights;
    double cell = 0.0;
    GeoReference geo;  // a GeoTIFF input's place and CRS, given to .tif outputs
    gi::AlbedoMap albedoMap;
    const gi::AlbedoMap* albedo = nullptr;
    std::unique_ptr<engine::LightRig> lights;  // frame f is lit by lights->at(f)
    gi::GiLighting lighting;                   // frame 0's
};

/// The inputs for `heights` (cellFromSource: the file's own cell size, 0
/// when it has none; --cell-size overrides it): reads the lights, the albedo
/// and the Phong exponent map the options name. Throws InputError / IoError.
GiInputs giInputsFor(const GiOptions& o, const ExponentSource& exponent, Grid heights, float cellFromSource,
                     GeoReference geo);

/// A frame's results, the maps `terrain gi` can write: the shade (direct
/// light, plus the indirect light with bounces), the ambient (sky-view) map
/// and the indirect light alone (when hasIndirect).
struct GiMaps {
    std::array<Grid, 3> shade;
    Grid ambient;
    std::array<Grid, 3> indirect;
    bool hasIndirect = false;
    Grid svf;                    // with --out-svf: the sky-view factor --svf-kind names
    gi::HorizonAngles horizons;  // with --out-horizons
};

/// The fast path (o.frames times on the same field, the first a warm-up;
/// --time prints each frame's stages) or, with o.reference, the ground
/// truth. Runs under o.threads worker threads.
GiMaps runGiFrames(const GiOptions& o, const gi::GiSettings& settings, const GiInputs& in);

/// Checks every map finite (InputError, nothing written, otherwise), then
/// writes the --out-shade, --out-ambient, --out-indirect and --out-exr files
/// given (with the input's georeferencing, heights and cell size).
void writeGiMaps(const GiOptions& o, const GiInputs& in, const GiMaps& maps);

}  // namespace terrain::app
