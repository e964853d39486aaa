#include "gi/receiver_change_bound.h"

#include <algorithm>

#include "core/error.h"
#include "core/parallel.h"

namespace terrain::gi {

namespace {

// Blocks a filter reaches on each side of the receiver's block: small enough
// to cost little per block, large enough that the covering blocks reach
// little past the square.
constexpr int kMaxFilterRadius = 8;

// A square max filter of the change pyramid: its level and its radius in
// blocks of that level.
struct SquareFilter {
    int level = 0, radius = 0;
    bool operator==(const SquareFilter&) const = default;
};

// The finest level from `finest` on whose blocks cover a square of half-size
// d (cells) around any cell within kMaxFilterRadius blocks of the cell's
// block (the top level covers everything). Cell c lies in block b = c >> k,
// and c - d and c + d in blocks b - ceil(d / 2^k) .. b + ceil(d / 2^k).
SquareFilter filterFor(int d, int finest, int levels) {
    int k = finest;
    const auto blocks = [&](int level) { return (d + (1 << level) - 1) >> level; };
    while (k + 1 < levels && blocks(k) > kMaxFilterRadius) ++k;
    return {k, blocks(k)};
}

// out(x, y) = the largest value of g within `radius` of (x, y) along each
// axis, cut to the grid: rows first, then columns.
void squareMax(const Grid& g, int radius, Grid& rows, Grid& out) {
    const int nx = g.nx, ny = g.ny;
    rows.ensureSize(nx, ny);
    out.ensureSize(nx, ny);
    parallelForRows(ny, nx, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) {
            const float* in = g.data() + static_cast<std::size_t>(y) * nx;
            float* o = rows.data() + static_cast<std::size_t>(y) * nx;
            for (int x = 0; x < nx; ++x) {
                float m = 0.0f;
                for (int u = std::max(0, x - radius); u <= std::min(nx - 1, x + radius); ++u) m = std::max(m, in[u]);
                o[x] = m;
            }
        }
    });
    parallelForRows(ny, nx, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) {
            float* o = out.data() + static_cast<std::size_t>(y) * nx;
            std::fill(o, o + nx, 0.0f);
            for (int v = std::max(0, y - radius); v <= std::min(ny - 1, y + radius); ++v) {
                const float* in = rows.data() + static_cast<std::size_t>(v) * nx;
                for (int x = 0; x < nx; ++x) o[x] = std::max(o[x], in[x]);
            }
        }
    });
}

}  // namespace

void boundSlopeChangePerReceiver(const MaxChangePyramid& dh, const HeightPyramid& pyr, std::vector<float>& out) {
    if (dh.nx != pyr.nx || dh.ny != pyr.ny)
        throw InputError("change bound: the height change grid and the height pyramid differ in size");
    const int nxr = pyr.nxr, nyr = pyr.nyr, s = pyr.subsample;
    const std::size_t receivers = static_cast<std::size_t>(nxr) * static_cast<std::size_t>(nyr);
    out.assign(receivers, 0.0f);
    if (dh.levels.empty() || maxChangeAll(dh) == 0.0f) return;
    const std::vector<StepSquare> steps = stepSquares(pyr);
    const int levels = static_cast<int>(dh.levels.size());
    // no level finer than the receivers' spacing: only the receivers' cells are read
    int finest = 0;
    while (finest + 1 < levels && (2 << finest) <= s) ++finest;
    // consecutive steps with the same filter read the same value: the
    // smallest t'_min among them gives their largest bound
    struct Group {
        SquareFilter filter;
        double tauMin;
    };
    std::vector<Group> groups;
    for (const StepSquare& q : steps) {
        const SquareFilter f = filterFor(q.halfSize, finest, levels);
        if (!groups.empty() && groups.back().filter == f)
            groups.back().tauMin = std::min(groups.back().tauMin, q.tauMin);
        else
            groups.push_back({f, q.tauMin});
    }
    std::vector<Grid> filtered(groups.size()), rows(groups.size());
    parallelFor(0, static_cast<int>(groups.size()), 1, [&](int g0, int g1) {
        for (int g = g0; g < g1; ++g) {
            const SquareFilter& f = groups[static_cast<std::size_t>(g)].filter;
            squareMax(dh.levels[static_cast<std::size_t>(f.level)], f.radius, rows[static_cast<std::size_t>(g)],
                      filtered[static_cast<std::size_t>(g)]);
        }
    });
    // per receiver, as boundOfTile: max over the steps of (L M_i + M0) / (t'_min cellSize),
    // M0 the change at the receiver's cell and M_i the largest within step i's square
    const double lipschitz = heightFilterLipschitz(pyr), cellSize = pyr.cellSize;
    const Grid& cells = dh.levels[0];
    parallelForRows(nyr, nxr, [&](int Y0, int Y1) {
        std::vector<double> best(static_cast<std::size_t>(nxr));
        for (int Y = Y0; Y < Y1; ++Y) {
            const int cy = s * Y;
            const float* m0 = cells.data() + static_cast<std::size_t>(cy) * cells.nx;
            std::fill(best.begin(), best.end(), 0.0);
            for (std::size_t g = 0; g < groups.size(); ++g) {
                const int k = groups[g].filter.level;
                const double denominator = groups[g].tauMin * cellSize;  // boundOfTile divides: the same roundings
                const float* m = filtered[g].data() + static_cast<std::size_t>(cy >> k) * filtered[g].nx;
                for (int X = 0; X < nxr; ++X) {
                    const int cx = s * X;
                    best[static_cast<std::size_t>(X)] =
                        std::max(best[static_cast<std::size_t>(X)], (lipschitz * m[cx >> k] + m0[cx]) / denominator);
                }
            }
            float* o = out.data() + static_cast<std::size_t>(Y) * nxr;
            for (int X = 0; X < nxr; ++X) o[X] = floatNotBelow(best[static_cast<std::size_t>(X)]);
        }
    });
}

}  // namespace terrain::gi
