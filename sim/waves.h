#pragma once
// Height-field water that carries real waves: the shallow-water equations on
// a staggered grid (depth at cell centres, velocities on faces), so waves
// travel at sqrt(g h) (the plain pipe model of Mei, Decaudin & Hu 2007 does not: its waves travel at a speed set by the pipe area). Wet/dry
// fronts, and well balanced: water at rest over any bottom stays at rest.
//
// Scheme (details and equations in waves.cpp): semi-discrete staggered
// (Arakawa C) shallow water after Stelling & Duinmeijer 2003, forward-backward
// in time: continuity with upwind face depths and a positivity limiter first,
// then momentum (pressure gradient from the new surface with hydrostatic
// reconstruction at every face, momentum-conservative upwind advection,
// optional Manning friction). Every pass is a gather over rows; results are
// bit-identical for any thread count.
//
// Clock: waveStep reads s.time as the time at the start of the step (drops
// fire when their time lies in [s.time, s.time + dt), the swell phase follows
// s.time) and does not advance s.time or s.tick: the caller owns the clock.
#include <vector>

#include "sim/terrain.h"

namespace terrain {

/// An impulse: a Gaussian raise of the surface at a time (adds water).
struct WaveDrop {
    double time = 0.0;    // s
    float x = 0.0f;       // m (grid point x sits at x * cellSize)
    float y = 0.0f;       // m
    float radius = 5.0f;  // m (Gaussian sigma)
    float height = 0.5f;  // m added at the centre
};

/// An incoming swell entering through one edge of the domain: a linear
/// wave eta_in(t) = amplitude * sin(2 pi t / period) imposed with a Flather
/// (radiation) condition, so outgoing waves leave through that edge too.
struct WaveSwell {
    bool enabled = false;
    int edge = 0;              // 0: -x, 1: +x, 2: -y, 3: +y
    float amplitude = 0.3f;    // m
    float period = 8.0f;       // s
    float seaLevel = 0.0f;     // m, still-water surface elevation outside the edge
    float rampPeriods = 1.0f;  // the amplitude ramps up linearly over this many periods from t = 0
};

struct WaveSettings {
    float gravity = 9.81f;     // m/s^2
    float courant = 0.5f;      // fraction of the CFL limit used for the default step (waveMaxDt)
    float maxCourant = 0.7f;   // hard limit: waveStep sub-steps internally above it (2-D forward-backward
                               // gravity waves need c dt / dx <= 1/sqrt(2))
    float dryDepth = 1.0e-4f;  // m: a face whose reconstructed depths are both below this carries no flow
    float friction = 0.0f;     // Manning n (s/m^(1/3), 0 = frictionless)
    bool advection = true;     // momentum advection (needed for dam breaks, bores)
    WaveSwell swell;
    std::vector<WaveDrop> drops;
};

/// Buffers reused across steps (sized on the first call; no allocation after).
struct WaveScratch {
    Grid outflow;       // 1/s: sum of outgoing face velocities per cell / cellSize (positivity limiter), nx x ny
    Grid fluxU, fluxV;  // m^2/s: face volume fluxes of the step, shaped like faceU / faceV
    Grid nextU, nextV;  // m/s: new face velocities; swapped with faceU / faceV at the end of a step
    std::vector<float> rowMaxDepth, rowMaxSpeed;  // per-row maxima for the internal CFL check
    int lastSubsteps = 0;                         // internal sub-steps taken by the last waveStep (1 normally)
};

/// The largest stable time step (s): courant * cellSize / (sqrt(g h_max) + |u|_max),
/// with h_max raised by pending drop heights and the swell amplitude. Finite and
/// positive for any finite state (a dry terrain uses h = dryDepth).
float waveMaxDt(const TerrainState& s, const WaveSettings& settings);

/// Advances water depth and face velocities by dt (sub-stepping internally
/// when dt exceeds maxCourant for the current state). Requires the layers
/// water and faceVelocity. Closed boundaries except where a swell enters.
/// Note: the storage of s.faceU / s.faceV is swapped with scratch buffers, so
/// pointers into them do not survive a step (their contents do).
void waveStep(TerrainState& s, const WaveSettings& settings, float dt, WaveScratch& scratch);

}  // namespace terrain
