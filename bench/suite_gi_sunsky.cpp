// `terrain_bench gi-sunsky`: the direct shade of the engine's sun and sky
// (the analytic gradient sky and the sun as a key light, from
// engine::LightRig) on every real DEM measured, at 1x, 2x and 4x, against the
// reference that integrates the sky's radiance function (not its SH
// projection) and the sun's cap exactly over the exactly visible sky
// (gi::renderReferenceSkyGradient + gi::addReferenceKeyLight). Writes
// gi_sunsky.md and .csv.
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "bench/suites.h"
#include "core/parallel.h"
#include "engine/light_rig.h"
#include "gi/frame.h"
#include "gi/reference.h"
#include "gi/reference_gi.h"

namespace terrain::bench {
namespace {
using namespace terrain::gi;

struct SunSkyOptions {
    int runs = 7;
    std::string cacheDir;   // references kept across runs (empty: a scratch folder)
    int keyAzimuths = 128;  // of the reference's sun cap
};

// The scene lights of `terrain gi --light sunsky --sun 10`: the gradient sky
// and the sun at 10:00 solar time on the June solstice at Chamonix.
engine::SceneLights sunAndSky() {
    LightSet set;
    set.environment.kind = EnvironmentSpec::Kind::SunSky;
    set.sun.enabled = true;
    set.sun.hour = 10.0f;
    return engine::LightRig(set).at(0);
}

SunSkySettings gradientOf(const engine::SceneLights& l) {
    SunSkySettings sky;
    for (std::size_t c = 0; c < 3; ++c) {
        sky.zenith[c] = l.zenith[c];
        sky.horizon[c] = l.horizon[c];
        sky.ground[c] = l.ground[c];
        sky.sun[c] = 0.0f;
    }
    return sky;
}

// The sky's and the sun's reference shades (albedo 1), cached in `dir`.
struct SkyReference {
    std::array<Grid, 3> sky, sun, total;
};

SkyReference reference(const Dem& d, const engine::SceneLights& l, const SunSkyOptions& o, const std::string& dir) {
    SkyReference r;
    const int nx = d.heights.nx, ny = d.heights.ny;
    const std::string base = dir + "/sunsky_reference_" + d.name + "_k" + std::to_string(o.keyAzimuths);
    if (!readCachedGrids(base + "_sky.bin", nx, ny, r.sky)) {
        std::fprintf(stderr, "sky reference for %s ...\n", d.name.c_str());
        ReferenceSettings rs;
        rs.progress = true;
        ReferenceResult rr;
        renderReferenceSkyGradient(d.heights.cview(), d.cell, gradientOf(l), nullptr, rs, rr);
        r.sky = rr.rgb;
        writeCachedGrids(base + "_sky.bin", r.sky);
    }
    if (!readCachedGrids(base + "_sun.bin", nx, ny, r.sun)) {
        std::fprintf(stderr, "sun reference for %s ...\n", d.name.c_str());
        for (Grid& g : r.sun) g.resize(nx, ny, 0.0f);
        for (const KeyLight& k : l.keys)
            addReferenceKeyLight(d.heights.cview(), d.cell, k, nullptr, o.keyAzimuths, r.sun);
        writeCachedGrids(base + "_sun.bin", r.sun);
    }
    for (std::size_t c = 0; c < 3; ++c) {
        r.total[c].resize(nx, ny);
        for (std::size_t i = 0; i < r.total[c].v.size(); ++i) r.total[c].v[i] = r.sky[c].v[i] + r.sun[c].v[i];
    }
    return r;
}

struct Measured {
    double total = 0.0, totalBias = 0.0, sky = 0.0, skyBias = 0.0, ms = 0.0;
};

// The direct shade of settings s: total (sky + sun) and sky alone against the
// reference; the frame time of the total, median of o.runs after a warm-up.
Measured measure(const Dem& d, const GiLighting& light, GiSettings s, const SkyReference& ref, int runs) {
    s.indirect.bounces = 0;
    Measured m;
    GiState st;
    withThreads(2, [&] {
        runGiFrame(d.heights.cview(), d.cell, light, s, st);
        std::vector<double> t;
        for (int r = 0; r < runs; ++r) {
            runGiFrame(d.heights.cview(), d.cell, light, s, st);
            t.push_back(st.timings.total);
        }
        m.ms = median(t);
        return 0;
    });
    m.total = relRmse(st.shade.rgb, ref.total, m.totalBias);
    GiLighting skyOnly = light;
    skyOnly.keys.clear();
    GiState skySt;
    withThreads(2, [&] { return runGiFrame(d.heights.cview(), d.cell, skyOnly, s, skySt), 0; });
    m.sky = relRmse(skySt.shade.rgb, ref.sky, m.skyBias);
    return m;
}

struct Setting {
    const char* label;
    GiSettings s;
};

std::vector<Setting> settingsCompared() {
    std::vector<Setting> out;
    for (int sub : {1, 2, 4}) {
        GiSettings s = wholeFrames(GiSettings{});
        s.subsample = sub;
        out.push_back({"engine", s});
    }
    GiSettings shAmbient = wholeFrames(GiSettings{});
    shAmbient.ambient = AmbientMethod::ShProduct;
    out.push_back({"engine, SH sky", shAmbient});
    out.push_back({"paper", wholeFrames(paperGiSettings())});
    return out;
}

int runSunSky(const SunSkyOptions& o, const BenchContext& ctx) {
    std::optional<ScratchDir> scratch;
    if (o.cacheDir.empty()) scratch.emplace();
    const std::string dir = scratch ? scratch->path() : o.cacheDir;
    const engine::SceneLights lights = sunAndSky();
    const GiLighting light = engine::giLighting(lights);
    const KeyLight& sun = lights.keys.at(0);
    char head[512];
    std::snprintf(head, sizeof head,
                  "# Sun and sky: the direct shade against the sky's radiance function\n\n"
                  "Lights: `--light sunsky --sun 10` (the gradient sky, zenith %.3f %.3f %.3f, horizon %.3f %.3f "
                  "%.3f, ground %.3f %.3f %.3f, and the sun at azimuth %.1f, elevation %.1f deg, radius %.1f deg, "
                  "RGB %.2f %.2f %.2f), albedo 1, no bounces.\n\n",
                  lights.zenith[0], lights.zenith[1], lights.zenith[2], lights.horizon[0], lights.horizon[1],
                  lights.horizon[2], lights.ground[0], lights.ground[1], lights.ground[2], sun.azimuthDeg,
                  sun.elevationDeg, sun.radiusDeg, sun.rgb[0], sun.rgb[1], sun.rgb[2]);
    std::string md = head;
    md +=
        "Reference: per texel the exact horizons of the bilinear field along 256 azimuths, the gradient sky's "
        "radiance integrated in closed form over each azimuth's visible elevations with the exact clamped "
        "cosine (gi::renderReferenceSkyGradient), and the sun as an exact cap over " +
        std::to_string(o.keyAzimuths) +
        " azimuths of its extent (gi::addReferenceKeyLight). Relative RMSE over the three channels on the interior "
        "(10 % border left out); bias = mean difference / RMS of the reference. \"sky\": the sky alone (no sun) "
        "against the sky's reference. \"engine, SH sky\": the environment wholly through the order-4 SH product "
        "(AmbientMethod::ShProduct). Time: the whole frame, 2 threads, median of " +
        std::to_string(o.runs) + " after a warm-up.\n\nMachine: " + machineDescription() + ".\n\nCommand: `" +
        ctx.command + "`.\n\n";
    md +=
        "| DEM | settings | sub-sampling | total rel. RMSE | bias | sky rel. RMSE | sky bias | ms |\n"
        "|---|---|---|---|---|---|---|---|\n";
    std::string csv = "dem,settings,subsample,total_rel_rmse,total_bias,sky_rel_rmse,sky_bias,ms\n";
    for (const Dem& d : realDems(ctx.dataDir)) {
        const SkyReference ref = reference(d, lights, o, dir);
        for (const Setting& row : settingsCompared()) {
            const Measured m = measure(d, light, row.s, ref, o.runs);
            char line[256];
            std::snprintf(line, sizeof line, "| %s | %s | %dx | %.2f %% | %+.2f %% | %.2f %% | %+.2f %% | %.1f |\n",
                          d.name.c_str(), row.label, row.s.subsample, 100 * m.total, 100 * m.totalBias, 100 * m.sky,
                          100 * m.skyBias, m.ms);
            md += line;
            std::fprintf(stderr, "%s", line);
            std::snprintf(line, sizeof line, "%s,%s,%d,%.5f,%.5f,%.5f,%.5f,%.2f\n", d.name.c_str(), row.label,
                          row.s.subsample, m.total, m.totalBias, m.sky, m.skyBias, m.ms);
            csv += line;
        }
    }
    writeResult(ctx.outDir, "gi_sunsky.md", md);
    writeResult(ctx.outDir, "gi_sunsky.csv", csv);
    return 0;
}

}  // namespace

Runner addGiSunSkySuite(CLI::App& app, const BenchContext& ctx) {
    auto o = std::make_shared<SunSkyOptions>();
    CLI::App* sub = app.add_subcommand(
        "gi-sunsky", "Sun-and-sky direct shade on the real DEMs against the sky function's exact integral");
    addRunsOption(*sub, o->runs, "Frames per timing after a warm-up");
    sub->add_option("--cache", o->cacheDir, "Folder to keep the references in across runs (default: none)");
    sub->add_option("--key-azimuths", o->keyAzimuths, "Azimuths across the sun's extent in the reference")
        ->check(CLI::Range(8, 4096))
        ->capture_default_str();
    return [o, &ctx] { return runSunSky(*o, ctx); };
}

}  // namespace terrain::bench
