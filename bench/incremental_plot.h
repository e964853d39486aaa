#pragma once
// The plot of `terrain_bench gi-incremental` (gi_incremental_cost.png): GI
// time of an incremental frame over a full frame's against the share of the
// surface that changed, one line per tolerance.
#include <string>
#include <vector>

namespace terrain::bench {

/// One measured change: its area share, its tolerance and the time ratio.
struct CostPoint {
    double changedArea;  // fraction of the cells whose height changed, (0, 1]
    float tolerance;
    double costRatio;  // incremental GI ms / full GI ms
};

/// Draws the points (log area axis, one polyline per tolerance) and writes the PNG to file.
void incrementalCostPlot(const std::vector<CostPoint>& pts, const std::string& file);

}  // namespace terrain::bench
