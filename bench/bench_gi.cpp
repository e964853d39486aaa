// bench_gi: accuracy of the GI fast path against the ground truth, convergence
// in m / k_v / o_v, and time per frame, on the real DEMs of ../shared/data.
//
//   bench_gi [accuracy] [convergence] [timing] [explore] [--data DIR] [--out DIR] [--runs N]
//
// Writes bench/results/gi_*.md and gi_*.csv (and gi_speed_vs_error.png).
// Ground truths are cached beside the build (gi_reference_*.bin) because they
// take minutes.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "gi/frame.h"
#include "gi/reference.h"
#include "sim/io.h"
#include "sim/parallel.h"

using namespace terrain;
using namespace terrain::gi;

namespace {

using Clock = std::chrono::steady_clock;

struct Dem {
    std::string name;
    Grid heights;
    float cell = 1.0f;
};

struct ErrorStats {
    double rmse = 0.0, bias = 0.0, maxAbs = 0.0;
    long count = 0;
};

std::string gDataDir = "/work/shared/data";
std::string gOutDir = "bench/results";
int gRuns = 5;

Dem loadAlps() {
    Dem d;
    d.name = "alps-montblanc";
    d.heights = readPngHeightmap(gDataDir + "/alps-montblanc.png", (4810.0f - 454.0f) / 65535.0f, 454.0f);
    d.cell = 60000.0f / 647.0f;
    return d;
}

Dem loadPerdu() {
    Dem d;
    d.name = "mtperdu_20m";
    d.heights = readPngHeightmap(gDataDir + "/mtperdu_20m.png", 0.1f, 0.0f);
    d.cell = 20.0f;
    return d;
}

Dem crop(const Dem& src, int size, const std::string& tag) {
    Dem d;
    d.name = src.name + "-" + tag;
    d.cell = src.cell;
    const int x0 = (src.heights.nx - size) / 2, y0 = (src.heights.ny - size) / 2;
    d.heights.resize(size, size);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) d.heights(x, y) = src.heights(x0 + x, y0 + y);
    return d;
}

// Reference ambient on the interior (10 % border left out), every `stride`-th texel, cached.
Grid referenceAmbient(const Dem& d, int stride, int border) {
    const char* cacheDir = std::getenv("GI_CACHE_DIR");
    const std::string cache = std::string(cacheDir ? cacheDir : "/tmp") + "/gi_reference_" + d.name + "_s" + std::to_string(stride) + "_b" +
                              std::to_string(border) + ".bin";
    Grid g(d.heights.nx, d.heights.ny);
    {
        std::ifstream in(cache, std::ios::binary);
        if (in && in.read(reinterpret_cast<char*>(g.data()), static_cast<std::streamsize>(g.size() * sizeof(float)))) return g;
    }
    std::fprintf(stderr, "reference for %s (stride %d) ...\n", d.name.c_str(), stride);
    const auto t0 = Clock::now();
    ReferenceSettings rs;
    rs.azimuths = 256;
    rs.border = border;
    rs.stride = stride;
    rs.progress = true;
    ReferenceResult rr;
    renderReference(d.heights.cview(), d.cell, nullptr, nullptr, rs, rr);
    std::fprintf(stderr, "reference: %.1f s\n", std::chrono::duration<double>(Clock::now() - t0).count());
    std::ofstream out(cache, std::ios::binary);
    out.write(reinterpret_cast<const char*>(rr.ambient.data()), static_cast<std::streamsize>(rr.ambient.size() * sizeof(float)));
    return rr.ambient;
}

ErrorStats compare(const Grid& fast, const Grid& ref, int stride, int border) {
    ErrorStats e;
    double s2 = 0.0, s1 = 0.0;
    for (int y = border; y < ref.ny - border; y += stride)
        for (int x = border; x < ref.nx - border; x += stride) {
            const double d = static_cast<double>(fast(x, y)) - ref(x, y);
            s2 += d * d;
            s1 += d;
            e.maxAbs = std::max(e.maxAbs, std::abs(d));
            ++e.count;
        }
    e.rmse = std::sqrt(s2 / std::max(e.count, 1L));
    e.bias = s1 / std::max(e.count, 1L);
    return e;
}

struct Timing {
    double median = 0.0, pyramid = 0.0, visibility = 0.0, key = 0.0, shading = 0.0;
};

// Median over gRuns frames after one warm-up frame.
Timing timeFrames(const Dem& d, const GiSettings& s, const GiLighting& light, GiState& st, int runs) {
    runGiFrame(d.heights.cview(), d.cell, light, s, st);
    std::vector<double> tot, pyr, vis, key, sh;
    for (int r = 0; r < runs; ++r) {
        runGiFrame(d.heights.cview(), d.cell, light, s, st);
        tot.push_back(st.timings.total);
        pyr.push_back(st.timings.pyramid + st.timings.gradient);
        vis.push_back(st.timings.visibility);
        key.push_back(st.timings.keyVisibility);
        sh.push_back(st.timings.shading);
    }
    // median, or with GI_MIN set the minimum (robust to a busy machine while developing)
    const bool useMin = std::getenv("GI_MIN") != nullptr;
    auto med = [useMin](std::vector<double> v) {
        std::sort(v.begin(), v.end());
        return useMin ? v.front() : v[v.size() / 2];
    };
    return {med(tot), med(pyr), med(vis), med(key), med(sh)};
}

std::string settingsName(const GiSettings& s) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "m=%d k_v=%d o_v=%d %s %s peak=%.2f %dx", s.visibility.azimuths, s.pyramid.levelsPerOctave,
                  s.pyramid.levelOffset, s.visibility.interp == AzimuthInterp::Linear ? "linear" : "bspline",
                  s.visibility.blockingMax == BlockingMax::Samples ? "max=samples" : "max=bspline", s.pyramid.peakBlend,
                  s.subsample);
    return buf;
}

GiSettings paperSettings() { return GiSettings{}; }

GiSettings engineDefaults() { return engineGiSettings(); }

void writeFile(const std::string& name, const std::string& text) {
    const std::string path = gOutDir + "/" + name;
    writeFileAtomic(path, text);
    std::fprintf(stderr, "wrote %s\n", path.c_str());
}

std::string machine() {
    std::string cpu = "unknown CPU";
    std::ifstream in("/proc/cpuinfo");
    std::string line;
    while (std::getline(in, line))
        if (line.rfind("model name", 0) == 0) {
            cpu = line.substr(line.find(':') + 2);
            break;
        }
    return cpu + ", " + std::to_string(std::thread::hardware_concurrency()) + " hardware threads";
}

// ---------------------------------------------------------------------------
// accuracy: paper settings vs engine defaults on alps at true scale
// ---------------------------------------------------------------------------
struct Row {
    std::string label;
    GiSettings s;
    ErrorStats e;
    Timing t;
};

// quick: alps ambient error of the engine defaults and paper settings at 1x/2x/4x (for trying changes)
void quickAccuracy() {
    const Dem alps = loadAlps();
    const int border = alps.heights.nx / 10;
    const Grid ref = referenceAmbient(alps, 1, border);
    for (const char* which : {"paper", "engine"})
        for (int s : {1, 2, 4}) {
            GiSettings set = std::string(which) == "paper" ? GiSettings{} : engineGiSettings();
            set.subsample = s;
            GiState st;
            withThreads(2, [&] {
                runGiFrame(alps.heights.cview(), alps.cell, GiLighting{}, set, st);
                return 0;
            });
            const ErrorStats e = compare(st.shade.ambient, ref, 1, border);
            std::printf("%-6s %dx: rmse %.5f bias %+.5f max %.4f\n", which, s, e.rmse, e.bias, e.maxAbs);
        }
}

void runSettingsRows(const Dem& d, const Grid& ref, int border, std::vector<Row>& rows, int threads) {
    for (Row& r : rows) {
        GiState st;
        withThreads(threads, [&] {
            r.t = timeFrames(d, r.s, GiLighting{}, st, gRuns);
            return 0;
        });
        r.e = compare(st.shade.ambient, ref, 1, border);
        std::fprintf(stderr, "%-60s rmse %.4f bias %+.4f max %.3f  %.1f ms\n", (r.label + " " + settingsName(r.s)).c_str(),
                     r.e.rmse, r.e.bias, r.e.maxAbs, r.t.median);
    }
}

void accuracy() {
    const Dem alps = loadAlps();
    const int border = alps.heights.nx / 10;
    const Grid ref = referenceAmbient(alps, 1, border);
    std::vector<Row> rows;
    rows.push_back({"paper settings", paperSettings(), {}, {}});
    rows.push_back({"engine defaults", engineDefaults(), {}, {}});
    runSettingsRows(alps, ref, border, rows, 2);
    std::string md = "# GI ambient accuracy on alps-montblanc (true scale)\n\n";
    md += "DEM: ../shared/data/alps-montblanc.png, 647 x 647, cell 92.74 m, heights 454..4810 m. ";
    md += "Interior only: a 64-texel (10 %) border is left out (" + std::to_string(rows[0].e.count) + " texels). ";
    md += "Ground truth: gi/reference (256 azimuths, exact march of the bilinear field, exact elevation integrals). ";
    md += "Ambient = direct irradiance / pi under a uniform unit sky (normal-weighted sky-view factor). ";
    md += "Time: whole frame (gradient, pyramid, visibility, shading; uniform sky, no key light) with 2 threads, median of " +
          std::to_string(gRuns) + " after a warm-up. Machine: " + machine() + ".\n\n";
    md += "| settings | RMSE | bias | max abs | ms/frame |\n|---|---|---|---|---|\n";
    std::string csv = "label,azimuths,levels_per_octave,level_offset,interp,blocking_max,peak_blend,subsample,rmse,bias,max_abs,ms\n";
    for (const Row& r : rows) {
        char buf[512];
        std::snprintf(buf, sizeof buf, "| %s: %s | %.4f | %+.4f | %.3f | %.1f |\n", r.label.c_str(), settingsName(r.s).c_str(),
                      r.e.rmse, r.e.bias, r.e.maxAbs, r.t.median);
        md += buf;
        std::snprintf(buf, sizeof buf, "%s,%d,%d,%d,%s,%s,%.2f,%d,%.5f,%.5f,%.4f,%.2f\n", r.label.c_str(), r.s.visibility.azimuths,
                      r.s.pyramid.levelsPerOctave, r.s.pyramid.levelOffset,
                      r.s.visibility.interp == AzimuthInterp::Linear ? "linear" : "bspline",
                      r.s.visibility.blockingMax == BlockingMax::Samples ? "samples" : "bspline", r.s.pyramid.peakBlend,
                      r.s.subsample, r.e.rmse, r.e.bias, r.e.maxAbs, r.t.median);
        csv += buf;
    }
    writeFile("gi_accuracy.md", md);
    writeFile("gi_accuracy.csv", csv);
}

// ---------------------------------------------------------------------------
// explore: many settings (used to choose the defaults)
// ---------------------------------------------------------------------------
void explore() {
    const Dem alps = loadAlps();
    const int border = alps.heights.nx / 10;
    const Grid ref = referenceAmbient(alps, 1, border);
    std::vector<Row> rows;
    for (int o : {2, 3, 4})
        for (float peak : {0.0f, 0.25f, 0.5f})
            for (BlockingMax bm : {BlockingMax::BsplineKnotsAndMidpoints, BlockingMax::Samples}) {
                GiSettings s;
                s.pyramid.levelOffset = o;
                s.pyramid.peakBlend = peak;
                s.visibility.blockingMax = bm;
                rows.push_back({"explore", s, {}, {}});
            }
    for (AzimuthInterp ip : {AzimuthInterp::Linear, AzimuthInterp::Bspline})
        for (int m : {24, 32, 48}) {
            GiSettings s = engineDefaults();
            s.visibility.interp = ip;
            s.visibility.azimuths = m;
            rows.push_back({"explore", s, {}, {}});
        }
    runSettingsRows(alps, ref, border, rows, 2);
    std::string csv = "azimuths,levels_per_octave,level_offset,interp,blocking_max,peak_blend,subsample,rmse,bias,max_abs,ms\n";
    for (const Row& r : rows) {
        char buf[256];
        std::snprintf(buf, sizeof buf, "%d,%d,%d,%s,%s,%.2f,%d,%.5f,%.5f,%.4f,%.2f\n", r.s.visibility.azimuths,
                      r.s.pyramid.levelsPerOctave, r.s.pyramid.levelOffset,
                      r.s.visibility.interp == AzimuthInterp::Linear ? "linear" : "bspline",
                      r.s.visibility.blockingMax == BlockingMax::Samples ? "samples" : "bspline", r.s.pyramid.peakBlend,
                      r.s.subsample, r.e.rmse, r.e.bias, r.e.maxAbs, r.t.median);
        csv += buf;
    }
    writeFile("gi_explore.csv", csv);
}

// ---------------------------------------------------------------------------
// convergence: error vs m, k_v, o_v
// ---------------------------------------------------------------------------
void convergence() {
    const Dem alps = loadAlps();
    const int border = alps.heights.nx / 10;
    const Grid ref = referenceAmbient(alps, 1, border);
    std::vector<Row> rows;
    auto base = [] {
        GiSettings s;
        s.visibility.blockingMax = BlockingMax::Samples;
        return s;
    };
    for (int m : {8, 16, 32, 64, 128}) {
        GiSettings s = base();
        s.visibility.azimuths = m;
        s.pyramid.levelsPerOctave = 8;
        s.pyramid.levelOffset = 6;
        rows.push_back({"vary m (k_v=8, o_v=6)", s, {}, {}});
    }
    for (int k : {1, 2, 4, 8, 16}) {
        GiSettings s = base();
        s.visibility.azimuths = 128;
        s.pyramid.levelsPerOctave = k;
        s.pyramid.levelOffset = 6;
        rows.push_back({"vary k_v (m=128, o_v=6)", s, {}, {}});
    }
    for (int o : {0, 1, 2, 3, 4, 6}) {
        GiSettings s = base();
        s.visibility.azimuths = 128;
        s.pyramid.levelsPerOctave = 8;
        s.pyramid.levelOffset = o;
        rows.push_back({"vary o_v (m=128, k_v=8)", s, {}, {}});
    }
    const int savedRuns = gRuns;
    gRuns = 1;
    runSettingsRows(alps, ref, border, rows, 2);
    gRuns = savedRuns;
    std::string md = "# GI convergence to the ground truth (alps-montblanc, true scale, interior)\n\n";
    md += "Ambient RMSE / bias against gi/reference (256 azimuths). The plain sample maximum is used (the B-spline "
          "maximum of Eq. 16 smooths the blocking-angle sequence and does not converge to the exact horizon). "
          "The remaining floor is the order-4 SH truncation of visibility. Times: 2 threads, one frame.\n\n";
    md += "| sweep | settings | RMSE | bias | ms/frame |\n|---|---|---|---|---|\n";
    std::string csv = "sweep,azimuths,levels_per_octave,level_offset,rmse,bias,ms\n";
    for (const Row& r : rows) {
        char buf[400];
        std::snprintf(buf, sizeof buf, "| %s | %s | %.4f | %+.4f | %.1f |\n", r.label.c_str(), settingsName(r.s).c_str(), r.e.rmse,
                      r.e.bias, r.t.median);
        md += buf;
        std::snprintf(buf, sizeof buf, "%s,%d,%d,%d,%.5f,%.5f,%.2f\n", r.label.c_str(), r.s.visibility.azimuths,
                      r.s.pyramid.levelsPerOctave, r.s.pyramid.levelOffset, r.e.rmse, r.e.bias, r.t.median);
        csv += buf;
    }
    writeFile("gi_convergence.md", md);
    writeFile("gi_convergence.csv", csv);
}

// ---------------------------------------------------------------------------
// timing: 256^2, 512^2, 1024^2 x 1x/2x/4x x 1/2 threads, one env + one key light
// ---------------------------------------------------------------------------
void timing() {
    const Dem alps = loadAlps();
    const Dem perdu = loadPerdu();
    struct Size { Dem dem; std::string source; };
    std::vector<Size> sizes;
    sizes.push_back({crop(alps, 256, "c256"), "alps-montblanc centre crop 256 x 256 (cell 92.74 m)"});
    sizes.push_back({crop(alps, 512, "c512"), "alps-montblanc centre crop 512 x 512 (cell 92.74 m)"});
    sizes.push_back({crop(perdu, 1024, "c1024"), "mtperdu_20m centre crop 1024 x 1024 (cell 20 m)"});
    GiLighting light;
    light.environment = sunSkyLight();
    KeyLight key;
    key.azimuthDeg = 135.0f;
    key.elevationDeg = 30.0f;
    key.radiusDeg = 4.0f;
    light.keys.push_back(key);
    std::string md = "# GI time per frame\n\n";
    md += "Frame = gradient + pyramid + environment visibility + key-light visibility + direct shading (Lambert, RGB), "
          "one sun-and-sky environment light (m azimuths) and one key light (3 azimuths). Median of " +
          std::to_string(gRuns) + " frames after a warm-up. Machine: " + machine() +
          ". Error: ambient RMSE / bias against gi/reference (256 azimuths) over the interior (10 % border left out), "
          "every 4th texel in x and y for 1024^2.\n\n";
    md += "| DEM | size | subsample | settings | threads | ms/frame | pyramid | visibility | key light | shading | RMSE | bias |\n";
    md += "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    std::string csv = "dem,size,subsample,settings,threads,ms,pyramid_ms,visibility_ms,key_ms,shading_ms,rmse,bias\n";
    for (const Size& sz : sizes) {
        const int n = sz.dem.heights.nx;
        const int border = n / 10;
        const int stride = n >= 1024 ? 4 : 1;
        const Grid ref = referenceAmbient(sz.dem, stride, border);
        for (const char* which : {"paper", "engine"})
            for (int s : {1, 2, 4})
                for (int threads : {1, 2}) {
                    GiSettings set = std::string(which) == "paper" ? paperSettings() : engineDefaults();
                    set.subsample = s;
                    GiState st;
                    Timing t;
                    withThreads(threads, [&] {
                        t = timeFrames(sz.dem, set, light, st, gRuns);
                        return 0;
                    });
                    const ErrorStats e = compare(st.shade.ambient, ref, stride, border);
                    char buf[600];
                    std::snprintf(buf, sizeof buf, "| %s | %d | %dx | %s | %d | %.1f | %.1f | %.1f | %.1f | %.1f | %.4f | %+.4f |\n",
                                  sz.source.c_str(), n, s, which, threads, t.median, t.pyramid, t.visibility, t.key, t.shading,
                                  e.rmse, e.bias);
                    md += buf;
                    std::snprintf(buf, sizeof buf, "%s,%d,%d,%s,%d,%.2f,%.2f,%.2f,%.2f,%.2f,%.5f,%.5f\n", sz.dem.name.c_str(), n, s,
                                  which, threads, t.median, t.pyramid, t.visibility, t.key, t.shading, e.rmse, e.bias);
                    csv += buf;
                    std::fprintf(stderr, "%s %d %dx %s %dT: %.1f ms (rmse %.4f)\n", sz.dem.name.c_str(), n, s, which, threads,
                                 t.median, e.rmse);
                }
    }
    writeFile("gi_timing.md", md);
    writeFile("gi_timing.csv", csv);
}

// ---------------------------------------------------------------------------
// stages: per-stage times of the target frames (quick check while optimising)
// ---------------------------------------------------------------------------
void stages() {
    const Dem alps = loadAlps();
    GiLighting light;
    light.environment = sunSkyLight();
    KeyLight key;
    key.azimuthDeg = 135.0f;
    key.elevationDeg = 30.0f;
    key.radiusDeg = 4.0f;
    light.keys.push_back(key);
    struct Case { const Dem* dem; int s; const char* which; };
    const Dem c512 = crop(alps, 512, "c512");
    for (const Case& c : {Case{&c512, 2, "engine"}, Case{&c512, 2, "paper"}, Case{&alps, 1, "engine"}, Case{&alps, 1, "paper"}}) {
        GiSettings set = std::string(c.which) == "paper" ? paperSettings() : engineDefaults();
        set.subsample = c.s;
        GiState st;
        Timing t;
        const int threads = std::getenv("GI_THREADS") ? std::atoi(std::getenv("GI_THREADS")) : 2;
        timespec c0{}, c1{};
        withThreads(threads, [&] {
            t = timeFrames(*c.dem, set, light, st, gRuns);
            clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c0);
            runGiFrame(c.dem->heights.cview(), c.dem->cell, light, set, st);
            clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c1);
            return 0;
        });
        const double cpu = (c1.tv_sec - c0.tv_sec) * 1e3 + (c1.tv_nsec - c0.tv_nsec) * 1e-6;
        std::printf("%-22s %dx %-6s %dT: %6.1f ms, cpu %6.1f ms (pyramid+grad %.1f, visibility %.1f, key %.1f, shading %.1f)\n",
                    c.dem->name.c_str(), c.s, c.which, threads, t.median, cpu, t.pyramid, t.visibility, t.key, t.shading);
        // GI_DUMP=write stores the outputs, GI_DUMP=compare reports the largest change against them
        if (const char* dump = std::getenv("GI_DUMP")) {
            const std::string file = "/tmp/gi_stage_" + c.dem->name + "_" + std::to_string(c.s) + c.which + ".bin";
            std::vector<const Grid*> grids = {&st.shade.ambient, &st.shade.rgb[0], &st.shade.rgb[1], &st.shade.rgb[2]};
            if (std::string(dump) == "write") {
                std::ofstream out(file, std::ios::binary);
                for (const Grid* g : grids) out.write(reinterpret_cast<const char*>(g->data()), static_cast<std::streamsize>(g->size() * 4));
            } else {
                std::ifstream in(file, std::ios::binary);
                double maxd[4] = {}, sumd[4] = {};
                for (int k = 0; k < 4; ++k) {
                    std::vector<float> old(grids[static_cast<std::size_t>(k)]->size());
                    in.read(reinterpret_cast<char*>(old.data()), static_cast<std::streamsize>(old.size() * 4));
                    for (std::size_t i = 0; i < old.size(); ++i) {
                        const double d = std::abs(static_cast<double>(grids[static_cast<std::size_t>(k)]->v[i]) - old[i]);
                        maxd[k] = std::max(maxd[k], d);
                        sumd[k] += d;
                    }
                    sumd[k] /= static_cast<double>(old.size());
                }
                std::printf("    vs stored: ambient max %.3g mean %.3g; rgb max %.3g %.3g %.3g\n", maxd[0], sumd[0], maxd[1], maxd[2], maxd[3]);
            }
        }
    }
}

// ---------------------------------------------------------------------------
// cpu: CPU time per stage, one thread, minimum over runs (robust on a busy machine)
// ---------------------------------------------------------------------------
double threadCpuMs() {
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
}

void cpuStages() {
    const Dem alps = loadAlps();
    const Dem c512 = crop(alps, 512, "c512");
    GiLighting light;
    light.environment = sunSkyLight();
    KeyLight key;
    key.azimuthDeg = 135.0f;
    key.elevationDeg = 30.0f;
    key.radiusDeg = 4.0f;
    light.keys.push_back(key);
    struct Case { const Dem* dem; int s; const char* which; };
    for (const Case& c : {Case{&c512, 2, "engine"}, Case{&c512, 2, "paper"}, Case{&alps, 1, "engine"}}) {
        GiSettings set = std::string(c.which) == "paper" ? paperSettings() : engineDefaults();
        set.subsample = c.s;
        withThreads(1, [&] {
            GiState st;
            runGiFrame(c.dem->heights.cview(), c.dem->cell, light, set, st);
            double best[5] = {1e30, 1e30, 1e30, 1e30, 1e30};
            for (int r = 0; r < gRuns; ++r) {
                double t0 = threadCpuMs();
                computeGradient(c.dem->heights.cview(), c.dem->cell, st.gradX, st.gradY);
                buildHeightPyramid(c.dem->heights.cview(), c.dem->cell, set.subsample, set.pyramid, st.pyramid);
                double t1 = threadCpuMs();
                VisibilityTarget env;
                env.op = &st.envOperator;
                computeVisibility(st.pyramid, st.gradX.cview(), st.gradY.cview(), set.visibility, env, st.visibilityState, st.envVisibility);
                double t2 = threadCpuMs();
                runGiFrame(c.dem->heights.cview(), c.dem->cell, light, set, st);
                double t3 = threadCpuMs();
                best[0] = std::min(best[0], t1 - t0);
                best[1] = std::min(best[1], t2 - t1);
                best[2] = std::min(best[2], t3 - t2);
                best[3] = std::min(best[3], st.timings.keyVisibility);
                best[4] = std::min(best[4], st.timings.shading);
            }
            std::printf("%-22s %dx %-6s cpu: grad+pyramid %.1f  env visibility %.1f  frame %.1f  (wall key %.1f shading %.1f)\n",
                        c.dem->name.c_str(), c.s, c.which, best[0], best[1], best[2], best[3], best[4]);
            return 0;
        });
    }
}

}  // namespace

int main(int argc, char** argv) {
    std::vector<std::string> modes;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--data" && i + 1 < argc) gDataDir = argv[++i];
        else if (a == "--out" && i + 1 < argc) gOutDir = argv[++i];
        else if (a == "--runs" && i + 1 < argc) gRuns = std::max(1, std::atoi(argv[++i]));
        else modes.push_back(a);
    }
    if (modes.empty()) modes = {"accuracy", "convergence", "timing"};
    try {
        for (const std::string& m : modes) {
            if (m == "accuracy") accuracy();
            else if (m == "convergence") convergence();
            else if (m == "timing") timing();
            else if (m == "explore") explore();
            else if (m == "stages") stages();
            else if (m == "quick") quickAccuracy();
            else if (m == "cpu") cpuStages();
            else {
                std::fprintf(stderr, "bench_gi: unknown mode %s\n", m.c_str());
                return 2;
            }
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bench_gi: error: %s\n", e.what());
        return 1;
    }
    return 0;
}
