#include "gi/radiance_sample_change.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "core/error.h"
#include "core/parallel.h"
#include "gi/visibility.h"

namespace terrain::gi {

namespace {

int levelCount(const RadiancePyramid& p) { return p.fields.empty() ? 0 : static_cast<int>(p.fields[0].levels.size()); }

// The levels compared texel by texel: those below octave `from`, and
// always octave 0's (S_0 is the radiance itself, no octave image).
int exactLevelCount(const HeightPyramid& f, int from) {
    const int kv = std::max(1, f.settings.levelsPerOctave);
    return std::clamp(kv * std::max(1, from), 0, static_cast<int>(f.levels.size()));
}

// The level texels (receivers, half-open) that may differ where the
// radiance changed only inside `changed`: its receivers within the level's
// reach, one more on each side (the receiver of a cell rounds either way).
CellBox levelBox(const HeightPyramid& f, int level, CellBox changed) {
    changed = changed.cut(f.nx, f.ny);
    if (changed.empty()) return CellBox::none();
    const int s = f.subsample;
    const int r = static_cast<int>(std::ceil(levelReachCells(f, level)));
    const auto lo = [&](int c) { return std::max(0, (c - r) / s - 1); };
    const auto hi = [&](int c, int n) { return std::min(n, (c - 1 + r) / s + 2); };
    return {lo(changed.x0), lo(changed.y0), hi(changed.x1, f.nxr), hi(changed.y1, f.nyr)};
}

ConstGridView levelView(const PaddedField& f) { return {f.data(), f.nx, f.ny, f.stride}; }

}  // namespace

bool RadianceLevelChange::fits(const RadiancePyramid& p) const {
    if (p.fields.size() != 3 || levelCount(p) != levels) return false;
    const HeightPyramid& f = p.fields[0];
    return f.nxr == nxr && f.nyr == nyr && exactLevels == exactLevelCount(f, octaveBoundFrom) &&
           anchor.size() == static_cast<std::size_t>(3 * exactLevels) && f.octaves == octaves &&
           anchorOctaves.size() == static_cast<std::size_t>(3 * (octaves - firstOctave));
}

void recordAnchorLevels(const RadiancePyramid& p, RadianceLevelChange& out, CellBox changed) {
    if (!out.fits(p)) {
        changed = {};
        out.levels = levelCount(p);
        const HeightPyramid* f = p.fields.empty() ? nullptr : &p.fields[0];
        out.nxr = f ? f->nxr : 0;
        out.nyr = f ? f->nyr : 0;
        out.exactLevels = f ? exactLevelCount(*f, out.octaveBoundFrom) : 0;
        out.anchor.resize(static_cast<std::size_t>(3 * out.exactLevels));
        out.change.clear();
        out.octaves = f ? f->octaves : 0;
        out.firstOctave = f && out.exactLevels < out.levels ? levelOctaves(*f, out.exactLevels).octave : out.octaves;
        out.anchorOctaves.resize(static_cast<std::size_t>(3 * (out.octaves - out.firstOctave)));
        out.octaveChange.clear();
    }
    const int kept = out.octaves - out.firstOctave;
    for (int c = 0; c < 3 && out.levels > 0; ++c) {
        const HeightPyramid& f = p.fields[static_cast<std::size_t>(c)];
        for (int l = 0; l < out.exactLevels; ++l) {
            const CellBox box = levelBox(f, l, changed);
            copyGrid(levelView(f.levels[static_cast<std::size_t>(l)]),
                     out.anchor[static_cast<std::size_t>(c * out.exactLevels + l)], box.rows());
        }
        for (int o = out.firstOctave; o < out.octaves; ++o)  // a few texels: whole
            copyGrid(f.meanOctaves[static_cast<std::size_t>(o - 1)].cview(),
                     out.anchorOctaves[static_cast<std::size_t>(c * kept + o - out.firstOctave)]);
    }
}

void buildLevelChanges(const RadiancePyramid& now, CellBox changed, RadianceLevelChange& out) {
    if (!out.fits(now)) throw InputError("radiance sample change: the pyramid is not of the anchor's grid");
    // no block sums: the sample bounds read maxima alone
    out.change.resize(static_cast<std::size_t>(out.exactLevels), MaxChangePyramid{.withSums = false});
    const int kept = out.octaves - out.firstOctave;
    out.octaveChange.resize(static_cast<std::size_t>(kept), MaxChangePyramid{.withSums = false});
    // the levels side by side (each build's own passes are parallel too)
    parallelFor(0, out.exactLevels, 1, [&](int l0, int l1) {
        for (int l = l0; l < l1; ++l) {
            std::array<ConstGridView, 3> before, after;
            for (std::size_t c = 0; c < 3; ++c) {
                before[c] =
                    out.anchor[c * static_cast<std::size_t>(out.exactLevels) + static_cast<std::size_t>(l)].cview();
                after[c] = levelView(now.fields[c].levels[static_cast<std::size_t>(l)]);
            }
            // an empty box still redoes the last build's changed cells, which may now be 0
            buildMaxChangePyramid(before, after, out.change[static_cast<std::size_t>(l)],
                                  levelBox(now.fields[0], l, changed));
        }
    });
    // B_o differs from the anchor's only in the texels that decimate a changed cell
    CellBox box = changed.cut(now.fields[0].nx, now.fields[0].ny);
    for (int o = 1; o < out.octaves; ++o) {
        box = box.halved();
        if (o < out.firstOctave) continue;
        std::array<ConstGridView, 3> before, after;
        for (std::size_t c = 0; c < 3; ++c) {
            before[c] =
                out.anchorOctaves[c * static_cast<std::size_t>(kept) + static_cast<std::size_t>(o - out.firstOctave)]
                    .cview();
            after[c] = now.fields[c].meanOctaves[static_cast<std::size_t>(o - 1)].cview();
        }
        buildMaxChangePyramid(before, after, out.octaveChange[static_cast<std::size_t>(o - out.firstOctave)], box);
    }
}

namespace {

// The larger of `above` and a bound on how far the samples of the
// receivers [X0, X1] x [Y0, Y1] at one step moved: each blends its tap a
// (k X + tap) and tap b (the texel after it across the ray) with the
// weights 1 - f and f every receiver shares at this step, so it moves by at
// most (1 - f) A + f B, A and B bounds on the largest change over the taps
// a and b of the tile (boxes cut to the field, whose padding replicates the
// last row and column; each rounded out to the change pyramid's covering
// blocks, maxChangeCoveringBox). One box over both taps first: when it
// cannot beat `above`, neither can the blend.
float tapsChange(const MaxChangePyramid& field, int k, const ScanStepInfo& si, int X0, int Y0, int X1, int Y1,
                 float above) {
    const auto box = [&](int dx0, int dy0, int dx1, int dy1, float floor) {
        return maxChangeCoveringBox(field, std::clamp(k * X0 + si.tapX + dx0, 0, field.nx - 1),
                                    std::clamp(k * Y0 + si.tapY + dy0, 0, field.ny - 1),
                                    std::clamp(k * X1 + si.tapX + dx1, 0, field.nx - 1),
                                    std::clamp(k * Y1 + si.tapY + dy1, 0, field.ny - 1), floor);
    };
    if (box(0, 0, si.nextX, si.nextY, above) <= above) return above;
    const float a = box(0, 0, 0, 0, 0.0f), b = box(si.nextX, si.nextY, si.nextX, si.nextY, 0.0f);
    const float wa = si.step.w[0][0], wb = si.step.w[1][0];
    // rounded up, and never 0 where a read texel moved and is weighed
    const float blend = std::nextafter(wa * a + wb * b, std::numeric_limits<float>::infinity());
    return std::max(above, std::min(std::max(a, b), (wa > 0.0f && a > 0.0f) || (wb > 0.0f && b > 0.0f) ? blend : 0.0f));
}

// The same for a level bounded through its octaves (RadianceLevelChange::
// exactLevels): every texel the receivers' two taps read lies in the box of
// level texels from tap a's to tap b's, where the level is (1 - q) S_o + q
// S_(o+1); a texel of S_o is a combination of the octave image's texels its
// B-spline taps read, with non-negative weights summing to 1, so it moved
// by at most the largest move A_o of those texels, and the sample by at
// most (1 - q) A_o + q A_(o+1).
float octaveTapsChange(const RadianceLevelChange& lc, const HeightPyramid& field, int level, const ScanStepInfo& si,
                       int X0, int Y0, int X1, int Y1, float above) {
    const int xa = std::clamp(X0 + si.tapX + std::min(0, si.nextX), 0, field.nxr - 1);
    const int xb = std::clamp(X1 + si.tapX + std::max(0, si.nextX), 0, field.nxr - 1);
    const int ya = std::clamp(Y0 + si.tapY + std::min(0, si.nextY), 0, field.nyr - 1);
    const int yb = std::clamp(Y1 + si.tapY + std::max(0, si.nextY), 0, field.nyr - 1);
    const LevelOctaves lo = levelOctaves(field, level);
    const auto octaveMove = [&](int o) {
        const MaxChangePyramid& c = lc.octaveChange[static_cast<std::size_t>(o - lc.firstOctave)];
        const RowSpan tx = synthesisTexels(field, o, c.nx, xa, xb), ty = synthesisTexels(field, o, c.ny, ya, yb);
        return maxChangeCoveringBox(c, tx.y0, ty.y0, tx.y1 - 1, ty.y1 - 1);
    };
    const float a = octaveMove(lo.octave), b = lo.q > 0.0f ? octaveMove(lo.octave + 1) : 0.0f;
    if (std::max(a, b) <= above) return above;
    // rounded up, and never 0 where a read texel moved
    const float blend =
        lo.q > 0.0f ? std::nextafter((1.0f - lo.q) * a + lo.q * b, std::numeric_limits<float>::infinity()) : a;
    return std::max(above, std::min(std::max(a, b), blend));
}

}  // namespace

void boundSampleChangeFromLevels(const MaxChangePyramid& raw, const RadianceLevelChange& levels,
                                 const HeightPyramid& field, int tileReceivers, std::span<const double> phi,
                                 std::vector<float>& tileBound, std::vector<float>& groupBound) {
    const int T = tileReceivers, m = static_cast<int>(phi.size()), nSteps = static_cast<int>(field.steps.size());
    if (T < 1 || m < 1) throw InputError("radiance sample change: tiles and azimuths must be at least 1");
    if (raw.nx != field.nx || raw.ny != field.ny || levels.nxr != field.nxr || levels.nyr != field.nyr ||
        static_cast<int>(levels.change.size()) != levels.exactLevels ||
        static_cast<int>(levels.octaveChange.size()) != levels.octaves - levels.firstOctave ||
        levels.levels != static_cast<int>(field.levels.size()))
        throw InputError("radiance sample change: the changes and the pyramid differ in size");
    const int tilesX = tileCount(field.nxr, T), tilesY = tileCount(field.nyr, T);
    const std::size_t tiles = static_cast<std::size_t>(tilesX) * tilesY;
    tileBound.assign(tiles * m, 0.0f);
    groupBound.assign(tiles * kDistanceGroups, 0.0f);
    // each step's taps and valid receivers, per azimuth (the scan's own table entries)
    std::vector<ScanStepInfo> info(static_cast<std::size_t>(m) * nSteps);
    std::vector<int> group(static_cast<std::size_t>(nSteps));
    for (int j = 0; j < m; ++j)
        for (int i = 0; i < nSteps; ++i)
            info[static_cast<std::size_t>(j) * nSteps + i] = scanStepInfo(
                field, i, std::cos(phi[static_cast<std::size_t>(j)]), std::sin(phi[static_cast<std::size_t>(j)]));
    for (int i = 0; i < nSteps; ++i)
        group[static_cast<std::size_t>(i)] = distanceGroup(field.steps[static_cast<std::size_t>(i)].tauCells);
    // tiles in parallel, each a chunk of its own at most (those near a change cost the most)
    parallelFor(0, tilesX * tilesY, 1, [&](int t0, int t1) {
        for (int k = t0; k < t1; ++k) {
            const int tx = k % tilesX, ty = k / tilesX;
            const auto t = static_cast<std::size_t>(k);
            const int X0 = tx * T, Y0 = ty * T;
            const int X1 = std::min(field.nxr, X0 + T) - 1, Y1 = std::min(field.nyr, Y0 + T) - 1;
            for (int j = 0; j < m; ++j)
                for (int i = 0; i < nSteps; ++i) {
                    const ScanStepInfo& si = info[static_cast<std::size_t>(j) * nSteps + i];
                    const int x0 = std::max(X0, si.xFirst), x1 = std::min(X1, si.xLast);
                    const int y0 = std::max(Y0, si.yFirst), y1 = std::min(Y1, si.yLast);
                    if (x0 > x1 || y0 > y1) continue;
                    float& az = tileBound[t * m + static_cast<std::size_t>(j)];
                    float& gr =
                        groupBound[t * kDistanceGroups + static_cast<std::size_t>(group[static_cast<std::size_t>(i)])];
                    // only a move above both running maxima changes either
                    const float above = std::min(az, gr);
                    const int level = field.steps[static_cast<std::size_t>(i)].level;
                    const float d =
                        level < 0 ? tapsChange(raw, field.subsample, si, x0, y0, x1, y1, above)
                        : level < levels.exactLevels
                            ? tapsChange(levels.change[static_cast<std::size_t>(level)], 1, si, x0, y0, x1, y1, above)
                            : octaveTapsChange(levels, field, level, si, x0, y0, x1, y1, above);
                    az = std::max(az, d);
                    gr = std::max(gr, d);
                }
        }
    });
}

}  // namespace terrain::gi
