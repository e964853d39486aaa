#include "sim/generators.h"

#include <cmath>

#include "core/error.h"
#include "core/parallel.h"
#include "sim/scene_ranges.h"
#include "sim/terrain.h"

namespace terrain {
namespace {

std::uint64_t mix64(std::uint64_t z) {
    z += 0x9e3779b97f4a7c15ull;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

// Unit gradient at an integer lattice point, from a hash of (seed, i, j).
void latticeGradient(std::int64_t i, std::int64_t j, std::uint64_t seed, float& gx, float& gy) {
    const std::uint64_t h = mix64(seed ^ mix64(static_cast<std::uint64_t>(i) * 0x632be59bd9b4e019ull ^
                                               static_cast<std::uint64_t>(j) * 0x85157af5ull));
    // 16 evenly spaced directions
    constexpr float kTwoPi = 6.28318530717958647692f;
    const float a = static_cast<float>(h & 15u) * (kTwoPi / 16.0f);
    gx = std::cos(a);
    gy = std::sin(a);
}

float fade(float t) { return t * t * t * (t * (t * 6.0f - 15.0f) + 10.0f); }

}  // namespace

float gradientNoise(float x, float y, std::uint64_t seed) {
    const float fx = std::floor(x), fy = std::floor(y);
    const auto i = static_cast<std::int64_t>(fx);
    const auto j = static_cast<std::int64_t>(fy);
    const float tx = x - fx, ty = y - fy;
    float g[4][2];
    latticeGradient(i, j, seed, g[0][0], g[0][1]);
    latticeGradient(i + 1, j, seed, g[1][0], g[1][1]);
    latticeGradient(i, j + 1, seed, g[2][0], g[2][1]);
    latticeGradient(i + 1, j + 1, seed, g[3][0], g[3][1]);
    const float n00 = g[0][0] * tx + g[0][1] * ty;
    const float n10 = g[1][0] * (tx - 1.0f) + g[1][1] * ty;
    const float n01 = g[2][0] * tx + g[2][1] * (ty - 1.0f);
    const float n11 = g[3][0] * (tx - 1.0f) + g[3][1] * (ty - 1.0f);
    const float u = fade(tx), v = fade(ty);
    const float nx0 = n00 + u * (n10 - n00);
    const float nx1 = n01 + u * (n11 - n01);
    return 1.4142135f * (nx0 + v * (nx1 - nx0));  // scale to about [-1, 1]
}

void generateNoise(Grid& out, int nx, int ny, float cellSize, std::uint64_t seed, const NoiseSettings& s) {
    checkDimensions(nx, ny, cellSize);
    namespace r = scene_ranges;
    checkRange(r::kAltitude, s.amplitude, "noise amplitude");
    checkRange(r::kLength, s.wavelength, "noise wavelength");
    checkRange(r::kOctaves, s.octaves, "noise octaves");
    checkRange(r::kLacunarity, s.lacunarity, "noise lacunarity");
    checkRange(r::kFraction, s.gain, "noise gain");
    checkRange(r::kAltitude, s.offset, "noise offset");
    out.resize(nx, ny);
    parallelForRows(ny, nx, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y)
            for (int x = 0; x < nx; ++x) {
                float freq = cellSize / s.wavelength;
                float amp = 1.0f;
                float sum = 0.0f;
                float weight = 1.0f;
                for (int o = 0; o < s.octaves; ++o) {
                    const std::uint64_t octaveSeed = mix64(seed + 0x1000193ull * static_cast<std::uint64_t>(o));
                    const float n = gradientNoise(static_cast<float>(x) * freq + 0.5f,
                                                  static_cast<float>(y) * freq + 0.5f, octaveSeed);
                    if (s.ridged) {
                        // Ridged multifractal: sharp crests where the noise crosses zero,
                        // rougher detail where earlier octaves are high.
                        float r = 1.0f - std::fabs(n);
                        r *= r;
                        sum += r * amp * weight;
                        weight = std::fmin(1.0f, std::fmax(0.0f, r * 2.0f));
                    } else {
                        sum += n * amp;
                    }
                    freq *= s.lacunarity;
                    amp *= s.gain;
                }
                out(x, y) = s.offset + s.amplitude * (s.ridged ? sum * 0.5f : sum * 0.5f + 0.5f);
            }
    });
}

void generateShape(Grid& out, int nx, int ny, float cellSize, const ShapeSettings& s) {
    checkDimensions(nx, ny, cellSize);
    namespace r = scene_ranges;
    checkRange(r::kAltitude, s.base, "shape base");
    checkRange(r::kAltitude, s.height, "shape height");
    checkRange(r::kLength, s.radius, "shape radius");
    checkRange(r::kLength, s.wavelength, "shape ridge wavelength");
    checkRange(r::kAngle, s.angleDeg, "shape angle");
    out.resize(nx, ny, s.base);
    const float cx = 0.5f * static_cast<float>(nx - 1) * cellSize;
    const float cy = 0.5f * static_cast<float>(ny - 1) * cellSize;
    const float ca = std::cos(s.angleDeg * 0.017453292519943295f);
    const float sa = std::sin(s.angleDeg * 0.017453292519943295f);
    for (int y = 0; y < ny; ++y)
        for (int x = 0; x < nx; ++x) {
            const float px = static_cast<float>(x) * cellSize - cx;
            const float py = static_cast<float>(y) * cellSize - cy;
            const float r = std::sqrt(px * px + py * py);
            float h = 0.0f;
            switch (s.shape) {
                case Shape::Flat:
                    break;
                case Shape::GaussianBump:
                    h = s.height * std::exp(-0.5f * r * r / (s.radius * s.radius));
                    break;
                case Shape::Cone:
                    h = s.height * std::fmax(0.0f, 1.0f - r / s.radius);
                    break;
                case Shape::CircularPit:
                    h = r <= s.radius ? -s.height : 0.0f;
                    break;
                case Shape::Step:
                    h = x >= nx / 2 ? s.height : 0.0f;
                    break;
                case Shape::Spike:
                    h = (x == nx / 2 && y == ny / 2) ? s.height : 0.0f;
                    break;
                case Shape::SineRidges: {
                    // distance across the crests: along the direction perpendicular to the crest line
                    const float across = -px * sa + py * ca;
                    h = 0.5f * s.height * (1.0f + std::cos(6.283185307179586f * across / s.wavelength));
                    break;
                }
            }
            out(x, y) = s.base + h;
        }
}

Shape parseShape(const std::string& name) {
    if (name == "flat") return Shape::Flat;
    if (name == "bump") return Shape::GaussianBump;
    if (name == "cone") return Shape::Cone;
    if (name == "pit") return Shape::CircularPit;
    if (name == "step" || name == "wall") return Shape::Step;
    if (name == "spike") return Shape::Spike;
    if (name == "ridges") return Shape::SineRidges;
    throw InputError("unknown shape '" + name + "' (flat, bump, cone, pit, step, spike, ridges)");
}

const char* shapeName(Shape s) {
    switch (s) {
        case Shape::Flat:
            return "flat";
        case Shape::GaussianBump:
            return "bump";
        case Shape::Cone:
            return "cone";
        case Shape::CircularPit:
            return "pit";
        case Shape::Step:
            return "step";
        case Shape::Spike:
            return "spike";
        case Shape::SineRidges:
            return "ridges";
    }
    return "?";
}

}  // namespace terrain
