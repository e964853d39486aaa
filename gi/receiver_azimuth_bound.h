#pragma once
// The per-azimuth blocking-slope bound of gi/change_bound.h for each
// receiver on its own, from the samples its scan reads rather than from the
// boxes that hold them.
//
// A scan sample is w_a f_l[a] + w_b f_l[b] (gi/visibility.h, stepSample):
// two texels of level l (or of the raw heights) with non-negative weights
// summing to 1. Every level blends, with non-negative weights, the B-spline
// syntheses (non-negative weights) of two octave images, each the blend of a
// mean and a maximum octave (gi/pyramid.cpp), and the octaves are 2 x 2
// means and maxima of the next finer one: |mean(a) - mean(b)| <= mean|a - b|
// and |max(a) - max(b)| <= max|a - b|. So the pyramid of the field |dh| built
// with the heights' own settings (the same levels, steps, layout and blends)
// holds at each texel a bound on |change| of the same texel of the height
// pyramid, and
//     |change of the slope of step i| <= (w_a D_l[a] + w_b D_l[b] + |dh_0|) / tau_i
// (dh_0: the receiver's own height's change). Its largest over a receiver's
// valid steps along azimuth j bounds the change of its maximum blocking slope
// along j, the counterpart of azimuthBoundOfTile for a tile of one receiver,
// in one vector read per step instead of a box query: a small change far away
// counts by what the filters let through to the very texels read, and a
// change beside the tile by its distance to this receiver, not to the tile's
// nearest one. The bound holds in real arithmetic, as gi/change_bound.h's,
// and is 0 where no height the receiver's samples read changed.
#include <span>
#include <vector>

#include "core/grid.h"
#include "gi/change_bound.h"
#include "gi/pyramid.h"
#include "gi/receiver_tiles.h"
#include "gi/visibility.h"

namespace terrain::gi {

/// One azimuth's walk over the |dh| pyramid: its steps' taps and the
/// receivers inside the domain at each (a receiver's valid prefix), up to
/// the first step from which on no step can move a slope by more than the
/// floor (below), and what those steps not walked can move one by.
struct ChangeWalk {
    struct Step {
        ScanStep step;
        int x0 = 0, x1 = -1, y0 = 0, y1 = -1;
        // the first tap of receiver (X, Y) at texel (k X + tapX, k Y + tapY)
        // of its field, the second one (nextX, nextY) further (ScanStepInfo)
        int k = 1, tapX = 0, tapY = 0, nextX = 0, nextY = 0;
        CellBox changed;  // the field's texels whose |dh| bound may not be 0
        int group = 0;    // the step's distance group (gi/pyramid.h)
    };
    std::vector<Step> steps;
    float tail = 0.0f;
};

/// The |dh| pyramid (above), the box of non-zero |dh| it was built from,
/// and the bounds' scratch (reused: no allocation once sized).
struct ChangeLevels {
    HeightPyramid bound;
    Grid input;                       // the |dh| `bound` was built from
    CellBox built = CellBox::none();  // holds every non-zero cell of `input`
    float largest = 0.0f;             // max |dh|
    bool valid = false;               // `bound` was built for the grid and settings of the last call
    std::vector<ChangeWalk> walks;
    std::vector<float> tails;
    // each azimuth's steps' taps (azimuth-major), kept while the pyramid's
    // layout and the azimuths are the same (a function of those alone)
    StepTableKey stepsKey;
    std::vector<ScanStepInfo> stepInfo;
    DirtySpans spans;
    std::vector<RowSpan> walkedBlocks;        // the blocks of receiver rows to walk
    std::vector<std::vector<float>> rows;     // per worker slot: a block's bounds per row and azimuth
    std::vector<std::vector<float>> columns;  // per worker slot: the row's gradient bounds' column maxima
};

/// Builds (or redoes, over the cells whose |dh| may differ from the last
/// build's: the old and the new box of non-zero |dh|) the |dh| pyramid of
/// `dh` (its level 0, |dh| per cell rounded up) for the pyramid `pyr` of
/// the field that changed by dh, with pyr's settings and steps: the heights',
/// or a radiance channel's (gi/radiance_pyramid.h; below). Nothing is redone
/// when dh is 0 everywhere (no walk reads the pyramid then; `largest` says
/// so) or equals the last build's input (a change undone and made again).
/// Throws InputError when the sizes of dh and pyr differ.
void buildChangeLevels(const MaxChangePyramid& dh, const HeightPyramid& pyr, ChangeLevels& out);

/// Whether `levels` holds a |dh| pyramid built for pyr's grid and settings
/// (a build for pyr then redoes only the cells its change reaches).
bool changeLevelsFit(const ChangeLevels& levels, const HeightPyramid& pyr);

/// Per receiver and azimuth phi_j (radians), a bound on |change| of its
/// maximum blocking slope's samples along phi_j (metres per metre; the
/// maximum's own rule multiplies it by blockingMaxLipschitz), azimuth-major:
/// out[(j nyr + Y) nxr + X]. With `only`, the receivers of its dirty tiles
/// alone; the others get 0. `floor`: precision not needed below it; a walk
/// stops at the first step from which on no step can change a slope by more
/// (at most twice the largest |dh| over the step's length) and every
/// receiver is charged that much instead, so the bound stays one (0: walk
/// every step that can see a change). Throws InputError when `levels` was
/// not built for `pyr`.
void boundSlopeChangePerReceiverAzimuth(ChangeLevels& levels, const HeightPyramid& pyr, std::span<const double> phi,
                                        const ReceiverTiles* only, float floor, std::vector<float>& out);

/// Per receiver (row-major), the bound on the change of its environment
/// V's ambient light (ambientChangeBoundPerAzimuth, what gi/visibility_cache.h
/// adds to a tile's drift, for the receiver alone): from the slope bounds
/// above along phi (the full circle's samples 2 pi j / m) times the
/// maximum's Lipschitz factor, and the gradient bound of the receiver's own
/// footprint (gradientBoundOfTile with tiles of one receiver, from dh: the
/// |dh| the levels were built from). With `only`, the receivers of its
/// dirty tiles alone; the others get 0. `floor` as above. With subsetOut,
/// also the same bound over the azimuths j = 0, k, 2k, ... alone (k =
/// subsetStride, a divisor of their count): what another scan that takes
/// every k-th of these azimuths reads (the indirect light's).
void boundEnvironmentPerReceiver(ChangeLevels& levels, const MaxChangePyramid& dh, const HeightPyramid& pyr,
                                 std::span<const double> phi, float lipschitz, const ReceiverTiles* only, float floor,
                                 std::vector<float>& out, int subsetStride = 0,
                                 std::vector<float>* subsetOut = nullptr);

/// The same walks for a radiance field's scan (gi/radiance_pyramid.h, whose
/// levels are plain means: the argument above holds for them): with
/// `levels` built by buildChangeLevels from |L - L_anchor| (max over the
/// channels) for channel 0's pyramid `field`, each step's sample moved by at
/// most w_a D_l[a] + w_b D_l[b]. Per receiver of `only`'s dirty tiles (every
/// receiver without), the largest move of its samples along each azimuth
/// phi_j, azimuthMove[(j nyr + Y) nxr + X], and in each distance group
/// (gi/pyramid.h) over every azimuth, groupMove[(g nyr + Y) nxr + X]: what
/// gi/indirect_cache.h weighs by the receiver's shares of its occlusion.
/// In real arithmetic, as the slopes' bound: the pyramids' own rounding
/// (the radiance's octaves and syntheses, up to about 1e-5 of the radiance)
/// is not counted; where a bound is 0 the samples are the anchor's bit for
/// bit (they read no changed texel). The other receivers' entries are left as they were (the planes are
/// sized, not cleared). Throws InputError when `levels` was not built for
/// `field`.
void boundSampleMovePerReceiver(ChangeLevels& levels, const HeightPyramid& field, std::span<const double> phi,
                                const ReceiverTiles* only, std::vector<float>& azimuthMove,
                                std::vector<float>& groupMove);

}  // namespace terrain::gi
