// Indirect light on the fast path (issue 4): gi/indirect, gi/radiance_pyramid
// and the amortised frame, checked against gi/reference_gi.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "gi/frame.h"
#include "gi/reference_gi.h"
#include "sim/parallel.h"

using namespace terrain;
using namespace terrain::gi;

namespace {

// A V-shaped valley along y: walls rising at `slope` (m per m) from the floor line.
Grid valley(int nx, int ny, float slope) {
    Grid g(nx, ny);
    const float c = 0.5f * static_cast<float>(nx - 1);
    for (int y = 0; y < ny; ++y)
        for (int x = 0; x < nx; ++x) g(x, y) = slope * std::fabs(static_cast<float>(x) - c);
    return g;
}

// Smooth rolling hills (a few sines), heights in metres.
[[maybe_unused]] Grid hills(int n, float amp) {
    Grid g(n, n);
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const float u = static_cast<float>(x) / static_cast<float>(n), v = static_cast<float>(y) / static_cast<float>(n);
            g(x, y) = amp * (std::sin(6.3f * u) * std::cos(4.1f * v) + 0.5f * std::sin(13.0f * u + 7.0f * v) +
                             0.25f * std::cos(23.0f * v - 3.0f * u));
        }
    return g;
}

AlbedoMap uniformAlbedo(int nx, int ny, float a) {
    AlbedoMap m;
    for (auto& c : m.channel) c.resize(nx, ny, a);
    return m;
}

GiSettings indirectSettings(int bounces, int subsample = 1) {
    GiSettings s = engineGiSettings();
    s.subsample = subsample;
    s.indirect.bounces = bounces;
    return s;
}

double meanOver(const Grid& g, int x0, int x1, int y0, int y1) {
    double sum = 0.0;
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) sum += g(x, y);
    return sum / ((x1 - x0) * (y1 - y0));
}

// Relative RMSE of a against b over the interior (border fraction excluded).
[[maybe_unused]] double relRmse(const Grid& a, const Grid& b, float border) {
    const int bx = static_cast<int>(border * a.nx), by = static_cast<int>(border * a.ny);
    double se = 0.0, sr = 0.0;
    int n = 0;
    for (int y = by; y < a.ny - by; ++y)
        for (int x = bx; x < a.nx - bx; ++x) {
            const double d = a(x, y) - b(x, y);
            se += d * d;
            sr += static_cast<double>(b(x, y)) * b(x, y);
            ++n;
        }
    return std::sqrt(se / n) / std::sqrt(sr / n);
}

}  // namespace

TEST_CASE("gi.indirect: V-shaped valley with white walls under a uniform sky matches the reference") {
    const int n = 49;
    const Grid h = valley(n, n, 1.0f);
    const AlbedoMap a = uniformAlbedo(n, n, 1.0f);
    GiLighting light;
    GiState st;
    const GiSettings s = indirectSettings(1);
    runGiFrame(h.view(), 1.0f, light, s, st, &a);
    ReferenceGiSettings rs;
    rs.directions = 4096;
    rs.azimuths = 256;
    rs.bounces = 1;
    ReferenceGiResult ref;
    renderReferenceGi(h.view(), 1.0f, light.environment, &a, rs, ref);
    const int c = n / 2;
    const double fast = meanOver(st.indirect.indirect[0], c - 1, c + 2, 12, n - 12);
    const double exact = meanOver(ref.indirect[0], c - 1, c + 2, 12, n - 12);
    const double fastWall = meanOver(st.indirect.indirect[0], c + 6, c + 12, 12, n - 12);
    const double exactWall = meanOver(ref.indirect[0], c + 6, c + 12, 12, n - 12);
    MESSAGE("valley bottom indirect: fast " << fast << ", reference " << exact << "; wall: fast " << fastWall << ", reference "
                                            << exactWall << "; direct bottom fast " << meanOver(st.shade.rgb[0], c - 1, c + 2, 12, n - 12)
                                            << " ref " << meanOver(ref.direct[0], c - 1, c + 2, 12, n - 12));
    CHECK(fast > 0.05);
    CHECK(fast == doctest::Approx(exact).epsilon(0.10));
    CHECK(fastWall == doctest::Approx(exactWall).epsilon(0.10));
}
