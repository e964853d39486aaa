#pragma once
// The terrain state: structure of arrays, one float grid per quantity.
// Each column names its unit and the stages that read (R) or write (W) it.
// A scene allocates only the layers its stages need; an unused layer is an
// empty grid (model only what a scene needs).
#include <cstdint>
#include <string>

#include "core/grid.h"

namespace terrain {

/// Which optional layers a terrain carries.
struct LayerSet {
    bool water = false;         // water depth (hydraulic, waves)
    bool sediment = false;      // suspended sediment (hydraulic)
    bool pipes = false;         // virtual-pipe outflow fluxes + cell velocity (hydraulic)
    bool faceVelocity = false;  // staggered face velocities (waves)
};

struct TerrainState {
    int nx = 0;             // columns (x, along image columns)
    int ny = 0;             // rows (y, along image rows, row 0 first)
    float cellSize = 1.0f;  // metres between grid points, both axes

    // --- always present ---------------------------------------------------
    Grid bedrock;  // m, elevation of the rock surface.       R: all  W: hydraulic, thermal
    Grid soil;     // m, loose material above bedrock (>= 0). R: all  W: hydraulic, thermal

    // --- water ------------------------------------------------------------
    Grid water;      // m, water depth (>= 0).                R: hydraulic, waves, render  W: hydraulic, waves
    Grid suspended;  // m, sediment carried by the water, as a material
                     // thickness per cell (>= 0).            R/W: hydraulic

    // --- virtual pipes (Mei et al. 2007), cell centred -------------------
    Grid fluxL, fluxR, fluxT, fluxB;  // m^3/s outflow to the -x, +x, -y, +y neighbour. R/W: hydraulic
    Grid velX, velY;                  // m/s water velocity at the cell centre.        W: hydraulic

    // --- staggered shallow water (waves) ----------------------------------
    Grid faceU;  // m/s, x velocity on vertical faces: (nx + 1) x ny, face x sits between cells x-1 and x.  R/W: waves
    Grid faceV;  // m/s, y velocity on horizontal faces: nx x (ny + 1).                                    R/W: waves

    double time = 0.0;  // s, simulated time
    std::int64_t tick = 0;

    /// Allocates bedrock/soil and the requested layers, all zero.
    void allocate(int w, int h, float cell, const LayerSet& layers);

    /// Total height of the ground: bedrock + soil at one cell.
    float ground(int x, int y) const { return bedrock(x, y) + soil(x, y); }
    /// Writes bedrock + soil into out (resized to nx x ny).
    void groundHeight(Grid& out) const;

    bool hasWater() const { return !water.empty(); }
};

/// Throws InputError naming the layer when any value is NaN or Inf.
void checkFinite(const TerrainState& s);

/// Throws InputError when a grid size or cell size is absurd (0 or negative
/// sizes, more than kMaxGridSide (core/size_limits.h) per side, non-finite or
/// non-positive cell size).
void checkDimensions(int nx, int ny, float cellSize);

/// 64-bit hash over every byte of the simulation state (all layers, sizes,
/// cell size, time and tick). Independent of thread count.
std::uint64_t hashState(const TerrainState& s);

/// The hash as 16 lower-case hexadecimal digits.
std::string hashHex(std::uint64_t h);

}  // namespace terrain
