#pragma once
// The images `terrain gi` writes: the shade map (.png sRGB after an
// exposure, or .exr linear), the ambient map (.npy or .exr) and the indirect
// light alone (.npy, .exr, or .png in false colour).
#include <array>
#include <string>

#include "core/grid.h"

namespace terrain::app {

/// Lower-case extension with its dot ("" when none).
std::string extensionOf(const std::string& file);

/// RGB shade: .exr as is; .png times `exposure`, clamped, sRGB-encoded.
void writeShade(const std::string& file, const std::array<Grid, 3>& rgb, float exposure);

/// The ambient map: .npy or .exr.
void writeAmbient(const std::string& file, const Grid& ambient);

/// The indirect light: .npy (rows, columns, 3) or .exr as is; .png as a
/// false-colour map of its luminance from 0 (black) to its 99th percentile
/// (white), through blue, magenta, orange and yellow, so that small
/// differences of a dim light show.
void writeIndirect(const std::string& file, const std::array<Grid, 3>& rgb);

}  // namespace terrain::app
