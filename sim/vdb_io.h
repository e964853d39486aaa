#pragma once
// OpenVDB frames of the terrain's layers. The OpenVDB headers stay inside
// sim/vdb_io.cpp: they are expensive to compile.
#include <string>

#include "sim/frame_layers.h"
#include "sim/terrain.h"

namespace terrain {

/// Writes the terrain's layers as 2-D OpenVDB FloatGrids named `height`
/// (bedrock + soil), `bedrock`, `water`, `sediment` (suspended, when present),
/// with the cell size in the transform (voxel size), z index 0.
void writeVdb(const std::string& file, const TerrainState& s);

/// Writes each layer of a frame as such a grid, named as the layer, in the
/// frame's order (writeVdb is this with stateLayers(s)).
void writeVdbLayers(const std::string& file, const FrameLayers& frame);

/// Reads a .vdb written by writeVdb (or any file with a FloatGrid named
/// `height`, or else the first FloatGrid): fills bedrock (and soil = 0, or the
/// water/sediment layers if present and allocated) and the cell size.
/// Rejects non-float grids, 3-D grids, non-uniform voxels and NaN/Inf values.
void readVdb(const std::string& file, TerrainState& s, const LayerSet& layers);

}  // namespace terrain
