#pragma once
// The water mesh pass's triangles that can show water.
//
// kSurfacePointFragment (render/shaders.h) drops every water fragment
// shallower than its threshold, and a fragment's depth interpolates its
// triangle's corners: a triangle whose corners are all shallower shows
// nothing. On eroded terrain a film of rain water reaches into every chunk
// yet shows on few pixels, so the water pass draws only the triangles with a
// corner at least kShownWaterDepth deep. The margin under the fragment
// shader's threshold lies far above the interpolation's rounding, so the
// image is the same as with every triangle; the order of the kept triangles
// is kept too (where water overlaps water on screen, the last drawn shows).
#include <cstdint>
#include <vector>

namespace terrain::render {

inline constexpr float kShownWaterDepth = 0.0199f;  // m; the fragment shader's threshold is 0.02

/// One byte per grid point, row-major: 1 where the water depth is at least
/// kShownWaterDepth. `heights`: 2 floats per point (ground, water depth).
void markShownWater(const std::vector<float>& heights, std::vector<std::uint8_t>& shown);

/// Where kMeshVertex puts a mesh's vertex ids: vertex id -> grid point
/// min(origin + (id % row, id / row) * step, grid - 1).
struct MeshPlacement {
    int originX = 0, originY = 0, step = 1, row = 1;
    int nx = 1, ny = 1;  // the grid
};

/// Appends to `out`, in order, the triangles of `triangles` (vertex ids,
/// three per triangle, `count` ids) placed by `p` that have a corner where
/// `shown` is 1; returns how many ids it appended.
std::int64_t appendShownTriangles(const std::uint16_t* triangles, std::int64_t count, const MeshPlacement& p,
                                  const std::vector<std::uint8_t>& shown, std::vector<std::uint16_t>& out);

/// The full grid's triangles (two per quad, the split of the full grid's
/// index buffer) that have a corner where `shown` is 1, in the full grid's order.
void shownGridTriangles(int nx, int ny, const std::vector<std::uint8_t>& shown, std::vector<std::uint32_t>& out);

}  // namespace terrain::render
