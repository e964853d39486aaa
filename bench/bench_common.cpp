#include "bench/bench_common.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <stdexcept>
#include <system_error>
#include <thread>
#include <utility>

#include <sys/utsname.h>
#include <sys/wait.h>
#include <unistd.h>

#include "core/error.h"
#include "core/file_io.h"
#include "core/png_io.h"
#include "sim/scene.h"

namespace terrain::bench {

ScratchDir::ScratchDir() {
    namespace fs = std::filesystem;
    std::random_device rd;
    for (int attempt = 0; attempt < 100; ++attempt) {
        char name[64];
        std::snprintf(name, sizeof name, "terrain_bench-%ld-%08x", static_cast<long>(getpid()), rd());
        const fs::path p = fs::temp_directory_path() / name;
        if (fs::create_directory(p)) {
            path_ = p.string();
            return;
        }
    }
    throw IoError(fs::temp_directory_path().string(), "cannot create a scratch folder there");
}

ScratchDir::~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
}

void writeResult(const std::string& outDir, const std::string& name, const std::string& text) {
    std::filesystem::create_directories(outDir);
    const std::string path = outDir + "/" + name;
    writeFileAtomic(path, text);
    std::fprintf(stderr, "wrote %s\n", path.c_str());
}

double median(std::vector<double> v) { return spreadOf(std::move(v)).median; }

namespace {
std::string cpuName() {
    std::ifstream f("/proc/cpuinfo");
    std::string line;
    while (std::getline(f, line))
        if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
    return "unknown CPU";
}
}  // namespace

std::string cpuAndThreads() {
    return cpuName() + ", " + std::to_string(std::thread::hardware_concurrency()) + " hardware threads";
}

std::string machineDescription() {
    utsname u{};
    uname(&u);
    return cpuAndThreads() + ", " + u.sysname + " " + u.release + "; " + buildDescription();
}

std::string loadAverage() {
    std::ifstream in("/proc/loadavg");
    std::string one, five;
    in >> one >> five;
    return one + " (1 min), " + five + " (5 min)";
}

std::string buildDescription() {
#ifdef TERRAIN_BUILD_DESCRIPTION
    return TERRAIN_BUILD_DESCRIPTION;
#else
    return "unknown build";
#endif
}

void drawPlot(const BenchContext& ctx, const std::string& script) {
#ifndef TERRAIN_PLOT_PYTHON
#define TERRAIN_PLOT_PYTHON ""
#endif
    const std::string python = TERRAIN_PLOT_PYTHON;
    const std::string path = std::string(TERRAIN_SOURCE_DIR) + "/bench/plots/" + script + ".py";
    if (python.empty())
        throw std::runtime_error("no Python 3 found when configuring; the CSV is written, the plot " + script +
                                 " is not (install python3-matplotlib and re-run cmake)");
    const pid_t pid = fork();
    if (pid < 0) throw std::runtime_error("cannot start " + python + " to draw the plot " + script);
    if (pid == 0) {
        const char* argv[] = {python.c_str(), path.c_str(), ctx.outDir.c_str(), nullptr};
        execv(argv[0], const_cast<char* const*>(argv));
        _exit(127);
    }
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {}
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
        throw std::runtime_error("the plot " + script + " was not drawn (" + python + " " + path +
                                 " failed; it needs python3-matplotlib); the CSV and Markdown are written");
}

Dem loadAlps(const std::string& dataDir) {
    Dem d;
    d.name = "alps-montblanc";
    d.heights = readPngHeightmap(dataDir + "/alps-montblanc.png", (4810.0f - 454.0f) / 65535.0f, 454.0f);
    d.cell = 60000.0f / 647.0f;
    return d;
}

Dem loadPerdu(const std::string& dataDir) {
    Dem d;
    d.name = "mtperdu_20m";
    d.heights = readPngHeightmap(dataDir + "/mtperdu_20m.png", 0.1f, 0.0f);
    d.cell = 20.0f;
    return d;
}

Dem boxDownsample(const Dem& d, int factor, const std::string& tag) {
    Dem out;
    out.name = d.name + "-" + tag;
    out.cell = d.cell * static_cast<float>(factor);
    out.heights = Grid(d.heights.nx / factor, d.heights.ny / factor);
    for (int y = 0; y < out.heights.ny; ++y)
        for (int x = 0; x < out.heights.nx; ++x) {
            double sum = 0.0;
            for (int j = 0; j < factor; ++j)
                for (int i = 0; i < factor; ++i) sum += d.heights(factor * x + i, factor * y + j);
            out.heights(x, y) = static_cast<float>(sum / (factor * factor));
        }
    return out;
}

Dem erodedScene(int size, int ticks) {
    Simulation sim(builtinScene("erosion", size, 1));
    for (int t = 0; t < ticks; ++t) sim.tick();
    Dem d;
    d.name = "erosion";
    d.note = "builtinScene(\"erosion\", " + std::to_string(size) + ", 1) after " + std::to_string(ticks) + " ticks";
    d.cell = sim.state().cellSize;
    sim.state().groundHeight(d.heights);
    return d;
}

Dem cropDem(const Dem& src, int size, const std::string& tag) {
    Dem d;
    d.name = src.name + "-" + tag;
    d.cell = src.cell;
    d.heights = centreCrop(src.heights, size);
    return d;
}

std::vector<Dem> realDems(const std::string& dataDir) {
    const Dem perdu = loadPerdu(dataDir);
    return {loadAlps(dataDir), cropDem(perdu, 512, "c512"), boxDownsample(perdu, 4, "80m"), erodedScene(256, 2000)};
}

Grid centreCrop(const Grid& g, int size) {
    Grid c(size, size);
    const int x0 = (g.nx - size) / 2, y0 = (g.ny - size) / 2;
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) c(x, y) = g(x0 + x, y0 + y);
    return c;
}

Grid alpsCentreCrop(const std::string& dataDir, int size, float& cell) {
    const Dem full = loadAlps(dataDir);
    cell = full.cell;
    return centreCrop(full.heights, size);
}

Dem alpsCrop(const std::string& dataDir, int size) {
    Dem d;
    d.name = "alps-montblanc";
    d.heights = alpsCentreCrop(dataDir, size, d.cell);
    char note[128];
    std::snprintf(note, sizeof note, "central %d^2 crop at true scale (cell %.2f m)", size, d.cell);
    d.note = note;
    return d;
}

gi::KeyLight benchKey() {
    gi::KeyLight k;
    k.azimuthDeg = 135.0f;
    k.elevationDeg = 35.0f;
    k.radiusDeg = 5.0f;
    k.rgb[0] = 1.2f;
    k.rgb[1] = 1.1f;
    k.rgb[2] = 1.0f;
    return k;
}

gi::GiLighting sunSkyAndBenchKey() {
    gi::GiLighting light;
    light.environment = gi::sunSkyLight();
    light.keys.push_back(benchKey());
    return light;
}

bool readCachedGrids(const std::string& file, int nx, int ny, std::span<Grid> grids) {
    std::ifstream in(file, std::ios::binary);
    for (Grid& g : grids) {
        g.resize(nx, ny);
        if (!in.read(reinterpret_cast<char*>(g.data()), static_cast<std::streamsize>(g.size() * sizeof(float))))
            return false;
    }
    return true;
}

void writeCachedGrids(const std::string& file, std::span<const Grid> grids) {
    std::ofstream out(file, std::ios::binary);
    for (const Grid& g : grids)
        out.write(reinterpret_cast<const char*>(g.data()), static_cast<std::streamsize>(g.size() * sizeof(float)));
}

double relRmse(const std::array<Grid, 3>& a, const std::array<Grid, 3>& b, double& bias) {
    const int bx = a[0].nx / 10, by = a[0].ny / 10;
    double se = 0.0, sr = 0.0, sd = 0.0;
    long n = 0;
    for (std::size_t c = 0; c < 3; ++c)
        for (int y = by; y < a[0].ny - by; ++y)
            for (int x = bx; x < a[0].nx - bx; ++x) {
                const double d = a[c](x, y) - b[c](x, y);
                se += d * d;
                sd += d;
                sr += static_cast<double>(b[c](x, y)) * b[c](x, y);
                ++n;
            }
    bias = sd / n / std::sqrt(sr / n);
    return std::sqrt(se / n) / std::sqrt(sr / n);
}

}  // namespace terrain::bench
