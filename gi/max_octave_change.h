#pragma once
// How far the max-decimated octave images of a height pyramid
// (HeightPyramid::maxOctaves, peak keeping) can have moved between two
// height fields, block by block.
//
// Octave o's texel is the maximum M of the heights over its block of
// 2^o x 2^o cells. The change bounds of gi/change_bound.h and
// gi/receiver_azimuth_bound.h charge a block the largest |dh| over all its
// cells, yet a cell far below the block's peak cannot move the maximum.
// With M and M' the maxima before and after, say M' >= M, and k the cell
// holding M': M' - M <= h'_k - h_k <= |dh_k|, and h'_k = M' >= min(M, M').
// So
//     |M' - M| <= max |dh_i| over the cells i of the block with
//                 max(h_i, h'_i) >= min(M, M')                       (1)
// (the other case is the same with before and after swapped). The bound
// nests: a cell that counts in a block counts in its sub-block too (the
// sub-block's min(M, M') is no higher), and the sub-block holding it has a
// maximum, before or after, no lower than the block's min(M, M'). So octave
// o's bound is the largest of its four octave o - 1 sub-blocks' bounds over
// those whose larger maximum reaches the block's min(M, M'), octave 0's the
// cells' own |dh| (rounded up), which bounds (1) from above in one pass per
// octave. On an eroding landscape, where the heights move in the valleys and
// the peaks stay, it is close to the true change of the maxima and far
// below the blocks' largest |dh| (bench/results/gi_bound_diagnosis.md).
#include <span>
#include <vector>

#include "core/grid.h"

namespace terrain::gi {

/// Per octave o >= 1 (at index o - 1, the size of HeightPyramid::maxOctaves'
/// image of that octave), a bound on |change| of each of its texels.
struct MaxOctaveChange {
    std::vector<Grid> bound;
    Grid cells;  // octave 0: each cell's |dh|, rounded up (kept: no allocation once sized)
};

/// The bounds (1) between the heights `before` and `after` (finite, the same
/// size) whose max-decimated octaves are maxBefore and maxAfter (the layout of
/// HeightPyramid::maxOctaves: octave o at index o - 1, each image half the
/// last one's size rounded up, a 2 x 2 maximum with the last row and column
/// replicated). Throws InputError when the sizes differ.
void boundMaxOctaveChange(ConstGridView before, ConstGridView after, std::span<const Grid> maxBefore,
                          std::span<const Grid> maxAfter, MaxOctaveChange& out);

}  // namespace terrain::gi
