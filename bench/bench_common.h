#pragma once
// Helpers shared by the suites of build/terrain_bench: where the DEMs and the
// results live, a scratch folder, the machine description every results file
// starts with, medians, the real DEMs at true scale and relative errors.
#include <array>
#include <cstdio>
#include <span>
#include <string>
#include <vector>

#include "bench/spread.h"
#include "core/grid.h"
#include "gi/lights.h"
#include "gi/settings.h"

namespace terrain::bench {

/// What every suite takes from the command line.
struct BenchContext {
    std::string dataDir;  // the real DEMs (alps-montblanc.png, mtperdu_20m.png)
    std::string outDir;   // results files (bench/results of the source tree by default)
    std::string command;  // "build/terrain_bench <arguments>", as results files quote it
};

/// A fresh folder under the system's temporary directory, removed with
/// everything in it when the object goes.
class ScratchDir {
public:
    ScratchDir();
    ~ScratchDir();
    ScratchDir(const ScratchDir&) = delete;
    ScratchDir& operator=(const ScratchDir&) = delete;
    const std::string& path() const { return path_; }

private:
    std::string path_;
};

/// Writes outDir/name atomically (creating outDir) and says so on stderr.
void writeResult(const std::string& outDir, const std::string& name, const std::string& text);

/// printf into a string of any length.
template <class... Args>
std::string fmt(const char* format, Args... args) {
    std::string out(static_cast<std::size_t>(std::snprintf(nullptr, 0, format, args...)), '\0');
    std::snprintf(out.data(), out.size() + 1, format, args...);
    return out;
}

/// Median (spreadOf's): the mean of the two middle values for an even count, 0 for none.
double median(std::vector<double> v);

/// "<cpu>, <n> hardware threads".
std::string cpuAndThreads();

/// "<cpu>, <n> hardware threads, <kernel>; <build>": the machine line of a results file.
std::string machineDescription();

/// "<1 min> (1 min), <5 min> (5 min)" from /proc/loadavg: how busy the
/// machine was around a timing (other work shares the cores).
std::string loadAverage();

/// "<compiler> <version>, <build type> (<flags>)".
std::string buildDescription();

/// Draws a plot from the CSV files in ctx.outDir: runs
/// bench/plots/<script>.py <outDir> with the configured Python (matplotlib),
/// which writes <name>.png and <name>.svg there. Throws with one line when
/// the interpreter or matplotlib is missing or the script fails.
void drawPlot(const BenchContext& ctx, const std::string& script);

/// A height field at true scale: heights and cell size in metres.
struct Dem {
    std::string name, note;
    Grid heights;
    float cell = 1.0f;
};

/// alps-montblanc.png at true scale: 647^2, cell 60000 / 647 m, heights 454 + v (4810 - 454) / 65535.
Dem loadAlps(const std::string& dataDir);

/// mtperdu_20m.png at true scale: cell 20 m, heights v / 10.
Dem loadPerdu(const std::string& dataDir);

/// The central size^2 texels of g.
Grid centreCrop(const Grid& g, int size);

/// The central size^2 texels of a DEM, named name + "-" + tag.
Dem cropDem(const Dem& src, int size, const std::string& tag);

/// Every real DEM the ambient and sky accuracy are measured on: Mont Blanc,
/// a 512^2 crop of Mont Perdu at 20 m, Mont Perdu downsampled to 80 m, and
/// an `erosion` frame (256^2 after 2000 ticks).
std::vector<Dem> realDems(const std::string& dataDir);

/// The mean of each factor x factor block (the last partial blocks left out):
/// the DEM at factor times its cell size, named name + "-" + tag.
Dem boxDownsample(const Dem& d, int factor, const std::string& tag);

/// The ground of builtinScene("erosion", size, 1) after `ticks` ticks (name "erosion").
Dem erodedScene(int size, int ticks);

/// The central size^2 crop of alps-montblanc at true scale; sets cell.
Grid alpsCentreCrop(const std::string& dataDir, int size, float& cell);

/// alpsCentreCrop as a Dem named "alps-montblanc", its note saying so.
Dem alpsCrop(const std::string& dataDir, int size);

/// The key light of the indirect-light suites: a warm sun cap (az 135, el 35, r 5 deg).
gi::KeyLight benchKey();

/// The indirect-light suites' lighting: sun-and-sky environment (as SH) + benchKey().
gi::GiLighting sunSkyAndBenchKey();

/// Grids cached in a file across runs (a reference that takes minutes):
/// read them when `file` holds that many nx x ny grids, else false.
bool readCachedGrids(const std::string& file, int nx, int ny, std::span<Grid> grids);
void writeCachedGrids(const std::string& file, std::span<const Grid> grids);

/// Relative RMSE of a against b over the interior (10 % border left out), all
/// three channels; bias = mean difference / RMS of b.
double relRmse(const std::array<Grid, 3>& a, const std::array<Grid, 3>& b, double& bias);

/// The settings with incremental frames off: the timing suites light the same
/// field frame after frame and time whole frames (a static field would
/// otherwise do no work after the first; gi-incremental measures that).
inline gi::GiSettings wholeFrames(gi::GiSettings s) {
    s.incremental = false;
    return s;
}

}  // namespace terrain::bench
