#include "gi/change_bound.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"
#include "core/parallel.h"

namespace terrain::gi {

namespace {

constexpr int kBlocksPerAxis = 4;  // blocks a box query reads per axis at most
// Rounded up: a sample moves by at most half a texel / |major| <= texel / sqrt2
// (|major| >= 1 / sqrt2), and one texel / |major| <= sqrt2 texels.
constexpr double kHalfDiagonal = 0.70710679;  // 1 / sqrt2
constexpr double kSqrt2Up = 1.41421357;       // sqrt2

// A float not below the non-negative double v.
float roundUp(double v) {
    float f = static_cast<float>(v);
    if (static_cast<double>(f) < v) f = std::nextafter(f, std::numeric_limits<float>::infinity());
    return f;
}

void sizeLevels(int nx, int ny, MaxChangePyramid& p) {
    p.nx = nx;
    p.ny = ny;
    int count = 1;
    for (int w = nx, h = ny; w > 1 || h > 1; w = (w + 1) / 2, h = (h + 1) / 2) ++count;
    p.levels.resize(static_cast<std::size_t>(count));
    int w = nx, h = ny;
    for (Grid& g : p.levels) {
        if (g.nx != w || g.ny != h) g.resize(w, h);
        w = (w + 1) / 2;
        h = (h + 1) / 2;
    }
}

// Levels 1.. from level 0: 2 x 2 maxima, the edge replicated inside its block.
void decimateLevels(MaxChangePyramid& p) {
    for (std::size_t k = 1; k < p.levels.size(); ++k) {
        const Grid& src = p.levels[k - 1];
        Grid& dst = p.levels[k];
        parallelForRows(dst.ny, dst.nx, [&](int y0, int y1) {
            for (int y = y0; y < y1; ++y) {
                const float* ra = src.data() + static_cast<std::size_t>(2 * y) * src.nx;
                const float* rb = src.data() + static_cast<std::size_t>(std::min(2 * y + 1, src.ny - 1)) * src.nx;
                float* out = dst.data() + static_cast<std::size_t>(y) * dst.nx;
                for (int x = 0; x < dst.nx; ++x) {
                    const int xa = 2 * x, xb = std::min(2 * x + 1, src.nx - 1);
                    out[x] = std::max(std::max(ra[xa], ra[xb]), std::max(rb[xa], rb[xb]));
                }
            }
        });
    }
}

void requireSameSize(const MaxChangePyramid& dh, const HeightPyramid& pyr, int tileReceivers) {
    if (tileReceivers < 1) throw InputError("change bound: tile size must be at least one receiver");
    if (dh.nx != pyr.nx || dh.ny != pyr.ny)
        throw InputError("change bound: the height change grid and the height pyramid differ in size");
}

// Cells of the receivers of tile (tx, ty): [x0, x1] x [y0, y1].
struct CellBox {
    int x0, y0, x1, y1;
};
CellBox tileCells(const HeightPyramid& pyr, int T, int tx, int ty) {
    const int s = pyr.subsample;
    const int X0 = T * tx, Y0 = T * ty;
    const int X1 = std::min(pyr.nxr - 1, X0 + T - 1), Y1 = std::min(pyr.nyr - 1, Y0 + T - 1);
    return {s * X0, s * Y0, s * X1, s * Y1};
}

// Distances (cells) at which step i can sample, and its reach.
struct StepExtent {
    double tauMin, tauMax, reach;
};

double octaveReach(int o) { return o == 0 ? 0.0 : 2.5 * std::ldexp(1.0, o) - 0.5; }

double stepReach(const HeightPyramid& pyr, int i) {
    const int level = pyr.steps[static_cast<std::size_t>(i)].level;
    if (level < 0) return 1.0;
    // the octaves blendLevels reads for this level (gi/pyramid.cpp)
    const int kv = std::max(1, pyr.settings.levelsPerOctave);
    const int nOctaves = static_cast<int>(pyr.synth.size());
    int o = level / kv;
    bool blended = level % kv != 0;
    if (o >= nOctaves - 1) {
        o = nOctaves - 1;
        blended = false;
    }
    return pyr.subsample + octaveReach(blended ? o + 1 : o);
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
float changeWithinStep(const MaxChangePyramid& dh, const HeightPyramid& pyr, const CellBox& c, int i) {
    const StepExtent e = stepExtent(pyr, i);
    const int d = static_cast<int>(std::ceil(e.tauMax + e.reach));
    return maxChangeInBox(dh, c.x0 - d, c.y0 - d, c.x1 + d, c.y1 + d);
}

// A step q such that steps 0..q see no change at all (-1: none known), by
// bisection: a box reading 0 holds no change, nor do the boxes nested in it.
int lastQuietStep(const MaxChangePyramid& dh, const HeightPyramid& pyr, const CellBox& c) {
    int quiet = -1, busy = static_cast<int>(pyr.steps.size());
    while (busy - quiet > 1) {
        const int mid = quiet + (busy - quiet) / 2;
        (changeWithinStep(dh, pyr, c, mid) == 0.0f ? quiet : busy) = mid;
    }
    return quiet;
}

// boundOfTile with the first level step found once per call.
float boundOfTileFrom(const MaxChangePyramid& dh, const HeightPyramid& pyr, int T, int tx, int ty, int firstLevel,
                      double lipschitz) {
    const CellBox c = tileCells(pyr, T, tx, ty);
    const double m0 = maxChangeInBox(dh, c.x0, c.y0, c.x1, c.y1);
    const double mAll = maxChangeAll(dh);
    const double cellSize = pyr.cellSize;
    // quiet steps' boxes hold the tile's own cells (m0 = 0): their slopes do not move
    const int first = m0 > 0.0 ? 0 : lastQuietStep(dh, pyr, c) + 1;
    double best = 0.0;
    for (int i = first; i < static_cast<int>(pyr.steps.size()); ++i) {
        // no later step can beat best even if it sees the largest change anywhere
        if ((lipschitz * mAll + m0) / (tauMinFrom(pyr, i, firstLevel) * cellSize) <= best) break;
        const double m = changeWithinStep(dh, pyr, c, i);
        best = std::max(best, (lipschitz * m + m0) / (stepExtent(pyr, i).tauMin * cellSize));
    }
    return roundUp(best);
}

// max |dh| within reach of step i's samples along direction (c, sn) from any
// receiver of the tile: the tile's cells swept from t'_min to t'_max along the
// direction, dilated by the reach plus one cell, and cut to the box of all
// azimuths (changeWithinStep), which holds the samples too.
float changeAlongStep(const MaxChangePyramid& dh, const StepExtent& e, const CellBox& c, double cs, double sn) {
    const double xa = e.tauMin * cs, xb = e.tauMax * cs, ya = e.tauMin * sn, yb = e.tauMax * sn;
    const double r = e.reach + 1.0;
    const int d = static_cast<int>(std::ceil(e.tauMax + e.reach));
    return maxChangeInBox(dh, c.x0 + std::max(-d, static_cast<int>(std::floor(std::min(xa, xb) - r))),
                          c.y0 + std::max(-d, static_cast<int>(std::floor(std::min(ya, yb) - r))),
                          c.x1 + std::min(d, static_cast<int>(std::ceil(std::max(xa, xb) + r))),
                          c.y1 + std::min(d, static_cast<int>(std::ceil(std::max(ya, yb) + r))));
}

// Per-step extents of a pyramid, and the smallest t'_min from each step on.
struct StepTable {
    std::vector<StepExtent> extent;
    std::vector<double> tauMinFrom;
};
StepTable stepTable(const HeightPyramid& pyr) {
    StepTable t;
    const int n = static_cast<int>(pyr.steps.size()), firstLevel = firstLevelStep(pyr);
    for (int i = 0; i < n; ++i) {
        t.extent.push_back(stepExtent(pyr, i));
        t.tauMinFrom.push_back(tauMinFrom(pyr, i, firstLevel));
    }
    return t;
}

double azimuthBoundFrom(const MaxChangePyramid& dh, const HeightPyramid& pyr, const StepTable& steps,
                        const CellBox& c, double m0, double cs, double sn, double lipschitz) {
    const double mAll = maxChangeAll(dh), cellSize = pyr.cellSize;
    double best = 0.0;
    for (std::size_t i = 0; i < steps.extent.size(); ++i) {
        // no later step can beat best even if it sees the largest change anywhere
        if ((lipschitz * mAll + m0) / (steps.tauMinFrom[i] * cellSize) <= best) break;
        const double m = changeAlongStep(dh, steps.extent[i], c, cs, sn);
        best = std::max(best, (lipschitz * m + m0) / (steps.extent[i].tauMin * cellSize));
    }
    return best;
}

// Fills one value per tile, tile rows in parallel.
template <class PerTile>
void forEachTile(const HeightPyramid& pyr, int T, std::vector<float>& out, PerTile&& perTile) {
    const int tilesX = tileCount(pyr.nxr, T), tilesY = tileCount(pyr.nyr, T);
    out.resize(static_cast<std::size_t>(tilesX) * static_cast<std::size_t>(tilesY));
    parallelFor(0, tilesY, 1, [&](int ty0, int ty1) {
        for (int ty = ty0; ty < ty1; ++ty)
            for (int tx = 0; tx < tilesX; ++tx)
                out[static_cast<std::size_t>(ty) * tilesX + static_cast<std::size_t>(tx)] = perTile(tx, ty);
    });
}

}  // namespace

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

void buildMaxChangePyramid(ConstGridView before, ConstGridView after, MaxChangePyramid& p) {
    if (before.nx != after.nx || before.ny != after.ny)
        throw InputError("change bound: the heights before and after differ in size");
    sizeLevels(before.nx, before.ny, p);
    Grid& base = p.levels[0];
    parallelForRows(before.ny, before.nx, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) {
            const float* a = before.row(y);
            const float* b = after.row(y);
            float* out = base.data() + static_cast<std::size_t>(y) * base.nx;
            // the difference of two floats is exact in double
            for (int x = 0; x < before.nx; ++x)
                out[x] = roundUp(std::fabs(static_cast<double>(b[x]) - static_cast<double>(a[x])));
        }
    });
    decimateLevels(p);
}

float maxChangeInBox(const MaxChangePyramid& p, int x0, int y0, int x1, int y1) {
    x0 = std::max(x0, 0);
    y0 = std::max(y0, 0);
    x1 = std::min(x1, p.nx - 1);
    y1 = std::min(y1, p.ny - 1);
    if (x0 > x1 || y0 > y1 || p.levels.empty()) return 0.0f;
    // the finest level whose blocks cover the box with at most kBlocksPerAxis per axis
    int k = 0;
    const int top = static_cast<int>(p.levels.size()) - 1;
    while (k < top && ((x1 >> k) - (x0 >> k) >= kBlocksPerAxis || (y1 >> k) - (y0 >> k) >= kBlocksPerAxis)) ++k;
    const Grid& g = p.levels[static_cast<std::size_t>(k)];
    float m = 0.0f;
    for (int by = y0 >> k; by <= y1 >> k; ++by) {
        const float* row = g.data() + static_cast<std::size_t>(by) * g.nx;
        for (int bx = x0 >> k; bx <= x1 >> k; ++bx) m = std::max(m, row[bx]);
    }
    return m;
}

float maxChangeAll(const MaxChangePyramid& p) {
    return p.levels.empty() || p.levels.back().empty() ? 0.0f : p.levels.back().v[0];
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

float blockingMaxLipschitz(BlockingMax rule) { return rule == BlockingMax::Samples ? 1.0f : 20.0f / 16.0f; }

float gradientBoundOfTile(const MaxChangePyramid& dh, const HeightPyramid& pyr, int tileReceivers, int tx, int ty) {
    const CellBox c = tileCells(pyr, tileReceivers, tx, ty);
    const int half = pyr.subsample / 2;
    const int x0 = std::max(c.x0 - half, 0), y0 = std::max(c.y0 - half, 0);
    const int x1 = std::min(c.x1 + half, pyr.nx - 1), y1 = std::min(c.y1 + half, pyr.ny - 1);
    const bool border = x0 == 0 || y0 == 0 || x1 == pyr.nx - 1 || y1 == pyr.ny - 1;  // one-sided differences
    const double m = maxChangeInBox(dh, x0 - 1, y0 - 1, x1 + 1, y1 + 1);
    return roundUp((border ? 2.0 : 1.0) * m / pyr.cellSize);
}

void boundGradientChange(const MaxChangePyramid& dh, const HeightPyramid& pyr, int tileReceivers,
                         std::vector<float>& tileBound) {
    requireSameSize(dh, pyr, tileReceivers);
    forEachTile(pyr, tileReceivers, tileBound,
                [&](int tx, int ty) { return gradientBoundOfTile(dh, pyr, tileReceivers, tx, ty); });
}

float ambientChangeBound(float slopeBound, float gradientBound, float maxSkyRadiance) {
    const double g = kSqrt2Up * gradientBound;  // bounds both the tangent slope's and the normal's move
    const double v = maxSkyRadiance * (kShadePerSlope * std::max<double>(slopeBound, g) + kShadePerNormal * g);
    return roundUp(v);
}

float azimuthBoundOfTile(const MaxChangePyramid& dh, const HeightPyramid& pyr, int tileReceivers, int tx, int ty,
                         double phi) {
    const CellBox c = tileCells(pyr, tileReceivers, tx, ty);
    const double m0 = maxChangeInBox(dh, c.x0, c.y0, c.x1, c.y1);
    return roundUp(azimuthBoundFrom(dh, pyr, stepTable(pyr), c, m0, std::cos(phi), std::sin(phi),
                                    heightFilterLipschitz(pyr)));
}

void boundSlopeChangePerAzimuth(const MaxChangePyramid& dh, const HeightPyramid& pyr, int tileReceivers,
                                int azimuths, std::vector<float>& tileBound) {
    requireSameSize(dh, pyr, tileReceivers);
    if (azimuths < 1) throw InputError("change bound: at least one azimuth");
    const StepTable steps = stepTable(pyr);
    const double lipschitz = heightFilterLipschitz(pyr);
    std::vector<double> cs(static_cast<std::size_t>(azimuths)), sn(cs.size());
    for (int j = 0; j < azimuths; ++j) {
        const double phi = 2.0 * 3.14159265358979323846 * j / azimuths;
        cs[static_cast<std::size_t>(j)] = std::cos(phi);
        sn[static_cast<std::size_t>(j)] = std::sin(phi);
    }
    const int T = tileReceivers, tilesX = tileCount(pyr.nxr, T), tilesY = tileCount(pyr.nyr, T);
    const std::size_t m = static_cast<std::size_t>(azimuths);
    tileBound.resize(static_cast<std::size_t>(tilesX) * static_cast<std::size_t>(tilesY) * m);
    parallelFor(0, tilesY, 1, [&](int ty0, int ty1) {
        for (int ty = ty0; ty < ty1; ++ty)
            for (int tx = 0; tx < tilesX; ++tx) {
                const CellBox c = tileCells(pyr, T, tx, ty);
                const double m0 = maxChangeInBox(dh, c.x0, c.y0, c.x1, c.y1);
                float* out = tileBound.data() + (static_cast<std::size_t>(ty) * tilesX + tx) * m;
                for (std::size_t j = 0; j < m; ++j)
                    out[j] = roundUp(azimuthBoundFrom(dh, pyr, steps, c, m0, cs[j], sn[j], lipschitz));
            }
    });
}

float ambientChangeBoundPerAzimuth(const float* slopeBound, int azimuths, float gradientBound, float maxSkyRadiance,
                                   bool withNormals) {
    const double g = kSqrt2Up * gradientBound;
    double sum = 0.0;
    for (int j = 0; j < azimuths; ++j) sum += std::max<double>(slopeBound[j], g);
    const double v = maxSkyRadiance * (kShadePerSlope * sum / azimuths + (withNormals ? kShadePerNormal * g : 0.0));
    return roundUp(v);
}

}  // namespace terrain::gi
