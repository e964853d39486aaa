// `terrain_bench gi-glossy`: glossy indirect light - the SH radiance-vector
// pyramid (GlossyIndirect::VectorPyramid, Fig. 5 middle) and the scalar shade
// pyramid (ScalarPyramid, Fig. 5 right) against the glossy reference
// (gi/reference_glossy), and the frame time of the glossy bounce. Writes
// gi_glossy.md.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "bench/suites.h"
#include "core/parallel.h"
#include "gi/frame.h"
#include "gi/reference_gi.h"

namespace terrain::bench {
namespace {
using namespace terrain::gi;
using Clock = std::chrono::steady_clock;

struct GlossyOptions {
    int runs = 5;
    int size = 96;          // side of the accuracy crop
    int directions = 2048;  // directions of the reference
};

constexpr float albedo = 0.6f;

GiSettings settingsFor(Brdf brdf, float exponent, int s, int bounces, GlossyIndirect mode) {
    GiSettings g = wholeFrames(GiSettings{});
    g.subsample = s;
    g.shading.brdf = brdf;
    g.shading.phongExponent = exponent;
    g.shading.specularWeight = 0.5f;
    g.indirect.bounces = bounces;
    g.indirect.glossy = mode;
    return g;
}

const char* brdfName(Brdf b) {
    return b == Brdf::Phong ? "phong" : (b == Brdf::LambertPlusPhong ? "mix 0.5" : "lambert");
}

// The lighting of every row: the sun-and-sky SH environment alone.
GiLighting sunSkyLighting() {
    GiLighting light;
    light.environment = sunSkyLight();
    return light;
}

// Accuracy against the glossy reference on the central o.size^2 crop of Mont Blanc.
std::string accuracySection(const GlossyOptions& o, const BenchContext& ctx) {
    std::string md;
    float cell = 1.0f;
    const Grid h = alpsCentreCrop(ctx.dataDir, o.size, cell);
    const AlbedoMap a = uniformAlbedo(o.size, o.size, albedo);
    const GiLighting light = sunSkyLighting();
    md += "## Accuracy: alps-montblanc, central " + std::to_string(o.size) + "^2 crop at true scale (cell 92.74 m)\n\n";
    md += "Reference: `renderReferenceGlossy` (" + std::to_string(o.directions) +
          " fixed directions, 256 azimuths for bounce 0; the same Phong lobe in order-4 SH, exact visibility and first "
          "hits). "
          "Relative RMSE and bias of the indirect light (bounce 1, RGB, 10 % border left out).\n\n";
    md +=
        "| BRDF | S | sub-sampling | vector pyramid RMSE | bias | scalar pyramid RMSE | bias | reference mean indirect "
        "| reference time (s) |\n";
    md += "|---|---|---|---|---|---|---|---|---|\n";
    for (Brdf brdf : {Brdf::Phong, Brdf::LambertPlusPhong})
        for (float S : {8.0f, 64.0f}) {
            if (brdf == Brdf::LambertPlusPhong && S != 64.0f) continue;
            ReferenceGiSettings rs;
            rs.directions = o.directions;
            rs.bounces = 1;
            rs.shading = settingsFor(brdf, S, 1, 1, GlossyIndirect::VectorPyramid).shading;
            ReferenceGiResult ref;
            const auto t0 = Clock::now();
            renderReferenceGi(h.cview(), cell, light.environment, &a, rs, ref);
            const double refSeconds = std::chrono::duration<double>(Clock::now() - t0).count();
            double refMean = 0.0;
            for (const Grid& g : ref.indirect)
                for (float v : g.v) refMean += v;
            refMean /= 3.0 * o.size * o.size;
            for (int s : {1, 2}) {
                double e[2], b[2];
                for (int k = 0; k < 2; ++k) {
                    GiState st;
                    const GlossyIndirect mode = k == 0 ? GlossyIndirect::VectorPyramid : GlossyIndirect::ScalarPyramid;
                    withThreads(2,
                                [&] { runGiFrame(h.cview(), cell, light, settingsFor(brdf, S, s, 1, mode), st, &a); });
                    e[k] = relRmse(st.indirect.indirect, ref.indirect, b[k]);
                }
                char line[512];
                std::snprintf(line, sizeof line, "| %s | %g | %dx | %.4f | %+.4f | %.4f | %+.4f | %.4f | %.1f |\n",
                              brdfName(brdf), S, s, e[0], b[0], e[1], b[1], refMean, refSeconds);
                std::fprintf(stderr, "%s", line);
                md += line;
            }
        }
    return md;
}

// Frame time of the glossy bounce at 256^2 and 512^2.
std::string frameTimeSection(const GlossyOptions& o, const BenchContext& ctx) {
    const GiLighting light = sunSkyLighting();
    std::string md;
    md += "\n## Frame time, alps-montblanc central crops, 2x sub-sampling, 1 bounce, 2 threads (median of " +
          std::to_string(o.runs) + " frames after a warm-up)\n\n";
    md += "| size | BRDF / glossy mode | frame (ms) | indirect (ms) | E + pyramids (ms) | scan (ms) | shading (ms) |\n";
    md += "|---|---|---|---|---|---|---|\n";
    for (int size : {256, 512}) {
        float c2 = 1.0f;
        const Grid hs = alpsCentreCrop(ctx.dataDir, size, c2);
        const AlbedoMap as = uniformAlbedo(size, size, albedo);
        struct Case {
            const char* name;
            Brdf brdf;
            GlossyIndirect mode;
        };
        for (const Case& cs : {Case{"lambert", Brdf::Lambert, GlossyIndirect::ScalarPyramid},
                               Case{"phong:32, scalar pyramid", Brdf::Phong, GlossyIndirect::ScalarPyramid},
                               Case{"phong:32, vector pyramid", Brdf::Phong, GlossyIndirect::VectorPyramid}}) {
            const GiSettings g = settingsFor(cs.brdf, 32.0f, 2, 1, cs.mode);
            GiState st;
            std::vector<double> frame, ind, pyr, scan, shade;
            withThreads(2, [&] {
                runGiFrame(hs.cview(), c2, light, g, st, &as);  // warm-up (allocations)
                for (int r = 0; r < o.runs; ++r) {
                    st.geometryChanged = true;
                    runGiFrame(hs.cview(), c2, light, g, st, &as);
                    frame.push_back(st.timings.total);
                    ind.push_back(st.timings.indirect);
                    pyr.push_back(st.indirect.timings.pyramid);
                    scan.push_back(st.indirect.timings.scan);
                    shade.push_back(st.indirect.timings.shading);
                }
            });
            char line[512];
            std::snprintf(line, sizeof line, "| %d^2 | %s | %.1f | %.1f | %.1f | %.1f | %.1f |\n", size, cs.name,
                          median(frame), median(ind), median(pyr), median(scan), median(shade));
            std::fprintf(stderr, "%s", line);
            md += line;
        }
    }
    return md;
}

int runGlossy(const GlossyOptions& o, const BenchContext& ctx) {
    std::string md = "# Glossy indirect light: vector vs scalar pyramid\n\n";
    md += "Machine: " + machineDescription() +
          " (shared with another engineer's builds and benchmarks while this ran: timings are indicative).\n\n";
    md += "Lighting: sun-and-sky SH environment (`sunSkyLight()`), viewer overhead, albedo " +
          std::to_string(albedo).substr(0, 3) +
          " (diffuse part), engine settings (`GiSettings{}`: m = 16, o_v = o_u = 3), 1 bounce.\n\n";
    md += accuracySection(o, ctx);
    md += frameTimeSection(o, ctx);
    writeResult(ctx.outDir, "gi_glossy.md", md);
    return 0;
}

}  // namespace

Runner addGiGlossySuite(CLI::App& app, const BenchContext& ctx) {
    auto o = std::make_shared<GlossyOptions>();
    CLI::App* sub =
        app.add_subcommand("gi-glossy", "Glossy indirect light: vector vs scalar pyramid, accuracy and frame time");
    addRunsOption(*sub, o->runs, "Frames per timing (the median is reported)");
    sub->add_option("--size", o->size, "Side of the accuracy crop")->check(CLI::Range(16, 4096))->capture_default_str();
    sub->add_option("--directions", o->directions, "Directions of the glossy reference")
        ->check(CLI::Range(64, 1 << 20))
        ->capture_default_str();
    return [o, &ctx] { return runGlossy(*o, ctx); };
}

}  // namespace terrain::bench
