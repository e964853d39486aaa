// The plot is rasterised here (lines, points, axes, a 5x7 font): no plotting library.
#include "bench/speed_error_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>

#include "core/png_io.h"

namespace terrain::bench {
namespace {

struct Canvas {
    int w, h;
    std::vector<std::uint8_t> px;
    Canvas(int width, int height) : w(width), h(height), px(static_cast<std::size_t>(width) * height * 3, 255) {}
    void set(int x, int y, const std::uint8_t c[3]) {
        if (x < 0 || y < 0 || x >= w || y >= h) return;
        for (int k = 0; k < 3; ++k) px[(static_cast<std::size_t>(y) * w + x) * 3 + k] = c[k];
    }
    void line(double x0, double y0, double x1, double y1, const std::uint8_t c[3], int thick = 1) {
        const int n = static_cast<int>(std::max(std::abs(x1 - x0), std::abs(y1 - y0))) + 1;
        for (int i = 0; i <= n; ++i) {
            const double t = static_cast<double>(i) / n;
            const int x = static_cast<int>(std::lround(x0 + t * (x1 - x0))),
                      y = static_cast<int>(std::lround(y0 + t * (y1 - y0)));
            for (int dy = -(thick / 2); dy <= thick / 2; ++dy)
                for (int dx = -(thick / 2); dx <= thick / 2; ++dx) set(x + dx, y + dy, c);
        }
    }
    void dot(double x, double y, int r, const std::uint8_t c[3]) {
        for (int dy = -r; dy <= r; ++dy)
            for (int dx = -r; dx <= r; ++dx)
                if (dx * dx + dy * dy <= r * r)
                    set(static_cast<int>(std::lround(x)) + dx, static_cast<int>(std::lround(y)) + dy, c);
    }
    void square(double x, double y, int r, const std::uint8_t c[3]) {
        for (int dy = -r; dy <= r; ++dy)
            for (int dx = -r; dx <= r; ++dx)
                set(static_cast<int>(std::lround(x)) + dx, static_cast<int>(std::lround(y)) + dy, c);
    }
    // 5x7 glyphs, each row a 5-bit mask (bit 4 = leftmost), scaled by `scale`
    void text(int x, int y, const std::string& str, const std::uint8_t c[3], int scale = 2) {
        for (char ch : str) {
            const std::uint8_t* g = glyph(ch);
            for (int r = 0; r < 7; ++r)
                for (int col = 0; col < 5; ++col)
                    if (g[r] & (16 >> col))
                        for (int sy = 0; sy < scale; ++sy)
                            for (int sx = 0; sx < scale; ++sx) set(x + col * scale + sx, y + r * scale + sy, c);
            x += 6 * scale;
        }
    }
    static const std::uint8_t* glyph(char ch) {
        static const struct {
            char c;
            std::uint8_t rows[7];
        } font[] = {
            {'0', {14, 17, 19, 21, 25, 17, 14}}, {'1', {4, 12, 4, 4, 4, 4, 14}},    {'2', {14, 17, 1, 2, 4, 8, 31}},
            {'3', {30, 1, 1, 14, 1, 1, 30}},     {'4', {2, 6, 10, 18, 31, 2, 2}},   {'5', {31, 16, 30, 1, 1, 17, 14}},
            {'6', {6, 8, 16, 30, 17, 17, 14}},   {'7', {31, 1, 2, 4, 8, 8, 8}},     {'8', {14, 17, 17, 14, 17, 17, 14}},
            {'9', {14, 17, 17, 15, 1, 2, 12}},   {'.', {0, 0, 0, 0, 0, 12, 12}},    {'x', {0, 0, 17, 10, 4, 10, 17}},
            {'m', {0, 0, 26, 21, 21, 21, 21}},   {'s', {0, 0, 15, 16, 14, 1, 30}},  {'R', {30, 17, 17, 30, 20, 18, 17}},
            {'M', {17, 27, 21, 21, 17, 17, 17}}, {'S', {15, 16, 16, 14, 1, 1, 30}}, {'E', {31, 16, 16, 30, 16, 16, 31}},
            {'p', {0, 0, 30, 17, 30, 16, 16}},   {'a', {0, 0, 14, 1, 15, 17, 15}},  {'e', {0, 0, 14, 17, 31, 16, 14}},
            {'r', {0, 0, 22, 25, 16, 16, 16}},   {'n', {0, 0, 22, 25, 17, 17, 17}}, {'g', {0, 0, 15, 17, 15, 1, 14}},
            {'i', {4, 0, 12, 4, 4, 4, 14}},      {'o', {0, 0, 14, 17, 17, 17, 14}}, {'f', {6, 9, 8, 28, 8, 8, 8}},
            {'t', {8, 8, 28, 8, 8, 9, 6}},       {'l', {12, 4, 4, 4, 4, 4, 14}},    {'h', {16, 16, 22, 25, 17, 17, 17}},
            {'d', {1, 1, 13, 19, 17, 19, 13}},   {'c', {0, 0, 14, 16, 16, 17, 14}}, {'u', {0, 0, 17, 17, 17, 19, 13}},
            {'b', {16, 16, 22, 25, 17, 17, 30}}, {'v', {0, 0, 17, 17, 17, 10, 4}},  {'w', {0, 0, 17, 17, 21, 21, 10}},
            {'k', {16, 16, 18, 20, 24, 20, 18}}, {'y', {0, 0, 17, 17, 15, 1, 14}},  {'T', {31, 4, 4, 4, 4, 4, 4}},
            {'(', {2, 4, 8, 8, 8, 4, 2}},        {')', {8, 4, 2, 2, 2, 4, 8}},      {',', {0, 0, 0, 0, 12, 4, 8}},
            {'-', {0, 0, 0, 31, 0, 0, 0}},       {'=', {0, 0, 31, 0, 31, 0, 0}},    {'/', {1, 1, 2, 4, 8, 16, 16}},
            {':', {0, 12, 12, 0, 12, 12, 0}},    {'^', {4, 10, 17, 0, 0, 0, 0}},    {' ', {0, 0, 0, 0, 0, 0, 0}},
            {'G', {14, 17, 16, 23, 17, 17, 15}}, {'I', {14, 4, 4, 4, 4, 4, 14}},    {'q', {0, 0, 15, 17, 15, 1, 1}},
        };
        static const std::uint8_t unknown[7] = {31, 17, 17, 17, 17, 17, 31};
        for (const auto& f : font)
            if (f.c == ch) return f.rows;
        return unknown;
    }
};

}  // namespace

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
