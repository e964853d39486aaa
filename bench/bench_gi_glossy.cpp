// bench_gi_glossy: glossy indirect light (issue 4) - the SH radiance-vector
// pyramid (GlossyIndirect::VectorPyramid, Fig. 5 middle) and the scalar
// shade pyramid (ScalarPyramid, Fig. 5 right) against the glossy reference
// (gi/reference_glossy), and the frame time of the glossy bounce.
//
//   bench_gi_glossy [--data DIR] [--out DIR] [--runs N] [--size N] [--directions K]
//
// Writes bench/results/gi_glossy.md.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "bench/bench_common.h"
#include "bench/bench_gi_common.h"
#include "gi/frame.h"
#include "gi/reference_gi.h"

#include "core/parallel.h"

using namespace terrain;
using namespace terrain::gi;

namespace {

using Clock = std::chrono::steady_clock;
std::string gDataDir = "/work/shared/data";
std::string gOutDir = "bench/results";
int gRuns = 5;
int gSize = 96;
int gDirections = 2048;

Grid alpsCrop(int size, float& cell) { return bench::alpsCentreCrop(gDataDir, size, cell); }
using bench::relRmse;

GiSettings settingsFor(Brdf brdf, float exponent, int s, int bounces, GlossyIndirect mode) {
    GiSettings g = engineGiSettings();
    g.subsample = s;
    g.shading.brdf = brdf;
    g.shading.phongExponent = exponent;
    g.shading.specularWeight = 0.5f;
    g.indirect.bounces = bounces;
    g.indirect.glossy = mode;
    return g;
}

const char* brdfName(Brdf b) { return b == Brdf::Phong ? "phong" : (b == Brdf::LambertPlusPhong ? "mix 0.5" : "lambert"); }

}  // namespace

int main(int argc, char** argv) {
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--data" && i + 1 < argc) gDataDir = argv[++i];
        else if (a == "--out" && i + 1 < argc) gOutDir = argv[++i];
        else if (a == "--runs" && i + 1 < argc) gRuns = std::max(1, std::atoi(argv[++i]));
        else if (a == "--size" && i + 1 < argc) gSize = std::max(16, std::atoi(argv[++i]));
        else if (a == "--directions" && i + 1 < argc) gDirections = std::max(64, std::atoi(argv[++i]));
        else {
            std::fprintf(stderr, "usage: bench_gi_glossy [--data DIR] [--out DIR] [--runs N] [--size N] [--directions K]\n");
            return 2;
        }
    }
    const float albedo = 0.6f;
    std::string md = "# Glossy indirect light: vector vs scalar pyramid\n\n";
    md += "Machine: " + bench::machineDescription() +
          " (shared with another engineer's builds and benchmarks while this ran: timings are indicative).\n\n";
    md += "Lighting: sun-and-sky SH environment (`sunSkyLight()`), viewer overhead, albedo " + std::to_string(albedo).substr(0, 3) +
          " (diffuse part), engine settings (`engineGiSettings()`: m = 16, o_v = o_u = 3), 1 bounce.\n\n";

    // ---- accuracy against the glossy reference -----------------------------------
    float cell = 1.0f;
    const Grid h = alpsCrop(gSize, cell);
    const AlbedoMap a = uniformAlbedo(gSize, gSize, albedo);
    GiLighting light;
    light.environment = sunSkyLight();
    md += "## Accuracy: alps-montblanc, central " + std::to_string(gSize) + "^2 crop at true scale (cell 92.74 m)\n\n";
    md += "Reference: `renderReferenceGlossy` (" + std::to_string(gDirections) +
          " fixed directions, 256 azimuths for bounce 0; the same Phong lobe in order-4 SH, exact visibility and first hits). "
          "Relative RMSE and bias of the indirect light (bounce 1, RGB, 10 % border left out).\n\n";
    md += "| BRDF | S | sub-sampling | vector pyramid RMSE | bias | scalar pyramid RMSE | bias | reference mean indirect | reference time (s) |\n";
    md += "|---|---|---|---|---|---|---|---|---|\n";
    for (Brdf brdf : {Brdf::Phong, Brdf::LambertPlusPhong})
        for (float S : {8.0f, 64.0f}) {
            if (brdf == Brdf::LambertPlusPhong && S != 64.0f) continue;
            ReferenceGiSettings rs;
            rs.directions = gDirections;
            rs.bounces = 1;
            rs.shading = settingsFor(brdf, S, 1, 1, GlossyIndirect::VectorPyramid).shading;
            ReferenceGiResult ref;
            const auto t0 = Clock::now();
            renderReferenceGi(h.cview(), cell, light.environment, &a, rs, ref);
            const double refSeconds = std::chrono::duration<double>(Clock::now() - t0).count();
            double refMean = 0.0;
            for (const Grid& g : ref.indirect)
                for (float v : g.v) refMean += v;
            refMean /= 3.0 * gSize * gSize;
            for (int s : {1, 2}) {
                double e[2], b[2];
                for (int k = 0; k < 2; ++k) {
                    GiState st;
                    const GlossyIndirect mode = k == 0 ? GlossyIndirect::VectorPyramid : GlossyIndirect::ScalarPyramid;
                    withThreads(2, [&] { runGiFrame(h.cview(), cell, light, settingsFor(brdf, S, s, 1, mode), st, &a); });
                    e[k] = relRmse(st.indirect.indirect, ref.indirect, b[k]);
                }
                char line[512];
                std::snprintf(line, sizeof line, "| %s | %g | %dx | %.4f | %+.4f | %.4f | %+.4f | %.4f | %.1f |\n", brdfName(brdf), S, s,
                              e[0], b[0], e[1], b[1], refMean, refSeconds);
                std::fprintf(stderr, "%s", line);
                md += line;
            }
        }

    // ---- frame time -----------------------------------------------------------
    md += "\n## Frame time, alps-montblanc central crops, 2x sub-sampling, 1 bounce, 2 threads (median of " + std::to_string(gRuns) +
          " frames after a warm-up)\n\n";
    md += "| size | BRDF / glossy mode | frame (ms) | indirect (ms) | E + pyramids (ms) | scan (ms) | shading (ms) |\n";
    md += "|---|---|---|---|---|---|---|\n";
    for (int size : {256, 512}) {
        float c2 = 1.0f;
        const Grid hs = alpsCrop(size, c2);
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
                for (int r = 0; r < gRuns; ++r) {
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
            std::snprintf(line, sizeof line, "| %d^2 | %s | %.1f | %.1f | %.1f | %.1f | %.1f |\n", size, cs.name, bench::median(frame),
                          bench::median(ind), bench::median(pyr), bench::median(scan), bench::median(shade));
            std::fprintf(stderr, "%s", line);
            md += line;
        }
    }
    std::ofstream(gOutDir + "/gi_glossy.md") << md;
    std::fprintf(stderr, "wrote %s/gi_glossy.md\n", gOutDir.c_str());
    return 0;
}
