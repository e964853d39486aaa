#pragma once
// The blocking-slope bound of gi/change_bound.h per receiver, for the whole
// field at once. A tile's bound (boundOfTile) charges each of its receivers
// with the largest height change within reach of any of them, so a change
// anywhere in the tile counts as if it lay next to each receiver; per
// receiver the bound is far smaller where changes are scattered
// (`terrain_bench gi-bound-diagnosis`, "Granularity" in README). Through
// boundSlopeChange with tiles of one receiver it costs a box query per
// receiver and step. Here each step's square (stepSquares) comes from one
// square max filter over the change pyramid's finest level whose blocks
// cover the square within a few blocks of the receiver's: one read per
// receiver and step, the same bound or a little larger where the blocks
// reach past the square.
#include <vector>

#include "gi/change_bound.h"
#include "gi/pyramid.h"

namespace terrain::gi {

/// Per receiver (row-major, pyr.nxr x pyr.nyr), a bound on |change| of
/// every blocking slope (metres per metre): at least boundOfTile's with
/// tiles of one receiver, and equal to it where no filter reaches past the
/// step's square (changes nowhere or everywhere alike). Throws InputError
/// when the sizes of dh and the pyramid differ.
void boundSlopeChangePerReceiver(const MaxChangePyramid& dh, const HeightPyramid& pyr, std::vector<float>& out);

}  // namespace terrain::gi
