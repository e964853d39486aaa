#pragma once
// Terrain I/O: 16-bit PNG heightmaps, 8-bit RGB images, OpenVDB layers.
// Every writer writes to a temporary name beside the target and renames it,
// so a failure never leaves a half-written file in place of a good one.
// Every reader throws IoError naming the file and what is wrong.
#include <cstdint>
#include <string>
#include <vector>

#include "sim/grid.h"
#include "sim/terrain.h"

namespace terrain {

/// Reads a greyscale PNG (16-bit, or 8-bit scaled to 16-bit) as heights:
/// height = zOffset + zScale * value, value the raw 16-bit sample (0..65535).
/// Row 0 of the image is y = 0. Colour PNGs are rejected.
Grid readPngHeightmap(const std::string& file, float zScale = 1.0f, float zOffset = 0.0f);

/// Writes heights as a 16-bit greyscale PNG: value = round((h - zOffset) / zScale),
/// clamped to 0..65535.
void writePngHeightmap(const std::string& file, const Grid& height, float zScale, float zOffset);

/// Picks zScale/zOffset so the grid's range maps onto 0..65535.
void pngRangeFor(const Grid& height, float& zScale, float& zOffset);

/// Writes 8-bit RGB (3 bytes per pixel, row 0 first) or RGBA when channels = 4.
void writePngRgb(const std::string& file, int width, int height, const std::vector<std::uint8_t>& pixels,
                 int channels = 3);

/// Writes 8-bit or 16-bit image data as any PNG (channels 1..4), generic form.
void writePng(const std::string& file, int width, int height, int channels, int bitDepth, const void* pixels);

/// Writes the terrain's layers as 2-D OpenVDB FloatGrids named `height`
/// (bedrock + soil), `bedrock`, `water`, `sediment` (suspended, when present),
/// with the cell size in the transform (voxel size), z index 0.
void writeVdb(const std::string& file, const TerrainState& s);

/// Reads a .vdb written by writeVdb (or any file with a FloatGrid named
/// `height`, or else the first FloatGrid): fills bedrock (and soil = 0, or the
/// water/sediment layers if present and allocated) and the cell size.
/// Rejects non-float grids, 3-D grids, non-uniform voxels and NaN/Inf values.
void readVdb(const std::string& file, TerrainState& s, const LayerSet& layers);

/// Reads a heightmap by extension: .png (with zScale/zOffset) or .vdb
/// (cellSize taken from the file when cellSizeOut is given).
Grid readHeightmap(const std::string& file, float zScale, float zOffset, float* cellSizeOut = nullptr);

/// Writes bytes to `file` atomically (temporary file + rename).
void writeFileAtomic(const std::string& file, const std::string& bytes);

/// Returns a temporary name beside `file` for an atomic write.
std::string temporaryNameFor(const std::string& file);

/// Renames tmp onto file, removing tmp and throwing IoError on failure.
void commitTemporary(const std::string& tmp, const std::string& file);

}  // namespace terrain
