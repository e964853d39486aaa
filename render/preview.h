#pragma once
// A CPU preview of a terrain frame: relief shading from a sun direction with
// a sky term, colour by altitude and slope, water blended by depth. Used by
// the headless demo and for quick looks at simulated frames; the OpenGL
// renderer with global illumination draws the real thing.
#include <cstdint>
#include <vector>

#include "sim/terrain.h"

namespace terrain {

struct PreviewSettings {
    float sunAzimuthDeg = 315.0f;   // from +x towards +y
    float sunElevationDeg = 35.0f;  // from the horizon up
    float verticalExaggeration = 1.0f;
    float zMin = 0.0f, zMax = 0.0f;  // colour ramp range; zMin == zMax: the frame's own range
};

/// Shades the terrain into 8-bit RGB (nx x ny pixels, row 0 = y 0).
void shadePreview(const TerrainState& s, const PreviewSettings& settings, std::vector<std::uint8_t>& rgb);

}  // namespace terrain
