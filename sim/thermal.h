#pragma once
// Thermal erosion: material on slopes steeper than the talus angle moves to
// its lower neighbours. Two gather passes (outflow per cell, then each cell
// takes what its neighbours send it), so results do not depend on threads.
#include "sim/terrain.h"

namespace terrain {

struct ThermalSettings {
    float talusAngleDeg = 33.0f;  // degrees: slopes above tan(talus) shed material
    float rate = 0.5f;            // 1/s: fraction of the excess moved per second (clamped per step)
    bool erodeBedrock = true;     // true: bedrock above the talus crumbles into soil too
};

struct ThermalScratch {
    Grid ground;  // m, bedrock + soil before the step
    Grid out;     // m, material leaving each cell this step
    Grid share;   // out / sum of the cell's excess heights over its neighbours
};

/// Moves material from cells steeper than the talus angle to lower
/// neighbours. Conserves bedrock + soil exactly (up to float rounding).
void thermalStep(TerrainState& s, const ThermalSettings& settings, float dt, ThermalScratch& scratch);

/// The largest slope (rise over run, in the 8-neighbourhood with diagonal
/// distances) anywhere on the ground surface; used by tests.
float maxGroundSlope(const TerrainState& s);

}  // namespace terrain
