#pragma once
// Holes in a heightmap (a DEM's nodata cells) filled from their surroundings.
#include <cstdint>
#include <vector>

#include "core/grid.h"

namespace terrain {

/// Gives every cell whose mask is set the value of its nearest unmasked
/// cell, in 4-connected steps. Ties go to the cell the breadth-first search
/// reaches from first: sources in row order, neighbours left, right, up,
/// down; so the result is the same on every run. Returns the cells filled;
/// InputError when every cell is masked (there is nothing to fill from).
std::int64_t fillNodata(Grid& g, const std::vector<std::uint8_t>& masked);

}  // namespace terrain
