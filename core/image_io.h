#pragma once
// Float image files: float EXR and NumPy .npy writers (atomic and checked,
// core/file_io.h), and equirectangular environment maps (.exr, Radiance
// .hdr) for lights. Every function throws IoError naming the file.
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

/// Half-float OpenEXR with 1 channel ("Y") or 3 ("R", "G", "B"): half floats
/// are all an image viewer needs (use .npy for exact float32 values).
void writeExr(const std::string& file, const std::vector<const Grid*>& channels);

/// Reads an RGB equirectangular image (.exr or .hdr): 3 floats per pixel, row 0 first.
std::vector<float> readEquirect(const std::string& file, int& width, int& height);

/// Reads the R, G, B channels of a single-part OpenEXR image (missing
/// channels read as 0). The header is checked before OpenEXR sees it
/// (data window within kMaxGridSide per side, the file long enough for it).
std::vector<float> readExrRgb(const std::string& file, int& width, int& height);

/// Reads a Radiance RGBE (.hdr) image, its size checked against kMaxGridSide
/// and the file's length before anything is allocated.
std::vector<float> readHdrRgb(const std::string& file, int& width, int& height);

}  // namespace terrain
