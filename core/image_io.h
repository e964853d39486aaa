#pragma once
// Float image files: float EXR and NumPy .npy writers (atomic:
// temporary file + rename), and equirectangular environment maps (.exr,
// Radiance .hdr) for lights. Every function throws IoError naming the file.
#include <array>
#include <string>
#include <vector>

#include "core/grid.h"

namespace terrain {

/// float32 .npy, shape (rows, columns), row 0 = the first grid row.
/// Writes float32 data (C order) with the given shape as a .npy file (atomic).
void writeNpyArray(const std::string& file, const std::vector<std::size_t>& shape, const float* data);
void writeNpy(const std::string& file, const Grid& g);

/// float32 .npy of an RGB map, shape (rows, columns, 3).
void writeNpyRgb(const std::string& file, const std::array<Grid, 3>& rgb);

/// Half-float OpenEXR with 1 channel ("Y") or 3 ("R", "G", "B").
void writeExr(const std::string& file, const std::vector<const Grid*>& channels);

/// Reads an RGB equirectangular image (.exr or .hdr): 3 floats per pixel, row 0 first.
std::vector<float> readEquirect(const std::string& file, int& width, int& height);

}  // namespace terrain
