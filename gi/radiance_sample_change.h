#pragma once
// How far the samples an indirect scan reads from an RGB radiance pyramid
// (gi/radiance_pyramid.h) have moved since an anchor, per receiver tile:
// taken from the pyramids themselves, not bounded through the filters.
//
// Step i of azimuth phi reads, for receiver (X, Y), two texels of its field
// (scanStepInfo's taps: a level at the receiver grid, or the full-resolution
// radiance for a raw step) and blends them with weights 1 - f and f that
// every receiver shares at that step. Over a tile's receivers the taps fill
// two shifted copies of the tile, cut to the receivers whose sample lies
// inside the field: with A and B the largest |level - anchor level| over
// each copy (max over the channels; block maxima of gi/change_bound.h,
// each copy rounded out to the blocks that cover it, maxChangeCoveringBox),
// every sample of the step moved by at most (1 - f) A + f B. Bounding the samples through the filters instead, as the
// heights' slopes are (gi/change_bound.h), charges a sample with the largest
// change of any cell within its reach, weighed by the filter's largest tap;
// here a far, filtered sample of a small change counts by what it really
// moved. The price is the anchor's pyramid levels, kept beside the anchor's
// radiance (3 channels x levels x receivers floats).
//
// The coarse levels (from kOctaveBoundFrom on) are the exception: their
// change is bounded through the octave images B_o they synthesise, kept
// beside the anchor's radiance in place of those levels (below).
//
// A level texel reads the radiance within the reach of its octaves' B-spline
// synthesis (gi/change_bound.h, levelReachCells: R_o = 2.5 2^o - 0.5 cells
// for octave o, the coarser octave of a blended level), so where the
// radiance equals the anchor's outside a box of texels, each level equals
// the anchor's level outside that box dilated by its reach.
#include <span>
#include <vector>

#include "core/grid.h"
#include "gi/change_bound.h"
#include "gi/pyramid.h"
#include "gi/radiance_pyramid.h"

namespace terrain::gi {

/// The levels from this octave on are bounded through their octave images
/// (below): their reach spans most of the field (2.5 2^o cells), so any
/// change makes the whole level differ from the anchor's and comparing them
/// texel by texel was most of a local change's plan, where B_o holds 4^-o
/// as many texels as the field. The finer levels, whose samples near
/// receivers read, are compared texel by texel. Chosen by the re-gathered
/// shares of the incremental suite's cases (README).
inline constexpr int kOctaveBoundFrom = 4;

/// The anchor's pyramid levels and this frame's change of each level: the
/// finer levels texel by texel, the levels from exactLevels on through the
/// octave images they synthesise: a level texel is (1 - q) S_o + q S_(o+1),
/// and a texel of S_o a combination of B_o's texels under its B-spline taps
/// with non-negative weights summing to 1, so it moves by at most the
/// largest move of those texels.
struct RadianceLevelChange {
    int octaveBoundFrom = kOctaveBoundFrom;  // set before the first recordAnchorLevels (1 or more)
    int levels = 0, nxr = 0, nyr = 0;
    int exactLevels = 0;                   // levels [0, exactLevels) compared texel by texel
    std::vector<Grid> anchor;              // channel c's level l at [c * exactLevels + l] (nxr x nyr, no padding)
    std::vector<MaxChangePyramid> change;  // per exact level: max over the channels of |level - anchor|, rounded up
    int firstOctave = 0, octaves = 0;      // the octave images [firstOctave, octaves) the other levels read
    std::vector<Grid> anchorOctaves;       // channel c's B_o at [c * (octaves - firstOctave) + o - firstOctave]
    std::vector<MaxChangePyramid> octaveChange;  // per such octave: max over the channels of |B_o - anchor's|
    bool fits(const RadiancePyramid& p) const;
};

/// Copies p's levels as the anchor's (whole; or, on the same grid, the rows
/// of each level that may differ where the radiance changed only inside the
/// box `changed` of texels).
void recordAnchorLevels(const RadiancePyramid& p, RadianceLevelChange& out, CellBox changed = {});

/// Builds each level's change from the anchor to `now` (out.change), where
/// the radiance differs from the anchor's only inside the box `changed` of
/// texels (every texel by default): only the level texels within each
/// level's reach of it are compared (the others are 0). Throws InputError
/// when `now` is not of the anchor's grid (fits).
void buildLevelChanges(const RadiancePyramid& now, CellBox changed, RadianceLevelChange& out);

/// Per tile of tileReceivers receivers and each azimuth phi[j] of the scan
/// (radians; the scan's own values, FoldedWedgeOperator::phi, so that the
/// taps are the ones it reads), the largest move of the samples its
/// receivers read (tileBound[t m + j], m = phi.size(), tiles row-major as
/// boundSlopeChange), and per tile and distance group (gi/pyramid.h) the
/// largest over the azimuths (groupBound[t kDistanceGroups + g]): level
/// steps from `levels.change`, raw steps from `raw`, the full-resolution
/// change (max over the channels) of the radiance. `field` is channel 0's
/// pyramid of this frame (its steps and level map, the same in every
/// channel). Throws InputError when tileReceivers < 1, there is no azimuth
/// or the sizes differ.
void boundSampleChangeFromLevels(const MaxChangePyramid& raw, const RadianceLevelChange& levels,
                                 const HeightPyramid& field, int tileReceivers, std::span<const double> phi,
                                 std::vector<float>& tileBound, std::vector<float>& groupBound);

}  // namespace terrain::gi
