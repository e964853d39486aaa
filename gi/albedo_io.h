#pragma once
// Albedo maps for the GI command line: a uniform R,G,B or an 8-bit
// sRGB PNG (decoded to linear reflectance) of the height field's size.
#include <string>
#include <vector>

#include "gi/shading.h"

namespace terrain::gi {

/// Parses "R,G,B" (each in [0, 1]) or reads a PNG of exactly nx x ny pixels.
/// Throws InputError (bad text, values out of range, size mismatch) or
/// IoError (unreadable file).
AlbedoMap loadAlbedo(const std::string& spec, int nx, int ny);

/// Per-texel Phong exponents for the command line (`--phong-exponent`): a
/// 16-bit greyscale PNG of exactly nx x ny pixels, sample v in 0..65535 mapped
/// log-uniformly to S = lo (hi / lo)^(v / 65535) (so equal steps of v are
/// equal ratios of S: the lobe width e^{-l^2/(2S)} varies smoothly), set into
/// map with setPhongExponentMap. Throws InputError (size mismatch, bad range)
/// or IoError (unreadable file).
void loadPhongExponentMap(const std::string& file, int nx, int ny, float lo, float hi, AlbedoMap& map);

}  // namespace terrain::gi
