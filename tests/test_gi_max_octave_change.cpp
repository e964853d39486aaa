// The bound on the change of the max-decimated octaves (gi/max_octave_change)
// against the true change of the height pyramid's own octave maxima: never
// below it for bumps, noise everywhere, spikes at the edges, a cliff
// collapse and a valley deepened below the peaks; never above the blocks'
// largest |dh|; 0 where the heights only moved below a block's peak that
// stayed, the whole |dh| where the peak itself moved.
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <doctest/doctest.h>

#include "core/error.h"
#include "gi/max_octave_change.h"
#include "gi/pyramid.h"

using namespace terrain;
using namespace terrain::gi;

namespace {

constexpr float kCell = 2.0f;  // metres

Grid hills(int nx, int ny) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> noise(-0.3f, 0.3f);
    Grid g(nx, ny);
    for (int y = 0; y < ny; ++y)
        for (int x = 0; x < nx; ++x)
            g(x, y) =
                20.0f * std::sin(0.11f * static_cast<float>(x)) * std::cos(0.08f * static_cast<float>(y)) + noise(rng);
    return g;
}

// 0: a bump, 1: noise everywhere, 2: spikes (inside, last row and column),
// 3: a cliff collapse (a band lowered by up to 15 m), 4: the valleys
// deepened (every cell below 0 m lowered by up to 0.5 m).
Grid changed(const Grid& base, int kind) {
    Grid g = base;
    std::mt19937 rng(31u + static_cast<unsigned>(kind));
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    const int nx = g.nx, ny = g.ny;
    for (int y = 0; y < ny; ++y)
        for (int x = 0; x < nx; ++x) {
            float& h = g(x, y);
            if (kind == 0) {
                const float dx = static_cast<float>(x) - 0.3f * nx, dy = static_cast<float>(y) - 0.7f * ny;
                h += 6.0f * std::exp(-(dx * dx + dy * dy) / 30.0f);
            } else if (kind == 1) {
                h += 0.05f * (u(rng) - 0.5f);
            } else if (kind == 3 && x > nx / 2 && x < nx / 2 + 9) {
                h -= 15.0f * u(rng);
            } else if (kind == 4 && h < 0.0f) {
                h -= 0.5f * u(rng);
            }
        }
    if (kind == 2) {
        g(nx / 4, ny / 3) += 9.0f;
        g(nx - 1, ny / 2) -= 5.0f;
        g(nx / 2, ny - 1) += 4.0f;
        g(nx - 1, ny - 1) += 2.0f;
    }
    return g;
}

std::vector<Grid> maxOctavesOf(const Grid& h) {
    HeightPyramid p;
    PyramidSettings ps;
    REQUIRE(ps.peakBlend > 0.0f);  // the pyramid keeps its max octaves
    buildHeightPyramid(h.cview(), kCell, 1, ps, p);
    return p.maxOctaves;
}

// The largest |dh| over the cells of octave o's texel (x, y).
float largestChangeInBlock(const Grid& a, const Grid& b, int o, int x, int y) {
    float m = 0.0f;
    for (int cy = y << o; cy < std::min(b.ny, (y + 1) << o); ++cy)
        for (int cx = x << o; cx < std::min(b.nx, (x + 1) << o); ++cx)
            m = std::max(m, std::fabs(b(cx, cy) - a(cx, cy)));
    return m;
}

}  // namespace

TEST_CASE("gi.max_octave_change: bounds the octave maxima's change, within the blocks' largest |dh|") {
    for (const auto& [nx, ny] : {std::pair{96, 64}, std::pair{131, 77}, std::pair{200, 1}}) {
        const Grid base = hills(nx, ny);
        const std::vector<Grid> before = maxOctavesOf(base);
        REQUIRE(!before.empty());
        for (int kind = 0; kind < 5; ++kind) {
            CAPTURE(nx);
            CAPTURE(ny);
            CAPTURE(kind);
            const Grid after = changed(base, kind);
            const std::vector<Grid> now = maxOctavesOf(after);
            MaxOctaveChange bound;
            boundMaxOctaveChange(base.cview(), after.cview(), before, now, bound);
            REQUIRE(bound.bound.size() == before.size());
            int below = 0, above = 0, tighter = 0, texels = 0, peakMoved = 0;
            for (std::size_t o = 0; o < before.size(); ++o) {
                const Grid& b = bound.bound[o];
                REQUIRE(b.nx == before[o].nx);
                REQUIRE(b.ny == before[o].ny);
                for (int y = 0; y < b.ny; ++y)
                    for (int x = 0; x < b.nx; ++x) {
                        const float truth = std::fabs(now[o](x, y) - before[o](x, y));
                        const float largest = largestChangeInBlock(base, after, static_cast<int>(o) + 1, x, y);
                        below += b(x, y) < truth ? 1 : 0;
                        // the cells' |dh| rounded up: at most one float above the plain difference
                        above += b(x, y) > std::nextafter(largest, 1e30f) ? 1 : 0;
                        tighter += b(x, y) < largest ? 1 : 0;
                        ++texels;
                        // valleys deepened: a block holding a cell at or above 0 m keeps its peak, and
                        // every sub-block the bound reads keeps its own
                        if (kind == 4 && before[o](x, y) >= 0.0f && b(x, y) != 0.0f) ++peakMoved;
                    }
            }
            CHECK(below == 0);
            CHECK(above == 0);
            CHECK(peakMoved == 0);
            MESSAGE(nx << " x " << ny << " change " << kind << ": " << tighter << " of " << texels
                       << " octave texels below their block's largest |dh|");
        }
    }
}

TEST_CASE("gi.max_octave_change: 0 below a peak that stayed, the whole change at a peak that moved") {
    Grid base(32, 32, 0.0f);
    base(1, 1) = 10.0f;  // the peak of octave 3's first 8 x 8 block
    Grid valley = base;
    valley(6, 5) -= 3.0f;  // far below the peak
    const std::vector<Grid> before = maxOctavesOf(base);
    MaxOctaveChange bound;
    boundMaxOctaveChange(base.cview(), valley.cview(), before, maxOctavesOf(valley), bound);
    REQUIRE(bound.bound.size() >= 3);
    CHECK(bound.bound[2](0, 0) == 0.0f);
    Grid peak = base;
    peak(1, 1) -= 4.0f;
    boundMaxOctaveChange(base.cview(), peak.cview(), before, maxOctavesOf(peak), bound);
    CHECK(bound.bound[2](0, 0) == 4.0f);
}

TEST_CASE("gi.max_octave_change: fields or octaves of different sizes are refused") {
    const Grid a = hills(32, 32), b = hills(32, 31);
    const std::vector<Grid> octaves = maxOctavesOf(a);
    MaxOctaveChange out;
    CHECK_THROWS_AS(boundMaxOctaveChange(a.cview(), b.cview(), octaves, octaves, out), InputError);
    std::vector<Grid> fewer(octaves.begin(), octaves.end() - 1);
    CHECK_THROWS_AS(boundMaxOctaveChange(a.cview(), a.cview(), octaves, fewer, out), InputError);
    CHECK_THROWS_AS(
        boundMaxOctaveChange(a.cview(), a.cview(), maxOctavesOf(hills(16, 16)), maxOctavesOf(hills(16, 16)), out),
        InputError);
}
