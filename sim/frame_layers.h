#pragma once
// A frame's named layers: the one list every frame writer (OpenVDB grids,
// EXR channels, GeoTIFF bands) takes its names, units and order from.
// Names are flat lower-case words (no dots: OpenEXR readers such as
// OpenImageIO and Houdini read `a.b` as channel b of layer a).
#include <string>
#include <vector>

#include "core/grid.h"
#include "sim/terrain.h"

namespace terrain {

class Simulation;

struct FrameLayer {
    std::string name;  // grid / channel / band name
    std::string unit;  // SI unit, "1" for a fraction
    Grid grid;         // nx x ny, row 0 first
};

struct FrameLayers {
    float cellSize = 1.0f;  // m between grid points
    std::vector<FrameLayer> layers;

    std::vector<std::string> names() const;
    std::vector<const Grid*> grids() const;
    /// The layer of that name, or nullptr.
    const FrameLayer* find(const std::string& name) const;
};

/// The state's own layers, in this order: height (bedrock + soil), bedrock,
/// soil, then water and sediment (suspended) when the terrain has them.
FrameLayers stateLayers(const TerrainState& s);

/// stateLayers, then the hydrology maps the scene has (sim/hydrology.h):
/// discharge, velocity, sediment_flux (with suspended sediment) when the
/// water flows; erosion, deposition, net_erosion when the ground moves;
/// wetness when the water is tracked.
FrameLayers frameLayers(const Simulation& sim);

}  // namespace terrain
