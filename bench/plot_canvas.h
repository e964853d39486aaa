#pragma once
// A small RGB raster for the benchmark plots: lines, points, squares and a
// 5x7 font, written as PNG by the caller (no plotting library).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace terrain::bench {

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
    static const std::uint8_t* glyph(char ch);
};

}  // namespace terrain::bench
