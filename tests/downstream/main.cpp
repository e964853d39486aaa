// Uses the installed terrain::gi the way another project would: lights a
// 64 x 64 height field with one bump under a uniform sky (one GI frame with
// the engine's settings) and checks the ambient map (normal-weighted sky-view
// factor): every value finite and in [0, 1], about 1 on the flat ground far
// from the bump, clearly below 1 at the bump's foot, where the bump hides
// part of the sky. Prints one line; exits non-zero on failure.
#include <cmath>
#include <cstdio>
#include <exception>

#include "core/error.h"
#include "core/grid.h"
#include "gi/frame.h"

namespace {

constexpr int kSize = 64;
constexpr float kCellSize = 1.0f;                    // m
constexpr int kBumpX = 16, kBumpY = 16;              // bump centre (cells), in one quadrant
constexpr float kBumpHeight = 12.0f;                 // m
constexpr float kBumpSigma = 3.0f;                   // cells
constexpr int kFlatX = 54, kFlatY = 54;              // flat ground far from the bump
constexpr int kFootX = kBumpX + 8, kFootY = kBumpY;  // flat ground at the bump's foot

terrain::Grid bumpHeights() {
    terrain::Grid h(kSize, kSize);
    for (int y = 0; y < kSize; ++y) {
        for (int x = 0; x < kSize; ++x) {
            const float dx = static_cast<float>(x - kBumpX), dy = static_cast<float>(y - kBumpY);
            h(x, y) = kBumpHeight * std::exp(-(dx * dx + dy * dy) / (2.0f * kBumpSigma * kBumpSigma));
        }
    }
    return h;
}

int fail(const char* what, float value) {
    std::printf("downstream: FAILED: %s (%g)\n", what, static_cast<double>(value));
    return 1;
}

}  // namespace

int main() {
    namespace gi = terrain::gi;
    try {
        const terrain::Grid heights = bumpHeights();
        gi::GiLighting lighting;
        lighting.environment = gi::uniformSkyLight(1.0f);
        gi::GiState state;
        gi::runGiFrame(heights.cview(), kCellSize, lighting, gi::GiSettings{}, state);

        const terrain::Grid& ambient = state.shade.ambient;
        if (ambient.nx != kSize || ambient.ny != kSize) return fail("ambient map size", static_cast<float>(ambient.nx));
        for (int y = 0; y < kSize; ++y) {
            for (int x = 0; x < kSize; ++x) {
                const float a = ambient(x, y);
                if (!std::isfinite(a) || a < 0.0f || a > 1.0f + 1e-3f) return fail("ambient not finite in [0, 1]", a);
            }
        }
        const float flat = ambient(kFlatX, kFlatY), foot = ambient(kFootX, kFootY);
        if (std::fabs(flat - 1.0f) > 0.01f) return fail("ambient of the flat ground is not about 1", flat);
        if (!(foot < flat - 0.02f)) return fail("ambient at the bump's foot is not below the flat ground's", foot);
        std::printf("downstream: ambient flat %.4f, bump foot %.4f\n", static_cast<double>(flat),
                    static_cast<double>(foot));
        return 0;
    } catch (const terrain::Error& e) {
        std::printf("downstream: FAILED: %s\n", e.what());
        return 1;
    }
}
