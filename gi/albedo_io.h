#pragma once
// Albedo maps for the GI command line (issue 4): a uniform R,G,B or an 8-bit
// sRGB PNG (decoded to linear reflectance) of the height field's size.
#include <string>
#include <vector>

#include "gi/shading.h"

namespace terrain::gi {

/// Parses a comma-separated list of numbers ("1,0.5,2"); throws InputError
/// naming `option` and the offending item when one is not a number.
std::vector<float> parseNumberList(const std::string& text, const std::string& option);

/// Parses "R,G,B" (each in [0, 1]) or reads a PNG of exactly nx x ny pixels.
/// Throws InputError (bad text, values out of range, size mismatch) or
/// IoError (unreadable file).
AlbedoMap loadAlbedo(const std::string& spec, int nx, int ny);

/// float32 .npy of an RGB map, shape (rows, columns, 3).
void writeNpyRgb(const std::string& file, const std::array<Grid, 3>& rgb);

}  // namespace terrain::gi
