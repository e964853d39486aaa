#pragma once
// Hydrology maps: what the water did, for frames a GIS or Houdini can read.
//
// Per frame (derived from the state as it is after a tick):
//   discharge      m^3/s  |(Qx, Qy)|, the cell's volume flow. Pipe model:
//                         Qx = ((inL - outL) + (outR - inR)) / 2, the mean of
//                         the signed flows (+x) through its left and right
//                         pipes in the last tick, Qy likewise; the same pipe
//                         fluxes that moved the water, so the sum of a
//                         cell's face flows times dt is exactly its volume
//                         change before rain and evaporation (tested).
//                         Waves: Qx = c * depth * (faceU(x) + faceU(x+1)) / 2.
//   velocity       m/s    |(u, v)| at the cell centre: the pipe model's
//                         velX/velY (its discharge over the mean wet cross
//                         section), or the mean of the two face velocities
//                         per axis for waves.
//   sediment_flux  m^3/s  discharge * suspended / depth: the volume of
//                         material carried through the cell per second (0
//                         where the depth is under kWetDepth or nothing is
//                         suspended).
// Accumulated over the run (from the first tick of a Simulation):
//   erosion        m      sum over ticks of the ground (bedrock + soil)
//                         decrease of each cell, in double precision
//   deposition     m      sum of the increases; erosion - deposition is the
//                         ground at the start minus the ground now
//   net_erosion    m      erosion - deposition
//   wetness        1      fraction of ticks after which the water was at
//                         least kWetDepth deep
#include <cstdint>
#include <vector>

#include "sim/terrain.h"

namespace terrain {

/// m: water at least this deep counts as wet (a film of rain on a slope,
/// some millimetres under the default rain and evaporation, does not).
inline constexpr float kWetDepth = 0.01f;

/// The run-accumulated maps. Updated once per tick by the Simulation; the
/// update writes each cell from that cell alone, so it is the same for any
/// thread count, and allocates nothing after start().
class HydrologyAccumulator {
public:
    /// Sizes the maps for s: ground maps when the scene moves the ground,
    /// wet ticks when it has water; neither = tracks nothing.
    void start(const TerrainState& s, bool trackGround, bool trackWater);

    /// Adds row y of one tick: groundBefore is bedrock + soil before the
    /// tick, the others the layers after it (water null without water). The
    /// Simulation calls it from the pass that already streams these rows for
    /// its change report, then countTick() once.
    void accumulateRow(int y, const float* bedrock, const float* soil, const float* groundBefore, const float* water);
    void countTick() { ++ticks_; }

    bool tracksGround() const { return !erosion_.empty(); }
    bool tracksWater() const { return !wetTicks_.empty(); }
    std::int64_t ticks() const { return ticks_; }

    /// m, double: the exact sums the float maps below are rounded from.
    const std::vector<double>& erosion() const { return erosion_; }
    const std::vector<double>& deposition() const { return deposition_; }

    void erosionMap(Grid& out) const;
    void depositionMap(Grid& out) const;
    void netErosionMap(Grid& out) const;
    /// Wet ticks / ticks, in [0, 1]; 0 everywhere before the first tick.
    void wetnessMap(Grid& out) const;

private:
    int nx_ = 0, ny_ = 0;
    std::int64_t ticks_ = 0;
    std::vector<double> erosion_, deposition_;
    std::vector<std::uint32_t> wetTicks_;  // a run of 2^32 ticks would take years
};

/// Whether the state carries the water flow the per-frame maps need (the
/// pipe fluxes or the face velocities).
bool hasWaterFlow(const TerrainState& s);

/// The pipe model's signed volume flows (m^3/s) through a cell's four faces
/// in the last tick, positive along +x / +y: west = inL - outL, east =
/// outR - inR, north (the -y face) = inU - outT, south = outB - inD, with a
/// neighbour's flux taken as 0 across the domain edge as the model does.
/// The cell's water volume changed by dt * (west - east + north - south)
/// besides rain and evaporation. Requires the pipe layers.
struct FaceFlows {
    float west = 0.0f, east = 0.0f, north = 0.0f, south = 0.0f;
};
FaceFlows cellFaceFlows(const TerrainState& s, int x, int y);

/// The cell's volume flow (Qx, Qy), m^3/s, as defined above.
void cellDischarge(const TerrainState& s, int x, int y, float& qx, float& qy);

/// Per-frame maps (resized to nx x ny); require hasWaterFlow(s).
void dischargeMap(const TerrainState& s, Grid& out);
void velocityMap(const TerrainState& s, Grid& out);
/// Sediment flux from the discharge map dischargeMap(s) gave.
void sedimentFluxMap(const TerrainState& s, const Grid& discharge, Grid& out);

}  // namespace terrain
