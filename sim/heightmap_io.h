#pragma once
// Heightmaps by file extension: 16-bit PNG (core/png_io.h) or OpenVDB
// (sim/vdb_io.h).
#include <string>

#include "core/grid.h"

namespace terrain {

/// Reads a heightmap by extension: .png (with zScale/zOffset) or .vdb
/// (cellSize taken from the file when cellSizeOut is given).
Grid readHeightmap(const std::string& file, float zScale, float zOffset, float* cellSizeOut = nullptr);

}  // namespace terrain
