// `terrain_bench gi-glossy`: glossy indirect light - the SH radiance-vector
// pyramid (GlossyIndirect::VectorPyramid, Fig. 5 middle), the scalar shade
// pyramid (ScalarPyramid, Fig. 5 right) and the lobe gather (LobeScan)
// against the glossy reference
// (gi/reference_glossy, exact), with and without the positivity clamp, and
// the frame time of the glossy bounce. Writes gi_glossy.md and gi_glossy.csv.
#include <chrono>
#include <cmath>
#include <cstdarg>
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
    int directions = 2048;  // directions of the reference (its Lambert part)
    int lobeRings = 12;     // lobe quadrature of the reference (rings x 2 rings directions per lobe)
    bool timing = true;     // the frame-time section
    bool accuracy = true;   // the accuracy section
    bool floors = false;    // the floors of the vector mode (gi_glossy_floors.md)
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

std::string strprintf(const char* fmt, ...) __attribute__((format(printf, 1, 2)));
std::string strprintf(const char* fmt, ...) {
    char buf[512];
    va_list args;
    va_start(args, fmt);
    std::vsnprintf(buf, sizeof buf, fmt, args);
    va_end(args);
    return buf;
}

// One accuracy row's engine frame: relative RMSE and bias of the indirect
// light against the reference, and the share of negative indirect values.
struct EngineError {
    double rmse, bias, negative;
};

EngineError engineError(const Grid& h, float cell, const GiLighting& light, const AlbedoMap& a, GiSettings g,
                        GlossyPositivity positivity, const ReferenceGiResult& ref) {
    g.shading.positivity = positivity;
    GiState st;
    withThreads(2, [&] { runGiFrame(h.cview(), cell, light, g, st, &a); });
    EngineError e{};
    e.rmse = relRmse(st.indirect.indirect, ref.indirect, e.bias);
    long neg = 0, n = 0;
    for (const Grid& c : st.indirect.indirect)
        for (float v : c.v) {
            neg += v < 0.0f;
            ++n;
        }
    e.negative = static_cast<double>(neg) / static_cast<double>(n);
    return e;
}

struct AccuracyRow {
    Brdf brdf;
    float S;
};

// The references of one row: exact, and the diagnostic whose first-bounce
// receivers shade the SH-projected incident radiance (first hits exact).
struct RowReferences {
    ReferenceGiResult exact, receiverSh;
    double mean = 0.0, seconds = 0.0;  // the exact one's mean indirect light and time
};

RowReferences rowReferences(const Grid& h, float cell, const GiLighting& light, const AlbedoMap& a,
                            const GlossyOptions& o, const AccuracyRow& row) {
    RowReferences r;
    ReferenceGiSettings rs;
    rs.directions = o.directions;
    rs.lobe = LobeLayout::uniform(o.lobeRings);
    rs.bounces = 1;
    rs.shading = settingsFor(row.brdf, row.S, 1, 1, GlossyIndirect::VectorPyramid).shading;
    const auto t0 = Clock::now();
    withThreads(2, [&] { renderReferenceGi(h.cview(), cell, light.environment, &a, rs, r.exact); });
    r.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    ReferenceGiSettings rsh = rs;
    rsh.receiverSh = true;
    withThreads(2, [&] { renderReferenceGi(h.cview(), cell, light.environment, &a, rsh, r.receiverSh); });
    for (const Grid& g : r.exact.indirect)
        for (float v : g.v) r.mean += v;
    r.mean /= 3.0 * h.nx * h.ny;
    return r;
}

// The engine's errors of one row at sub-sampling s: e [vector, scalar][clamp,
// off] against the exact reference; d, the vector mode [clamp, off] against
// the diagnostic reference; az, the vector mode (clamp) with 16 and 32 scan
// azimuths; lobe, the lobe gather (engine default quadrature) and quad, the
// lobe gather at kLobeColumns. Each also a CSV line.
struct LobeColumn {
    int rings, innerDirections, azimuths;
    bool pyramidSteps = false;  // the walks on the height pyramid's own steps (no denser near steps)
    int nearSteps = 0;          // raw steps per octave (0: the engine's default)
};
constexpr LobeColumn kLobeColumns[] = {{2, 4, 28}, {2, 5, 16}, {2, 5, 28}, {2, 5, 28, true},
                                       {2, 6, 28}, {3, 3, 28}, {3, 4, 28}, {2, 5, 32, false, 16},
                                       {2, 5, 64}, {4, 4, 64}};

// "2 rings (5, 10), 28 az": the rings' directions from the lobe's axis out
// (LobeLayout numbers its rings from the outermost).
std::string quadratureName(const LobeColumn& q) {
    const LobeLayout layout = LobeLayout::growing(q.rings, q.innerDirections);
    std::string rings;
    for (int i = layout.rings - 1; i >= 0; --i)
        rings += (i < layout.rings - 1 ? ", " : "") + std::to_string(layout.ringDirections(i));
    return strprintf("%d rings (%s), %d az%s%s", q.rings, rings.c_str(), q.azimuths,
                     q.pyramidSteps ? ", pyramid steps" : "",
                     q.nearSteps > 0 ? strprintf(", %d near steps", q.nearSteps).c_str() : "");
}
constexpr int kLobeColumnCount = sizeof kLobeColumns / sizeof kLobeColumns[0];

struct RowErrors {
    EngineError e[2][2], d[2], az[2], lobe, lobeSh, quad[kLobeColumnCount];
};

RowErrors rowErrors(const Grid& h, float cell, const GiLighting& light, const AlbedoMap& a, const AccuracyRow& row,
                    int s, const RowReferences& ref, std::string& csv) {
    RowErrors r;
    auto csvLine = [&](const std::string& mode, const char* positivity, const EngineError& e) {
        csv += strprintf("%s,%g,%d,%s,%s,%.5f,%+.5f,%.4f,%.5f,%.1f\n", brdfName(row.brdf), row.S, s, mode.c_str(),
                         positivity, e.rmse, e.bias, e.negative, ref.mean, ref.seconds);
    };
    for (int k = 0; k < 2; ++k)
        for (int p = 0; p < 2; ++p) {
            const GlossyIndirect mode = k == 0 ? GlossyIndirect::VectorPyramid : GlossyIndirect::ScalarPyramid;
            const GlossyPositivity pos = p == 0 ? GlossyPositivity::Clamp : GlossyPositivity::Off;
            r.e[k][p] = engineError(h, cell, light, a, settingsFor(row.brdf, row.S, s, 1, mode), pos, ref.exact);
            csvLine(k == 0 ? "vector" : "scalar", p == 0 ? "clamp" : "off", r.e[k][p]);
        }
    for (int p = 0; p < 2; ++p) {
        const GlossyPositivity pos = p == 0 ? GlossyPositivity::Clamp : GlossyPositivity::Off;
        r.d[p] = engineError(h, cell, light, a, settingsFor(row.brdf, row.S, s, 1, GlossyIndirect::VectorPyramid), pos,
                             ref.receiverSh);
        csvLine("vector vs receiver-SH reference", p == 0 ? "clamp" : "off", r.d[p]);
    }
    for (int k = 0; k < 2; ++k) {
        GiSettings g = settingsFor(row.brdf, row.S, s, 1, GlossyIndirect::VectorPyramid);
        g.indirect.azimuths = 16 << k;
        r.az[k] = engineError(h, cell, light, a, g, GlossyPositivity::Clamp, ref.exact);
        csvLine("vector " + std::to_string(16 << k) + " azimuths", "clamp", r.az[k]);
    }
    r.lobe = engineError(h, cell, light, a, settingsFor(row.brdf, row.S, s, 1, GlossyIndirect::LobeScan),
                         GlossyPositivity::Clamp, ref.exact);
    csvLine("lobe", "clamp", r.lobe);
    GiSettings gsh = settingsFor(row.brdf, row.S, s, 1, GlossyIndirect::LobeScan);
    gsh.indirect.lobeMembers = GlossyLobeMembers::Sh;
    r.lobeSh = engineError(h, cell, light, a, gsh, GlossyPositivity::Clamp, ref.exact);
    csvLine("lobe, SH members", "clamp", r.lobeSh);
    for (int q = 0; q < kLobeColumnCount; ++q) {
        GiSettings g = settingsFor(row.brdf, row.S, s, 1, GlossyIndirect::LobeScan);
        g.indirect.lobeRings = kLobeColumns[q].rings;
        g.indirect.lobeInnerDirections = kLobeColumns[q].innerDirections;
        g.indirect.lobeAzimuths = kLobeColumns[q].azimuths;
        if (kLobeColumns[q].pyramidSteps) {
            g.indirect.lobeNearStepsPerOctave = g.pyramid.levelsPerOctave;
            g.indirect.lobeNearOctaves = g.pyramid.levelOffset;
        }
        if (kLobeColumns[q].nearSteps > 0) g.indirect.lobeNearStepsPerOctave = kLobeColumns[q].nearSteps;
        r.quad[q] = engineError(h, cell, light, a, g, GlossyPositivity::Clamp, ref.exact);
        csvLine("lobe " + quadratureName(kLobeColumns[q]), "clamp", r.quad[q]);
    }
    return r;
}

// Accuracy against the exact glossy reference on the central o.size^2 crop of
// Mont Blanc: both glossy modes, with the positivity clamp (engine default)
// and without it (paper), 1x and 2x.
std::string accuracySection(const GlossyOptions& o, const BenchContext& ctx, std::string& csv) {
    std::string md, diag, azim, quad;
    float cell = 1.0f;
    const Grid h = alpsCentreCrop(ctx.dataDir, o.size, cell);
    const AlbedoMap a = uniformAlbedo(o.size, o.size, albedo);
    const GiLighting light = sunSkyLighting();
    md += "## Accuracy: alps-montblanc, central " + std::to_string(o.size) + "^2 crop at true scale (cell 92.74 m)\n\n";
    md +=
        "Reference: `renderReferenceGlossy`, exact: the Phong lobes of the receiver and of every first hit "
        "integrated against the exact incident radiance (the SH sky through exact horizons at 256 azimuths), " +
        std::to_string(o.lobeRings) + " x " + std::to_string(2 * o.lobeRings) +
        " lobe quadrature directions per lobe, " + std::to_string(o.directions) +
        " fixed directions for the Lambert part. Relative RMSE and bias of the indirect light (bounce 1, RGB, 10 % "
        "border left out); clamp: `--glossy-positivity clamp` (engine default), off: the paper's linear SH "
        "values; neg: share of negative indirect values without the clamp (with it: none); lobe: `--glossy lobe` "
        "(the lobe gather, never negative; its first bounce's surface sends its lobe-filtered light times the "
        "part of its lobe above its horizon, `--glossy-lobe-members windowed`); lobe SH: the same gather with the "
        "surface sending its order-4 SH exit radiance (`--glossy-lobe-members sh`).\n\n";
    md +=
        "| BRDF | S | sub-sampling | vector clamp RMSE | bias | vector off RMSE | bias | vector off neg | scalar clamp "
        "RMSE | bias | scalar off RMSE | bias | scalar off neg | lobe RMSE | bias | lobe SH RMSE | bias | reference "
        "mean indirect | "
        "reference "
        "time (s) |\n";
    md += "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    csv += "brdf,S,subsample,mode,positivity,rel_rmse,bias,negative_share,reference_mean,reference_seconds\n";
    for (const AccuracyRow& row :
         {AccuracyRow{Brdf::Phong, 8.0f}, AccuracyRow{Brdf::Phong, 16.0f}, AccuracyRow{Brdf::Phong, 32.0f},
          AccuracyRow{Brdf::Phong, 64.0f}, AccuracyRow{Brdf::LambertPlusPhong, 64.0f}}) {
        const RowReferences ref = rowReferences(h, cell, light, a, o, row);
        for (int s : {1, 2}) {
            const RowErrors r = rowErrors(h, cell, light, a, row, s, ref, csv);
            azim += strprintf("| %s | %g | %dx | %.4f | %.4f | %.4f |\n", brdfName(row.brdf), row.S, s, r.e[0][0].rmse,
                              r.az[0].rmse, r.az[1].rmse);
            quad += strprintf("| %s | %g | %dx |", brdfName(row.brdf), row.S, s);
            for (const EngineError& q : r.quad) quad += strprintf(" %.4f |", q.rmse);
            quad += "\n";
            diag += strprintf("| %s | %g | %dx | %.4f | %+.4f | %.4f | %+.4f |\n", brdfName(row.brdf), row.S, s,
                              r.d[0].rmse, r.d[0].bias, r.d[1].rmse, r.d[1].bias);
            const std::string line = strprintf(
                "| %s | %g | %dx | %.4f | %+.4f | %.4f | %+.4f | %.1f %% | %.4f | %+.4f | %.4f | %+.4f | %.1f "
                "%% | %.4f | %+.4f | %.4f | %+.4f | %.4f | %.1f |\n",
                brdfName(row.brdf), row.S, s, r.e[0][0].rmse, r.e[0][0].bias, r.e[0][1].rmse, r.e[0][1].bias,
                100.0 * r.e[0][1].negative, r.e[1][0].rmse, r.e[1][0].bias, r.e[1][1].rmse, r.e[1][1].bias,
                100.0 * r.e[1][1].negative, r.lobe.rmse, r.lobe.bias, r.lobeSh.rmse, r.lobeSh.bias, ref.mean,
                ref.seconds);
            std::fprintf(stderr, "%s", line.c_str());
            md += line;
        }
    }
    md +=
        "\nDiagnostic: the vector pyramid against the reference whose first-bounce receivers shade the incident "
        "radiance projected to order-4 SH with the lobe factors g_l, as the fast path's receivers do "
        "(`ReferenceGiSettings::receiverSh`; first hits exact): the error of what the casting-set members send, "
        "without the receivers' order-4 lobe.\n\n";
    md +=
        "| BRDF | S | sub-sampling | vector clamp RMSE | bias | vector off RMSE | bias "
        "|\n|---|---|---|---|---|---|---|\n";
    md += diag;
    md += "\nScan azimuths (`IndirectSettings::azimuths`, engine default " +
          std::to_string(IndirectSettings{}.azimuths) +
          "): relative RMSE of the vector pyramid (clamp) against the exact reference.\n\n";
    md += "| BRDF | S | sub-sampling | default | 16 azimuths | 32 azimuths |\n|---|---|---|---|---|---|\n";
    md += azim;
    const IndirectSettings defaults;
    md += "\nLobe quadrature (`--glossy lobe`, engine default " + std::to_string(defaults.lobeRings) +
          " rings, the innermost of " + std::to_string(defaults.lobeInnerDirections) + " directions, " +
          std::to_string(defaults.lobeAzimuths) +
          " azimuths): relative RMSE of the lobe gather against the exact reference with n rings, ring i from the "
          "lobe's axis holding i k directions (k: `--glossy-lobe-inner-directions`), and M global azimuths; the "
          "walks' raw steps out to " +
          std::to_string(1 << defaults.lobeNearOctaves) + " cells at " +
          std::to_string(defaults.lobeNearStepsPerOctave) +
          " per octave, or on the height pyramid's own steps (`--glossy-lobe-near-steps` and "
          "`--glossy-lobe-near-octaves` set to its levels per octave and level offset).\n\n| BRDF | S | sub-sampling |";
    std::string rule = "|---|---|---|";
    for (const LobeColumn& q : kLobeColumns) {
        md += " " + quadratureName(q) + " |";
        rule += "---|";
    }
    md += "\n" + rule + "\n" + quad;
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
            GlossyLobeMembers members = GlossyLobeMembers::Windowed;
        };
        for (const Case& cs : {Case{"lambert", Brdf::Lambert, GlossyIndirect::ScalarPyramid},
                               Case{"phong:32, scalar pyramid", Brdf::Phong, GlossyIndirect::ScalarPyramid},
                               Case{"phong:32, vector pyramid", Brdf::Phong, GlossyIndirect::VectorPyramid},
                               Case{"phong:32, lobe gather", Brdf::Phong, GlossyIndirect::LobeScan},
                               Case{"phong:32, lobe gather, SH members", Brdf::Phong, GlossyIndirect::LobeScan,
                                    GlossyLobeMembers::Sh}}) {
            GiSettings g = settingsFor(cs.brdf, 32.0f, 2, 1, cs.mode);
            g.indirect.lobeMembers = cs.members;
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

// What gi_glossy_floors.md measures, before its table.
std::string floorsIntro(const GlossyOptions& o) {
    std::string md = "# Floors of the vector glossy mode\n\n";
    md += "Machine: " + machineDescription() + ".\n\n";
    md += "Alps-montblanc, central " + std::to_string(o.size) +
          "^2 crop at true scale, sun-and-sky SH environment, Phong, one bounce, 1x. Relative RMSE (10 % border "
          "left out) of `renderReferenceGlossy` with one of the fast path's approximations against the exact "
          "reference (" +
          std::to_string(o.lobeRings) + " x " + std::to_string(2 * o.lobeRings) +
          " lobe directions at the receivers and at every first hit): members SH: the first hits send the Phong part "
          "of their incident radiance projected to order-4 SH (`ReferenceGiSettings::membersSh`, what the vector "
          "pyramid's E sends, without its pyramid and scan); receivers SH: the receivers shade their incident "
          "radiance projected to order-4 SH (`receiverSh`); N rays: the receivers' lobe sampled by the same "
          "quadrature with N directions (2 or 3 rings); M azimuths: each of the receivers' lobe rays takes the "
          "first hits at its elevation along the two nearest of M evenly spaced azimuths (the fast path's scan "
          "azimuths, 8 by default), linearly weighted (`receiverAzimuths`): what a receiver that integrates its "
          "own lobe over the scan's incident radiance could reach; members windowed: the first hits send the "
          "lobe-filtered light times the part of their lobe above their exact horizon along R's azimuth "
          "(`membersWindowed`, what the lobe gather's first-bounce members send, gi/glossy_lobe_members.h).\n\n";
    return md;
}

// The floors of the vector mode: the exact reference against its own
// diagnostics, each keeping one of the fast path's approximations and nothing
// else: the first hits sending their order-4 SH exit radiance (membersSh), the
// receivers shading order-4 SH incident radiance (receiverSh), both, and the
// receivers' lobe sampled by a few rays (2 or 3 rings of the lobe quadrature:
// 8 or 18 rays) with exact or order-4 members, and the receivers' lobe seeing
// its incident radiance along the scan's azimuths only (receiverAzimuths: 8,
// the engine's, 16 or 32), and windowed members (membersWindowed) alone and
// as the lobe gather has them. Phong, 1x, on the accuracy crop.
void floorsSection(const GlossyOptions& o, const BenchContext& ctx) {
    float cell = 1.0f;
    const Grid h = alpsCentreCrop(ctx.dataDir, o.size, cell);
    const AlbedoMap a = uniformAlbedo(o.size, o.size, albedo);
    const GiLighting light = sunSkyLighting();
    struct Variant {
        const char* name;
        bool membersSh, receiverSh;
        bool membersWindowed;
        int rings;     // 0: the reference's
        int azimuths;  // ReferenceGiSettings::receiverAzimuths (0: every ray its own)
    };
    const Variant variants[] = {{"members SH", true, false, false, 0, 0},
                                {"receivers SH", false, true, false, 0, 0},
                                {"both SH", true, true, false, 0, 0},
                                {"receivers 8 rays", false, false, false, 2, 0},
                                {"receivers 18 rays", false, false, false, 3, 0},
                                {"8 rays, members SH", true, false, false, 2, 0},
                                {"18 rays, members SH", true, false, false, 3, 0},
                                {"members SH, 8 azimuths", true, false, false, 0, 8},
                                {"18 rays, members SH, 8 azimuths", true, false, false, 3, 8},
                                {"18 rays, members SH, 16 azimuths", true, false, false, 3, 16},
                                {"18 rays, members SH, 32 azimuths", true, false, false, 3, 32},
                                {"members windowed", false, false, true, 0, 0},
                                {"18 rays, members windowed, 32 azimuths", false, false, true, 3, 32}};
    std::string md = floorsIntro(o);
    std::string head = "| S |", rule = "|---|";
    for (const Variant& v : variants) {
        head += std::string(" ") + v.name + " |";
        rule += "---|";
    }
    md += head + "\n" + rule + "\n";
    std::string csv = "S,variant,rel_rmse,bias\n";
    for (float S : {8.0f, 16.0f, 32.0f, 64.0f}) {
        ReferenceGiSettings rs;
        rs.directions = o.directions;
        rs.lobe = LobeLayout::uniform(o.lobeRings);
        rs.bounces = 1;
        rs.shading = settingsFor(Brdf::Phong, S, 1, 1, GlossyIndirect::VectorPyramid).shading;
        ReferenceGiResult exact;
        withThreads(2, [&] { renderReferenceGi(h.cview(), cell, light.environment, &a, rs, exact); });
        std::string line = strprintf("| %g |", S);
        for (const Variant& v : variants) {
            ReferenceGiSettings d = rs;
            d.membersSh = v.membersSh;
            d.membersWindowed = v.membersWindowed;
            d.receiverSh = v.receiverSh;
            if (v.rings > 0) d.lobe = LobeLayout::uniform(v.rings);
            d.receiverAzimuths = v.azimuths;
            ReferenceGiResult r;
            withThreads(2, [&] { renderReferenceGi(h.cview(), cell, light.environment, &a, d, r); });
            double bias = 0.0;
            const double e = relRmse(r.indirect, exact.indirect, bias);
            line += strprintf(" %.1f %% |", 100.0 * e);
            csv += strprintf("%g,%s,%.5f,%+.5f\n", S, v.name, e, bias);
            std::fprintf(stderr, "S %g, %s: %.4f (bias %+.4f)\n", S, v.name, e, bias);
        }
        md += line + "\n";
    }
    writeResult(ctx.outDir, "gi_glossy_floors.md", md);
    writeResult(ctx.outDir, "gi_glossy_floors.csv", csv);
}

int runGlossy(const GlossyOptions& o, const BenchContext& ctx) {
    std::string md = "# Glossy indirect light: vector pyramid, scalar pyramid, lobe gather\n\n";
    md += "Machine: " + machineDescription() +
          " (shared with another engineer's builds and benchmarks while this ran: timings are indicative).\n\n";
    md += "Lighting: sun-and-sky SH environment (`sunSkyLight()`), viewer overhead, albedo " +
          std::to_string(albedo).substr(0, 3) +
          " (diffuse part), engine settings (`GiSettings{}`: m = 16, o_v = o_u = 3), 1 bounce.\n\n";
    std::string csv;
    if (o.accuracy) md += accuracySection(o, ctx, csv);
    if (o.timing) md += frameTimeSection(o, ctx);
    if (o.accuracy || o.timing) writeResult(ctx.outDir, "gi_glossy.md", md);
    if (o.accuracy) writeResult(ctx.outDir, "gi_glossy.csv", csv);
    if (o.floors) floorsSection(o, ctx);
    return 0;
}

}  // namespace

Runner addGiGlossySuite(CLI::App& app, const BenchContext& ctx) {
    auto o = std::make_shared<GlossyOptions>();
    CLI::App* sub = app.add_subcommand(
        "gi-glossy", "Glossy indirect light: vector pyramid, scalar pyramid and lobe gather, accuracy and frame time");
    addRunsOption(*sub, o->runs, "Frames per timing (the median is reported)");
    sub->add_option("--size", o->size, "Side of the accuracy crop")->check(CLI::Range(16, 4096))->capture_default_str();
    sub->add_option("--directions", o->directions, "Directions of the glossy reference")
        ->check(CLI::Range(64, 1 << 20))
        ->capture_default_str();
    sub->add_option("--lobe-rings", o->lobeRings,
                    "Lobe quadrature of the glossy reference (rings; 2x as many azimuths)")
        ->check(CLI::Range(1, 256))
        ->capture_default_str();
    sub->add_flag("!--no-timing", o->timing, "Skip the frame-time section");
    sub->add_flag("!--no-accuracy", o->accuracy, "Skip the accuracy section");
    sub->add_flag("--floors", o->floors,
                  "Also the floors of the vector mode: the reference with one approximation at a time "
                  "(gi_glossy_floors.md, .csv; about 20 minutes)");
    return [o, &ctx] { return runGlossy(*o, ctx); };
}

}  // namespace terrain::bench
