#include "gi/change_bound.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>

#include "core/error.h"
#include "core/parallel.h"
#include "core/prefetch.h"

namespace terrain::gi {

namespace {

constexpr int kBlocksPerAxis = 4;          // blocks a box query reads per axis at most
constexpr int kCoveringBlocksPerAxis = 8;  // the same for maxChangeCoveringBox (no descent)
// Rounded up: a sample moves by at most half a texel / |major| <= texel / sqrt2
// (|major| >= 1 / sqrt2), and one texel / |major| <= sqrt2 texels.
constexpr double kHalfDiagonal = 0.70710679;  // 1 / sqrt2
constexpr double kSqrt2Up = 1.41421357;       // sqrt2

void sizeLevels(int nx, int ny, MaxChangePyramid& p) {
    p.nx = nx;
    p.ny = ny;
    int count = 1;
    for (int w = nx, h = ny; w > 1 || h > 1; w = (w + 1) / 2, h = (h + 1) / 2) ++count;
    p.levels.resize(static_cast<std::size_t>(count));
    p.sums.resize(p.withSums ? p.levels.size() : 0);
    int w = nx, h = ny;
    for (std::size_t k = 0; k < p.levels.size(); ++k) {
        if (p.levels[k].nx != w || p.levels[k].ny != h) p.levels[k].resize(w, h);
        if (p.withSums && k > 0 && (p.sums[k].nx != w || p.sums[k].ny != h)) p.sums[k].resize(w, h);
        w = (w + 1) / 2;
        h = (h + 1) / 2;
    }
}

// Block sums of the next level over the blocks of `blocks` (cut to dst):
// each cell of the cut edge blocks counted once.
void sumLevel(const Grid& src, Grid& dst, const CellBox& blocks) {
    parallelForRows(blocks.rows(), blocks.x1 - blocks.x0, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) {
            const float* ra = src.data() + static_cast<std::size_t>(2 * y) * src.nx;
            const float* rb = 2 * y + 1 < src.ny ? ra + src.nx : nullptr;
            float* out = dst.data() + static_cast<std::size_t>(y) * dst.nx;
            for (int x = blocks.x0; x < blocks.x1; ++x) {
                const int xa = 2 * x;
                const bool pair = xa + 1 < src.nx;
                double v = static_cast<double>(ra[xa]) + (pair ? ra[xa + 1] : 0.0f);
                if (rb) v += static_cast<double>(rb[xa]) + (pair ? rb[xa + 1] : 0.0f);
                out[x] = floatNotBelow(v);
            }
        }
    });
}

// The blocks with a change at the first level of at most 64 x 64 blocks.
void findChangedBox(MaxChangePyramid& p) {
    auto& c = p.changed;
    c = {};
    std::size_t k = 0;
    while (k + 1 < p.levels.size() && p.levels[k].v.size() > 64 * 64) ++k;
    if (p.levels.empty()) return;
    const Grid& g = p.levels[k];
    int bx0 = g.nx, by0 = g.ny, bx1 = -1, by1 = -1;
    for (int by = 0; by < g.ny; ++by)
        for (int bx = 0; bx < g.nx; ++bx)
            if (g.v[static_cast<std::size_t>(by) * g.nx + bx] > 0.0f) {
                bx0 = std::min(bx0, bx);
                bx1 = std::max(bx1, bx);
                by0 = std::min(by0, by);
                by1 = std::max(by1, by);
            }
    if (bx1 < 0) return;
    c.x0 = bx0 << k;
    c.y0 = by0 << k;
    c.x1 = std::min(((bx1 + 1) << k) - 1, p.nx - 1);
    c.y1 = std::min(((by1 + 1) << k) - 1, p.ny - 1);
}

// Whether the cells [x0, x1] x [y0, y1] miss the changed box.
bool missesChange(const MaxChangePyramid& p, int x0, int y0, int x1, int y1) {
    const auto& c = p.changed;
    return x1 < c.x0 || y1 < c.y0 || x0 > c.x1 || y0 > c.y1;
}

// Levels 1.. from level 0: 2 x 2 maxima, the edge replicated inside its
// block; only the blocks holding a cell of `redone` (level 0's cells that
// were rewritten; every block holding none keeps its value).
void decimateLevels(MaxChangePyramid& p, CellBox redone = {}) {
    redone = redone.cut(p.nx, p.ny);
    for (std::size_t k = 1; k < p.levels.size() && !redone.empty(); ++k) {
        const Grid& src = p.levels[k - 1];
        Grid& dst = p.levels[k];
        redone = redone.halved().cut(dst.nx, dst.ny);
        const CellBox blocks = redone;
        parallelForRows(blocks.rows(), blocks.x1 - blocks.x0, [&](int y0, int y1) {
            for (int y = y0; y < y1; ++y) {
                const float* ra = src.data() + static_cast<std::size_t>(2 * y) * src.nx;
                const float* rb = src.data() + static_cast<std::size_t>(std::min(2 * y + 1, src.ny - 1)) * src.nx;
                float* out = dst.data() + static_cast<std::size_t>(y) * dst.nx;
                for (int x = blocks.x0; x < blocks.x1; ++x) {
                    const int xa = 2 * x, xb = std::min(2 * x + 1, src.nx - 1);
                    out[x] = std::max(std::max(ra[xa], ra[xb]), std::max(rb[xa], rb[xb]));
                }
            }
        });
        if (p.withSums) sumLevel(k == 1 ? p.levels[0] : p.sums[k - 1], p.sums[k], blocks);
    }
    findChangedBox(p);
}

// Cells [x0, x1] x [y0, y1], inclusive.
struct InclusiveCells {
    int x0, y0, x1, y1;
};

// Raises m to the largest |dh| of the cells of block (bx, by) of level k that
// lie in the box (clamped to the grid), descending into the blocks the box
// cuts only while they could beat m.
void maxOfBlockInBox(const MaxChangePyramid& p, const InclusiveCells& box, int k, int bx, int by, float& m) {
    const Grid& g = p.levels[static_cast<std::size_t>(k)];
    if (bx >= g.nx || by >= g.ny) return;
    const float v = g.v[static_cast<std::size_t>(by) * g.nx + bx];
    if (v <= m) return;
    const int cx0 = bx << k, cy0 = by << k;
    const int cx1 = std::min(((bx + 1) << k) - 1, p.nx - 1), cy1 = std::min(((by + 1) << k) - 1, p.ny - 1);
    if (cx0 > box.x1 || cy0 > box.y1 || cx1 < box.x0 || cy1 < box.y0) return;
    if (k == 0 || (cx0 >= box.x0 && cy0 >= box.y0 && cx1 <= box.x1 && cy1 <= box.y1)) {
        m = v;
        return;
    }
    for (int cy = 2 * by; cy <= 2 * by + 1; ++cy)
        for (int cx = 2 * bx; cx <= 2 * bx + 1; ++cx) maxOfBlockInBox(p, box, k - 1, cx, cy, m);
}

void requireSameSize(const MaxChangePyramid& dh, const HeightPyramid& pyr, int tileReceivers) {
    if (tileReceivers < 1) throw InputError("change bound: tile size must be at least one receiver");
    if (dh.nx != pyr.nx || dh.ny != pyr.ny)
        throw InputError("change bound: the height change grid and the height pyramid differ in size");
}

// Cells of the receivers of tile (tx, ty).
InclusiveCells tileCells(const HeightPyramid& pyr, int T, int tx, int ty) {
    const int s = pyr.subsample;
    const int X0 = T * tx, Y0 = T * ty;
    const int X1 = std::min(pyr.nxr - 1, X0 + T - 1), Y1 = std::min(pyr.nyr - 1, Y0 + T - 1);
    return {s * X0, s * Y0, s * X1, s * Y1};
}

// Distances (cells) at which step i can sample, and its reach.
struct StepExtent {
    double tauMin, tauMax, reach;
};

double octaveReach(int o) { return o == 0 ? 0.0 : 2.5 * octaveScale(o) - 0.5; }

double stepReach(const HeightPyramid& pyr, int i) {
    const int level = pyr.steps[static_cast<std::size_t>(i)].level;
    return level < 0 ? 1.0 : pyr.subsample + levelReachCells(pyr, level);
}

StepExtent stepExtent(const HeightPyramid& pyr, int i) {
    const PyramidStep& st = pyr.steps[static_cast<std::size_t>(i)];
    const double unit = st.level < 0 ? 1.0 : static_cast<double>(pyr.subsample);
    StepExtent e;
    e.tauMin = std::max(unit, st.tauCells - kHalfDiagonal * unit);
    e.tauMax = std::max(kSqrt2Up * unit, st.tauCells + kHalfDiagonal * unit);
    e.reach = stepReach(pyr, i);
    return e;
}

// Half-size (cells) of the square around a cell that holds every cell step
// i's samples read from it along any azimuth: the farthest sample plus the
// reach.
int stepHalfSize(const StepExtent& e) { return static_cast<int>(std::ceil(e.tauMax + e.reach)); }

// The smallest tauMin of steps i.. : tauMin grows with i within the raw steps
// and within the level steps, and may drop once where the texel size changes.
double tauMinFrom(const HeightPyramid& pyr, int i, int firstLevelStep) {
    double t = stepExtent(pyr, i).tauMin;
    if (i < firstLevelStep && firstLevelStep < static_cast<int>(pyr.steps.size()))
        t = std::min(t, stepExtent(pyr, firstLevelStep).tauMin);
    return t;
}

int firstLevelStep(const HeightPyramid& pyr) {
    int i = 0;
    while (i < static_cast<int>(pyr.steps.size()) && pyr.steps[static_cast<std::size_t>(i)].level < 0) ++i;
    return i;
}

// max |dh| within reach of step i's samples from any receiver of the tile
// (cells c): the tile's cells dilated by the farthest sample plus the reach.
// The dilation never shrinks from one step to the next (t'_max, the texel
// size and the reach grow with i), so the boxes are nested.
float changeWithinStep(const MaxChangePyramid& dh, const HeightPyramid& pyr, const InclusiveCells& c, int i) {
    const int d = stepHalfSize(stepExtent(pyr, i));
    return maxChangeInBox(dh, c.x0 - d, c.y0 - d, c.x1 + d, c.y1 + d);
}

// A step q such that steps 0..q see no change at all (-1: none known), by
// bisection: a box reading 0 holds no change, nor do the boxes nested in it.
int lastQuietStep(const MaxChangePyramid& dh, const HeightPyramid& pyr, const InclusiveCells& c) {
    int quiet = -1, busy = static_cast<int>(pyr.steps.size());
    while (busy - quiet > 1) {
        const int mid = quiet + (busy - quiet) / 2;
        (changeWithinStep(dh, pyr, c, mid) == 0.0f ? quiet : busy) = mid;
    }
    return quiet;
}

// The first step whose samples may see a change: quiet steps' boxes hold the
// tile's own cells, so with a change there (m0 > 0) every step counts.
int firstBusyStep(const MaxChangePyramid& dh, const HeightPyramid& pyr, const InclusiveCells& c, double m0) {
    return m0 > 0.0 ? 0 : lastQuietStep(dh, pyr, c) + 1;
}

// boundOfTile with the first level step found once per call.
float boundOfTileFrom(const MaxChangePyramid& dh, const HeightPyramid& pyr, int T, int tx, int ty, int firstLevel,
                      double lipschitz) {
    const InclusiveCells c = tileCells(pyr, T, tx, ty);
    const double m0 = maxChangeInBox(dh, c.x0, c.y0, c.x1, c.y1);
    const double mAll = maxChangeAll(dh);
    const double cellSize = pyr.cellSize;
    // quiet steps' boxes hold the tile's own cells (m0 = 0): their slopes do not move
    const int first = firstBusyStep(dh, pyr, c, m0);
    double best = 0.0;
    for (int i = first; i < static_cast<int>(pyr.steps.size()); ++i) {
        // no later step can beat best even if it sees the largest change anywhere
        if ((lipschitz * mAll + m0) / (tauMinFrom(pyr, i, firstLevel) * cellSize) <= best) break;
        const double m = changeWithinStep(dh, pyr, c, i);
        best = std::max(best, (lipschitz * m + m0) / (stepExtent(pyr, i).tauMin * cellSize));
    }
    return floatNotBelow(best);
}

// The directions a bound covers: cos and sin of the azimuths range over
// [cMin, cMax] x [sMin, sMax] (one azimuth: a point).
struct Directions {
    double cMin, cMax, sMin, sMax;
};

Directions oneDirection(double cs, double sn) { return {cs, cs, sn, sn}; }

// The cos and sin ranges over the azimuths [phi0, phi1] (radians, phi0 <= phi1):
// the ends, and the extremes of the multiples of pi / 2 between them.
Directions directionsOver(double phi0, double phi1) {
    constexpr double kHalfPi = 1.57079632679489661923;
    Directions d{std::min(std::cos(phi0), std::cos(phi1)), std::max(std::cos(phi0), std::cos(phi1)),
                 std::min(std::sin(phi0), std::sin(phi1)), std::max(std::sin(phi0), std::sin(phi1))};
    for (long k = static_cast<long>(std::ceil(phi0 / kHalfPi));
         k * kHalfPi <= phi1 && k <= std::ceil(phi0 / kHalfPi) + 4; ++k) {
        const long q = ((k % 4) + 4) % 4;  // 0: +x, 1: +y, 2: -x, 3: -y
        if (q == 0) d.cMax = 1.0;
        if (q == 1) d.sMax = 1.0;
        if (q == 2) d.cMin = -1.0;
        if (q == 3) d.sMin = -1.0;
    }
    return d;
}

// Cells within reach of step i's samples along any of the directions from
// any receiver of the tile: the tile's cells swept from t'_min to t'_max
// along them, dilated by the reach plus one cell, and cut to the box of all
// azimuths (changeWithinStep), which holds the samples too.
InclusiveCells stepBoxOver(const StepExtent& e, const InclusiveCells& c, const Directions& dir) {
    const double x0 = std::min(e.tauMin * dir.cMin, e.tauMax * dir.cMin);
    const double x1 = std::max(e.tauMin * dir.cMax, e.tauMax * dir.cMax);
    const double y0 = std::min(e.tauMin * dir.sMin, e.tauMax * dir.sMin);
    const double y1 = std::max(e.tauMin * dir.sMax, e.tauMax * dir.sMax);
    const double r = e.reach + 1.0;
    const int d = stepHalfSize(e);
    return {c.x0 + std::max(-d, static_cast<int>(std::floor(x0 - r))),
            c.y0 + std::max(-d, static_cast<int>(std::floor(y0 - r))),
            c.x1 + std::min(d, static_cast<int>(std::ceil(x1 + r))),
            c.y1 + std::min(d, static_cast<int>(std::ceil(y1 + r)))};
}

// The finer octave a level step reads (0 for raw steps: the heights themselves).
int stepOctave(const HeightPyramid& pyr, int i) {
    const int level = pyr.steps[static_cast<std::size_t>(i)].level;
    if (level < 0) return 0;
    const int kv = std::max(1, pyr.settings.levelsPerOctave);
    return std::min(level / kv, pyr.octaves - 1);
}

// Per axis, the largest weight of one cell in a level sample of the mean
// octave o >= 1 over the cells [a0, a1]: its weight in its texel of B_o
// (2^-o in whole blocks, larger in the last block when the grid's edge cuts
// it: replicated cells count twice in a 2 x 2 mean) times the largest weight
// the sample gives that texel. The sample is a convex combination (bilinear
// read, level blend) of B-spline syntheses, each of which weighs a texel by
// one tap's weight, at most 2/3 (w_1 at fraction 0; kTapWeight covers the
// float weights' rounding), except where clamping at the image's edge puts
// several taps on its first or last texel (then up to 1).
struct AxisWeights {
    static constexpr double kTapWeight = 2.0 / 3.0 * (1.0 + 1e-6);
    std::vector<int> lastStart;               // per octave: first cell of the last block
    std::vector<std::vector<double>> suffix;  // per octave: max weight from cell lastStart + k on
    double maxOver(int o, int a0, int a1) const {
        const double inside = 1.0 / octaveScale(o);
        const int start = lastStart[static_cast<std::size_t>(o)];
        const bool edgeTexel = a0 < (1 << o) || a1 >= start;
        const double tap = edgeTexel ? 1.0 : kTapWeight;
        if (a1 < start) return tap * inside;
        const std::vector<double>& suf = suffix[static_cast<std::size_t>(o)];
        const int k = std::clamp(a0 - start, 0, static_cast<int>(suf.size()) - 1);
        return tap * std::max(inside, suf[static_cast<std::size_t>(k)]);
    }
};

AxisWeights axisWeights(int n, int octaves) {
    AxisWeights a;
    std::vector<double> w(static_cast<std::size_t>(n), 1.0);
    int size = n;  // texels of octave o - 1
    for (int o = 0; o < octaves; ++o) {
        if (o > 0) {
            for (int x = 0; x < n; ++x) {
                const int t = x >> (o - 1);
                w[static_cast<std::size_t>(x)] *= t == size - 1 && t % 2 == 0 ? 1.0 : 0.5;
            }
            size = (size + 1) / 2;
        }
        const int start = std::min((size - 1) << o, n - 1);
        std::vector<double> suf(static_cast<std::size_t>(n - start));
        double m = 0.0;
        for (int x = n - 1; x >= start; --x) suf[static_cast<std::size_t>(x - start)] = m = std::max(m, w[x]);
        a.lastStart.push_back(start);
        a.suffix.push_back(std::move(suf));
    }
    return a;
}

// Per-step extents of a pyramid, the smallest t'_min from each step on, and
// what the filters make of a change (see change_bound.h).
struct StepTable {
    std::vector<StepExtent> extent;
    std::vector<double> tauMinFrom;
    std::vector<int> octave;
    AxisWeights wx, wy;
    double meanPart = 1.0, maxPart = 0.0;  // |1 - b|, |b|
};
StepTable stepTable(const HeightPyramid& pyr) {
    StepTable t;
    const int n = static_cast<int>(pyr.steps.size()), firstLevel = firstLevelStep(pyr);
    for (int i = 0; i < n; ++i) {
        t.extent.push_back(stepExtent(pyr, i));
        t.tauMinFrom.push_back(tauMinFrom(pyr, i, firstLevel));
        t.octave.push_back(stepOctave(pyr, i));
    }
    const int octaves = std::max(1, pyr.octaves);
    t.wx = axisWeights(pyr.nx, octaves);
    t.wy = axisWeights(pyr.ny, octaves);
    const double b = pyr.settings.peakBlend;
    if (b > 0.0) {
        t.meanPart = std::fabs(1.0 - b);
        t.maxPart = std::fabs(b);
    }
    return t;
}

// D: the largest move of step i's level samples from the changes in box.
double filteredChange(const MaxChangePyramid& dh, const StepTable& t, int i, const InclusiveCells& box) {
    const double m = maxChangeInBox(dh, box.x0, box.y0, box.x1, box.y1);
    const int o = t.octave[static_cast<std::size_t>(i)];
    if (o == 0 || m == 0.0) return (t.meanPart + t.maxPart) * m;
    const int x0 = std::max(box.x0, 0), y0 = std::max(box.y0, 0);
    const int x1 = std::min(box.x1, dh.nx - 1), y1 = std::min(box.y1, dh.ny - 1);
    const double w = t.wx.maxOver(o, x0, x1) * t.wy.maxOver(o, y0, y1);
    const double mean = std::min(m, w * sumChangeInBox(dh, x0, y0, x1, y1));
    return t.meanPart * mean + t.maxPart * m;
}

// Steps before `first` see no change from any azimuth (lastQuietStep).
double azimuthBoundFrom(const MaxChangePyramid& dh, const HeightPyramid& pyr, const StepTable& steps,
                        const InclusiveCells& c, double m0, int first, const Directions& dir, double lipschitz) {
    const double mAll = maxChangeAll(dh), cellSize = pyr.cellSize;
    double best = 0.0;
    for (std::size_t i = static_cast<std::size_t>(first); i < steps.extent.size(); ++i) {
        // no later step can beat best even if it sees the largest change anywhere
        if ((lipschitz * mAll + m0) / (steps.tauMinFrom[i] * cellSize) <= best) break;
        const InclusiveCells box = stepBoxOver(steps.extent[i], c, dir);
        const double d = filteredChange(dh, steps, static_cast<int>(i), box);
        best = std::max(best, (d + m0) / (steps.extent[i].tauMin * cellSize));
    }
    return best;
}

// Fills one value per tile, tiles in parallel (each a chunk of its own at
// most: a local change makes a few tiles' bounds far costlier than the
// rest's).
template <class PerTile>
void forEachTile(const HeightPyramid& pyr, int T, std::vector<float>& out, PerTile&& perTile) {
    const int tilesX = tileCount(pyr.nxr, T), tilesY = tileCount(pyr.nyr, T);
    out.resize(static_cast<std::size_t>(tilesX) * static_cast<std::size_t>(tilesY));
    parallelFor(0, tilesX * tilesY, 1, [&](int t0, int t1) {
        for (int t = t0; t < t1; ++t) out[static_cast<std::size_t>(t)] = perTile(t % tilesX, t / tilesX);
    });
}

// Fills `azimuths` values per tile (tile-major) at the m samples phi_j = 2 pi
// j / m of the full circle: start(the tile's cells) once per tile, then
// value(its start, the tile's cells, cos phi_j, sin phi_j) for each
// azimuth, the (tile, azimuth) pairs in parallel, each a chunk of its own at
// most (beside a local change one tile's azimuths cost far more than most
// tiles'); with `only`, the flagged tiles' (the others get 0).
template <class Start, class Value>
void forEachTileAndAzimuth(const MaxChangePyramid& dv, const HeightPyramid& pyr, int T, int azimuths,
                           std::vector<float>& out, std::span<const std::uint8_t> only, Start&& start, Value&& value) {
    requireSameSize(dv, pyr, T);
    if (azimuths < 1) throw InputError("change bound: at least one azimuth");
    std::vector<double> cs(static_cast<std::size_t>(azimuths)), sn(cs.size());
    for (int j = 0; j < azimuths; ++j) {
        const double phi = 2.0 * 3.14159265358979323846 * j / azimuths;
        cs[static_cast<std::size_t>(j)] = std::cos(phi);
        sn[static_cast<std::size_t>(j)] = std::sin(phi);
    }
    const int tilesX = tileCount(pyr.nxr, T), tilesY = tileCount(pyr.nyr, T);
    const int tiles = tilesX * tilesY;
    if (!only.empty() && only.size() != static_cast<std::size_t>(tiles))
        throw InputError("change bound: one flag per tile");
    const auto flagged = [&](int t) { return only.empty() || only[static_cast<std::size_t>(t)]; };
    const auto cells = [&](int t) { return tileCells(pyr, T, t % tilesX, t / tilesX); };
    std::vector<std::invoke_result_t<Start&, const InclusiveCells&>> starts(static_cast<std::size_t>(tiles));
    parallelFor(0, tiles, 1, [&](int t0, int t1) {
        for (int t = t0; t < t1; ++t)
            if (flagged(t)) starts[static_cast<std::size_t>(t)] = start(cells(t));
    });
    out.resize(static_cast<std::size_t>(tiles) * cs.size());
    parallelFor(0, tiles * azimuths, 1, [&](int k0, int k1) {
        for (int k = k0; k < k1; ++k) {
            const int t = k / azimuths;
            const auto j = static_cast<std::size_t>(k % azimuths);
            out[static_cast<std::size_t>(k)] =
                flagged(t) ? value(starts[static_cast<std::size_t>(t)], cells(t), cs[j], sn[j]) : 0.0f;
        }
    });
}

// out[x] = max(out[x], |b[x] - a[x]| rounded up) over [x0, x1): whole
// vectors, then the rest one by one (the same IEEE operations, so the 4-
// and 8-wide builds give the same bits).
template <class V>
[[gnu::always_inline]] inline void raiseToChangeWith(const float* a, const float* b, float* out, int x0, int x1) {
    constexpr int L = simd::kLaneCount<V>;
    int x = x0;
    for (; x + L <= x1; x += L)
        simd::store(out + x,
                    simd::vmax(simd::load<V>(out + x), absDifferenceUp(simd::load<V>(a + x), simd::load<V>(b + x))));
    for (; x < x1; ++x) out[x] = std::max(out[x], absDifferenceUp(a[x], b[x]));
}
void raiseToChangeSse(const float* a, const float* b, float* out, int x0, int x1) {
    raiseToChangeWith<simd::F4>(a, b, out, x0, x1);
}
[[gnu::target("avx2"), gnu::flatten]] void raiseToChangeAvx2(const float* a, const float* b, float* out, int x0,
                                                             int x1) {
    raiseToChangeWith<simd::F8>(a, b, out, x0, x1);
}

}  // namespace

float floatNotBelow(double v) {
    float f = static_cast<float>(v);
    if (static_cast<double>(f) < v) f = std::nextafter(f, std::numeric_limits<float>::infinity());
    return f;
}

void buildMaxChangePyramid(ConstGridView dh, MaxChangePyramid& p) {
    sizeLevels(dh.nx, dh.ny, p);
    Grid& base = p.levels[0];
    parallelForRows(dh.ny, dh.nx, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) {
            const float* in = dh.row(y);
            float* out = base.data() + static_cast<std::size_t>(y) * base.nx;
            for (int x = 0; x < dh.nx; ++x) out[x] = std::fabs(in[x]);
        }
    });
    decimateLevels(p);
}

void buildMaxChangePyramid(ConstGridView before, ConstGridView after, MaxChangePyramid& p, CellBox differing) {
    buildMaxChangePyramid(std::span<const ConstGridView>(&before, 1), std::span<const ConstGridView>(&after, 1), p,
                          differing);
}

void buildMaxChangePyramid(std::span<const ConstGridView> before, std::span<const ConstGridView> after,
                           MaxChangePyramid& p, CellBox differing) {
    if (before.empty() || before.size() != after.size())
        throw InputError("change bound: as many fields before as after, at least one");
    const int nx = before[0].nx, ny = before[0].ny;
    for (std::size_t c = 0; c < before.size(); ++c)
        if (before[c].nx != nx || before[c].ny != ny || after[c].nx != nx || after[c].ny != ny)
            throw InputError("change bound: the fields before and after differ in size");
    // the cells to redo: those that may differ, and those the last build
    // found changed (outside both, |dh| was 0 and still is)
    CellBox region = differing.cut(nx, ny);
    const auto& last = p.changed;
    // sums switched on since the last build: every block's sum is missing
    const bool noSums = p.withSums && p.sums.size() != p.levels.size();
    if (p.nx != nx || p.ny != ny || p.levels.empty() || noSums)
        region = CellBox{}.cut(nx, ny);
    else if (last.x0 <= last.x1)
        region = region.joined({last.x0, last.y0, last.x1 + 1, last.y1 + 1});
    sizeLevels(nx, ny, p);
    Grid& base = p.levels[0];
    const int x0 = region.x0, x1 = region.x1;
    const auto raiseToChange = simd::wideEnabled() ? raiseToChangeAvx2 : raiseToChangeSse;
    parallelForRows(region.rows(), x1 - x0, [&](int y0, int y1) {
        // the chunk's rows of every field first: a local change's are short (core/prefetch.h)
        for (int y = y0; y < y1; ++y)
            for (std::size_t c = 0; c < before.size(); ++c) {
                prefetchRow(before[c].row(y), x0, x1);
                prefetchRow(after[c].row(y), x0, x1);
            }
        for (int y = y0; y < y1; ++y) {
            float* out = base.data() + static_cast<std::size_t>(y) * base.nx;
            std::fill(out + x0, out + x1, 0.0f);
            for (std::size_t c = 0; c < before.size(); ++c) {
                raiseToChange(before[c].row(y), after[c].row(y), out, x0, x1);
            }
        }
    });
    decimateLevels(p, region);
}

namespace {

// Clamps the box to the grid and returns the finest level whose blocks cover
// it with at most `blocks` per axis; -1 for an empty box.
int clampBoxToLevel(const MaxChangePyramid& p, int& x0, int& y0, int& x1, int& y1, int blocks = kBlocksPerAxis) {
    x0 = std::max(x0, 0);
    y0 = std::max(y0, 0);
    x1 = std::min(x1, p.nx - 1);
    y1 = std::min(y1, p.ny - 1);
    if (x0 > x1 || y0 > y1 || p.levels.empty()) return -1;
    int k = 0;
    const int top = static_cast<int>(p.levels.size()) - 1;
    while (k < top && ((x1 >> k) - (x0 >> k) >= blocks || (y1 >> k) - (y0 >> k) >= blocks)) ++k;
    return k;
}

}  // namespace

float maxChangeInBox(const MaxChangePyramid& p, int x0, int y0, int x1, int y1, float above) {
    if (missesChange(p, x0, y0, x1, y1) || maxChangeAll(p) <= above) return above;
    const int k = clampBoxToLevel(p, x0, y0, x1, y1);
    if (k < 0) return above;
    const InclusiveCells box{x0, y0, x1, y1};
    float m = above;
    for (int by = y0 >> k; by <= y1 >> k; ++by)
        for (int bx = x0 >> k; bx <= x1 >> k; ++bx) maxOfBlockInBox(p, box, k, bx, by, m);
    return m;
}

float maxChangeCoveringBox(const MaxChangePyramid& p, int x0, int y0, int x1, int y1, float above) {
    if (missesChange(p, x0, y0, x1, y1) || maxChangeAll(p) <= above) return above;
    const int k = clampBoxToLevel(p, x0, y0, x1, y1, kCoveringBlocksPerAxis);
    if (k < 0) return above;
    const Grid& g = p.levels[static_cast<std::size_t>(k)];
    float m = above;
    for (int by = y0 >> k; by <= y1 >> k; ++by) {
        const float* row = g.data() + static_cast<std::size_t>(by) * g.nx;
        for (int bx = x0 >> k; bx <= x1 >> k; ++bx) m = std::max(m, row[bx]);
    }
    return m;
}

double sumChangeInBox(const MaxChangePyramid& p, int x0, int y0, int x1, int y1) {
    if (!p.withSums) throw InputError("change bound: this change pyramid was built without its sums");
    const int k = clampBoxToLevel(p, x0, y0, x1, y1);
    if (k < 0) return 0.0;
    // the blocks read cover the box, rounded out to level k's blocks
    if (missesChange(p, (x0 >> k) << k, (y0 >> k) << k, (((x1 >> k) + 1) << k) - 1, (((y1 >> k) + 1) << k) - 1))
        return 0.0;
    const Grid& g = k == 0 ? p.levels[0] : p.sums[static_cast<std::size_t>(k)];
    double sum = 0.0;
    for (int by = y0 >> k; by <= y1 >> k; ++by) {
        const float* row = g.data() + static_cast<std::size_t>(by) * g.nx;
        for (int bx = x0 >> k; bx <= x1 >> k; ++bx) sum += row[bx];
    }
    return sum;
}

float maxChangeAll(const MaxChangePyramid& p) {
    return p.levels.empty() || p.levels.back().empty() ? 0.0f : p.levels.back().v[0];
}

double levelReachCells(const HeightPyramid& pyr, int level) {
    // the coarser of the octaves blendLevels reads for this level (gi/pyramid.cpp)
    const LevelOctaves lo = levelOctaves(pyr, level);
    return octaveReach(lo.q > 0.0f ? lo.octave + 1 : lo.octave);
}

std::vector<float> stepReachCells(const HeightPyramid& pyr) {
    std::vector<float> out(pyr.steps.size());
    for (std::size_t i = 0; i < out.size(); ++i) out[i] = static_cast<float>(stepReach(pyr, static_cast<int>(i)));
    return out;
}

float heightFilterLipschitz(const HeightPyramid& pyr) {
    const float b = pyr.settings.peakBlend;
    return b > 0.0f ? std::fabs(1.0f - b) + std::fabs(b) : 1.0f;
}

float boundOfTile(const MaxChangePyramid& dh, const HeightPyramid& pyr, int tileReceivers, int tx, int ty) {
    return boundOfTileFrom(dh, pyr, tileReceivers, tx, ty, firstLevelStep(pyr), heightFilterLipschitz(pyr));
}

void boundSlopeChange(const MaxChangePyramid& dh, const HeightPyramid& pyr, int tileReceivers,
                      std::vector<float>& tileBound) {
    requireSameSize(dh, pyr, tileReceivers);
    const int firstLevel = firstLevelStep(pyr);
    const double lipschitz = heightFilterLipschitz(pyr);
    forEachTile(pyr, tileReceivers, tileBound,
                [&](int tx, int ty) { return boundOfTileFrom(dh, pyr, tileReceivers, tx, ty, firstLevel, lipschitz); });
}

std::vector<StepSquare> stepSquares(const HeightPyramid& pyr) {
    std::vector<StepSquare> out;
    for (int i = 0; i < static_cast<int>(pyr.steps.size()); ++i) {
        const StepExtent e = stepExtent(pyr, i);
        out.push_back({e.tauMin, stepHalfSize(e)});
    }
    return out;
}

float blockingMaxLipschitz(BlockingMax rule) { return rule == BlockingMax::Samples ? 1.0f : 20.0f / 16.0f; }

namespace {

// Along one axis, the cells [first, last] of the footprint texels of the
// receivers whose own cells span [lo, hi] (offsets up to half = s / 2
// cells, clamped to the n cells), and whether it reaches an edge, where the
// gradient is a one-sided difference.
struct FootprintSpan {
    int first, last;
    bool edge;
};
FootprintSpan footprintSpan(int lo, int hi, int half, int n) {
    const int first = std::max(lo - half, 0), last = std::min(hi + half, n - 1);
    return {first, last, first == 0 || last == n - 1};
}

// The gradient bound from m, the largest |dh| over the footprint dilated by one cell.
float gradientBoundFrom(double m, bool edge, float cellSize) {
    return floatNotBelow((edge ? 2.0 : 1.0) * m / cellSize);
}

}  // namespace

float gradientBoundOfTile(const MaxChangePyramid& dh, const HeightPyramid& pyr, int tileReceivers, int tx, int ty) {
    const InclusiveCells c = tileCells(pyr, tileReceivers, tx, ty);
    const int half = pyr.subsample / 2;
    const FootprintSpan fx = footprintSpan(c.x0, c.x1, half, pyr.nx), fy = footprintSpan(c.y0, c.y1, half, pyr.ny);
    const double m = maxChangeInBox(dh, fx.first - 1, fy.first - 1, fx.last + 1, fy.last + 1);
    return gradientBoundFrom(m, fx.edge || fy.edge, pyr.cellSize);
}

void receiverGradientBounds(const MaxChangePyramid& dh, const HeightPyramid& pyr, int Y, int X0, int X1, float* out,
                            std::vector<float>& columnMax) {
    if (X0 >= X1) return;
    const int s = pyr.subsample, half = s / 2, nx = pyr.nx, ny = pyr.ny;
    // gradientBoundOfTile's footprints of the row's receivers, dilated by one
    // cell and clamped (as maxChangeInBox clamps)
    const FootprintSpan fy = footprintSpan(s * Y, s * Y, half, ny);
    const int ry0 = std::max(fy.first - 1, 0), ry1 = std::min(fy.last + 1, ny - 1);
    const int cx0 = std::max(footprintSpan(s * X0, s * X0, half, nx).first - 1, 0);
    const int cx1 = std::min(footprintSpan(s * (X1 - 1), s * (X1 - 1), half, nx).last + 1, nx - 1);
    // each column's largest |dh| over the dilated rows, then each receiver's over its columns
    const Grid& level0 = dh.levels[0];
    columnMax.assign(static_cast<std::size_t>(cx1 - cx0 + 1), 0.0f);
    for (int y = ry0; y <= ry1; ++y) {
        const float* row = level0.data() + static_cast<std::size_t>(y) * level0.nx;
        for (int x = cx0; x <= cx1; ++x)
            columnMax[static_cast<std::size_t>(x - cx0)] =
                std::max(columnMax[static_cast<std::size_t>(x - cx0)], row[x]);
    }
    for (int X = X0; X < X1; ++X) {
        const FootprintSpan fx = footprintSpan(s * X, s * X, half, nx);
        float m = 0.0f;
        for (int x = std::max(fx.first - 1, 0); x <= std::min(fx.last + 1, nx - 1); ++x)
            m = std::max(m, columnMax[static_cast<std::size_t>(x - cx0)]);
        out[X] = gradientBoundFrom(m, fx.edge || fy.edge, pyr.cellSize);
    }
}

float largestReceiverGradientBound(const MaxChangePyramid& dh, const HeightPyramid& pyr, int tileReceivers, int tx,
                                   int ty) {
    const InclusiveCells c = tileCells(pyr, tileReceivers, tx, ty);
    const int half = pyr.subsample / 2;
    const bool inside = c.x0 - half > 0 && c.y0 - half > 0 && c.x1 + half < pyr.nx - 1 && c.y1 + half < pyr.ny - 1;
    // inside: the receivers' boxes make up the tile's, with no one-sided differences in any
    if (inside) return gradientBoundOfTile(dh, pyr, tileReceivers, tx, ty);
    float largest = 0.0f;
    const int s = pyr.subsample;
    for (int Y = c.y0 / s; Y <= c.y1 / s; ++Y)
        for (int X = c.x0 / s; X <= c.x1 / s; ++X) largest = std::max(largest, gradientBoundOfTile(dh, pyr, 1, X, Y));
    return largest;
}

void boundGradientChange(const MaxChangePyramid& dh, const HeightPyramid& pyr, int tileReceivers,
                         std::vector<float>& tileBound) {
    requireSameSize(dh, pyr, tileReceivers);
    forEachTile(pyr, tileReceivers, tileBound,
                [&](int tx, int ty) { return gradientBoundOfTile(dh, pyr, tileReceivers, tx, ty); });
}

float ambientChangeBound(float slopeBound, float gradientBound, float maxSkyRadiance, bool withNormals) {
    const double g = kSqrt2Up * gradientBound;  // bounds both the tangent slope's and the normal's move
    const double v =
        maxSkyRadiance * (kShadePerSlope * std::max<double>(slopeBound, g) + (withNormals ? kShadePerNormal * g : 0.0));
    return floatNotBelow(v);
}

float azimuthBoundOfTile(const MaxChangePyramid& dh, const HeightPyramid& pyr, int tileReceivers, int tx, int ty,
                         double phi) {
    const InclusiveCells c = tileCells(pyr, tileReceivers, tx, ty);
    const double m0 = maxChangeInBox(dh, c.x0, c.y0, c.x1, c.y1);
    return floatNotBelow(azimuthBoundFrom(dh, pyr, stepTable(pyr), c, m0, firstBusyStep(dh, pyr, c, m0),
                                          oneDirection(std::cos(phi), std::sin(phi)), heightFilterLipschitz(pyr)));
}

void boundSlopeChangePerAzimuth(const MaxChangePyramid& dh, const HeightPyramid& pyr, int tileReceivers, int azimuths,
                                std::vector<float>& tileBound, std::span<const std::uint8_t> only) {
    const StepTable steps = stepTable(pyr);
    const double lipschitz = heightFilterLipschitz(pyr);
    // per tile: the largest change among its own cells, and the first step that may see one
    struct TileStart {
        double m0 = 0.0;
        int first = 0;
    };
    forEachTileAndAzimuth(
        dh, pyr, tileReceivers, azimuths, tileBound, only,
        [&](const InclusiveCells& c) {
            const double m0 = maxChangeInBox(dh, c.x0, c.y0, c.x1, c.y1);
            return TileStart{m0, firstBusyStep(dh, pyr, c, m0)};
        },
        [&](const TileStart& t, const InclusiveCells& c, double cs, double sn) {
            return floatNotBelow(azimuthBoundFrom(dh, pyr, steps, c, t.m0, t.first, oneDirection(cs, sn), lipschitz));
        });
}

float ambientChangeBoundPerAzimuth(const float* slopeBound, int azimuths, float gradientBound, float maxSkyRadiance,
                                   bool withNormals) {
    const double g = kSqrt2Up * gradientBound;
    double sum = 0.0;
    for (int j = 0; j < azimuths; ++j) sum += std::max<double>(slopeBound[j], g);
    const double v = maxSkyRadiance * (kShadePerSlope * sum / azimuths + (withNormals ? kShadePerNormal * g : 0.0));
    return floatNotBelow(v);
}

float keyLightFractionBound(float slopeBound, float gradientBound, float sinLow, float sinHigh) {
    const double dt = std::max<double>(slopeBound, kSqrt2Up * gradientBound);
    if (dt == 0.0) return 0.0f;
    const double window = static_cast<double>(sinHigh) - sinLow;
    return window > 0.0 ? floatNotBelow(std::min(1.0, dt / window)) : 1.0f;
}

float rangeBoundOfTile(const MaxChangePyramid& dh, const HeightPyramid& pyr, int tileReceivers, int tx, int ty,
                       double phi0, double phi1) {
    const InclusiveCells c = tileCells(pyr, tileReceivers, tx, ty);
    const double m0 = maxChangeInBox(dh, c.x0, c.y0, c.x1, c.y1);
    return floatNotBelow(azimuthBoundFrom(dh, pyr, stepTable(pyr), c, m0, firstBusyStep(dh, pyr, c, m0),
                                          directionsOver(phi0, phi1), heightFilterLipschitz(pyr)));
}

void boundSlopeChangeOverRange(const MaxChangePyramid& dh, const HeightPyramid& pyr, int tileReceivers, double phi0,
                               double phi1, std::vector<float>& tileBound, std::span<const std::uint8_t> only) {
    requireSameSize(dh, pyr, tileReceivers);
    if (!(phi0 <= phi1)) throw InputError("change bound: an azimuth range needs phi0 <= phi1");
    const int tilesX = tileCount(pyr.nxr, tileReceivers);
    if (!only.empty() && only.size() != static_cast<std::size_t>(tilesX) * tileCount(pyr.nyr, tileReceivers))
        throw InputError("change bound: one flag per tile");
    const StepTable steps = stepTable(pyr);
    const double lipschitz = heightFilterLipschitz(pyr);
    const Directions dir = directionsOver(phi0, phi1);
    forEachTile(pyr, tileReceivers, tileBound, [&](int tx, int ty) {
        if (!only.empty() && !only[static_cast<std::size_t>(ty) * tilesX + tx]) return 0.0f;
        const InclusiveCells c = tileCells(pyr, tileReceivers, tx, ty);
        const double m0 = maxChangeInBox(dh, c.x0, c.y0, c.x1, c.y1);
        return floatNotBelow(azimuthBoundFrom(dh, pyr, steps, c, m0, firstBusyStep(dh, pyr, c, m0), dir, lipschitz));
    });
}

}  // namespace terrain::gi
