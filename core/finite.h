#pragma once
// The last guard of every stage: no NaN or infinity leaves it. Inputs are
// range-checked where they are read, so a non-finite result means a limit
// was too wide; these checks turn it into an error instead of an output.
#include <span>
#include <string>

#include "core/grid.h"

namespace terrain {

/// Whether every value is finite (no NaN, no infinity).
bool allFinite(std::span<const float> values);

/// Throws InputError "<what> has a non-finite value (v) at x=.., y=.." at the
/// grid's first NaN or infinity.
void requireFinite(const Grid& g, const std::string& what);

}  // namespace terrain
