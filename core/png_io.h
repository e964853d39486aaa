#pragma once
// PNG files: 16-bit greyscale heightmaps, 8-bit RGB(A) images. Writers are
// atomic and checked (core/file_io.h); readers throw IoError naming the file
// and what is wrong, and check the declared image size (core/size_limits.h)
// and the file's length before allocating anything of that size.
//
// Heightmaps are greyscale. 16-bit samples are read as they are. 8-bit (and
// 1, 2, 4-bit) greyscale is accepted, scaled to the 16-bit range (v * 257):
// plenty of DEM exports are 8-bit and still make a usable terrain, and the
// caller learns the depth (sourceBitDepth) to warn that 256 levels show as
// terraces. Colour PNGs (RGB, RGBA, palette) are rejected: a colour image has
// no single defined height (luminance weights, or DEM encodings that spread
// one height over the channels, would each give a different terrain), so
// guessing would silently produce a wrong one. An alpha channel on a grey
// image is ignored.
#include <cstdint>
#include <string>
#include <vector>

#include "core/grid.h"

namespace terrain {

/// What a PNG's header (IHDR) declares.
struct PngHeader {
    int width = 0;
    int height = 0;
    int bitDepth = 0;
    int colorType = 0;  // libpng's PNG_COLOR_TYPE_* value
};

/// Reads and checks a PNG's signature and header without decoding it:
/// IoError unless the size is within kMaxGridSide per side and the file is
/// long enough to hold that many pixels (a deflate stream expands at most
/// 1032 times).
PngHeader peekPngHeader(const std::string& file);

/// Reads a greyscale PNG (see above) as heights:
/// height = zOffset + zScale * value, value the 16-bit sample (0..65535).
/// Row 0 of the image is y = 0. A non-finite height is an IoError naming the
/// first such pixel. sourceBitDepth, when given, receives the file's depth.
Grid readPngHeightmap(const std::string& file, float zScale = 1.0f, float zOffset = 0.0f,
                      int* sourceBitDepth = nullptr);

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
