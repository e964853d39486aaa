#include "gi/pyramid.h"

#include <algorithm>
#include <atomic>
#include <cmath>

#include "core/parallel.h"

namespace terrain::gi {

void PaddedField::resize(int w, int h) {
    nx = w;
    ny = h;
    stride = w + 1;
    v.resize(static_cast<std::size_t>(w + 1) * static_cast<std::size_t>(h + 1) + 2 * kFieldGuard, 0.0f);
}

void PaddedField::padEdges(CellBox changed) {
    changed = changed.cut(nx, ny);
    if (changed.empty()) return;
    if (changed.x1 == nx)  // the last column changed in these rows
        for (int y = changed.y0; y < changed.y1; ++y) row(y)[nx] = row(y)[nx - 1];
    if (changed.y1 == ny) std::copy(row(ny - 1), row(ny - 1) + stride, row(ny));
}

namespace {

// Octaves o with o k_v < nLevels: those whose synthesis is a level.
int octavesInLevels(int nLevels, int kv) { return nLevels <= 0 ? 0 : (nLevels - 1) / kv + 1; }

// S_o: level o k_v, or a field of its own above the last level.
template <class Pyramid>
auto& octaveField(Pyramid& p, int o) {
    const int kv = std::max(1, p.settings.levelsPerOctave);
    const int inLevels = octavesInLevels(static_cast<int>(p.levels.size()), kv);
    return o < inLevels ? p.levels[static_cast<std::size_t>(o * kv)] : p.synth[static_cast<std::size_t>(o - inLevels)];
}

}  // namespace

const PaddedField& octaveSynthesis(const HeightPyramid& p, int o) { return octaveField(p, o); }

LevelOctaves levelOctaves(const HeightPyramid& p, int level) {
    const int kv = std::max(1, p.settings.levelsPerOctave);
    LevelOctaves out{level / kv, static_cast<float>(level % kv) / static_cast<float>(kv)};
    if (out.octave >= p.octaves - 1) out = {p.octaves - 1, 0.0f};
    return out;
}

int distanceGroup(double tauCells) {
    int g = 0;
    for (double edge = 4.0; g + 1 < kDistanceGroups && tauCells >= edge; edge *= 2.0) ++g;
    return g;
}

int pyramidStepCount(int nx, int ny, int levelsPerOctave) {
    const double diag = std::sqrt(static_cast<double>(nx - 1) * (nx - 1) + static_cast<double>(ny - 1) * (ny - 1));
    if (diag <= 1.0) return 1;
    return static_cast<int>(std::ceil(levelsPerOctave * std::log2(diag))) + 1;
}

namespace {

// Cubic B-spline weights for fraction a, taps k0-1 .. k0+2.
inline void bsplineWeights(float a, float w[4]) {
    const float b = 1.0f - a;
    w[0] = b * b * b / 6.0f;
    w[1] = (3.0f * a * a * a - 6.0f * a * a + 4.0f) / 6.0f;
    w[2] = (-3.0f * a * a * a + 3.0f * a * a + 3.0f * a + 1.0f) / 6.0f;
    w[3] = a * a * a / 6.0f;
}

// ---- algorithm: one octave decimation row (2x2 box or 2x2 max) ----------
// The 2x2 cells' value: their maximum, or their mean.
template <bool UseMax>
[[gnu::always_inline]] inline float decimated(float a, float b, float c, float d) {
    return UseMax ? std::max(std::max(a, b), std::max(c, d)) : 0.25f * ((a + b) + (c + d));
}

// Rows [y0, y1), columns [x0, x1) of dst.
template <bool UseMax>
void decimateRowsOf(ConstGridView src, Grid& dst, int y0, int y1, int x0, int x1) {
    // columns whose 2x2 cells are all inside src (a loop the compiler
    // vectorises), then the last column of an odd width (its cells replicate
    // the last source column)
    const int inside = src.nx / 2;
    const int insideEnd = std::min(x1, inside);
    for (int y = y0; y < y1; ++y) {
        const float* ra = src.row(std::min(2 * y, src.ny - 1));
        const float* rb = src.row(std::min(2 * y + 1, src.ny - 1));
        float* out = dst.data() + static_cast<std::size_t>(y) * dst.nx;
        for (int x = x0; x < insideEnd; ++x)
            out[x] = decimated<UseMax>(ra[2 * x], ra[2 * x + 1], rb[2 * x], rb[2 * x + 1]);
        for (int x = std::max(x0, inside); x < x1; ++x) {
            const int xa = std::min(2 * x, src.nx - 1), xb = std::min(2 * x + 1, src.nx - 1);
            out[x] = decimated<UseMax>(ra[xa], ra[xb], rb[xa], rb[xb]);
        }
    }
}

void decimateRows(ConstGridView src, Grid& dst, bool useMax, int y0, int y1, int x0, int x1) {
    if (useMax)
        decimateRowsOf<true>(src, dst, y0, y1, x0, x1);
    else
        decimateRowsOf<false>(src, dst, y0, y1, x0, x1);
}

// The receivers [r0, r1) whose synthesis taps (4 per receiver, nondecreasing
// along the axis) read a texel of [t0, t1); r0 >= r1 when none does.
RowSpan receiversReading(const int* taps, int receivers, int t0, int t1) {
    int r0 = 0, r1 = receivers;
    while (r0 < r1 && taps[4 * r0 + 3] < t0) ++r0;
    while (r1 > r0 && taps[4 * (r1 - 1)] >= t1) --r1;
    return {r0, r1};
}

// Receiver X's position in octave o's texels (spacing 2^o): receivers sit
// at cells s * X (full-resolution cell centres at integers), octave texel k
// is centred at (k + 0.5) 2^o - 0.5. Its B-spline taps are floor(u) - 1 ..
// floor(u) + 2.
double synthesisCoordinate(int X, int subsample, int octave) {
    return (subsample * X + 0.5) / octaveScale(octave) - 0.5;
}

// Taps of the B-spline synthesis of octave o at the receivers.
void synthesisTaps(int receivers, int subsample, int octave, int octaveSize, int* index, float* weight) {
    for (int X = 0; X < receivers; ++X) {
        const double u = synthesisCoordinate(X, subsample, octave);
        const double k0 = std::floor(u);
        bsplineWeights(static_cast<float>(u - k0), weight + 4 * X);
        for (int k = 0; k < 4; ++k) index[4 * X + k] = std::clamp(static_cast<int>(k0) - 1 + k, 0, octaveSize - 1);
    }
}

// ---- steps (Eq. 14) and the level each reads (level offset o_v) ------
// Sub-sampling: the stack lives at the receiver grid (Nowrouzezahrai & Snyder
// 2009, Section 9), so the first step is one receiver spacing, tau_0 = s cells
// (steps shorter than the receiver spacing would sample relief that the
// interpolated SH vectors cannot carry). Returns the highest level read
// (-1: none).
int buildSteps(HeightPyramid& p, int kv, float cellSize) {
    const int s = p.subsample;
    const int i0 = kv * (s == 4 ? 2 : (s == 2 ? 1 : 0));
    const int nSteps = std::max(1, pyramidStepCount(p.nx, p.ny, kv) - i0);
    p.steps.resize(static_cast<std::size_t>(nSteps));
    int maxLevel = -1;
    for (int ii = 0; ii < nSteps; ++ii) {
        const int i = ii + i0;
        PyramidStep& st = p.steps[static_cast<std::size_t>(ii)];
        st.tauCells = std::exp2(static_cast<double>(i) / kv);
        st.invTauWorld = static_cast<float>(1.0 / (st.tauCells * cellSize));
        st.level = i - kv * p.settings.levelOffset;
        if (st.level < 0) st.level = -1;
        maxLevel = std::max(maxLevel, st.level);
    }
    return maxLevel;
}

// ---- raw heights, split by column phase --------------------------------
// Only the `changed` rows of the heights (and the replicated row below the
// last when it is one of them); returns the rows of the planes it wrote.
RowSpan splitRawPhases(ConstGridView heights, RowSpan changed, HeightPyramid& p) {
    const int nx = p.nx, ny = p.ny, s = p.subsample;
    const int wp = nx / s + 1;
    p.rawPhaseWidth = wp;
    p.rawPhasePlane = static_cast<std::ptrdiff_t>(wp) * (ny + 1);
    p.rawPhase.resize(static_cast<std::size_t>(s) * static_cast<std::size_t>(p.rawPhasePlane) + 2 * kFieldGuard, 0.0f);
    changed = changed.cut(ny);
    const RowSpan rows{changed.y0, changed.y1 == ny ? ny + 1 : changed.y1};
    parallelForRows(rows, nx, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) {
            const float* src = heights.row(std::min(y, ny - 1));
            for (int q = 0; q < s; ++q) {
                float* d = p.rawPhase.data() + kFieldGuard + q * p.rawPhasePlane + static_cast<std::ptrdiff_t>(y) * wp;
                // columns inside the row (a strided copy the compiler
                // vectorises for s = 2), then the replicated last column
                const int inside = q > nx - 1 ? 0 : std::min(wp, (nx - 1 - q) / s + 1);
                if (s == 2)
                    for (int x = 0; x < inside; ++x) d[x] = src[2 * x + q];
                else
                    for (int x = 0; x < inside; ++x) d[x] = src[s * x + q];
                for (int x = inside; x < wp; ++x) d[x] = src[nx - 1];
            }
        }
    });
    return rows;
}

// Octaves needed for nLevels levels: up to floor((nLevels - 1) / kv) + 1,
// stopping at 1x1.
int octaveCount(int nx, int ny, int nLevels, int kv) {
    const int wanted = (nLevels - 1) / kv + 2;
    int w = nx, h = ny, count = 1;
    while (count < wanted && (w > 1 || h > 1)) {
        w = (w + 1) / 2;
        h = (h + 1) / 2;
        ++count;
    }
    return count;
}

// ---- octave images B_o (2x2 decimation) ---------------------------------
// Only the cells that read a changed height: changed[o] is octave o's box
// (changed[0] the heights').
void decimateOctaves(ConstGridView heights, int nOctaves, bool withMax, const std::vector<CellBox>& changed,
                     HeightPyramid& p) {
    p.meanOctaves.resize(static_cast<std::size_t>(nOctaves - 1));
    p.maxOctaves.resize(withMax ? static_cast<std::size_t>(nOctaves - 1) : 0u);
    for (int pass = 0; pass < (withMax ? 2 : 1); ++pass) {
        std::vector<Grid>& oct = pass == 0 ? p.meanOctaves : p.maxOctaves;
        ConstGridView src = heights;
        for (int o = 1; o < nOctaves; ++o) {
            Grid& dst = oct[static_cast<std::size_t>(o - 1)];
            const int w = (src.nx + 1) / 2, h = (src.ny + 1) / 2;
            dst.ensureSize(w, h);
            const CellBox& box = changed[static_cast<std::size_t>(o)];
            if (!box.empty())
                parallelForRows(box.rows(), box.x1 - box.x0,
                                [&](int y0, int y1) { decimateRows(src, dst, pass == 1, y0, y1, box.x0, box.x1); });
            src = dst.cview();
        }
    }
}

// Each octave image's box of cells that read a changed height.
std::vector<CellBox> octaveBoxes(const CellBox& heightsBox, int nx, int ny, int nOctaves) {
    std::vector<CellBox> boxes(static_cast<std::size_t>(std::max(1, nOctaves)));
    boxes[0] = heightsBox;
    for (int o = 1; o < nOctaves; ++o) {
        nx = (nx + 1) / 2;
        ny = (ny + 1) / 2;
        boxes[static_cast<std::size_t>(o)] = boxes[static_cast<std::size_t>(o - 1)].halved().cut(nx, ny);
    }
    return boxes;
}

// S_0: level 0 is the height field itself (Nowrouzezahrai & Snyder 2009,
// Section 5.2: level i is reduced by 2^(i / k_v), so f_0 = f, unfiltered),
// taken at the receivers. (A B-spline synthesis of octave 0 would smooth it
// by (1, 4, 1) / 6 per axis and lower the near blockers.)
void receiverHeights(ConstGridView heights, int s, RowSpan changed, PaddedField& out) {
    const int nxr = out.nx, nyr = out.ny;
    changed = changed.cut(heights.ny);
    const RowSpan receivers = RowSpan{(changed.y0 + s - 1) / s, (changed.y1 + s - 1) / s}.cut(nyr);  // s Y in changed
    parallelForRows(receivers, nxr, [&](int Y0, int Y1) {
        for (int Y = Y0; Y < Y1; ++Y) {
            const float* src = heights.row(s * Y);
            float* d = out.row(Y);
            for (int X = 0; X < nxr; ++X) d[X] = src[s * X];
        }
    });
    out.padEdges({0, receivers.y0, nxr, receivers.y1});
}

// The receivers at cells s X, s Y of a box of cells.
CellBox receiversIn(const CellBox& cells, int s, int nxr, int nyr) {
    if (cells.empty()) return CellBox::none();
    return CellBox{(cells.x0 + s - 1) / s, (cells.y0 + s - 1) / s, (cells.x1 + s - 1) / s, (cells.y1 + s - 1) / s}.cut(
        nxr, nyr);
}

// Octave o's synthesis taps for a B_o of srcNx x srcNy texels, computed
// when the grids differ from the last build's.
const HeightPyramid::OctaveTaps& octaveTaps(HeightPyramid& p, int o, int srcNx, int srcNy) {
    HeightPyramid::OctaveTaps& t = p.taps[static_cast<std::size_t>(o)];
    const std::array<int, 5> grid{p.nxr, p.nyr, p.subsample, srcNx, srcNy};
    if (t.grid != grid || t.index.empty()) {
        t.index.resize(static_cast<std::size_t>(4 * (p.nxr + p.nyr)));
        t.weight.resize(t.index.size());
        synthesisTaps(p.nxr, p.subsample, o, srcNx, t.index.data(), t.weight.data());
        synthesisTaps(p.nyr, p.subsample, o, srcNy, t.index.data() + 4 * p.nxr, t.weight.data() + 4 * p.nxr);
        t.grid = grid;
    }
    return t;
}

// One pass (0: the mean octave, 1: the max octave) of the B-spline synthesis
// of octave o >= 1 at the receiver grid, weighted by `blend`: pass 0 writes
// out, pass 1 adds to it. Separable: rows of B_o to receiver columns
// (rowTmp), then columns to receiver rows. Only the receivers whose taps read
// a texel of `changed` (a box of B_o), each with the same arithmetic as the
// whole pass; returns their box.
CellBox synthesisePass(ConstGridView src, int o, int pass, float blend, const CellBox& changed, HeightPyramid& p,
                       PaddedField& out) {
    if (changed.empty()) return CellBox::none();
    const int nxr = p.nxr, nyr = p.nyr;
    const HeightPyramid::OctaveTaps& taps = octaveTaps(p, o, src.nx, src.ny);
    const int* ix = taps.index.data();
    const int* iy = ix + 4 * nxr;
    const float* wx = taps.weight.data();
    const float* wy = wx + 4 * nxr;
    const RowSpan cols = receiversReading(ix, nxr, changed.x0, changed.x1);
    const RowSpan rows = receiversReading(iy, nyr, changed.y0, changed.y1);
    if (cols.y0 >= cols.y1 || rows.y0 >= rows.y1) return CellBox::none();
    const int X0 = cols.y0, X1 = cols.y1;
    // each octave's own (the octaves are synthesised side by side); sized
    // once per grid, its rows written before they are read
    std::vector<float>& rowTmp = p.rowTmp[static_cast<std::size_t>(o)];
    const std::size_t tmpSize = static_cast<std::size_t>(src.ny) * nxr;
    if (rowTmp.size() < tmpSize) rowTmp.resize(tmpSize);
    float* tmp = rowTmp.data();
    // the rows of B_o those receiver rows read (taps nondecreasing)
    const RowSpan tmpRows{iy[4 * rows.y0], iy[4 * (rows.y1 - 1) + 3] + 1};
    parallelForRows(tmpRows, X1 - X0, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) {
            const float* in = src.row(y);
            float* t = tmp + static_cast<std::size_t>(y) * nxr;
            for (int X = X0; X < X1; ++X) {
                const int* k = ix + 4 * X;
                const float* w = wx + 4 * X;
                t[X] = (w[0] * in[k[0]] + w[1] * in[k[1]]) + (w[2] * in[k[2]] + w[3] * in[k[3]]);
            }
        }
    });
    parallelForRows(rows, X1 - X0, [&](int y0, int y1) {
        for (int Y = y0; Y < y1; ++Y) {
            const int* k = iy + 4 * Y;
            const float* w = wy + 4 * Y;
            const float* r0 = tmp + static_cast<std::size_t>(k[0]) * nxr;
            const float* r1 = tmp + static_cast<std::size_t>(k[1]) * nxr;
            const float* r2 = tmp + static_cast<std::size_t>(k[2]) * nxr;
            const float* r3 = tmp + static_cast<std::size_t>(k[3]) * nxr;
            float* d = out.row(Y);
            for (int X = X0; X < X1; ++X) {
                const float v = (w[0] * r0[X] + w[1] * r1[X]) + (w[2] * r2[X] + w[3] * r3[X]);
                d[X] = pass == 0 ? blend * v : d[X] + blend * v;
            }
        }
    });
    return {X0, rows.y0, X1, rows.y1};
}

// ---- B-spline synthesis of each octave at the receiver grid ---------------
// S_o; mean and (optionally) max syntheses are blended here. S_o is level
// o k_v itself (q = 0), so it is synthesised straight into that level; only
// the octaves above the last level, which the top levels blend towards, get
// fields of their own (HeightPyramid::synth). Only the receivers that read a
// changed octave texel (changed[o]); returns each octave's box of them.
std::vector<CellBox> synthesiseOctaves(ConstGridView heights, const std::vector<CellBox>& changed, int nLevels,
                                       int nOctaves, bool withMax, HeightPyramid& p) {
    const int nxr = p.nxr, nyr = p.nyr, kv = std::max(1, p.settings.levelsPerOctave);
    p.octaves = nOctaves;
    p.levels.resize(static_cast<std::size_t>(nLevels));
    p.synth.resize(static_cast<std::size_t>(std::max(0, nOctaves - octavesInLevels(nLevels, kv))));
    p.taps.resize(static_cast<std::size_t>(nOctaves));
    p.rowTmp.resize(static_cast<std::size_t>(nOctaves));
    for (int o = 0; o < nOctaves; ++o) octaveField(p, o).resize(nxr, nyr);
    std::vector<CellBox> receivers(static_cast<std::size_t>(nOctaves));
    // the octaves side by side: each reads its own B_o and writes its own
    // field, taps and scratch (a local change's boxes are too small for
    // their row loops to split)
    parallelFor(0, nOctaves, 1, [&](int o0, int o1) {
        for (int o = o0; o < o1; ++o) {
            PaddedField& out = octaveField(p, o);
            const CellBox& box = changed[static_cast<std::size_t>(o)];
            if (o == 0) {
                receiverHeights(heights, p.subsample, box.rows(), out);
                receivers[0] = receiversIn(box, p.subsample, nxr, nyr);
                continue;
            }
            for (int pass = 0; pass < (withMax ? 2 : 1); ++pass) {
                ConstGridView src = (pass == 0 ? p.meanOctaves : p.maxOctaves)[static_cast<std::size_t>(o - 1)].cview();
                const float blend = withMax ? (pass == 0 ? 1.0f - p.settings.peakBlend : p.settings.peakBlend) : 1.0f;
                receivers[static_cast<std::size_t>(o)] = synthesisePass(src, o, pass, blend, box, p, out);
            }
            out.padEdges(receivers[static_cast<std::size_t>(o)]);
        }
    });
    return receivers;
}

// ---- levels between octaves: f_l = (1 - q) S_o + q S_(o+1) -----------------
// Levels past the last octave repeat it. Only the receivers of the two
// octaves' boxes (`receivers`); the padding then replicates the edges, as
// the blend of the octaves' replicated edges would.
void blendLevel(int l, int nOctaves, int kv, const std::vector<CellBox>& receivers, HeightPyramid& p) {
    const LevelOctaves lo = levelOctaves(p, l);
    const int o = lo.octave, ob = std::min(o + 1, nOctaves - 1);
    if (l == o * kv) return;  // the octave itself, synthesised in place
    PaddedField& lev = p.levels[static_cast<std::size_t>(l)];
    const PaddedField& a = octaveSynthesis(p, o);
    const PaddedField& b = octaveSynthesis(p, ob);
    const float wa = 1.0f - lo.q, wb = lo.q;
    const CellBox box =
        receivers[static_cast<std::size_t>(o)].joined(receivers[static_cast<std::size_t>(ob)]).cut(p.nxr, p.nyr);
    if (box.empty()) return;
    parallelForRows(box.rows(), box.x1 - box.x0, [&](int y0, int y1) {
        for (int Y = y0; Y < y1; ++Y) {
            const float* ra = a.row(Y);
            const float* rb = b.row(Y);
            float* d = lev.row(Y);
            for (int X = box.x0; X < box.x1; ++X) d[X] = wa * ra[X] + wb * rb[X];
        }
    });
    lev.padEdges(box);
}

// Every level, side by side (each writes its own field alone).
void blendLevels(int nLevels, int nOctaves, int kv, const std::vector<CellBox>& receivers, HeightPyramid& p) {
    for (int l = 0; l < nLevels; ++l) p.levels[static_cast<std::size_t>(l)].resize(p.nxr, p.nyr);
    parallelFor(0, nLevels, 1, [&](int l0, int l1) {
        for (int l = l0; l < l1; ++l) blendLevel(l, nOctaves, kv, receivers, p);
    });
}

}  // namespace

void buildHeightPyramid(ConstGridView heights, float cellSize, int subsample, const PyramidSettings& settings,
                        HeightPyramid& p, CellBox changed) {
    const int nx = heights.nx, ny = heights.ny, s = subsample;
    // only on the same grid and settings are the other cells' results there
    if (p.nx != nx || p.ny != ny || p.subsample != s || !(p.settings == settings) || p.rawPhase.empty()) changed = {};
    changed = changed.cut(nx, ny);
    static std::atomic<std::uint64_t> builds{0};
    const bool whole = changed.x0 == 0 && changed.y0 == 0 && changed.x1 == nx && changed.y1 == ny;
    p.basedOn = whole ? 0 : p.buildId;
    p.buildId = ++builds;
    p.rawRowsRedone = {};  // every row, until the raw phases are split
    const int kv = std::max(1, settings.levelsPerOctave);
    p.nx = nx;
    p.ny = ny;
    p.subsample = s;
    p.nxr = receiverCount(nx, s);
    p.nyr = receiverCount(ny, s);
    p.cellSize = cellSize;
    p.settings = settings;

    const int maxLevel = buildSteps(p, kv, cellSize);
    p.rawRowsRedone = splitRawPhases(heights, changed.rows(), p);
    const int nLevels = maxLevel + 1;
    if (nLevels <= 0) {
        p.levels.resize(0);
        p.synth.resize(0);
        p.octaves = 0;
        return;
    }
    const int nOctaves = octaveCount(nx, ny, nLevels, kv);
    const bool withMax = settings.peakBlend > 0.0f;
    const std::vector<CellBox> octaveChanges = octaveBoxes(changed, nx, ny, nOctaves);
    decimateOctaves(heights, nOctaves, withMax, octaveChanges, p);
    const std::vector<CellBox> receivers = synthesiseOctaves(heights, octaveChanges, nLevels, nOctaves, withMax, p);
    blendLevels(nLevels, nOctaves, kv, receivers, p);
}

RowSpan synthesisTexels(const HeightPyramid& p, int octave, int size, int r0, int r1) {
    const auto first = [&](int X) { return static_cast<int>(std::floor(synthesisCoordinate(X, p.subsample, octave))); };
    return {std::clamp(first(r0) - 1, 0, size - 1), std::clamp(first(r1) + 2, 0, size - 1) + 1};
}

}  // namespace terrain::gi
