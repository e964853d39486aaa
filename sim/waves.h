#pragma once
// Height-field water that carries real waves: the shallow-water equations on
// a staggered grid (depth at cell centres, velocities on faces), so waves
// travel at sqrt(g h) (the plain pipe model does not: GUIDE 3). Wet/dry
// fronts, and well balanced: water at rest over any bottom stays at rest.
#include <vector>

#include "sim/terrain.h"

namespace terrain {

/// An impulse: a Gaussian raise of the surface at a time.
struct WaveDrop {
    double time = 0.0;     // s
    float x = 0.0f;        // m
    float y = 0.0f;        // m
    float radius = 5.0f;   // m (Gaussian sigma)
    float height = 0.5f;   // m added at the centre
};

/// An incoming swell entering through one edge of the domain.
struct WaveSwell {
    bool enabled = false;
    int edge = 0;             // 0: -x, 1: +x, 2: -y, 3: +y
    float amplitude = 0.3f;   // m
    float period = 8.0f;      // s
};

struct WaveSettings {
    float gravity = 9.81f;      // m/s^2
    float courant = 0.5f;       // fraction of the CFL limit used for the default step
    float dryDepth = 1.0e-4f;   // m: below this a cell counts as dry
    float friction = 0.0f;      // Manning n (0 = frictionless)
    bool advection = true;      // momentum advection (needed for dam breaks, bores)
    WaveSwell swell;
    std::vector<WaveDrop> drops;
};

struct WaveScratch {
    Grid a, b, c;  // temporaries
};

/// The largest stable time step (s): CFL with the wave speed sqrt(g h) + |u|.
float waveMaxDt(const TerrainState& s, const WaveSettings& settings);

/// Advances water depth and face velocities by dt. Requires the layers water
/// and faceVelocity. Closed boundaries except where a swell enters.
void waveStep(TerrainState& s, const WaveSettings& settings, float dt, WaveScratch& scratch);

}  // namespace terrain
