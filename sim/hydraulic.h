#pragma once
// Hydraulic erosion with the virtual-pipe model of Mei, Decaudin & Hu 2007
// ("Fast Hydraulic Erosion Simulation and Visualization on GPU"), with a
// conservative (flux-form) sediment transport instead of the paper's
// semi-Lagrangian step, which creates and destroys sediment.
//
// One step, as two gather passes over cells (no pass reads what it writes):
//   pass A: rain (uniform, cancels in head differences); outflow fluxes
//           through four pipes, scaled (K) so that depth never goes negative;
//           sin^2 of the ground tilt; sediment per unit outflow (m / d * dt / c^2)
//   pass B: water update from the net pipe volume; velocity field; sediment
//           transport in flux form with the pass-A fluxes (what leaves one
//           cell is exactly what its neighbour computes it receives);
//           capacity C = Kc * max(sin(tilt), minTilt) * |v| * min(depth, maxErosionDepth);
//           dissolve soil (then bedrock, scaled by bedrockHardness) or deposit;
//           evaporation.
// Material moves between soil/bedrock and the water by realised differences,
// so bedrock + soil + suspended is conserved to rounding with closed edges.
#include "sim/terrain.h"

namespace terrain {

struct HydraulicSettings {
    float gravity = 9.81f;          // m/s^2
    float pipeArea = 1.0f;          // pipe cross-section, in units of cellSize^2 (scaled by cellSize^2)
    float rainRate = 2.0e-5f;       // m/s of water added everywhere (0 = no rain); 2e-5 m/s = 72 mm/h
    float capacity = 1.0f;          // Kc, sediment capacity constant
    float dissolve = 0.5f;          // Ks, 1/s fraction of the capacity deficit dissolved per second
    float deposit = 1.0f;           // Kd, 1/s fraction of the excess deposited per second
    float evaporation = 0.015f;     // Ke, 1/s fraction of water evaporated per second
    float minTilt = 0.05f;          // lower bound on sin(tilt) in the capacity, so flat cells still erode a little
    float bedrockHardness = 0.3f;   // Ks multiplier for bedrock once the soil is gone (0..1)
    float maxErosionDepth = 10.0f;  // m, water depth beyond which capacity stops growing (depth limiter)
    bool closedBoundary =
        true;  // true: no flux leaves the domain; false: water (and its sediment) pours out at the edges
};

/// Per-run scratch buffers (explicit state, reused across ticks).
struct HydraulicScratch {
    Grid conc;  // suspended * dt / (depth * cellSize^2): sediment sent per m^3/s of outflow this step
    Grid sin2;  // max(sin^2(local tilt), minTilt^2) of the ground before this step's erosion
};

/// The largest stable time step (s) for the pipe model on this terrain:
/// 0.5 * sqrt(cellSize / (2 g pipeArea)), half the linear stability limit of
/// the explicit flux/depth update (derivation in hydraulic.cpp). Depth does
/// not enter: pipe waves travel at sqrt(g pipeArea cellSize), and the
/// K-scaling keeps depths non-negative for any dt.
float hydraulicMaxDt(const TerrainState& s, const HydraulicSettings& settings);

/// Advances water, fluxes, velocity, soil, bedrock and suspended sediment by dt.
/// Requires the layers water, sediment and pipes. Does not advance s.time or
/// s.tick (the caller owns the clock).
void hydraulicStep(TerrainState& s, const HydraulicSettings& settings, float dt, HydraulicScratch& scratch);

}  // namespace terrain
