#include "bench/incremental_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "bench/plot_canvas.h"
#include "core/png_io.h"

namespace terrain::bench {

namespace {

// Axes: changed area from 0.01 % to 100 % (log), cost from 0 to 120 % of a full frame.
struct Axes {
    int w = 1000, h = 640, left = 110, right = 220, top = 60, bottom = 90;
    double x(double area) const { return left + (std::log10(area) + 4.0) / 4.0 * (w - left - right); }
    double y(double ratio) const { return h - bottom - ratio / 1.2 * (h - top - bottom); }
};

void drawAxes(const Axes& a, Canvas& c) {
    const std::uint8_t black[3] = {0, 0, 0}, grey[3] = {215, 215, 215};
    for (const double area : {1e-4, 1e-3, 1e-2, 1e-1, 1.0}) {
        c.line(a.x(area), a.top, a.x(area), a.h - a.bottom, grey);
        char b[32];
        std::snprintf(b, sizeof b, "%g%%", 100.0 * area);
        c.text(static_cast<int>(a.x(area)) - 18, a.h - a.bottom + 10, b, black);
    }
    for (int pct = 0; pct <= 120; pct += 20) {
        c.line(a.left, a.y(pct / 100.0), a.w - a.right, a.y(pct / 100.0), grey);
        c.text(a.left - 60, static_cast<int>(a.y(pct / 100.0)) - 7, std::to_string(pct) + "%", black);
    }
    c.line(a.left, a.top, a.left, a.h - a.bottom, black, 2);
    c.line(a.left, a.h - a.bottom, a.w - a.right, a.h - a.bottom, black, 2);
    c.text(a.left + 140, a.h - 40, "share of the cells changed (log scale)", black);
    c.text(20, 20, "incremental GI time / full frame", black);
}

}  // namespace

void incrementalCostPlot(const std::vector<CostPoint>& pts, const std::string& file) {
    const Axes a;
    Canvas c(a.w, a.h);
    drawAxes(a, c);
    std::vector<float> tolerances;
    for (const CostPoint& p : pts)
        if (std::find(tolerances.begin(), tolerances.end(), p.tolerance) == tolerances.end())
            tolerances.push_back(p.tolerance);
    const std::uint8_t colours[4][3] = {{200, 40, 40}, {40, 110, 200}, {30, 150, 60}, {150, 80, 170}};
    int legendY = a.top + 10;
    for (std::size_t k = 0; k < tolerances.size(); ++k) {
        const std::uint8_t* colour = colours[k % 4];
        std::vector<CostPoint> line;
        for (const CostPoint& p : pts)
            if (p.tolerance == tolerances[k]) line.push_back(p);
        std::sort(line.begin(), line.end(),
                  [](const CostPoint& l, const CostPoint& r) { return l.changedArea < r.changedArea; });
        for (std::size_t i = 0; i + 1 < line.size(); ++i)
            c.line(a.x(line[i].changedArea), a.y(line[i].costRatio), a.x(line[i + 1].changedArea),
                   a.y(line[i + 1].costRatio), colour, 3);
        for (const CostPoint& p : line) c.dot(a.x(p.changedArea), a.y(p.costRatio), 5, colour);
        char b[48];
        std::snprintf(b, sizeof b, "tolerance %g", static_cast<double>(tolerances[k]));
        c.dot(a.w - a.right + 26, legendY + 7, 5, colour);
        c.text(a.w - a.right + 40, legendY, b, colour);
        legendY += 24;
    }
    writePngRgb(file, a.w, a.h, c.px);
    std::fprintf(stderr, "wrote %s\n", file.c_str());
}

}  // namespace terrain::bench
