#include "gi/max_octave_change.h"

#include <algorithm>

#include "core/error.h"
#include "core/parallel.h"
#include "gi/change_bound.h"

namespace terrain::gi {

namespace {

// One octave's image: heights before and after (octave 0) or their maxima,
// and the bound on its texels' change.
struct OctaveLayer {
    ConstGridView before, after;
    ConstGridView bound;
};

// Octave o's bounds from octave o - 1's (`finer`): per texel, the largest
// bound of its 2 x 2 sub-blocks (the last row and column replicated) whose
// larger maximum reaches min(M, M') of the texel.
void nextOctave(const OctaveLayer& finer, ConstGridView maxBefore, ConstGridView maxAfter, Grid& out) {
    out.ensureSize(maxBefore.nx, maxBefore.ny);
    parallelForRows(maxBefore.ny, maxBefore.nx, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y)
            for (int x = 0; x < maxBefore.nx; ++x) {
                const float reach = std::min(maxBefore(x, y), maxAfter(x, y));
                float bound = 0.0f;
                for (int dy = 0; dy < 2; ++dy)
                    for (int dx = 0; dx < 2; ++dx) {
                        const int fx = std::min(2 * x + dx, finer.before.nx - 1);
                        const int fy = std::min(2 * y + dy, finer.before.ny - 1);
                        if (std::max(finer.before(fx, fy), finer.after(fx, fy)) >= reach)
                            bound = std::max(bound, finer.bound(fx, fy));
                    }
                out(x, y) = bound;
            }
    });
}

}  // namespace

void boundMaxOctaveChange(ConstGridView before, ConstGridView after, std::span<const Grid> maxBefore,
                          std::span<const Grid> maxAfter, MaxOctaveChange& out) {
    if (before.nx != after.nx || before.ny != after.ny || maxBefore.size() != maxAfter.size())
        throw InputError("max octave change: the two height fields or their octaves differ in size");
    int nx = before.nx, ny = before.ny;
    for (std::size_t o = 0; o < maxBefore.size(); ++o) {
        nx = (nx + 1) / 2;
        ny = (ny + 1) / 2;
        const Grid &a = maxBefore[o], &b = maxAfter[o];
        if (a.nx != nx || a.ny != ny || b.nx != nx || b.ny != ny)
            throw InputError("max octave change: an octave image is not half the size of the one before");
    }
    // octave 0: each cell's own |dh|, rounded up
    Grid& cells = out.cells;
    cells.ensureSize(before.nx, before.ny);
    parallelForRows(before.ny, before.nx, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y)
            for (int x = 0; x < before.nx; ++x) cells(x, y) = absDifferenceUp(before(x, y), after(x, y));
    });
    out.bound.resize(maxBefore.size());
    OctaveLayer finer{before, after, cells.cview()};
    for (std::size_t o = 0; o < maxBefore.size(); ++o) {
        nextOctave(finer, maxBefore[o].cview(), maxAfter[o].cview(), out.bound[o]);
        finer = {maxBefore[o].cview(), maxAfter[o].cview(), out.bound[o].cview()};
    }
}

}  // namespace terrain::gi
