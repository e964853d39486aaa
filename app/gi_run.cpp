#include "app/gi_run.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "app/gi_images.h"
#include "core/error.h"
#include "core/finite.h"
#include "core/parallel.h"
#include "gi/frame.h"
#include "gi/horizon_angles.h"
#include "gi/reference.h"
#include "gi/reference_gi.h"
#include "gi/sky_view.h"
#include "sim/scene_ranges.h"

namespace terrain::app {
namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

// The ground truth: the direct-light reference, or with bounces, key lights,
// indirect output or a glossy BRDF the gathering reference (gi/reference_gi.h).
GiMaps runReference(const GiOptions& o, const gi::GiSettings& settings, const GiInputs& in) {
    const int bounces = settings.indirect.bounces;
    const auto t0 = Clock::now();
    GiMaps maps;
    if (bounces > 0 || !o.outIndirect.empty() || !in.lighting.keys.empty() ||
        settings.shading.brdf != gi::Brdf::Lambert) {
        gi::ReferenceGiSettings gs;
        gs.bounces = bounces;
        gs.directions = o.referenceDirections;
        gs.lobe = gi::LobeLayout::uniform(o.referenceLobeRings);
        gs.progress = o.progress;
        gs.keys = in.lighting.keys;  // key lights enter the ground truth as exact caps, not as SH
        gs.shading = settings.shading;
        gi::ReferenceGiResult gr;
        gi::renderReferenceGi(in.heights.cview(), static_cast<float>(in.cell), in.lighting.environment, in.albedo, gs,
                              gr);
        if (o.time) std::printf("reference: %.1f ms\n", msSince(t0));
        maps.shade = std::move(gr.total);
        maps.ambient = std::move(gr.ambient);
        maps.indirect = std::move(gr.indirect);
        maps.hasIndirect = true;
        return maps;
    }
    gi::ReferenceSettings rs;
    rs.progress = o.progress;
    gi::ReferenceResult rr;
    gi::renderReference(in.heights.cview(), static_cast<float>(in.cell), &in.lighting.environment, in.albedo, rs, rr);
    if (o.time) std::printf("reference: %.1f ms\n", msSince(t0));
    maps.shade = std::move(rr.rgb);
    maps.ambient = std::move(rr.ambient);
    return maps;
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
GiMaps runFastPath(const GiOptions& o, const gi::GiSettings& settings, const GiInputs& in) {
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
    GiMaps maps;
    maps.shade = std::move(bounces > 0 ? state.indirect.total : state.shade.rgb);
    maps.ambient = std::move(state.shade.ambient);
    if (bounces > 0) {
        maps.indirect = std::move(state.indirect.indirect);
        maps.hasIndirect = true;
    }
    if (!o.outSvf.empty()) {
        if (svfKindOf(o) == SvfKind::Normal)
            maps.svf = maps.ambient;
        else
            gi::skyViewFactor(state, in.heights.cview(), maps.svf);
    }
    if (!o.outHorizons.empty()) {
        gi::horizonAnglesFromScan(state.envVisibility, state.envOperator.phi, settings.subsample, in.heights.nx,
                                  in.heights.ny, maps.horizons);
        gi::raiseHorizonAnglesToNearField(in.heights.cview(), static_cast<float>(in.cell), settings.subsample,
                                          maps.horizons);
    }
    return maps;
}

// The ground truth's sky-view factor and horizons: the exact horizons, the
// plain factor along 256 azimuths, the horizons along the scan's azimuths.
void addReferenceHorizonMaps(const GiOptions& o, const gi::GiSettings& settings, const GiInputs& in, GiMaps& maps) {
    const float cell = static_cast<float>(in.cell);
    if (!o.outSvf.empty()) {
        if (svfKindOf(o) == SvfKind::Normal)
            maps.svf = maps.ambient;
        else
            gi::referenceSkyViewFactor(in.heights.cview(), cell, gi::ReferenceSettings{}.azimuths, maps.svf);
    }
    if (!o.outHorizons.empty())
        gi::referenceHorizonAngles(in.heights.cview(), cell, gi::scanAzimuths(settings.visibility.azimuths),
                                   maps.horizons);
}

}  // namespace

GiInputs giInputsFor(const GiOptions& o, const ExponentSource& exponent, Grid heights, float cellFromSource,
                     GeoReference geo) {
    GiInputs in;
    LightSet lights;  // a uniform sky of radiance 1 unless the options say otherwise
    applyLightOptions(o.lights, lights);
    in.lights = std::make_unique<engine::LightRig>(lights);
    in.lighting = engine::giLighting(in.lights->at(0));
    in.heights = std::move(heights);
    in.geo = std::move(geo);
    // --cell-size overrides the source's own (a .tif's geotransform, a .vdb's voxel size)
    in.cell = o.cellSize > 0.0 ? o.cellSize : cellFromSource;
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

GiMaps runGiFrames(const GiOptions& o, const gi::GiSettings& settings, const GiInputs& in) {
    return withThreads(o.threads, [&] {
        if (!o.reference) return runFastPath(o, settings, in);
        GiMaps maps = runReference(o, settings, in);
        addReferenceHorizonMaps(o, settings, in, maps);
        return maps;
    });
}

// No NaN or Inf leaves the command, and a failing run leaves earlier files
// as they were.
void writeGiMaps(const GiOptions& o, const GiInputs& in, const GiMaps& maps) {
    const GeoReference& geo = in.geo;
    try {
        for (const Grid& g : maps.shade) requireFinite(g, "the shade map");
        requireFinite(maps.ambient, "the ambient map");
        if (!o.outSvf.empty()) requireFinite(maps.svf, "the sky-view factor");
        for (const Grid& g : maps.horizons.degrees) requireFinite(g, "the horizon angles");
        if (maps.hasIndirect)
            for (const Grid& g : maps.indirect) requireFinite(g, "the indirect light");
    } catch (const InputError& e) {
        throw InputError(std::string(e.what()) + "; nothing written");
    }
    if (!o.outShade.empty()) writeShade(o.outShade, maps.shade, o.exposure, geo);
    if (!o.outAmbient.empty()) writeAmbient(o.outAmbient, maps.ambient, geo);
    if (!o.outIndirect.empty()) writeIndirect(o.outIndirect, maps.indirect, geo);
    if (!o.outSvf.empty()) writeAmbient(o.outSvf, maps.svf, geo);
    if (!o.outHorizons.empty()) writeHorizons(o.outHorizons, maps.horizons, geo);
    if (!o.outExr.empty())
        writeGiExr(o.outExr, in.heights, static_cast<float>(in.cell), maps.shade, maps.ambient,
                   maps.hasIndirect ? &maps.indirect : nullptr);
}

}  // namespace terrain::app
