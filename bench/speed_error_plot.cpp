// The plot is rasterised on a Canvas (bench/plot_canvas.h): no plotting library.
#include "bench/speed_error_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>

#include "bench/plot_canvas.h"
#include "core/png_io.h"

namespace terrain::bench {

void speedErrorPlot(const std::vector<PlotPoint>& pts, const std::string& file) {
    const int W = 1000, H = 680, left = 110, right = 250, top = 60, bottom = 90;
    Canvas c(W, H);
    const std::uint8_t black[3] = {0, 0, 0}, grey[3] = {215, 215, 215};
    double msLo = 1e30, msHi = 0.0, eHi = 0.0;
    for (const PlotPoint& p : pts)
        if (p.threads == 2) {
            msLo = std::min(msLo, p.ms);
            msHi = std::max(msHi, p.ms);
            eHi = std::max(eHi, p.rmse);
        }
    const double lx0 = std::floor(std::log10(msLo)), lx1 = std::ceil(std::log10(msHi));
    const double eTop = std::ceil(eHi / 0.01) * 0.01;
    auto X = [&](double ms) { return left + (std::log10(ms) - lx0) / (lx1 - lx0) * (W - left - right); };
    auto Y = [&](double e) { return H - bottom - e / eTop * (H - top - bottom); };
    // grid and axes
    for (double d = lx0; d <= lx1 + 1e-9; d += 1.0)
        for (int k = 1; k < 10; ++k) {
            const double v = std::pow(10.0, d) * k;
            if (std::log10(v) > lx1 + 1e-9) break;
            c.line(X(v), top, X(v), H - bottom, grey);
            if (k == 1 || (lx1 - lx0 <= 3.0 ? (k == 2 || k == 5) : k == 3)) {  // sparser labels over many decades
                char b[32];
                std::snprintf(b, sizeof b, "%g", v);
                c.text(static_cast<int>(X(v)) - 6 * static_cast<int>(std::string(b).size()), H - bottom + 10, b, black);
            }
        }
    for (double e = 0.0; e <= eTop + 1e-9; e += 0.005) {
        c.line(left, Y(e), W - right, Y(e), grey);
        char b[32];
        std::snprintf(b, sizeof b, "%.3f", e);
        c.text(left - 80, static_cast<int>(Y(e)) - 7, b, black);
    }
    c.line(left, top, left, H - bottom, black, 2);
    c.line(left, H - bottom, W - right, H - bottom, black, 2);
    c.text(left + 120, H - 40, "ms per frame (2 threads, log scale)", black);
    c.text(20, 20, "ambient RMSE vs ground truth", black);
    c.text(left + 330, 20, "GI frame: speed vs error", black);
    // one polyline per (size, settings) through 4x -> 2x -> 1x; 15 ms target line
    const std::uint8_t colours[3][3] = {{200, 40, 40}, {40, 110, 200}, {30, 150, 60}};
    const int sizes[3] = {256, 512, 1024};
    const std::uint8_t target[3] = {150, 150, 150};
    c.line(X(15.0), top, X(15.0), H - bottom, target, 1);
    c.text(static_cast<int>(X(15.0)) + 4, top + 4, "15 ms target", target);
    int legendY = top + 10;
    for (int si = 0; si < 3; ++si)
        for (const char* which : {"paper", "engine"}) {
            std::vector<const PlotPoint*> line;
            for (int sub : {4, 2, 1})
                for (const PlotPoint& p : pts)
                    if (p.threads == 2 && p.size == sizes[si] && p.settings == which && p.subsample == sub)
                        line.push_back(&p);
            const bool paper = std::string(which) == "paper";
            for (std::size_t i = 0; i + 1 < line.size(); ++i)
                c.line(X(line[i]->ms), Y(line[i]->rmse), X(line[i + 1]->ms), Y(line[i + 1]->rmse), colours[si],
                       paper ? 1 : 3);
            for (const PlotPoint* p : line) {
                if (paper)
                    c.square(X(p->ms), Y(p->rmse), 4, colours[si]);
                else
                    c.dot(X(p->ms), Y(p->rmse), 5, colours[si]);
                char b[8];
                std::snprintf(b, sizeof b, "%dx", p->subsample);
                c.text(static_cast<int>(X(p->ms)) + 7, static_cast<int>(Y(p->rmse)) - 16, b, colours[si]);
            }
            const int lx = W - right + 20;
            if (paper)
                c.square(lx + 6, legendY + 7, 4, colours[si]);
            else
                c.dot(lx + 6, legendY + 7, 5, colours[si]);
            c.text(lx + 20, legendY, std::to_string(sizes[si]) + "^2 " + which, colours[si]);
            legendY += 24;
        }
    c.text(W - right + 20, legendY + 10, "squares: paper", black);
    c.text(W - right + 20, legendY + 34, "dots: engine", black);
    writePngRgb(file, W, H, c.px);
    std::fprintf(stderr, "wrote %s\n", file.c_str());
}

}  // namespace terrain::bench
