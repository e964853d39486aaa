// The near field of sub-sampled texels (gi/near_field.h): its steps taken two
// at a time give what they give one at a time, bit for bit, at the field's
// edges and over part of a row too.
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <doctest/doctest.h>

#include "gi/near_field.h"

using namespace terrain;
using namespace terrain::gi;

namespace {

// Each step over the whole range before the next, as the definition reads.
void raiseStepByStep(ConstGridView heights, int y, std::span<const NearFieldStep> steps, float* horizon, int x0,
                     int x1) {
    for (const NearFieldStep& st : steps) {
        const int ya = y + st.ay, yb = y + st.by;
        if (ya < 0 || yb < 0 || ya >= heights.ny || yb >= heights.ny) continue;
        for (int x = x0; x < x1; ++x) {
            const int xa = x + st.ax, xb = x + st.bx;
            if (xa < 0 || xb < 0 || xa >= heights.nx || xb >= heights.nx) continue;
            const float slope =
                (st.wA * heights.row(ya)[xa] + st.wB * heights.row(yb)[xb] - heights.row(y)[x]) * st.invTau;
            horizon[x] = horizon[x] > slope ? horizon[x] : slope;
        }
    }
}

}  // namespace

TEST_CASE("near field: steps two at a time equal one at a time, edges and partial rows included") {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> height(-40.0f, 60.0f), slope(-1.5f, 1.5f);
    const int nx = 37, ny = 23;
    Grid heights(nx, ny);
    for (float& h : heights.v) h = height(rng);
    // 17 azimuths: steps with and without a second sample, along both axes
    std::vector<float> cosSin;
    for (int a = 0; a < 17; ++a) {
        const double phi = 2.0 * M_PI * (a + 0.3) / 17.0;
        cosSin.push_back(static_cast<float>(std::cos(phi)));
        cosSin.push_back(static_cast<float>(std::sin(phi)));
    }
    for (int s : {2, 3, 4}) {
        std::vector<NearFieldStep> steps;
        buildNearFieldSteps(cosSin, s, 12.5f, steps);
        for (int a = 0; a < 17; ++a) {
            const std::span<const NearFieldStep> mine(steps.data() + static_cast<std::size_t>(a) * s,
                                                      static_cast<std::size_t>(s));
            for (int y : {0, 1, s - 1, ny / 2, ny - s, ny - 1})
                for (auto [x0, x1] : {std::pair{0, nx}, std::pair{0, 3}, std::pair{nx - 2, nx}, std::pair{5, 29}}) {
                    std::vector<float> start(nx);
                    for (float& t : start) t = slope(rng);
                    std::vector<float> fused = start, alone = start;
                    raiseToNearField(heights.cview(), y, mine, fused.data(), x0, x1);
                    raiseStepByStep(heights.cview(), y, mine, alone.data(), x0, x1);
                    for (int x = 0; x < nx; ++x)
                        REQUIRE(std::bit_cast<std::uint32_t>(fused[x]) == std::bit_cast<std::uint32_t>(alone[x]));
                }
        }
    }
}
