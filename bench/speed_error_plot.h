#pragma once
// The speed-vs-error plot of `terrain_bench gi timing` (gi_speed_error.png):
// ambient RMSE against ms per frame, one line per size and settings through
// 4x -> 2x -> 1x sub-sampling.
#include <string>
#include <vector>

namespace terrain::bench {

/// One row of gi_timing.csv.
struct PlotPoint {
    int size, subsample, threads;
    std::string settings;  // "paper" or "engine"
    double ms, rmse;
};

/// Draws the 2-thread points of pts and writes the PNG to file.
void speedErrorPlot(const std::vector<PlotPoint>& pts, const std::string& file);

}  // namespace terrain::bench
