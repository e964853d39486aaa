// svf-saga: the engine's sky-view factors side by side with SAGA's "Sky View
// Factor" (saga_cmd ta_lighting 3) on Mont Blanc at true scale, time and
// error against exact references on the same grid. SAGA is run only when
// saga_cmd is on the PATH; it is never a build or test dependency.
//
// SAGA's factor is not the plain one: per sector it sums cos S cos^2 F + sin S
// cos(z - A) (pi/2 - F - sin F cos F) (Oke; Haentzschel et al. 2005), the
// cosine-weighted sky at the cell's normal, with F its horizon raised to the
// horizontal (sky below the horizontal never counts). So there are three
// exact references, all from the same exact horizons (the march of the
// bilinear field, gi/reference.h, along M azimuths 2 pi (j + 1/2) / M):
//   plain  = 1 - mean sin(max(0, H)) (the engine's --svf-kind plain),
//   normal = (1/pi) int (N . w) dw above max(H, tangent plane) (--svf-kind
//            normal, the engine's ambient map),
//   saga   = SAGA's formula with F = max(0, H), both with the same central
//            difference slope and aspect.
// Each output is measured against its own definition's reference; the gap
// between the definitions is measured reference against reference.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <cpl_conv.h>
#include <gdal.h>
#include <ogr_srs_api.h>
#include <sys/utsname.h>

#include "bench/suites.h"
#include "core/error.h"
#include "core/geotiff_io.h"
#include "core/image_io.h"
#include "core/parallel.h"
#include "gi/frame.h"
#include "gi/horizon_angles.h"
#include "gi/reference.h"
#include "gi/sh.h"

namespace terrain::bench {
namespace {

struct SvfSagaOptions {
    int runs = 3;
    int azimuths = 256;
    int border = 2;
    int threads = 2;
    std::string cacheDir;
    std::string terrain;  // the terrain executable; default: beside terrain_bench
};

// The three exact references of one grid.
struct SvfReferences {
    Grid plain, normal, saga;
    Grid plainHalfA, plainHalfB;  // plain from the even and the odd azimuths alone (M / 2 each)
};

// One texel's three factors from its exact horizons along M azimuths.
void referenceTexel(ConstGridView h, float cell, const Grid& gx, const Grid& gy, int x, int y, int M, double heightMax,
                    SvfReferences& r) {
    const double g0x = gx(x, y), g0y = gy(x, y);
    const double n = std::sqrt(1.0 + g0x * g0x + g0y * g0y);
    double plain[2] = {0.0, 0.0}, normal = 0.0, saga = 0.0;
    // the cosine-weighted sky above elevation e along an azimuth whose tangent slope is g
    auto cosineWeighted = [&](double e, double g) {
        const double se = std::sin(e), ce = std::cos(e);
        return (ce * ce - g * (0.5 * gi::kPi - e - se * ce)) / n;
    };
    for (int j = 0; j < M; ++j) {
        const double phi = 2.0 * gi::kPi * (j + 0.5) / M;
        const double c = std::cos(phi), s = std::sin(phi);
        const double slope = gi::referenceMaxSlope(h, cell, x, y, c, s, heightMax);
        const double g = g0x * c + g0y * s;
        plain[j % 2] += slope > 0.0 ? slope / std::sqrt(1.0 + slope * slope) : 0.0;
        normal += cosineWeighted(std::atan(std::max(slope, g)), g);
        saga += cosineWeighted(std::atan(std::max(slope, 0.0)), g);
    }
    r.plain(x, y) = static_cast<float>(1.0 - (plain[0] + plain[1]) / M);
    r.plainHalfA(x, y) = static_cast<float>(1.0 - plain[0] / (M / 2));
    r.plainHalfB(x, y) = static_cast<float>(1.0 - plain[1] / (M / 2));
    r.normal(x, y) = static_cast<float>(normal / M);
    r.saga(x, y) = static_cast<float>(saga / M);
}

SvfReferences computeReferences(const Dem& d, int M) {
    const int nx = d.heights.nx, ny = d.heights.ny;
    Grid gx, gy;
    gi::computeGradient(d.heights.cview(), d.cell, gx, gy);
    double heightMax = -HUGE_VAL;
    for (float v : d.heights.v) heightMax = std::max(heightMax, static_cast<double>(v));
    SvfReferences r;
    for (Grid* g : {&r.plain, &r.normal, &r.saga, &r.plainHalfA, &r.plainHalfB}) g->resize(nx, ny);
    parallelForRows(ny, nx * 64, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y)
            for (int x = 0; x < nx; ++x) referenceTexel(d.heights.cview(), d.cell, gx, gy, x, y, M, heightMax, r);
    });
    return r;
}

// The references, from the cache file when it holds them (computed and stored otherwise).
SvfReferences cachedReferences(const Dem& d, int M, const std::string& dir) {
    const std::string file = dir + "/svf_saga_reference_" + d.name + "_m" + std::to_string(M) + ".bin";
    SvfReferences r;
    Grid* grids[] = {&r.plain, &r.normal, &r.saga, &r.plainHalfA, &r.plainHalfB};
    const std::size_t count = d.heights.size();
    if (std::ifstream in(file, std::ios::binary); in) {
        bool ok = true;
        for (Grid* g : grids) {
            g->resize(d.heights.nx, d.heights.ny);
            ok = ok && in.read(reinterpret_cast<char*>(g->data()), static_cast<std::streamsize>(count * sizeof(float)));
        }
        if (ok && in.peek() == EOF) return r;
    }
    std::fprintf(stderr, "svf-saga: exact references of %s along %d azimuths (minutes)...\n", d.name.c_str(), M);
    r = computeReferences(d, M);
    std::ofstream out(file, std::ios::binary);
    for (Grid* g : grids)
        out.write(reinterpret_cast<const char*>(g->data()), static_cast<std::streamsize>(count * sizeof(float)));
    return r;
}

// The DEM as a float32 GeoTIFF SAGA and the engine both read: UTM zone 32N
// (where the massif lies; the origin only places it roughly: SAGA and the
// engine use the cell size alone), north up.
std::string writeDemGeoTiff(const Dem& d, const std::string& dir) {
    GeoReference geo;
    geo.transform = {304000.0, d.cell, 0.0, 5107000.0, 0.0, -static_cast<double>(d.cell)};
    OGRSpatialReferenceH srs = OSRNewSpatialReference(nullptr);
    char* wkt = nullptr;
    if (OSRImportFromEPSG(srs, 32632) != OGRERR_NONE || OSRExportToWkt(srs, &wkt) != OGRERR_NONE) {
        OSRDestroySpatialReference(srs);
        throw IoError("EPSG:32632", "GDAL cannot make the CRS (is its proj database installed?)");
    }
    geo.crsWkt = wkt;
    CPLFree(wkt);
    OSRDestroySpatialReference(srs);
    const std::string file = dir + "/" + d.name + ".tif";
    writeGeoTiff(file, std::span<const Grid>(&d.heights, 1), geo);
    return file;
}

// Error of a map against a reference over the interior (a band of `border` cells left out).
struct ErrorStats {
    double rmse = 0.0, bias = 0.0, maxAbs = 0.0;
};
ErrorStats errorOf(const Grid& a, const Grid& ref, int border) {
    if (a.nx != ref.nx || a.ny != ref.ny) throw InputError("svf-saga: a map of another size than the reference");
    ErrorStats s;
    double sum = 0.0, sum2 = 0.0;
    long count = 0;
    for (int y = border; y < ref.ny - border; ++y)
        for (int x = border; x < ref.nx - border; ++x) {
            const double e = static_cast<double>(a(x, y)) - ref(x, y);
            sum += e;
            sum2 += e * e;
            s.maxAbs = std::max(s.maxAbs, std::abs(e));
            ++count;
        }
    s.rmse = std::sqrt(sum2 / std::max(count, 1L));
    s.bias = sum / std::max(count, 1L);
    return s;
}

// The first line a shell command prints ("" when it fails).
std::string firstLineOf(const std::string& command) {
    std::unique_ptr<FILE, int (*)(FILE*)> p(popen(command.c_str(), "r"), pclose);
    if (!p) return "";
    char buf[512];
    std::string line;
    while (std::fgets(buf, sizeof buf, p.get()))
        if (line.empty()) line = buf;
    while (!line.empty() && (line.back() == '\n' || line.back() == '\r')) line.pop_back();
    return line;
}

// Wall time (s) of one run of a shell command; throws when it fails.
double secondsOf(const std::string& command) {
    const auto t0 = std::chrono::steady_clock::now();
    if (std::system(command.c_str()) != 0) throw IoError(command, "the command failed");
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// One map measured: how it is made, which reference it is measured against.
struct SvfRun {
    std::string tool, definition, settings;
    std::string command, output;
    double seconds = 0.0;
    ErrorStats error;
};

std::vector<SvfRun> engineRuns(const SvfSagaOptions& o, const std::string& dem, const std::string& dir) {
    std::vector<SvfRun> runs;
    struct Variant {
        int subsample, azimuths;
    };
    for (const char* kind : {"plain", "normal"})
        for (const Variant v : {Variant{1, 16}, Variant{2, 16}, Variant{4, 16}, Variant{1, 64}}) {
            SvfRun r;
            r.tool = "engine";
            r.definition = kind;
            r.settings = std::to_string(v.subsample) + "x, " + std::to_string(v.azimuths) + " azimuths";
            r.output = dir + "/engine_" + kind + "_" + std::to_string(v.subsample) + "x_" + std::to_string(v.azimuths) +
                       ".tif";
            r.command = o.terrain + " gi --heightmap " + dem + " --threads " + std::to_string(o.threads) +
                        " --subsample " + std::to_string(v.subsample) + " --azimuths " + std::to_string(v.azimuths) +
                        " --svf-kind " + kind + " --out-svf " + r.output + " >/dev/null";
            runs.push_back(r);
        }
    return runs;
}

std::vector<SvfRun> sagaRuns(const SvfSagaOptions& o, const std::string& dem, const std::string& dir) {
    struct Variant {
        const char *name, *args;
    };
    std::vector<SvfRun> runs;
    for (const Variant v : {Variant{"default: 8 sectors, radius 10 km, cell-size steps", ""},
                            Variant{"16 sectors, unlimited radius", " -NDIRS=16 -RADIUS=0"},
                            Variant{"32 sectors, unlimited radius", " -NDIRS=32 -RADIUS=0"}}) {
        SvfRun r;
        r.tool = "SAGA";
        r.definition = "saga";
        r.settings = v.name;
        r.output = dir + "/saga_" + std::to_string(runs.size()) + ".tif";
        const std::string t = std::to_string(o.threads);
        r.command = "OMP_NUM_THREADS=" + t + " saga_cmd -f=q -c=" + t + " ta_lighting 3 -DEM=" + dem +
                    " -SVF=" + r.output + " -VISIBLE=" + dir + "/saga_visible.tif" + v.args + " >/dev/null";
        runs.push_back(r);
    }
    return runs;
}

const Grid& referenceOf(const SvfReferences& r, const std::string& definition) {
    return definition == "plain" ? r.plain : definition == "normal" ? r.normal : r.saga;
}

std::string resultsText(const SvfSagaOptions& o, const BenchContext& ctx, const std::vector<SvfRun>& runs,
                        const SvfReferences& ref, const std::string& sagaVersion, const std::string& loadBefore,
                        const std::string& loadAfter, std::string& csv) {
    char line[512];
    std::ostringstream md;
    md << "# Sky-view factor: the engine against SAGA\n\nCommand: `" << ctx.command << "` (bench/svf_saga.sh).\n"
       << "Machine: " << machineDescription() << "; load average " << loadBefore << " before, " << loadAfter
       << " after (a shared machine: other builds ran beside it when the load is above 1-2).\n"
       << "SAGA: " << (sagaVersion.empty() ? "not found (saga_cmd not on the PATH): engine rows only" : sagaVersion)
       << ", `saga_cmd ta_lighting 3`, OMP_NUM_THREADS=" << o.threads << " and -c=" << o.threads
       << "; engine: `terrain gi --threads " << o.threads << " --out-svf X.tif`, GDAL "
       << GDALVersionInfo("RELEASE_NAME")
       << ".\nDEM: alps-montblanc.png at true scale (647 x 647, 92.74 m, 454-4810 m) as a float32 GeoTIFF, read by "
          "both. Time: median wall time of "
       << o.runs
       << " runs of the whole command (read, compute, write). Error: against the exact reference of the map's own "
          "definition on the same grid (exact horizons of the bilinear field along "
       << o.azimuths << " azimuths), a band of " << o.border
       << " cells at each border left out; bias = mean(map - reference).\n\n"
          "Definitions (bench/suite_svf_saga.cpp): plain = 1 - mean sin(max(0, H)); normal = the cosine-weighted "
          "sky above max(H, tangent plane) at the cell's normal (the engine's ambient map); saga = SAGA's formula, "
          "mean of cos S cos^2 F + sin S cos(z - A) (pi/2 - F - sin F cos F) with F = max(0, H): the "
          "cosine-weighted sky above the horizontal only. SAGA is measured against saga, each engine map against "
          "its own definition.\n\n";
    md << "| tool | definition | settings | time (s) | RMSE | bias | max abs |\n|---|---|---|---|---|---|---|\n";
    csv = "tool,definition,settings,seconds,runs,rmse,bias,max_abs,border\n";
    for (const SvfRun& r : runs) {
        std::snprintf(line, sizeof line, "| %s | %s | %s | %.2f | %.4f | %+.4f | %.3f |\n", r.tool.c_str(),
                      r.definition.c_str(), r.settings.c_str(), r.seconds, r.error.rmse, r.error.bias, r.error.maxAbs);
        md << line;
        std::snprintf(line, sizeof line, "%s,%s,\"%s\",%.4f,%d,%.6f,%.6f,%.6f,%d\n", r.tool.c_str(),
                      r.definition.c_str(), r.settings.c_str(), r.seconds, o.runs, r.error.rmse, r.error.bias,
                      r.error.maxAbs, o.border);
        csv += line;
    }
    md << "\nThe definitions against each other (exact references, same band):\n\n"
          "| map | against | RMSE | bias | max abs |\n|---|---|---|---|---|\n";
    struct Gap {
        const char *a, *b;
        const Grid &ga, &gb;
    };
    for (const Gap& g :
         {Gap{"saga (exact)", "normal (exact)", ref.saga, ref.normal},
          Gap{"plain (exact)", "normal (exact)", ref.plain, ref.normal},
          Gap{"plain, even azimuths only", "plain, odd azimuths only", ref.plainHalfA, ref.plainHalfB}}) {
        const ErrorStats e = errorOf(g.ga, g.gb, o.border);
        std::snprintf(line, sizeof line, "| %s | %s | %.4f | %+.4f | %.3f |\n", g.a, g.b, e.rmse, e.bias, e.maxAbs);
        md << line;
    }
    for (const SvfRun& r : runs)
        if (r.tool == "SAGA") {
            const ErrorStats e = errorOf(readGeoTiffHeights(r.output).heights, ref.normal, o.border);
            std::snprintf(line, sizeof line, "| SAGA %s | normal (exact) | %.4f | %+.4f | %.3f |\n", r.settings.c_str(),
                          e.rmse, e.bias, e.maxAbs);
            md << line;
        }
    return md.str();
}

// The engine's horizon angles (--out-horizons) at 1x, 2x and 4x against the
// exact ones along the same 16 azimuths, in degrees, over the same interior
// and over the 10 % interior (the border cells see little terrain outwards,
// where the scan's first step and the receivers' spacing matter most).
std::string horizonAccuracyText(const Dem& d, int border) {
    const int wide = d.heights.nx / 10;
    std::string md =
        "\nHorizon angles (`terrain gi --out-horizons`, 16 azimuths) against the exact ones along the same "
        "azimuths, degrees (signed; -90 where no terrain lies in the direction), band of " +
        std::to_string(border) + " cells and of " + std::to_string(wide) +
        " cells (10 %) left out:\n\n"
        "| sub-sampling | band | RMSE | bias | max abs |\n|---|---|---|---|---|\n";
    gi::HorizonAngles exact;
    gi::referenceHorizonAngles(d.heights.cview(), d.cell, gi::scanAzimuths(16), exact);
    for (int s : {1, 2, 4}) {
        gi::GiSettings settings;
        settings.subsample = s;
        gi::GiState st;
        gi::runGiFrame(d.heights.cview(), d.cell, gi::GiLighting{}, settings, st);
        gi::HorizonAngles fast;
        gi::horizonAnglesFromScan(st.envVisibility, st.envOperator.phi, s, d.heights.nx, d.heights.ny, fast);
        gi::raiseHorizonAnglesToNearField(d.heights.cview(), d.cell, s, fast);
        for (int band : {border, wide}) {
            double sum = 0.0, sum2 = 0.0, worst = 0.0;
            for (std::size_t j = 0; j < exact.degrees.size(); ++j) {
                const ErrorStats e = errorOf(fast.degrees[j], exact.degrees[j], band);
                sum += e.bias;
                sum2 += e.rmse * e.rmse;
                worst = std::max(worst, e.maxAbs);
            }
            const double m = static_cast<double>(exact.degrees.size());
            char line[160];
            std::snprintf(line, sizeof line, "| %dx | %d | %.3f | %+.3f | %.2f |\n", s, band, std::sqrt(sum2 / m),
                          sum / m, worst);
            md += line;
        }
    }
    return md;
}

int runSvfSaga(const SvfSagaOptions& o, const BenchContext& ctx) {
    std::optional<ScratchDir> scratch;
    if (o.cacheDir.empty()) scratch.emplace();
    const std::string dir = scratch ? scratch->path() : o.cacheDir;
    std::filesystem::create_directories(dir);
    const Dem alps = loadAlps(ctx.dataDir);
    const std::string dem = writeDemGeoTiff(alps, dir);
    const SvfReferences ref = cachedReferences(alps, o.azimuths, dir);
    const bool haveSaga = std::system("command -v saga_cmd >/dev/null 2>&1") == 0;
    const std::string sagaVersion =
        haveSaga ? firstLineOf("saga_cmd --version 2>&1 | grep -i -m1 'version' | sed 's/.*[Vv]ersion:* */SAGA /'")
                 : "";
    std::vector<SvfRun> runs = engineRuns(o, dem, dir);
    if (haveSaga)
        for (SvfRun& r : sagaRuns(o, dem, dir)) runs.push_back(r);
    const std::string loadBefore = loadAverage();
    // alternate the tools run by run, so that a change of the machine's load falls on all of them
    std::vector<std::vector<double>> seconds(runs.size());
    for (int k = 0; k < o.runs; ++k)
        for (std::size_t i = 0; i < runs.size(); ++i) {
            std::fprintf(stderr, "svf-saga: run %d/%d: %s %s %s\n", k + 1, o.runs, runs[i].tool.c_str(),
                         runs[i].definition.c_str(), runs[i].settings.c_str());
            seconds[i].push_back(secondsOf(runs[i].command));
        }
    for (std::size_t i = 0; i < runs.size(); ++i) {
        runs[i].seconds = median(seconds[i]);
        runs[i].error =
            errorOf(readGeoTiffHeights(runs[i].output).heights, referenceOf(ref, runs[i].definition), o.border);
    }
    std::string csv;
    const std::string md = resultsText(o, ctx, runs, ref, sagaVersion, loadBefore, loadAverage(), csv) +
                           horizonAccuracyText(alps, o.border);
    writeResult(ctx.outDir, "svf_saga.md", md);
    writeResult(ctx.outDir, "svf_saga.csv", csv);
    return 0;
}

std::string besideThisProgram(const std::string& name) {
    std::error_code ec;
    const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", ec);
    return ec ? "build/" + name : (self.parent_path() / name).string();
}

}  // namespace

Runner addSvfSagaSuite(CLI::App& app, const BenchContext& ctx) {
    auto o = std::make_shared<SvfSagaOptions>();
    o->terrain = besideThisProgram("terrain");
    CLI::App* sub = app.add_subcommand(
        "svf-saga",
        "Sky-view factor on Mont Blanc: the engine (plain and normal-weighted, 1x/2x/4x) and SAGA's ta_lighting 3 "
        "(when saga_cmd is installed), time and error against exact references (svf_saga.md, .csv)");
    addRunsOption(*sub, o->runs, "Runs per tool and setting (median wall time)");
    sub->add_option("--azimuths", o->azimuths, "Azimuths of the exact references")->check(CLI::Range(2, 4096));
    sub->add_option("--border", o->border, "Cells left out at each border")->check(CLI::Range(0, 100));
    sub->add_option("--threads", o->threads, "Threads of both tools")->check(CLI::Range(1, 256));
    sub->add_option("--cache", o->cacheDir, "Folder to keep the references and outputs in across runs (default: none)");
    sub->add_option("--terrain", o->terrain, "The terrain executable")->capture_default_str();
    return [o, &ctx] { return runSvfSaga(*o, ctx); };
}

}  // namespace terrain::bench
