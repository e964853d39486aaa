// `terrain_bench gi-indirect`: accuracy of the indirect light against
// gi/reference_gi (the paper's Table 1 frame times are `terrain_bench
// table1`). Writes gi_indirect_accuracy.{md,csv}; --diagnose writes
// gi_indirect_diagnosis.md; --probe prints one frame time only.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "bench/indirect_frame.h"
#include "bench/suites.h"
#include "core/parallel.h"
#include "core/simd.h"
#include "gi/frame.h"
#include "gi/reference_gi.h"
#include "sim/scene.h"

namespace terrain::bench {
namespace {
using namespace terrain::gi;
using Clock = std::chrono::steady_clock;

struct IndirectOptions {
    int runs = 5;
    bool quick = false;        // 96^2 accuracy crops, fewer erosion ticks
    bool diagnose = false;     // the error breakdown instead of the tables
    bool shKernel = false;     // the engine settings with the paper's SH Lambert kernel and receiver planes
    int indirectAzimuths = 0;  // azimuths of the indirect scan (0: the settings' own)
    int radianceK = 0;         // the engine's radiance pyramid k_u (0: the engine default)
    int radianceO = -1;        // the engine's radiance pyramid o_u (-1: the engine default)
    int probe = 0;             // only the frame time of a probe^2 erosion frame, 2x, one bounce (stderr)
    int probeThreads = 2;      // threads of the probe (1: every instruction on the calling thread, for profiles)
};

// ---- error breakdown (--diagnose) ---------------------------------------------------
std::string fmtErr(const char* what, double e, double b) {
    char line[256];
    std::snprintf(line, sizeof line, "| %s | %.4f | %+.4f |\n", what, e, b);
    std::fprintf(stderr, "%s", line);
    return line;
}

std::string diagnose(const Dem& d, const GiLighting& light, float albedo) {
    const AlbedoMap a = uniformAlbedo(d.heights.nx, d.heights.ny, albedo);
    std::string md = "## " + d.name + ": " + d.note + "\n\n| quantity | rel. RMSE | bias |\n|---|---|---|\n";
    ReferenceGiSettings s;
    s.bounces = 0;
    // (a) direct: exact caps vs the SH-folded key light
    ReferenceGiResult folded, capRef, keyOnly;
    withThreads(0, [&] { renderReferenceGi(d.heights.cview(), d.cell, foldKeys(light), &a, s, folded); });
    s.keys = light.keys;
    withThreads(0, [&] { renderReferenceGi(d.heights.cview(), d.cell, light.environment, &a, s, capRef); });
    std::array<Grid, 3> keyRef;
    for (const KeyLight& k : light.keys) addReferenceKeyLight(d.heights.cview(), d.cell, k, &a, 48, keyRef);
    // indirect references (1 bounce) from the exact direct: cosine and SH kernel
    std::array<Grid, 3> ind, indSh;
    withThreads(0, [&] { gatherReferenceBounce(d.heights.cview(), d.cell, capRef.direct, &a, s, ind); });
    ReferenceGiSettings sh = s;
    sh.shLambert = true;
    withThreads(0, [&] { gatherReferenceBounce(d.heights.cview(), d.cell, capRef.direct, &a, sh, indSh); });
    double b = 0.0, e = 0.0;
    e = relRmse(folded.direct, capRef.direct, b);
    md += fmtErr("ref. direct, key folded into SH vs exact cap", e, b);
    e = relRmse(indSh, ind, b);
    md += fmtErr("(d) ref. indirect, SH Lambert kernel vs cosine (truncation floor)", e, b);
    for (int sub : {1, 2}) {
        GiSettings g = wholeFrames(GiSettings{});
        g.subsample = sub;
        g.indirect.bounces = 1;
        GiState st;
        withThreads(2, [&] { runGiFrame(d.heights.cview(), d.cell, light, g, st, &a); });
        const std::string tag = std::to_string(sub) + "x";
        e = relRmse(st.shade.rgb, capRef.direct, b);
        md += fmtErr(("(a) " + tag + " direct vs exact-cap ref. direct").c_str(), e, b);
        e = relRmse(st.shade.rgb, folded.direct, b);
        md += fmtErr(("(a) " + tag + " direct vs SH-folded ref. direct").c_str(), e, b);
        {
            GiLighting kl = light;
            kl.environment = ShRgb{};
            GiState sk;
            withThreads(2, [&] { runGiFrame(d.heights.cview(), d.cell, kl, g, sk, &a); });
            e = relRmse(sk.shade.rgb, keyRef, b);
            md += fmtErr(("(a) " + tag + " key light alone vs exact cap").c_str(), e, b);
        }
        e = relRmse(st.indirect.indirect, ind, b);
        md += fmtErr(("" + tag + " indirect (own direct) vs ref.").c_str(), e, b);
        std::array<Grid, 3> tot = capRef.direct;
        for (int c = 0; c < 3; ++c)
            for (std::size_t i = 0; i < tot[c].v.size(); ++i) tot[c].v[i] += ind[c].v[i];
        e = relRmse(st.indirect.total, tot, b);
        md += fmtErr(("" + tag + " total vs ref.").c_str(), e, b);
        // (b) the reference's direct light as bounce 0; (c) radiance pyramid settings
        for (int ou : {0, 1, 2, 3})
            for (int ku : {4, 8}) {
                if (ku == 8 && ou != 2) continue;
                IndirectSettings is = g.indirect;
                is.radiance.levelOffset = ou;
                is.radiance.levelsPerOctave = ku;
                IndirectState ist;
                withThreads(2, [&] {
                    const IndirectInputs in{st.pyramid,       st.gradX.cview(), st.gradY.cview(), st.envOperator,
                                            st.envVisibility, capRef.direct,    nullptr,          &a,
                                            g.shading};
                    computeIndirect(in, is, ist);
                });
                const std::string name = "(b,c) " + tag + " indirect from ref. direct, o_u " + std::to_string(ou) +
                                         ", k_u " + std::to_string(ku);
                e = relRmse(ist.indirect, ind, b);
                md += fmtErr((name + " vs ref.").c_str(), e, b);
                e = relRmse(ist.indirect, indSh, b);
                md += fmtErr((name + " vs SH-kernel ref.").c_str(), e, b);
            }
    }
    return md + "\n";
}

// Lower bound of any scheme that interpolates a smooth field from the
// receivers: the reference's own indirect light, sampled at the s x s
// receivers and re-interpolated bilinearly.
std::string interpolationBound(const GiReference& ref, int s) {
    std::array<Grid, 3> ip = ref.indirectUpTo[0];
    const Grid& r0 = ref.indirectUpTo[0][0];
    for (int c = 0; c < 3; ++c)
        for (int y = 0; y < r0.ny; ++y)
            for (int x = 0; x < r0.nx; ++x) {
                const int X0 = std::min(x / s * s, (r0.nx - 1) / s * s), Y0 = std::min(y / s * s, (r0.ny - 1) / s * s);
                const int X1 = std::min(X0 + s, (r0.nx - 1) / s * s), Y1 = std::min(Y0 + s, (r0.ny - 1) / s * s);
                const float fx = X1 > X0 ? float(x - X0) / s : 0.0f, fy = Y1 > Y0 ? float(y - Y0) / s : 0.0f;
                const Grid& g = ref.indirectUpTo[0][c];
                ip[c](x, y) =
                    (1 - fy) * ((1 - fx) * g(X0, Y0) + fx * g(X1, Y0)) + fy * ((1 - fx) * g(X0, Y1) + fx * g(X1, Y1));
            }
    double b = 0.0;
    const double e = relRmse(ip, ref.indirectUpTo[0], b);
    char line[256];
    std::snprintf(line, sizeof line,
                  "Bound of interpolation: the reference's own indirect light sampled at the %dx receivers and "
                  "interpolated bilinearly is off by %.4f rel. RMSE (bias %+.4f).\n\n",
                  s, e, b);
    std::fprintf(stderr, "%s", line);
    return line;
}

// One run of the suite: the options, the lighting and the accuracy terrains
// shared by its tables.
class IndirectSuite {
public:
    IndirectSuite(const IndirectOptions& o, const BenchContext& ctx) : o_(o), ctx_(ctx) {
        variant.indirectAzimuths = o_.indirectAzimuths;
        variant.radianceK = o_.radianceK;
        variant.radianceO = o_.radianceO;
        variant.shKernel = o_.shKernel;
    }

    int run() {
        if (o_.probe > 0) {
            probe();
            return 0;
        }
        if (o_.diagnose) {
            std::string md = "# Indirect light: error breakdown (terrain_bench gi-indirect --diagnose)\n\n";
            for (const Dem& d : {alpsCrop(ctx_.dataDir, accSize), erodedScene(accSize, o_.quick ? 200 : 2000)})
                md += diagnose(d, light, albedo);
            writeResult(ctx_.outDir, "gi_indirect_diagnosis.md", md);
            return 0;
        }
        dems = {alpsCrop(ctx_.dataDir, accSize), erodedScene(accSize, o_.quick ? 200 : 2000)};
        accuracy();
        return 0;
    }

private:
    const IndirectOptions& o_;
    const BenchContext& ctx_;
    const int accSize = o_.quick ? 96 : 256;
    const int refDirections = 2048;
    const float albedo = kIndirectFrameAlbedo;
    const GiLighting light = sunSkyAndBenchKey();
    IndirectVariant variant;
    std::vector<Dem> dems;  // the accuracy terrains: Mont Blanc and an eroded frame

    GiSettings settingsFor(int s, int bounces, bool paper) const {
        return indirectFrameSettings(s, bounces, paper, variant);
    }

    void probe() const;
    void accuracy();
    std::string accuracyRows(const Dem& d, const AlbedoMap& a, const GiReference& ref, std::string& summary,
                             std::string& accCsv) const;
};

void IndirectSuite::probe() const {
    const Dem d = erodedScene(o_.probe, 0);
    const AlbedoMap a = uniformAlbedo(o_.probe, o_.probe, albedo);
    GiState st;
    std::vector<double> t, ti, ts, parts[9];
    withThreads(o_.probeThreads, [&] {
        for (int f = 0; f <= o_.runs; ++f) {
            const auto t0 = Clock::now();
            runGiFrame(d.heights.cview(), d.cell, light, settingsFor(2, 1, false), st, &a);
            if (f == 0) continue;
            t.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
            ti.push_back(st.timings.indirect);
            ts.push_back(st.indirect.timings.scan);
            const double v[9] = {st.timings.gradient,      st.timings.pyramid,          st.timings.visibility,
                                 st.timings.keyVisibility, st.timings.shading,          st.indirect.timings.pyramid,
                                 st.indirect.timings.scan, st.indirect.timings.shading, st.indirect.timings.total};
            for (int k = 0; k < 9; ++k) parts[k].push_back(v[k]);
        }
    });
    std::fprintf(stderr,
                 "%d^2 2x 1 bounce: frame %.1f ms, indirect %.1f ms, scan %.1f ms (medians of %d, %d threads)\n",
                 o_.probe, median(t), median(ti), median(ts), o_.runs, o_.probeThreads);
    std::fprintf(stderr,
                 "  gradient %.2f, height pyramid %.2f, env visibility %.2f, key visibility %.2f, direct shading %.2f; "
                 "indirect: radiance pyramid %.2f, scan %.2f, shading %.2f, total %.2f ms\n",
                 median(parts[0]), median(parts[1]), median(parts[2]), median(parts[3]), median(parts[4]),
                 median(parts[5]), median(parts[6]), median(parts[7]), median(parts[8]));
}

// The error table of one terrain: paper and engine settings at 1x/2x/4x, 1..3
// bounces; adds the summary rows (one bounce) and the CSV rows.
std::string IndirectSuite::accuracyRows(const Dem& d, const AlbedoMap& a, const GiReference& ref, std::string& summary,
                                        std::string& accCsv) const {
    std::string accMd;
    for (int paper = 0; paper < 2; ++paper)
        for (int s : {1, 2, 4})
            for (int b : {1, 2, 3}) {
                if (paper && b > 1) continue;
                GiState st;
                withThreads(2, [&] { runGiFrame(d.heights.cview(), d.cell, light, settingsFor(s, b, paper), st, &a); });
                const IndirectErrors e = indirectErrors(st, ref, b);
                const char* name =
                    paper ? "paper (m 32, k 4, o 2, SH kernel)" : "engine (m 16 / 8 indirect, o 3, blocker radiance)";
                char line[512];
                std::snprintf(line, sizeof line, "| %s | %dx | %d | %.4f | %+.4f | %.4f | %+.4f |\n", name, s, b,
                              e.total, e.totalBias, e.indirect, e.indirectBias);
                accMd += line;
                if (b == 1 && (s == 2 || !paper)) {
                    std::snprintf(line, sizeof line, "| %s | %s | %dx | %.1f %% | %.1f %% |\n", d.name.c_str(),
                                  paper ? "paper" : "engine", s, 100.0 * e.total, 100.0 * e.indirect);
                    summary += line;
                }
                std::snprintf(line, sizeof line, "%s,%s,%d,%d,%.5f,%.5f,%.5f,%.5f,%.2f\n", d.name.c_str(),
                              paper ? "paper" : "engine", s, b, e.total, e.totalBias, e.indirect, e.indirectBias,
                              st.timings.total);
                accCsv += line;
                std::fprintf(stderr, "%s", line);
            }
    return accMd + "\n";
}

void IndirectSuite::accuracy() {
    std::string accMd = "# GI indirect light: accuracy against the reference (gi/reference_gi)\n\n";
    std::string summary;
    accMd += "Machine: " + machineDescription() +
             ". Lighting: sun-and-sky environment + one key light (az 135, el 35, r 5 deg; "
             "integrated as an exact cap by the reference), albedo " +
             std::to_string(albedo).substr(0, 3) +
             " everywhere, Lambert. Reference: exact direct light (256 azimuths) and " + std::to_string(refDirections) +
             " fixed gathering directions per texel, march step 0.5 cell. Relative RMSE over all three channels on the "
             "interior "
             "(10 % border excluded); bias = mean difference / RMS of the reference. Engine settings: " +
             indirectSettingsSummary(variant) + ".\n\n";
    std::string accCsv =
        "dem,settings,subsample,bounces,total_rel_rmse,total_bias,indirect_rel_rmse,indirect_bias,frame_ms\n";
    for (const Dem& d : dems) {
        const AlbedoMap a = uniformAlbedo(d.heights.nx, d.heights.ny, albedo);
        std::fprintf(stderr, "reference %s %dx%d ...\n", d.name.c_str(), d.heights.nx, d.heights.ny);
        const GiReference ref = withThreads(0, [&] { return computeReference(d, light, a, 3, refDirections); });
        accMd += "## " + d.name + ": " + d.note + "\n\nReference: " + std::to_string(static_cast<int>(ref.seconds)) +
                 " s (3 bounces).\n\n";
        accMd +=
            "| settings | sub-sampling | bounces | total rel. RMSE | total bias | indirect rel. RMSE | indirect bias "
            "|\n|---|---|---|---|---|---|---|\n";
        accMd += accuracyRows(d, a, ref, summary, accCsv);
        for (int s : {2, 4}) accMd += interpolationBound(ref, s);
    }
    const std::size_t head = accMd.find("\n\n") + 2;
    accMd.insert(
        head,
        "## Summary (one bounce; targets: total <= 3 %, indirect <= 10 % relative RMSE at 2x)\n\n"
        "| terrain | settings | sub-sampling | total rel. RMSE | indirect rel. RMSE |\n|---|---|---|---|---|\n" +
            summary +
            "\nWhy the engine's indirect light differs from the paper's (exact cosine at the receivers, footprint "
            "tangent "
            "planes, 8 indirect azimuths): gi/indirect.h, gi/visibility.h and gi_indirect_diagnosis.md.\n\n");
    writeResult(ctx_.outDir, "gi_indirect_accuracy.md", accMd);
    writeResult(ctx_.outDir, "gi_indirect_accuracy.csv", accCsv);
}

}  // namespace

Runner addGiIndirectSuite(CLI::App& app, const BenchContext& ctx) {
    auto o = std::make_shared<IndirectOptions>();
    CLI::App* sub = app.add_subcommand("gi-indirect", "Indirect light: accuracy against gi/reference_gi");
    addRunsOption(*sub, o->runs, "Frames per timing (the median is reported)");
    sub->add_flag("--quick", o->quick, "96^2 accuracy crops, fewer erosion ticks");
    sub->add_flag("--diagnose", o->diagnose, "Error breakdown instead of the tables (gi_indirect_diagnosis.md)");
    sub->add_flag("--sh-kernel", o->shKernel, "Engine settings with the paper's SH Lambert kernel and receiver planes");
    sub->add_option("--indirect-azimuths", o->indirectAzimuths, "Azimuths of the indirect scan (0: the settings' own)");
    sub->add_option("--radiance-k", o->radianceK, "The engine's radiance pyramid k_u (0: the engine default)");
    sub->add_option("--radiance-o", o->radianceO, "The engine's radiance pyramid o_u (-1: the engine default)");
    sub->add_option("--probe", o->probe, "Only the frame time of an N^2 erosion frame, 2x, one bounce (on stderr)");
    sub->add_option("--probe-threads", o->probeThreads, "Threads of --probe")
        ->check(CLI::Range(1, 256))
        ->capture_default_str();
    return [o, &ctx] { return IndirectSuite(*o, ctx).run(); };
}

}  // namespace terrain::bench
