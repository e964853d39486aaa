#pragma once
// Which texel rows an incremental frame's direct shading must redo (the
// frame's one place for it; shadeTexels only takes the rows).
//
// A texel's direct light is a pure function of the visibility (environment
// and key lights) of the up to four receivers it interpolates, of its own
// height gradient, and of the lights and the albedo. When only the heights
// changed and the visibility was recomputed by tiles (gi/visibility_cache.h),
// a row's inputs are bit for bit the last frame's unless
//  - the heights of that row or of a row next to it changed (the gradient's
//    differences reach one cell, one-sided on the border rows), or
//  - it reads a receiver row of a tile whose environment or key-light
//    visibility was recomputed;
// the other rows keep their shading, identical to recomputing it.
#include <cstdint>
#include <vector>

#include "core/grid.h"
#include "gi/receiver_tiles.h"

namespace terrain::gi {

/// Flags (rows: one per texel row of `after`) the rows whose direct shading
/// must be redone after the heights went from `before` to `after` (same
/// size) and the visibility of the dirty tiles of `env` and `keys` (on the
/// receiver grid of `subsample`) was recomputed. Throws InputError when the
/// sizes differ.
void changedShadingRows(ConstGridView before, ConstGridView after, const ReceiverTiles& env, const ReceiverTiles& keys,
                        int subsample, std::vector<std::uint8_t>& rows);

}  // namespace terrain::gi
