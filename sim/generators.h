#pragma once
// Scene generators: seeded noise mountains and the analytic shapes the tests
// use. Every generator writes heights in metres into a grid it sizes itself;
// noise is a pure function of (seed, cell), so results do not depend on the
// thread count.
#include <cstdint>
#include <string>

#include "core/grid.h"

namespace terrain {

struct NoiseSettings {
    float amplitude = 800.0f;    // m, peak-to-valley scale of the first octave
    float wavelength = 6000.0f;  // m, wavelength of the first octave
    int octaves = 8;
    float lacunarity = 2.0f;  // wavelength divisor per octave
    float gain = 0.5f;        // amplitude factor per octave
    bool ridged = false;      // ridged multifractal (sharp crests) instead of fBm
    float offset = 0.0f;      // m added everywhere
};

/// Seeded fBm or ridged-noise mountains on an nx x ny grid with the given cell size.
void generateNoise(Grid& out, int nx, int ny, float cellSize, std::uint64_t seed, const NoiseSettings& settings);

/// Gradient noise in [-1, 1] at (x, y) in noise units; pure function of the seed.
float gradientNoise(float x, float y, std::uint64_t seed);

enum class Shape { Flat, GaussianBump, Cone, CircularPit, Step, Spike, SineRidges };

struct ShapeSettings {
    Shape shape = Shape::Flat;
    float base = 0.0f;         // m, height of the surrounding plane
    float height = 10.0f;      // m, bump/cone/step/spike/ridge height, or pit depth
    float radius = 20.0f;      // m, bump sigma, cone/pit radius
    float wavelength = 50.0f;  // m, sine ridges
    float angleDeg = 0.0f;     // ridge crest direction, degrees from +x towards +y
};

/// Analytic shapes centred in the grid: flat, Gaussian bump, cone, circular
/// pit (flat floor of the given radius and depth, vertical wall), vertical
/// wall/step (at the middle column, high side at +x), one-texel spike (the
/// centre cell), sine ridges.
void generateShape(Grid& out, int nx, int ny, float cellSize, const ShapeSettings& settings);

/// Parses a shape name ("flat", "bump", "cone", "pit", "step", "spike", "ridges").
Shape parseShape(const std::string& name);
const char* shapeName(Shape s);

}  // namespace terrain
