// `terrain gi`: light a DEM with the GI fast path (Nowrouzezahrai & Snyder 2009) or the ground
// truth, write the shade and ambient maps, time the stages. The options and
// the run are app/gi_options.h and app/gi_run.h, shared with the Python module.
#include <cstdio>
#include <memory>
#include <string>

#include "app/commands.h"
#include "app/gi_options.h"
#include "app/gi_run.h"
#include "core/setting_range.h"
#include "sim/heightmap_io.h"
#include "sim/scene_ranges.h"

namespace terrain::app {
namespace {

GiInputs readInputs(const GiOptions& o, const ExponentSource& exponent) {
    float cellFromFile = 0.0f;
    GeoReference geo;
    Grid heights =
        readHeightmap(o.heightmap, static_cast<float>(o.zScale), static_cast<float>(o.zOffset), &cellFromFile, &geo);
    return giInputsFor(o, exponent, std::move(heights), cellFromFile, std::move(geo));
}

int runGi(const GiOptions& o) {
    checkGiOptions(o);
    ExponentSource exponent;
    const gi::GiSettings settings = giSettingsFrom(o, exponent);
    const GiInputs in = readInputs(o, exponent);
    // on stdout: stderr carries errors only
    std::printf("terrain gi: %s, %d x %d cells of %.4g m\n", o.heightmap.c_str(), in.heights.nx, in.heights.ny,
                in.cell);
    std::fflush(stdout);
    writeGiMaps(o, in, runGiFrames(o, settings, in));
    return 0;
}

}  // namespace

Runner addGiCommand(CLI::App& app) {
    auto o = std::make_shared<GiOptions>();
    CLI::App* sub =
        app.add_subcommand("gi", "Global illumination of a height field: soft shadows from sky and key lights");
    sub->add_option("--heightmap", o->heightmap, "16-bit PNG (height = O + S * value), .tif, float .exr or .vdb")
        ->required();
    namespace sr = scene_ranges;
    sub->add_option("--cell-size", o->cellSize, describe(sr::kDemCellSize) + " (required for PNG)");
    sub->add_option("--z-scale", o->zScale, describe(sr::kDemZScale) + " (S)")->capture_default_str();
    sub->add_option("--z-offset", o->zOffset, describe(sr::kAltitude) + ": the height of PNG value 0 (O)")
        ->capture_default_str();
    addGiOptions(sub, *o);
    return [o] { return runGi(*o); };
}

}  // namespace terrain::app
