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

/// float32 OpenEXR with one channel per grid, named as given (flat names:
/// OpenEXR readers take `a.b` as channel b of layer a), ZIP-compressed
/// (lossless), data and display window (0, 0) to (nx - 1, ny - 1), row 0 the
/// top row. A cell size > 0 is stored as the float attribute
/// `terrain:cellSize` (metres). The grids must share one size.
void writeExrChannels(const std::string& file, const std::vector<std::string>& names,
                      const std::vector<const Grid*>& grids, float cellSize = 0.0f);

/// The channels of an EXR read as float grids (half and uint converted).
struct ExrChannels {
    std::vector<std::string> names;  // in the file's order (OpenEXR sorts them by name)
    std::vector<Grid> grids;
    std::vector<std::string> available;  // every channel in the file, read or not
    float cellSize = 0.0f;               // the `terrain:cellSize` attribute, 0 when absent
};

/// Reads every channel of a single-part flat EXR, or only the one named
/// `only` (none when the file has no such channel). The header is checked
/// before OpenEXR sees it (core/exr_header.h); sub-sampled channels, more
/// than 2^28 floats (1 GiB) in all, and more than 1 MiB + 1032 bytes of
/// floats per byte of the file (beyond deflate's expansion) are refused.
/// IoError naming the file.
ExrChannels readExrChannels(const std::string& file, const std::string& only = "");

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
