#pragma once
// Helpers shared by the GI benchmarks: the Mont Blanc crop at true scale and
// the relative error of an RGB result against a reference.
#include <array>
#include <cmath>
#include <string>

#include "core/grid.h"
#include "core/png_io.h"

namespace terrain::bench {

// alps-montblanc at true scale (cell 60000 / 647 m, heights 454 + v (4810 - 454) / 65535), central size^2 crop.
inline Grid alpsCentreCrop(const std::string& dataDir, int size, float& cell) {
    const Grid full = readPngHeightmap(dataDir + "/alps-montblanc.png", (4810.0f - 454.0f) / 65535.0f, 454.0f);
    cell = 60000.0f / 647.0f;
    Grid g(size, size);
    const int x0 = (full.nx - size) / 2, y0 = (full.ny - size) / 2;
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) g(x, y) = full(x0 + x, y0 + y);
    return g;
}

// Relative RMSE of a against b over the interior (10 % border left out), all
// three channels; bias = mean difference / RMS of b.
inline double relRmse(const std::array<Grid, 3>& a, const std::array<Grid, 3>& b, double& bias) {
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
