// `terrain gi`: light a DEM with the GI fast path (Nowrouzezahrai & Snyder 2009) or the ground
// truth, write the shade and ambient maps, time the stages.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "app/commands.h"
#include "app/gi_images.h"
#include "app/light_options.h"
#include "app/option_ranges.h"
#include "app/progress.h"
#include "core/error.h"
#include "core/finite.h"
#include "core/geotiff_io.h"
#include "core/parallel.h"
#include "core/parse.h"
#include "engine/light_rig.h"
#include "gi/albedo_io.h"
#include "gi/frame.h"
#include "gi/reference.h"
#include "gi/reference_gi.h"
#include "sim/heightmap_io.h"
#include "sim/scene_ranges.h"

namespace terrain::app {
namespace {

struct GiOptions {
    std::string heightmap;
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
    std::string outShade, outAmbient;
    float exposure = 1.0f;  // of the .png shade map
    int frames = 1;
    bool time = false;
    // indirect light
    std::string brdf = "lambert";
    std::string albedo;
    std::string outIndirect;
    std::string outExr;  // every map as channels of one float32 EXR
    int referenceDirections = 2048;
    std::string glossy;         // vector | scalar (glossy indirect light)
    std::string phongExponent;  // VALUE or a 16-bit PNG
    std::string phongExponentRange = "1,1000";
};

// --brdf lambert | phong:EXP | mix:W[,EXP] (Lambert + W x normalised Phong)
void parseBrdf(const std::string& text, gi::ShadingSettings& s) {
    auto number = [&](const std::string& item) {
        try {
            std::size_t used = 0;
            const float v = std::stof(item, &used);
            if (used != item.size() || !std::isfinite(v)) throw std::invalid_argument(item);
            return v;
        } catch (const std::exception&) {
            throw InputError("--brdf '" + text + "': '" + item + "' is not a number");
        }
    };
    if (text == "lambert") {
        s.brdf = gi::Brdf::Lambert;
    } else if (text.rfind("phong:", 0) == 0) {
        s.brdf = gi::Brdf::Phong;
        s.phongExponent = number(text.substr(6));
    } else if (text.rfind("mix:", 0) == 0) {
        s.brdf = gi::Brdf::LambertPlusPhong;
        const std::string rest = text.substr(4);
        const auto comma = rest.find(',');
        s.specularWeight = number(rest.substr(0, comma));
        if (comma != std::string::npos) s.phongExponent = number(rest.substr(comma + 1));
        checkRange(gi::ranges::kSpecularWeight, s.specularWeight, "--brdf mix: weight");
    } else {
        throw InputError("--brdf must be lambert, phong:EXP or mix:W[,EXP] (got '" + text + "')");
    }
    checkRange(gi::ranges::kPhongExponent, s.phongExponent, "--brdf: Phong exponent");
}

// The phong exponent option: a constant, or a 16-bit PNG mapped to a range.
struct ExponentSource {
    bool fromFile = false;
    float lo = 1.0f, hi = 1000.0f;
};

ExponentSource parsePhongExponent(const GiOptions& o, gi::GiSettings& settings) {
    ExponentSource e;
    if (o.phongExponent.empty()) return e;
    const bool numeric = o.phongExponent.find_first_not_of("0123456789.eE+-") == std::string::npos;
    if (numeric) {
        const std::vector<float> v = parseNumberList(o.phongExponent, "--phong-exponent");
        if (v.size() != 1 || !gi::ranges::kPhongExponent.contains(v[0]))
            throw InputError("--phong-exponent: a constant must be one number, " +
                             gi::describe(gi::ranges::kPhongExponent) + " (got '" + o.phongExponent + "')");
        settings.shading.phongExponent = v[0];
        return e;
    }
    e.fromFile = true;
    const std::vector<float> r = parseNumberList(o.phongExponentRange, "--phong-exponent-range");
    if (r.size() != 2)
        throw InputError("--phong-exponent-range: expected MIN,MAX (got '" + o.phongExponentRange + "')");
    e.lo = r[0];
    e.hi = r[1];
    if (!(gi::ranges::kPhongExponent.contains(e.lo) && gi::ranges::kPhongExponent.contains(e.hi) && e.lo <= e.hi))
        throw InputError("--phong-exponent-range: need MIN <= MAX, both in " +
                         gi::describe(gi::ranges::kPhongExponent) + " (got '" + o.phongExponentRange + "')");
    return e;
}

// The frame's settings from the options: the modes named by strings, then
// one range check of everything (gi/settings.h).
gi::GiSettings settingsFrom(const GiOptions& o, ExponentSource& exponent) {
    gi::GiSettings settings = o.settings;
    parseBrdf(o.brdf, settings.shading);
    if (!o.glossy.empty()) {
        if (o.glossy == "vector")
            settings.indirect.glossy = gi::GlossyIndirect::VectorPyramid;
        else if (o.glossy == "scalar")
            settings.indirect.glossy = gi::GlossyIndirect::ScalarPyramid;
        else
            throw InputError("--glossy must be vector or scalar (got '" + o.glossy + "')");
    }
    exponent = parsePhongExponent(o, settings);
    if (!o.indirectKernel.empty()) {
        if (o.indirectKernel == "sh")
            settings.indirect.lambert = gi::LambertIndirect::ShKernel;
        else if (o.indirectKernel == "blocker")
            settings.indirect.lambert = gi::LambertIndirect::BlockerRadiance;
        else
            throw InputError("--indirect-kernel must be blocker or sh (got '" + o.indirectKernel + "')");
    }
    if (!o.interp.empty()) {
        if (o.interp == "linear")
            settings.visibility.interp = gi::AzimuthInterp::Linear;
        else if (o.interp == "bspline")
            settings.visibility.interp = gi::AzimuthInterp::Bspline;
        else
            throw InputError("--interp must be linear or bspline (got '" + o.interp + "')");
    }
    gi::validateGiSettings(settings);
    return settings;
}

// The GI settings the flags set, each in its range (naming the flag;
// validateGiSettings checks them all again, with what no flag sets).
void checkGiFlags(const gi::GiSettings& s) {
    namespace r = gi::ranges;
    checkRange(r::kSubsample, s.subsample, "--subsample");
    checkRange(r::kAzimuths, s.visibility.azimuths, "--azimuths");
    checkRange(r::kLevelsPerOctave, s.pyramid.levelsPerOctave, "--levels-per-octave");
    checkRange(r::kLevelOffset, s.pyramid.levelOffset, "--level-offset");
    checkRange(r::kBounces, s.indirect.bounces, "--bounces");
    checkRange(r::kTolerance, s.tolerance, "--gi-tolerance");
    checkRange(r::kRefreshEvery, s.refreshEvery, "--gi-refresh");
    checkRange(r::kRadianceLevelsPerOctave, s.indirect.radiance.levelsPerOctave, "--radiance-levels-per-octave");
    checkRange(r::kRadianceLevelOffset, s.indirect.radiance.levelOffset, "--radiance-level-offset");
    checkRange(r::kIndirectAzimuths, s.indirect.azimuths, "--indirect-azimuths");
}

// The output files, before any work: each must be a file in a folder we can write to.
void checkOutputs(const GiOptions& o) {
    const auto oneOf = [](const std::string& file, std::initializer_list<const char*> exts) {
        const std::string ext = extensionOf(file);
        return file.empty() || isGeoTiffPath(file) || std::find(exts.begin(), exts.end(), ext) != exts.end();
    };
    if (!oneOf(o.outShade, {".png", ".exr"}))
        throw InputError("--out-shade must end in .png, .exr or .tif (got '" + o.outShade + "')");
    if (!oneOf(o.outAmbient, {".npy", ".exr"}))
        throw InputError("--out-ambient must end in .npy, .exr or .tif (got '" + o.outAmbient + "')");
    if (!oneOf(o.outIndirect, {".npy", ".exr", ".png"}))
        throw InputError("--out-indirect must end in .npy, .exr, .png or .tif (got '" + o.outIndirect + "')");
    if (!o.outExr.empty() && extensionOf(o.outExr) != ".exr")
        throw InputError("--out-exr must end in .exr (got '" + o.outExr + "')");
    if (!o.outIndirect.empty() && o.settings.indirect.bounces == 0 && !o.reference)
        throw InputError("--out-indirect needs --bounces >= 1");
    for (const std::string* out : {&o.outShade, &o.outAmbient, &o.outIndirect, &o.outExr})
        if (!out->empty()) checkWritableFile(*out);
}

// Everything about the options that can be wrong, before any input is read.
void checkOptions(const GiOptions& o) {
    namespace r = option_ranges;
    namespace sr = scene_ranges;
    checkRange(r::kThreads, o.threads);
    checkRange(r::kFrames, o.frames);
    checkRange(r::kExposure, o.exposure);
    checkRange(r::kReferenceDirections, o.referenceDirections);
    checkRange(widened(sr::kDemCellSize), o.cellSize, "--cell-size");
    checkRange(widened(sr::kDemZScale), o.zScale, "--z-scale");
    checkRange(widened(sr::kAltitude), o.zOffset, "--z-offset");
    // said rather than ignored: a user giving them expects them applied
    if (isGeoTiffPath(o.heightmap) && (o.zScale != 1.0 || o.zOffset != 0.0))
        throw InputError(
            "--z-scale and --z-offset apply to PNG heightmaps; a GeoTIFF's heights are used as stored, "
            "in metres");
    if (extensionOf(o.heightmap) == ".exr" && (o.zScale != 1.0 || o.zOffset != 0.0))
        throw InputError(
            "--z-scale and --z-offset apply to PNG heightmaps; an EXR's heights are used as stored, in metres");
    checkGiFlags(o.settings);
    checkLightOptions(o.lights);
    checkOutputs(o);
}

// What a frame lights: the heights, their cell size and the albedo maps.
struct GiInputs {
    Grid heights;
    double cell = 0.0;
    GeoReference geo;  // a GeoTIFF input's place and CRS, given to .tif outputs
    gi::AlbedoMap albedoMap;
    const gi::AlbedoMap* albedo = nullptr;
    std::unique_ptr<engine::LightRig> lights;  // frame f is lit by lights->at(f)
    gi::GiLighting lighting;                   // frame 0's
};

GiInputs readInputs(const GiOptions& o, const ExponentSource& exponent) {
    GiInputs in;
    LightSet lights;  // a uniform sky of radiance 1 unless the options say otherwise
    applyLightOptions(o.lights, lights);
    in.lights = std::make_unique<engine::LightRig>(lights);
    in.lighting = engine::giLighting(in.lights->at(0));
    float cellFromFile = 0.0f;
    in.heights =
        readHeightmap(o.heightmap, static_cast<float>(o.zScale), static_cast<float>(o.zOffset), &cellFromFile, &in.geo);
    // --cell-size overrides the file's own (a .tif's geotransform, a .vdb's voxel size)
    in.cell = o.cellSize > 0.0 ? o.cellSize : cellFromFile;
    if (!(in.cell > 0.0))
        throw InputError("--cell-size is needed for a PNG or EXR heightmap (metres between grid points)");
    // the outputs keep the input's origin; an overriding --cell-size rescales their pixels
    if (in.geo.georeferenced() && o.cellSize > 0.0) in.geo = in.geo.withCellSize(o.cellSize);
    checkRange(scene_ranges::kCellSize, static_cast<float>(in.cell), o.heightmap + ": cell size");
    if (!o.albedo.empty()) in.albedoMap = gi::loadAlbedo(o.albedo, in.heights.nx, in.heights.ny);
    if (exponent.fromFile)
        gi::loadPhongExponentMap(o.phongExponent, in.heights.nx, in.heights.ny, exponent.lo, exponent.hi, in.albedoMap);
    in.albedo = o.albedo.empty() && !exponent.fromFile ? nullptr : &in.albedoMap;
    return in;
}

// A frame's results, the maps `terrain gi` can write.
struct GiResults {
    const std::array<Grid, 3>* shade = nullptr;
    const Grid* ambient = nullptr;
    const std::array<Grid, 3>* indirect = nullptr;  // null: none computed
};

// Every result is checked finite before any file is written: no NaN or Inf
// leaves the command, and a failing run leaves earlier files as they were.
void writeResults(const GiOptions& o, const GiInputs& in, const GiResults& r) {
    const GeoReference& geo = in.geo;
    try {
        for (const Grid& g : *r.shade) requireFinite(g, "the shade map");
        requireFinite(*r.ambient, "the ambient map");
        if (r.indirect)
            for (const Grid& g : *r.indirect) requireFinite(g, "the indirect light");
    } catch (const InputError& e) {
        throw InputError(std::string(e.what()) + "; nothing written");
    }
    if (!o.outShade.empty()) writeShade(o.outShade, *r.shade, o.exposure, geo);
    if (!o.outAmbient.empty()) writeAmbient(o.outAmbient, *r.ambient, geo);
    if (!o.outIndirect.empty()) writeIndirect(o.outIndirect, *r.indirect, geo);
    if (!o.outExr.empty())
        writeGiExr(o.outExr, in.heights, static_cast<float>(in.cell), *r.shade, *r.ambient, r.indirect);
}

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

// The ground truth: the direct-light reference, or with bounces, key lights,
// indirect output or a glossy BRDF the gathering reference (gi/reference_gi.h).
int runReference(const GiOptions& o, const gi::GiSettings& settings, const GiInputs& in) {
    const int bounces = settings.indirect.bounces;
    const auto t0 = Clock::now();
    if (bounces > 0 || !o.outIndirect.empty() || !in.lighting.keys.empty() ||
        settings.shading.brdf != gi::Brdf::Lambert) {
        gi::ReferenceGiSettings gs;
        gs.bounces = bounces;
        gs.directions = o.referenceDirections;
        gs.progress = true;
        gs.keys = in.lighting.keys;  // key lights enter the ground truth as exact caps, not as SH
        gs.shading = settings.shading;
        gi::ReferenceGiResult gr;
        gi::renderReferenceGi(in.heights.cview(), static_cast<float>(in.cell), in.lighting.environment, in.albedo, gs,
                              gr);
        if (o.time) std::printf("reference: %.1f ms\n", msSince(t0));
        writeResults(o, in, {&gr.total, &gr.ambient, &gr.indirect});
        return 0;
    }
    gi::ReferenceSettings rs;
    rs.progress = true;
    gi::ReferenceResult rr;
    gi::renderReference(in.heights.cview(), static_cast<float>(in.cell), &in.lighting.environment, in.albedo, rs, rr);
    if (o.time) std::printf("reference: %.1f ms\n", msSince(t0));
    writeResults(o, in, {&rr.rgb, &rr.ambient, nullptr});
    return 0;
}

void printFrameTimes(int f, int frames, const gi::GiState& state, int bounces) {
    const gi::GiTimings& t = state.timings;
    std::printf(
        "frame %d: gradient %.2f ms, pyramid %.2f ms, visibility %.2f ms, key lights %.2f ms, shading %.2f ms, "
        "indirect %.2f ms, total %.2f ms%s\n",
        f, t.gradient, t.pyramid, t.visibility, t.keyVisibility, t.shading, t.indirect, t.total,
        f == 0 && frames > 1 ? " (warm-up)" : "");
    if (bounces > 0 && state.indirectUpdated)
        std::printf("  indirect: radiance pyramids %.2f ms, scans %.2f ms, shading %.2f ms\n",
                    state.indirect.timings.pyramid, state.indirect.timings.scan, state.indirect.timings.shading);
}

// The fast path, o.frames times on the same field (the first a warm-up).
int runFastPath(const GiOptions& o, const gi::GiSettings& settings, const GiInputs& in) {
    gi::GiState state;
    std::vector<double> totals;
    const int bounces = settings.indirect.bounces;
    for (int f = 0; f < o.frames; ++f) {
        state.geometryChanged = f == 0;  // the same field every frame: static geometry after the first
        // a sun moving with the time of day lights each frame anew
        const gi::GiLighting lighting = f == 0 ? in.lighting : engine::giLighting(in.lights->at(f));
        gi::runGiFrame(in.heights.cview(), static_cast<float>(in.cell), lighting, settings, state, in.albedo);
        if (o.time) printFrameTimes(f, o.frames, state, bounces);
        if (f > 0 || o.frames == 1) totals.push_back(state.timings.total);
    }
    if (o.time) {
        std::sort(totals.begin(), totals.end());
        std::printf("%.2f ms per frame\n", totals[totals.size() / 2]);
    }
    writeResults(o, in,
                 {bounces > 0 ? &state.indirect.total : &state.shade.rgb, &state.shade.ambient,
                  bounces > 0 ? &state.indirect.indirect : nullptr});
    return 0;
}

int runGi(const GiOptions& o) {
    checkOptions(o);
    ExponentSource exponent;
    const gi::GiSettings settings = settingsFrom(o, exponent);
    const GiInputs in = readInputs(o, exponent);
    // on stdout: stderr carries errors only
    std::printf("terrain gi: %s, %d x %d cells of %.4g m\n", o.heightmap.c_str(), in.heights.nx, in.heights.ny,
                in.cell);
    std::fflush(stdout);
    return withThreads(o.threads,
                       [&] { return o.reference ? runReference(o, settings, in) : runFastPath(o, settings, in); });
}

}  // namespace

Runner addGiCommand(CLI::App& app) {
    auto o = std::make_shared<GiOptions>();
    CLI::App* sub =
        app.add_subcommand("gi", "Global illumination of a height field: soft shadows from sky and key lights");
    sub->add_option("--heightmap", o->heightmap, "16-bit PNG (height = O + S * value), .tif, float .exr or .vdb")
        ->required();
    namespace sr = scene_ranges;
    namespace opt = option_ranges;
    sub->add_option("--cell-size", o->cellSize, describe(sr::kDemCellSize) + " (required for PNG)");
    sub->add_option("--z-scale", o->zScale, describe(sr::kDemZScale) + " (S)")->capture_default_str();
    sub->add_option("--z-offset", o->zOffset, describe(sr::kAltitude) + ": the height of PNG value 0 (O)")
        ->capture_default_str();
    addLightOptions(sub, o->lights, "a uniform sky of radiance 1, no key light, no sun");
    gi::GiSettings& gs = o->settings;
    namespace r = gi::ranges;
    sub->add_option("--subsample", gs.subsample, gi::describe(r::kSubsample))->capture_default_str();
    sub->add_option("--azimuths", gs.visibility.azimuths, gi::describe(r::kAzimuths) + " (paper 32)")
        ->capture_default_str();
    sub->add_option("--levels-per-octave", gs.pyramid.levelsPerOctave, gi::describe(r::kLevelsPerOctave))
        ->capture_default_str();
    sub->add_option("--level-offset", gs.pyramid.levelOffset, gi::describe(r::kLevelOffset) + " (paper 2)")
        ->capture_default_str();
    sub->add_option("--interp", o->interp, "Azimuthal interpolation: linear | bspline");
    sub->add_option("--threads", o->threads, describe(opt::kThreads))->capture_default_str();
    sub->add_flag("--reference", o->reference, "Ground truth instead of the fast path (slow)");
    sub->add_option("--out-shade", o->outShade, "RGB shade map (.png sRGB 8-bit, or .exr / .tif float32)");
    sub->add_option("--exposure", o->exposure, describe(opt::kExposure) + " (of the .png shade map, before sRGB)")
        ->capture_default_str();
    sub->add_option("--out-ambient", o->outAmbient, "Ambient (sky-view) map (.npy float32, .exr or .tif)");
    sub->add_option("--out-exr", o->outExr,
                    "Every map as float32 channels of one .exr: height, ambient, shade.R/G/B and, with bounces, "
                    "indirect.R/G/B");
    sub->add_option("--frames", o->frames,
                    describe(opt::kFrames) + ": run the frame N times on the same field (first = warm-up)")
        ->capture_default_str();
    sub->add_flag("--time", o->time, "Print the time of each stage and the median ms per frame");
    sub->add_option("--bounces", gs.indirect.bounces, gi::describe(r::kBounces))->capture_default_str();
    sub->add_option("--brdf", o->brdf, "lambert | phong:EXP | mix:W[,EXP] (Lambert + W x Phong)");
    sub->add_option("--albedo", o->albedo, "Albedo R,G,B in [0, 1] or an sRGB PNG of the field's size");
    sub->add_option("--gi-incremental", gs.incremental,
                    "on: with --frames, rerun only the stages whose inputs changed (the same field: no work after the "
                    "first frame); off: every frame recomputes everything")
        ->capture_default_str();
    sub->add_option("--gi-tolerance", gs.tolerance, gi::describe(r::kTolerance))->capture_default_str();
    sub->add_option("--gi-refresh", gs.refreshEvery, gi::describe(r::kRefreshEvery))->capture_default_str();
    sub->add_flag("--amortise", gs.indirect.amortise,
                  "With --frames on static geometry: alternate direct and indirect updates");
    sub->add_option(
        "--out-indirect", o->outIndirect,
        "Indirect light alone, RGB (.npy float32 (rows, columns, 3), .exr, .tif, or .png: its luminance in false "
        "colour, black to white at its 99th percentile)");
    sub->add_option("--radiance-levels-per-octave", gs.indirect.radiance.levelsPerOctave,
                    gi::describe(r::kRadianceLevelsPerOctave) + " (paper 4)")
        ->capture_default_str();
    sub->add_option("--radiance-level-offset", gs.indirect.radiance.levelOffset,
                    gi::describe(r::kRadianceLevelOffset) + " (paper 2)")
        ->capture_default_str();
    sub->add_option("--indirect-azimuths", gs.indirect.azimuths, gi::describe(r::kIndirectAzimuths))
        ->capture_default_str();
    sub->add_option(
        "--indirect-kernel", o->indirectKernel,
        "Lambert indirect light: blocker (exact cosine at the receivers, between them the blockers' mean radiance "
        "times each texel's occlusion, engine default) | sh (order-4 SH kernel, paper)");
    sub->add_option("--reference-directions", o->referenceDirections, describe(opt::kReferenceDirections))
        ->capture_default_str();
    sub->add_option("--glossy", o->glossy,
                    "Glossy indirect light (phong/mix BRDFs): vector (SH radiance-vector pyramid, Fig. 5 middle) | "
                    "scalar (shade pyramid, Fig. 5 right)");
    sub->add_option("--phong-exponent", o->phongExponent,
                    "Phong exponent: a constant VALUE, or a 16-bit PNG of the field's size mapped log-uniformly to "
                    "--phong-exponent-range");
    sub->add_option("--phong-exponent-range", o->phongExponentRange,
                    "MIN,MAX exponents of PNG values 0 and 65535 (default 1,1000)");
    return [o] { return runGi(*o); };
}

}  // namespace terrain::app
