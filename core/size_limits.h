#pragma once
// The largest grid or image the engine accepts, checked against what a file
// declares before anything of that size is allocated.
#include <cstdint>
#include <string>

namespace terrain {

/// Largest side, in cells or pixels, of any grid the engine allocates and of
/// any image it reads (heightmaps, exponent and albedo maps, environment
/// maps, OpenVDB layers). A 16384² layer is 1 GiB of floats; a terrain holds
/// several layers and the GI several more buffers of that size, so larger
/// grids do not fit the machines the engine runs on. Readers check a file's
/// declared size against it before allocating, so a small hostile file cannot
/// ask for gigabytes.
inline constexpr int kMaxGridSide = 16384;

/// Throws IoError naming `file` unless width and height are each 1 to
/// kMaxGridSide (`what` names the unit: "pixels", "cells").
void checkDeclaredSize(const std::string& file, std::int64_t width, std::int64_t height, const char* what);

}  // namespace terrain
