#include "app/gi_options.h"

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <stdexcept>
#include <string>
#include <vector>

#include "app/gi_images.h"
#include "app/named_choice.h"
#include "app/option_ranges.h"
#include "app/progress.h"
#include "core/error.h"
#include "core/geotiff_io.h"
#include "core/parse.h"
#include "core/setting_range.h"
#include "gi/settings_ranges.h"
#include "sim/scene_ranges.h"

namespace terrain::app {
namespace {

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
    checkRange(r::kLobeRings, s.indirect.lobeRings, "--glossy-lobe-rings");
    checkRange(r::kLobeInnerDirections, s.indirect.lobeInnerDirections, "--glossy-lobe-inner-directions");
    checkRange(r::kLobeAzimuths, s.indirect.lobeAzimuths, "--glossy-lobe-azimuths");
    checkRange(r::kLobeNearStepsPerOctave, s.indirect.lobeNearStepsPerOctave, "--glossy-lobe-near-steps");
    checkRange(r::kLobeNearOctaves, s.indirect.lobeNearOctaves, "--glossy-lobe-near-octaves");
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
    if (!oneOf(o.outSvf, {".npy", ".exr"}))
        throw InputError("--out-svf must end in .npy, .exr or .tif (got '" + o.outSvf + "')");
    if (!oneOf(o.outHorizons, {".npy", ".exr"}))
        throw InputError("--out-horizons must end in .npy, .exr or .tif (got '" + o.outHorizons + "')");
    svfKindOf(o);
    if (!o.outExr.empty() && extensionOf(o.outExr) != ".exr")
        throw InputError("--out-exr must end in .exr (got '" + o.outExr + "')");
    if (!o.outIndirect.empty() && o.settings.indirect.bounces == 0 && !o.reference)
        throw InputError("--out-indirect needs --bounces >= 1");
    for (const std::string* out : {&o.outShade, &o.outAmbient, &o.outIndirect, &o.outExr, &o.outSvf, &o.outHorizons})
        if (!out->empty()) checkWritableFile(*out);
}

// The flags of the visibility, the run and the outputs. Those of the
// settings bind straight into the engine's settings: their defaults and
// ranges are the engine's own.
void addFrameFlags(CLI::App* sub, GiOptions& o) {
    namespace r = gi::ranges;
    namespace opt = option_ranges;
    gi::GiSettings& gs = o.settings;
    sub->add_option("--subsample", gs.subsample, gi::describe(r::kSubsample))->capture_default_str();
    sub->add_option("--azimuths", gs.visibility.azimuths, gi::describe(r::kAzimuths) + " (paper 32)")
        ->capture_default_str();
    sub->add_option("--levels-per-octave", gs.pyramid.levelsPerOctave, gi::describe(r::kLevelsPerOctave))
        ->capture_default_str();
    sub->add_option("--level-offset", gs.pyramid.levelOffset, gi::describe(r::kLevelOffset) + " (paper 2)")
        ->capture_default_str();
    sub->add_option("--interp", o.interp, "Azimuthal interpolation: linear | bspline");
    sub->add_option("--threads", o.threads, describe(opt::kThreads))->capture_default_str();
    sub->add_flag("--reference", o.reference, "Ground truth instead of the fast path (slow)");
    sub->add_option("--out-shade", o.outShade, "RGB shade map (.png sRGB 8-bit, or .exr / .tif float32)");
    sub->add_option("--exposure", o.exposure, describe(opt::kExposure) + " (of the .png shade map, before sRGB)")
        ->capture_default_str();
    sub->add_option("--out-ambient", o.outAmbient, "Ambient (sky-view) map (.npy float32, .exr or .tif)");
    sub->add_option("--frames", o.frames,
                    describe(opt::kFrames) + ": run the frame N times on the same field (first = warm-up)")
        ->capture_default_str();
    sub->add_flag("--time", o.time, "Print the time of each stage and the median ms per frame");
}

// The flags of the BRDF, the incremental frames and the indirect light.
void addLightTransportFlags(CLI::App* sub, GiOptions& o) {
    namespace r = gi::ranges;
    namespace opt = option_ranges;
    gi::GiSettings& gs = o.settings;
    sub->add_option("--bounces", gs.indirect.bounces, gi::describe(r::kBounces))->capture_default_str();
    sub->add_option("--brdf", o.brdf, "lambert | phong:EXP | mix:W[,EXP] (Lambert + W x Phong)");
    sub->add_option("--albedo", o.albedo, "Albedo R,G,B in [0, 1] or an sRGB PNG of the field's size");
    sub->add_option("--gi-incremental", gs.incremental,
                    "on: with --frames, rerun only the stages whose inputs changed (the same field: no work after the "
                    "first frame); off: every frame recomputes everything")
        ->capture_default_str();
    sub->add_option("--gi-tolerance", gs.tolerance, gi::describe(r::kTolerance))->capture_default_str();
    sub->add_option("--gi-refresh", gs.refreshEvery, gi::describe(r::kRefreshEvery))->capture_default_str();
    sub->add_flag("--amortise", gs.indirect.amortise,
                  "With --frames on static geometry: alternate direct and indirect updates");
    sub->add_option("--out-svf", o.outSvf,
                    "Sky-view factor (.npy float32, .exr or .tif), the one --svf-kind names, from the same horizons "
                    "as the frame (with --reference: the exact horizons along 256 azimuths)");
    sub->add_option("--svf-kind", o.svfKind,
                    "Which sky-view factor --out-svf writes. plain (Zaksek et al. 2011; RVT, GRASS r.skyview): the "
                    "open fraction of the upper hemisphere over the horizontal plane, SVF = 1 - (1/m) sum_j "
                    "sin(max(0, H_j)), H_j the horizon elevation along azimuth j. normal (Oke; Dozier & Frew; SAGA's "
                    "Sky View Factor is this with H_j raised to 0): the cosine-weighted sky visible above max(H_j, "
                    "tangent plane) at the texel's own normal N, (1/pi) int (N . w) dw, 1 on an open plane of any "
                    "tilt; the same map as --out-ambient (README: \"Sky-view factor and horizons\")")
        ->capture_default_str();
    sub->add_option("--out-horizons", o.outHorizons,
                    "Horizon elevation angle per azimuth of the scan (degrees above the horizontal, signed; -90 where "
                    "no terrain lies in that direction), full resolution: .npy float32 (azimuths, rows, columns), "
                    ".exr (one float32 channel per azimuth, named azDDD_FFF: compass bearing in degrees) or .tif (one "
                    "band per azimuth, described by its bearing); bearings clockwise from north, row 0 north unless "
                    "a GeoTIFF input says otherwise; planes in ascending bearing. With --reference: the exact "
                    "horizons along the same azimuths");
    sub->add_option("--out-exr", o.outExr,
                    "Every map as float32 channels of one .exr: height, ambient, shade.R/G/B and, with bounces, "
                    "indirect.R/G/B");
    sub->add_option(
        "--out-indirect", o.outIndirect,
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
    sub->add_option("--glossy-lobe-rings", gs.indirect.lobeRings, gi::describe(r::kLobeRings) + " (--glossy lobe)")
        ->capture_default_str();
    sub->add_option("--glossy-lobe-inner-directions", gs.indirect.lobeInnerDirections,
                    gi::describe(r::kLobeInnerDirections) + " (--glossy lobe)")
        ->capture_default_str();
    sub->add_option("--glossy-lobe-azimuths", gs.indirect.lobeAzimuths,
                    gi::describe(r::kLobeAzimuths) + " (--glossy lobe)")
        ->capture_default_str();
    sub->add_option("--glossy-lobe-members", o.glossyLobeMembers,
                    "What the first bounce's surface sends back to the lobe gather (--glossy lobe): windowed (its "
                    "lobe-filtered light times the part of its lobe above its horizon, default) | sh (its order-4 SH "
                    "exit radiance)");
    sub->add_option("--glossy-lobe-near-steps", gs.indirect.lobeNearStepsPerOctave,
                    gi::describe(r::kLobeNearStepsPerOctave) + " (--glossy lobe)")
        ->capture_default_str();
    sub->add_option("--glossy-lobe-near-octaves", gs.indirect.lobeNearOctaves,
                    gi::describe(r::kLobeNearOctaves) + " (--glossy lobe)")
        ->capture_default_str();
    sub->add_option(
        "--indirect-kernel", o.indirectKernel,
        "Lambert indirect light: blocker (exact cosine at the receivers, between them the blockers' mean radiance "
        "times each texel's occlusion, engine default) | sh (order-4 SH kernel, paper)");
    sub->add_option("--reference-directions", o.referenceDirections, describe(opt::kReferenceDirections))
        ->capture_default_str();
    sub->add_option("--reference-lobe-rings", o.referenceLobeRings, describe(opt::kReferenceLobeRings))
        ->capture_default_str();
    sub->add_option(
        "--glossy", o.glossy,
        "Glossy indirect light (phong/mix BRDFs): vector (SH radiance-vector pyramid, Fig. 5 middle) | "
        "scalar (shade pyramid, Fig. 5 right) | lobe (the vector pyramid's members gathered by each receiver's own "
        "Phong lobe)");
    sub->add_option("--glossy-positivity", o.glossyPositivity,
                    "Phong / mix shading and glossy indirect light: clamp (no negative radiance: members send and "
                    "texels shade max(0, .), engine default) | off (the order-4 SH lobe's linear values, paper)");
    sub->add_option("--phong-exponent", o.phongExponent,
                    "Phong exponent: a constant VALUE, or a 16-bit PNG of the field's size mapped log-uniformly to "
                    "--phong-exponent-range");
    sub->add_option("--phong-exponent-range", o.phongExponentRange,
                    "MIN,MAX exponents of PNG values 0 and 65535 (default 1,1000)");
}

}  // namespace

void addGiOptions(CLI::App* sub, GiOptions& o) {
    addLightOptions(sub, o.lights, "a uniform sky of radiance 1, no key light, no sun");
    addFrameFlags(sub, o);
    addLightTransportFlags(sub, o);
}

// Everything about the options that can be wrong, before any input is read.
void checkGiOptions(const GiOptions& o) {
    namespace r = option_ranges;
    namespace sr = scene_ranges;
    checkRange(r::kThreads, o.threads);
    checkRange(r::kFrames, o.frames);
    checkRange(r::kExposure, o.exposure);
    checkRange(r::kReferenceDirections, o.referenceDirections);
    checkRange(r::kReferenceLobeRings, o.referenceLobeRings);
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

SvfKind svfKindOf(const GiOptions& o) {
    return namedChoice<SvfKind>("--svf-kind", o.svfKind, {{"plain", SvfKind::Plain}, {"normal", SvfKind::Normal}});
}

// The frame's settings from the options: the modes named by strings, then
// one range check of everything (gi/settings.h).
gi::GiSettings giSettingsFrom(const GiOptions& o, ExponentSource& exponent) {
    gi::GiSettings settings = o.settings;
    parseBrdf(o.brdf, settings.shading);
    if (!o.glossy.empty())
        settings.indirect.glossy = namedChoice<gi::GlossyIndirect>("--glossy", o.glossy,
                                                                   {{"vector", gi::GlossyIndirect::VectorPyramid},
                                                                    {"scalar", gi::GlossyIndirect::ScalarPyramid},
                                                                    {"lobe", gi::GlossyIndirect::LobeScan}});
    if (!o.glossyLobeMembers.empty())
        settings.indirect.lobeMembers = namedChoice<gi::GlossyLobeMembers>(
            "--glossy-lobe-members", o.glossyLobeMembers,
            {{"windowed", gi::GlossyLobeMembers::Windowed}, {"sh", gi::GlossyLobeMembers::Sh}});
    if (!o.glossyPositivity.empty())
        settings.shading.positivity = namedChoice<gi::GlossyPositivity>(
            "--glossy-positivity", o.glossyPositivity,
            {{"clamp", gi::GlossyPositivity::Clamp}, {"off", gi::GlossyPositivity::Off}});
    exponent = parsePhongExponent(o, settings);
    if (!o.indirectKernel.empty())
        settings.indirect.lambert = namedChoice<gi::LambertIndirect>(
            "--indirect-kernel", o.indirectKernel,
            {{"blocker", gi::LambertIndirect::BlockerRadiance}, {"sh", gi::LambertIndirect::ShKernel}});
    if (!o.interp.empty())
        settings.visibility.interp = namedChoice<gi::AzimuthInterp>(
            "--interp", o.interp, {{"linear", gi::AzimuthInterp::Linear}, {"bspline", gi::AzimuthInterp::Bspline}});
    gi::validateGiSettings(settings);
    return settings;
}

}  // namespace terrain::app
