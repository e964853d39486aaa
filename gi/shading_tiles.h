#pragma once
// Which texels an incremental frame's direct shading must redo (the frame's
// one place for it; the shading kernels only take the runs, gi/texel_runs.h).
//
// A texel's direct light (the SH shading, the exact ambient and sky, the key
// lights' exact cosine) is a pure function of
//  - its own height gradient (the heights within one cell of it),
//  - at sub-sampling s > 1, its near field (the exact ambient's samples at
//    the first s crossings of each azimuth's ray with the grid, read between
//    two texels across it: within s + 1 cells),
//  - the visibility of the up to four receivers it interpolates, and their
//    horizons raised to their lowest tangent slope (the footprint box's
//    gradients, within s / 2 + 1 cells of a receiver, itself within s cells
//    of the texel),
//  - the lights and the albedo.
// When only the heights changed and the visibility was recomputed by tiles
// (gi/visibility_cache.h), a texel has the last frame's inputs bit for bit
// unless it reads a receiver of a tile whose environment visibility was
// recomputed or whose key-light visibility changed (below), or a height within s + s / 2 + 1 cells of the
// texels of its tile (gi/texel_runs.h) changed; the others keep their light,
// identical to recomputing it. The exact ambient (and the analytic sky's
// parts) reads the environment's horizons, not the key lights': its texels
// are those of the environment's dirty tiles and the changed heights alone,
// so a local change that a low key light looks across redoes the shade of a
// strip of tiles but the ambient of a few.
#include <array>
#include <span>
#include <vector>

#include "core/grid.h"
#include "gi/receiver_tiles.h"
#include "gi/texel_runs.h"
#include "gi/visibility.h"

namespace terrain::gi {

/// The cells within this many of a texel that its direct light reads.
inline int shadingReach(int subsample) { return subsample + subsample / 2 + 1; }

/// Receivers [x0, x1) of receiver row y.
struct ReceiverRun {
    int y = 0, x0 = 0, x1 = 0;
};

/// The texels whose exact ambient (`ambient`) and whose direct light
/// (`shading`) must be redone after the heights went from `before` to
/// `after` (same size), the visibility of the dirty tiles of `env` (on the
/// receiver grid of `subsample`) was recomputed and that of the receivers
/// of `keys` changed: the texels that read a receiver of a dirty tile or
/// (the shading alone) of `keys`, and those of the texel tiles within
/// shadingReach of a changed height (appendTexelsToRedo; `differing` holds
/// every height that may differ, every cell by default). `rects` is
/// scratch. Throws InputError when the sizes differ.
void changedDirectTexels(ConstGridView before, ConstGridView after, const ReceiverTiles& env,
                         std::span<const ReceiverRun> keys, int subsample, std::vector<TexelRect>& rects,
                         TexelRuns& ambient, TexelRuns& shading, CellBox differing = {});

// A key light's tile is recomputed when its bound allows a change, which
// is often none at all (a local change beside a light's region of the sky
// moves its far, filtered samples, not whether the window is visible), and
// within a tile whose shadows did move, most receivers' visibility is
// often what it was (a shadow's edge crosses a few of them): the receivers
// whose visibility the scan left bit for bit as it was need no shading,
// and a texel that reads only such receivers keeps its light.

/// The key lights' visibility (every light's planes) of the receivers of
/// the dirty tiles of `tiles`, kept before a scan recomputes them.
struct KeyVisibilityBefore {
    std::vector<float> values;
    std::vector<std::array<int, 3>> layout;  // per light: nxr, nyr, planes
};

/// Keeps the key lights' visibility of the dirty tiles of `tiles` (in `out`).
void keepKeyVisibility(const std::vector<VisibilityField>& keys, const ReceiverTiles& tiles, KeyVisibilityBefore& out);

/// `changed`: per receiver row of each dirty tile of `tiles`, the run from
/// its first to its last receiver where some light's visibility differs
/// (bits) from `before`, kept of the same tiles (none where none differs);
/// every receiver of the dirty tiles when the lights or their fields'
/// layout differ from the kept ones.
void keyReceiversChanged(const std::vector<VisibilityField>& keys, const ReceiverTiles& tiles,
                         const KeyVisibilityBefore& before, std::vector<ReceiverRun>& changed);

}  // namespace terrain::gi
