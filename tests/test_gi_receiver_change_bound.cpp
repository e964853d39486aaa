// gi/receiver_change_bound: the blocking-slope bound per receiver from max
// filters of the change pyramid, against boundSlopeChange with tiles of one
// receiver (which test_gi_change_bound checks against the engine's slopes):
// never below it, equal to it where every cell changed alike.
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <doctest/doctest.h>

#include "core/error.h"
#include "gi/change_bound.h"
#include "gi/pyramid.h"
#include "gi/receiver_change_bound.h"
#include "tests/gi_test_terrain.h"

using namespace terrain;
using namespace terrain::gi;

namespace {

constexpr float kCell = 2.0f;  // metres

// Hills with a little noise, and changes of several kinds: a bump, noise
// everywhere, spikes (one inside, some on the last row and column), a
// channel deepened along a wavy line.
Grid terrainOf(int nx, int ny) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> noise(-0.2f, 0.2f);
    Grid g(nx, ny);
    for (int y = 0; y < ny; ++y)
        for (int x = 0; x < nx; ++x)
            g(x, y) =
                12.0f * std::sin(0.12f * static_cast<float>(x)) * std::cos(0.09f * static_cast<float>(y)) + noise(rng);
    return g;
}

Grid changed(const Grid& base, int kind) {
    Grid g = base;
    std::mt19937 rng(17u + static_cast<unsigned>(kind));
    const int nx = g.nx, ny = g.ny;
    if (kind == 0) {
        for (int y = 0; y < ny; ++y)
            for (int x = 0; x < nx; ++x) {
                const float dx = static_cast<float>(x) - 0.4f * nx, dy = static_cast<float>(y) - 0.6f * ny;
                g(x, y) += 2.5f * std::exp(-(dx * dx + dy * dy) / 18.0f);
            }
    } else if (kind == 1) {
        std::uniform_real_distribution<float> u(-0.03f, 0.03f);
        for (float& v : g.v) v += u(rng);
    } else if (kind == 2) {
        g(nx / 3, ny / 5) += 7.0f;
        g(nx - 1, ny - 1) -= 4.0f;
        g(nx / 2, ny - 1) += 3.0f;
    } else {
        for (int y = 0; y < ny; ++y) {
            const int x = static_cast<int>(0.55f * nx + 5.0f * std::sin(0.3f * static_cast<float>(y)));
            for (int dx = -1; dx <= 1; ++dx)
                g(std::clamp(x + dx, 0, nx - 1), y) -= 0.01f * static_cast<float>(1 + y % 4);
        }
    }
    return g;
}

}  // namespace

TEST_CASE("gi.receiver_change_bound: per receiver never below the one-receiver tiles' bound") {
    struct Case {
        int nx, ny, subsample;
    };
    for (const Case c : {Case{97, 70, 1}, Case{120, 83, 2}, Case{150, 118, 4}, Case{300, 260, 2}}) {
        const Grid base = terrainOf(c.nx, c.ny);
        for (int kind = 0; kind < 4; ++kind) {
            CAPTURE(c.nx);
            CAPTURE(c.subsample);
            CAPTURE(kind);
            const Grid after = changed(base, kind);
            HeightPyramid pyr;
            buildHeightPyramid(after.cview(), kCell, c.subsample, PyramidSettings{}, pyr);
            MaxChangePyramid dh;
            buildMaxChangePyramid(base.cview(), after.cview(), dh);
            std::vector<float> perReceiver, tiles;
            boundSlopeChangePerReceiver(dh, pyr, perReceiver);
            boundSlopeChange(dh, pyr, 1, tiles);
            REQUIRE(perReceiver.size() == tiles.size());
            REQUIRE(perReceiver.size() == static_cast<std::size_t>(pyr.nxr) * static_cast<std::size_t>(pyr.nyr));
            int below = 0;
            std::vector<double> ratio;
            for (std::size_t r = 0; r < tiles.size(); ++r) {
                below += perReceiver[r] < tiles[r] ? 1 : 0;
                if (tiles[r] > 0.0f) ratio.push_back(perReceiver[r] / tiles[r]);
            }
            CHECK(below == 0);
            std::sort(ratio.begin(), ratio.end());
            if (!ratio.empty())
                MESSAGE(c.nx << " x " << c.ny << " s=" << c.subsample << " change " << kind
                             << ": per receiver / one-receiver tiles, median " << ratio[ratio.size() / 2]
                             << ", largest " << ratio.back());
        }
    }
}

TEST_CASE(
    "gi.receiver_change_bound: equal to the one-receiver tiles' bound where every cell changed alike; zero "
    "without a change") {
    for (int s : {1, 2, 3}) {
        CAPTURE(s);
        // heights on a grid of 1/16 m, so that raising each by 0.25 m changes each by exactly that
        Grid base = terrainOf(83, 61);
        for (float& v : base.v) v = std::round(16.0f * v) / 16.0f;
        Grid raised = base;
        for (float& v : raised.v) v += 0.25f;
        HeightPyramid pyr;
        buildHeightPyramid(raised.cview(), kCell, s, PyramidSettings{}, pyr);
        MaxChangePyramid dh;
        buildMaxChangePyramid(base.cview(), raised.cview(), dh);
        std::vector<float> perReceiver, tiles;
        boundSlopeChangePerReceiver(dh, pyr, perReceiver);
        boundSlopeChange(dh, pyr, 1, tiles);
        CHECK(perReceiver == tiles);
        CHECK(perReceiver.front() > 0.0f);
        buildMaxChangePyramid(base.cview(), base.cview(), dh);
        boundSlopeChangePerReceiver(dh, pyr, perReceiver);
        CHECK(std::all_of(perReceiver.begin(), perReceiver.end(), [](float v) { return v == 0.0f; }));
    }
    HeightPyramid pyr;
    buildHeightPyramid(terrainOf(40, 30).cview(), kCell, 1, PyramidSettings{}, pyr);
    MaxChangePyramid other;
    buildMaxChangePyramid(terrainOf(30, 30).cview(), other);
    std::vector<float> out;
    CHECK_THROWS_AS(boundSlopeChangePerReceiver(other, pyr, out), InputError);
}
