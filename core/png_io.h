#pragma once
// PNG files: 16-bit greyscale heightmaps, 8-bit RGB(A) images. Writers are
// atomic (core/file_io.h); readers throw IoError naming the file and what is
// wrong.
#include <cstdint>
#include <string>
#include <vector>

#include "core/grid.h"

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

}  // namespace terrain
