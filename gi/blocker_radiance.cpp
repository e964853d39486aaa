#include "gi/blocker_radiance.h"

#include <algorithm>
#include <cmath>

#include "core/parallel.h"
#include "core/simd.h"
#include "gi/receiver_tiles.h"
#include "gi/visibility.h"

namespace terrain::gi {

namespace {

using namespace simd;

constexpr int kRowsPerBlock = 8;
constexpr int kLanePad = 8;           // rows padded to the widest lane group
constexpr float kOutside = -1.0e30f;  // height outside the domain: a sample there blocks nothing

// The rows of block b of n rows in blocks of kRowsPerBlock.
RowSpan rowsOfBlock(int b, int n) { return {b * kRowsPerBlock, std::min(n, (b + 1) * kRowsPerBlock)}; }

inline int padLanes(int n) { return (n + kLanePad - 1) / kLanePad * kLanePad; }

// One row of texels: inputs and the occlusion sum.
struct OcclusionRow {
    const float* h;         // padded heights of this row at column 0 (taps reach s cells around)
    std::ptrdiff_t stride;  // of the padded heights
    const float *gx, *gy;   // padded rows of the gradient
    float* far;             // padded row: the receivers' horizon of this azimuth, interpolated
    float* sum;             // padded row: running sum of F(horizon) - F(plane)
    int n;                  // padded length
};

// Adds one azimuth's clamped-cosine integral below the texels' horizons:
// horizon = max(near samples, far), F(t) = f2 - g f1 (t = tan of the
// elevation, f1 = (w + sin w cos w) / 2, f2 = sin^2 w / 2; with sin^2 w =
// t^2 / (1 + t^2), sin w cos w = t / (1 + t^2)), clamped to the texel's
// plane g (as the indirect scan's exact moment).
template <class V>
[[gnu::always_inline]] inline void occlusionAzimuthImpl(const OcclusionRow& r, const NearTap* taps, int nTaps,
                                                        float cosPhi, float sinPhi) {
    constexpr int L = LaneTraits<V>::n;
    const V one = splat<V>(1.0f), half = splat<V>(0.5f), lim = splat<V>(1e6f), nlim = splat<V>(-1e6f);
    for (int x = 0; x < r.n; x += L) {
        const V h0 = load<V>(r.h + x);
        const V margin = (h0 < splat<V>(0.0f) ? -h0 : h0) * splat<V>(kHeightMarginRel);
        V hor = load<V>(r.far + x);
        for (int k = 0; k < nTaps; ++k) {
            const NearTap& t = taps[k];
            const float* a = r.h + t.dy * r.stride + t.dx + x;
            const float* b = a + r.stride;
            const V v = (splat<V>(t.w00) * load<V>(a) + splat<V>(t.w10) * load<V>(a + 1)) +
                        (splat<V>(t.w01) * load<V>(b) + splat<V>(t.w11) * load<V>(b + 1));
            const V slope = ((v - h0) - margin) * splat<V>(t.invDist);
            hor = slope > hor ? slope : hor;
        }
        const V g = load<V>(r.gx + x) * splat<V>(cosPhi) + load<V>(r.gy + x) * splat<V>(sinPhi);
        const V gc = g < nlim ? nlim : (g > lim ? lim : g);
        V tc = hor < gc ? gc : hor;
        tc = tc > lim ? lim : tc;
        // F(t) = (t (t - g) / (1 + t^2) - g atan t) / 2, so F(g) = -g atan(g) / 2
        const V f = half * (tc * (tc - g) / (one + tc * tc) - g * (atanv(tc) - atanv(gc)));
        // below the plane nothing: exactly 0
        store(r.sum + x, load<V>(r.sum + x) + (tc > gc ? f : splat<V>(0.0f)));
    }
}
void occlusionAzimuthSse(const OcclusionRow& r, const NearTap* taps, int nTaps, float c, float s) {
    occlusionAzimuthImpl<F4>(r, taps, nTaps, c, s);
}
[[gnu::target("avx2"), gnu::flatten]] void occlusionAzimuthAvx2(const OcclusionRow& r, const NearTap* taps, int nTaps,
                                                                float c, float s) {
    occlusionAzimuthImpl<F8>(r, taps, nTaps, c, s);
}

using AzimuthFn = void (*)(const OcclusionRow&, const NearTap*, int, float, float);

// A block's row buffers: gradients, horizons, the occlusion sum (pad floats each).
struct RowScratch {
    float *gx, *gy, *far, *sum;
    static RowScratch at(float* p, int pad) { return {p, p + pad, p + 2 * pad, p + 3 * pad}; }
};

// A row of points: full-resolution row y, columns step * i (i < n; rows padded to pad).
struct PointRow {
    int y, step, n, pad;
    const float* heights;  // the padded heights at (0, y), for the near samples (null: none)
    std::ptrdiff_t stride;
    int nTaps;
};

// A run of points [x0, x1) widened to whole lane groups within the padded row.
struct LaneRun {
    int a, b;
};
LaneRun laneRun(const ColumnSpan& run, int pad) {
    return {run.x0 / kLanePad * kLanePad, std::min(pad, padLanes(run.x1))};
}

// O / pi of the runs of one row of points: per azimuth fillFar(j, far, a, b)
// sets the horizons of the points [a, min(b, n)), then the kernel adds the
// azimuth's integral. Each point's value is its own lanes' arithmetic, the
// same whatever the runs. The runs start on multiples of kLanePad (a tile's
// texels and receivers do: tiles are multiples of 16 receivers), so their
// lane groups never overlap and no point is summed twice.
// `running` (null: not kept): after azimuth j, the running sum at the runs'
// points, at running + j * plane.
template <class FillFar>
void occlusionOfRow(ConstGridView gradX, ConstGridView gradY, const PointRow& p, std::span<const ColumnSpan> runs,
                    const RowScratch& r, const NearTap* taps, const float* cosPhi, const float* sinPhi, int m,
                    float scale, AzimuthFn azimuth, FillFar&& fillFar, float* out, float* running = nullptr,
                    std::size_t plane = 0) {
    for (const ColumnSpan& run : runs) {
        const LaneRun lr = laneRun(run, p.pad);
        for (int i = lr.a; i < lr.b; ++i) {
            const int x = std::min(p.step * i, gradX.nx - 1);
            r.gx[i] = i < p.n ? gradX(x, p.y) : 0.0f;
            r.gy[i] = i < p.n ? gradY(x, p.y) : 0.0f;
            r.sum[i] = 0.0f;
        }
    }
    // without near samples the heights are not read
    const float* heights = p.heights ? p.heights : r.far;
    for (int j = 0; j < m; ++j) {
        const NearTap* jTaps = taps ? taps + static_cast<std::size_t>(j) * p.nTaps : nullptr;
        for (const ColumnSpan& run : runs) {
            const LaneRun lr = laneRun(run, p.pad);
            fillFar(j, r.far, lr.a, std::min(lr.b, p.n));
            if (lr.b > p.n) std::fill(r.far + std::max(lr.a, p.n), r.far + lr.b, kNoBlocker);
            const OcclusionRow row{heights + lr.a, p.stride,     r.gx + lr.a, r.gy + lr.a,
                                   r.far + lr.a,   r.sum + lr.a, lr.b - lr.a};
            azimuth(row, jTaps, p.nTaps, cosPhi[j], sinPhi[j]);
        }
        if (running)
            for (const ColumnSpan& run : runs)
                std::copy(r.sum + run.x0, r.sum + run.x1, running + static_cast<std::size_t>(j) * plane + run.x0);
    }
    for (const ColumnSpan& run : runs)
        for (int i = run.x0; i < run.x1; ++i)
            out[i] = scale * r.sum[i] / std::sqrt(1.0f + r.gx[i] * r.gx[i] + r.gy[i] * r.gy[i]);
}

// Full-resolution heights with a border of B cells (kOutside there), rows of
// `stride` floats (column x is column x / s of phase plane x % s). A copy of
// the build this pyramid redid rows of takes those rows alone.
void fillBorderedHeights(const HeightPyramid& pyr, int B, std::ptrdiff_t stride, BlockerRadianceState& st) {
    const int nx = pyr.nx, ny = pyr.ny, s = pyr.subsample;
    // the border and the padding keep kOutside from the first fill of this layout
    const std::array<std::ptrdiff_t, 4> layout{nx, ny, B, stride};
    if (st.heightsLayout != layout) {
        st.heights.assign(static_cast<std::size_t>(stride) * (ny + 2 * B + 1), kOutside);
        st.heightsLayout = layout;
        st.heightsOfBuild = 0;
    }
    RowSpan rows{0, ny};
    if (st.heightsOfBuild != 0 && st.heightsOfBuild == pyr.buildId) rows = {0, 0};
    if (st.heightsOfBuild != 0 && st.heightsOfBuild == pyr.basedOn) rows = pyr.rawRowsRedone.cut(ny);
    st.heightsOfBuild = 0;  // until the copy is whole
    parallelForRows(rows, nx, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) {
            float* row = st.heights.data() + (y + B) * stride + B;
            for (int q = 0; q < s; ++q) {
                const float* src = pyr.rawPhaseRow(q, y);
                for (int x = q; x < nx; x += s) row[x] = src[x / s];
            }
        }
    });
    st.heightsOfBuild = pyr.buildId;
}

// The near samples of every azimuth (t = 0.5, 1, ..., s - 0.5 cells; nTaps
// each) and the azimuths' cos, sin.
void buildNearTaps(const HeightPyramid& pyr, const std::vector<double>& phi, int nTaps, BlockerRadianceState& st) {
    const int m = static_cast<int>(phi.size());
    std::vector<NearTap>& taps = st.taps;
    std::vector<float>& cosPhi = st.cosPhi;
    std::vector<float>& sinPhi = st.sinPhi;
    taps.resize(static_cast<std::size_t>(m) * nTaps);
    cosPhi.resize(static_cast<std::size_t>(m));
    sinPhi.resize(static_cast<std::size_t>(m));
    for (int j = 0; j < m; ++j) {
        const double c = std::cos(phi[static_cast<std::size_t>(j)]), sn = std::sin(phi[static_cast<std::size_t>(j)]);
        cosPhi[static_cast<std::size_t>(j)] = static_cast<float>(c);
        sinPhi[static_cast<std::size_t>(j)] = static_cast<float>(sn);
        for (int k = 0; k < nTaps; ++k) {
            const double t = 0.5 * (k + 1), ox = t * c, oy = t * sn;
            const double fx0 = std::floor(ox), fy0 = std::floor(oy), fx = ox - fx0, fy = oy - fy0;
            NearTap& tp = taps[static_cast<std::size_t>(j) * nTaps + k];
            tp.dx = static_cast<int>(fx0);
            tp.dy = static_cast<int>(fy0);
            tp.w00 = static_cast<float>((1.0 - fx) * (1.0 - fy));
            tp.w10 = static_cast<float>(fx * (1.0 - fy));
            tp.w01 = static_cast<float>((1.0 - fx) * fy);
            tp.w11 = static_cast<float>(fx * fy);
            tp.invDist = static_cast<float>(1.0 / (t * pyr.cellSize));
        }
    }
}

// What both occlusion passes share: the azimuth kernel and its scale.
struct OcclusionPass {
    int m;
    float scale;  // (2 pi / m) / pi
    AzimuthFn azimuth;
};

// O / pi at the texels of st.texelRuns: the receivers' horizons
// interpolated between rows, then along the row, and the near samples from
// the bordered heights.
void occlusionAtTexels(const HeightPyramid& pyr, ConstGridView gradX, ConstGridView gradY, int B, std::ptrdiff_t stride,
                       int nTaps, const OcclusionPass& pass, BlockerRadianceState& st) {
    const int nx = pyr.nx, ny = pyr.ny, s = pyr.subsample, nxr = pyr.nxr, nyr = pyr.nyr;
    const int pad = padLanes(nx);
    const int nBlocks = (ny + kRowsPerBlock - 1) / kRowsPerBlock;
    const std::size_t perBlock = static_cast<std::size_t>(5) * pad;  // gx, gy, far, sum, receivers' row
    st.scratch.resize(perBlock * nBlocks);
    blocksWithRuns(
        &st.texelRuns, nBlocks, [&](int block) { return rowsOfBlock(block, ny); }, st.busyBlocks);
    parallelForEach(st.busyBlocks, [&](int block) {
        const RowScratch r = RowScratch::at(st.scratch.data() + perBlock * block, pad);
        float* recv = r.sum + pad;
        const RowSpan rows = rowsOfBlock(block, ny);
        for (int y = rows.y0; y < rows.y1; ++y) {
            const ReceiverLerp ry = receiverLerp(y, s, nyr);
            const std::span<const ColumnSpan> runs = st.texelRuns.ofRow(y);
            if (runs.empty()) continue;
            const PointRow pts{y, 1, nx, pad, st.heights.data() + (y + B) * stride + B, stride, nTaps};
            const auto fillFar = [&](int j, float* far, int a, int e) {
                const float* fs = st.farSlope.data() + static_cast<std::size_t>(j) * nxr * nyr;
                const float* f0 = fs + static_cast<std::size_t>(ry.i0) * nxr;
                const float* f1 = fs + static_cast<std::size_t>(ry.i1) * nxr;
                const ColumnSpan read = receiversReadBy(st.cols[static_cast<std::size_t>(a)].i0,
                                                        st.cols[static_cast<std::size_t>(e - 1)].i0, nxr);
                for (int X = read.x0; X < read.x1; ++X) recv[X] = f0[X] + ry.f * (f1[X] - f0[X]);
                for (int x = a; x < e; ++x) {
                    const ReceiverLerp& rx = st.cols[static_cast<std::size_t>(x)];
                    far[x] = recv[rx.i0] + rx.f * (recv[rx.i1] - recv[rx.i0]);
                }
            };
            occlusionOfRow(gradX, gradY, pts, runs, r, st.taps.data(), st.cosPhi.data(), st.sinPhi.data(), pass.m,
                           pass.scale, pass.azimuth, fillFar, st.occlusion.data() + static_cast<std::size_t>(y) * nx);
        }
    });
}

// O_k at the receivers of st.receiverRuns below the scan's horizons alone,
// the blockers E_k saw (no near samples: the scan starts s cells away), so
// that E_k / O_k is their mean radiance; at a receiver's own texel the near
// field then adds O(x) / O_k at that radiance
void occlusionAtReceivers(const HeightPyramid& pyr, ConstGridView gradX, ConstGridView gradY, const OcclusionPass& pass,
                          BlockerRadianceState& st) {
    const int ny = pyr.ny, s = pyr.subsample, nxr = pyr.nxr, nyr = pyr.nyr;
    const int padR = padLanes(nxr);
    const int nBlocksR = (nyr + kRowsPerBlock - 1) / kRowsPerBlock;
    const std::size_t perBlockR = static_cast<std::size_t>(4) * padR;  // gx, gy, far, sum
    if (st.scratch.size() < perBlockR * nBlocksR) st.scratch.resize(perBlockR * nBlocksR);
    blocksWithRows(
        nBlocksR, [&](int block) { return rowsOfBlock(block, nyr); },
        [&](int Y) { return !st.receiverRuns.ofRow(Y).empty(); }, st.busyBlocks);
    parallelForEach(st.busyBlocks, [&](int block) {
        const RowScratch r = RowScratch::at(st.scratch.data() + perBlockR * block, padR);
        const RowSpan rows = rowsOfBlock(block, nyr);
        for (int Y = rows.y0; Y < rows.y1; ++Y) {
            const std::span<const ColumnSpan> runs = st.receiverRuns.ofRow(Y);
            if (runs.empty()) continue;
            const PointRow pts{std::min(s * Y, ny - 1), s, nxr, padR, nullptr, 0, 0};
            const auto fillFar = [&](int j, float* far, int a, int e) {
                const float* fs =
                    st.farSlope.data() + static_cast<std::size_t>(j) * nxr * nyr + static_cast<std::size_t>(Y) * nxr;
                std::copy(fs + a, fs + std::max(a, e), far + a);
            };
            occlusionOfRow(gradX, gradY, pts, runs, r, nullptr, st.cosPhi.data(), st.sinPhi.data(), pass.m, pass.scale,
                           pass.azimuth, fillFar, st.receiverOcclusion.data() + static_cast<std::size_t>(Y) * nxr,
                           st.receiverOcclusionRunning.data() + static_cast<std::size_t>(Y) * nxr,
                           static_cast<std::size_t>(nxr) * nyr);
        }
    });
}

// The runs of the texel passes: the receivers of the dirty tiles, and
// `runs` or the tiles' texels (every one without tiles).
void planRuns(const ReceiverTiles* tiles, const TexelRuns* runs, BlockerRadianceState& st) {
    dirtySpans(tiles, st.nxr, st.nyr, st.receiverRuns);
    if (tiles && runs)
        st.texelRuns = *runs;
    else
        texelRunsOfTiles(tiles, st.nx, st.ny, st.subsample, st.texelRuns);
}

}  // namespace

void prepareBlockerRadiance(const HeightPyramid& pyr, int azimuths, BlockerRadianceState& st) {
    if (st.nx != pyr.nx || st.ny != pyr.ny || st.subsample != pyr.subsample || st.azimuths != azimuths)
        st.occlusionValid = false;
    st.nx = pyr.nx;
    st.ny = pyr.ny;
    st.nxr = pyr.nxr;
    st.nyr = pyr.nyr;
    st.subsample = pyr.subsample;
    st.azimuths = azimuths;
    const std::size_t planeR = static_cast<std::size_t>(pyr.nxr) * pyr.nyr;
    for (std::vector<float>& v : st.receiverShade) v.resize(planeR);
    if (pyr.subsample == 1) return;  // every texel a receiver: E alone
    st.farSlope.resize(planeR * static_cast<std::size_t>(azimuths));
    st.receiverOcclusion.resize(planeR);
    st.receiverOcclusionRunning.resize(planeR * static_cast<std::size_t>(azimuths));
    st.receiverGroupOcclusion.resize(planeR * static_cast<std::size_t>(kDistanceGroups));
    st.occlusion.ensureSize(pyr.nx, pyr.ny);
}

void computeTexelOcclusion(const HeightPyramid& pyr, ConstGridView gradX, ConstGridView gradY,
                           const std::vector<double>& phi, const ReceiverTiles* tiles, const TexelRuns* runs,
                           BlockerRadianceState& st) {
    const int nx = pyr.nx, s = pyr.subsample, nxr = pyr.nxr;
    const int m = static_cast<int>(phi.size());
    const int B = s;  // border: the near samples reach s - 0.5 cells, their taps s cells
    const int pad = padLanes(nx);
    const std::ptrdiff_t stride = pad + 2 * B + kLanePad;
    fillBorderedHeights(pyr, B, stride, st);
    const int nTaps = 2 * s - 1;
    buildNearTaps(pyr, phi, nTaps, st);
    // per full-resolution column: the receivers it interpolates
    st.cols.resize(static_cast<std::size_t>(nx));
    for (int x = 0; x < nx; ++x) st.cols[static_cast<std::size_t>(x)] = receiverLerp(x, s, nxr);
    planRuns(st.occlusionValid ? tiles : nullptr, runs, st);
    const OcclusionPass pass{m, 2.0f / static_cast<float>(m),
                             simd::wideEnabled() ? occlusionAzimuthAvx2 : occlusionAzimuthSse};
    occlusionAtTexels(pyr, gradX, gradY, B, stride, nTaps, pass, st);
    occlusionAtReceivers(pyr, gradX, gradY, pass, st);
    st.occlusionValid = true;
}

namespace {

// The bounce's exit radiance at the texels [x0, x1) of row y (s > 1), the
// receivers' rows interpolated over the receivers those texels read.
void shadeTexelRun(const BlockerRadianceState& st, const float* const alb[3], int y, int x0, int x1, float* oRow,
                   float* const eRow[3], std::array<Grid, 3>& rgb) {
    const int nx = st.nx, nxr = st.nxr;
    const ReceiverLerp ry = receiverLerp(y, st.subsample, st.nyr);
    const std::size_t r0 = static_cast<std::size_t>(ry.i0) * nxr, r1 = static_cast<std::size_t>(ry.i1) * nxr;
    const ColumnSpan read =
        receiversReadBy(st.cols[static_cast<std::size_t>(x0)].i0, st.cols[static_cast<std::size_t>(x1 - 1)].i0, nxr);
    const float* o = st.receiverOcclusion.data();
    for (int X = read.x0; X < read.x1; ++X) oRow[X] = o[r0 + X] + ry.f * (o[r1 + X] - o[r0 + X]);
    for (int c = 0; c < 3; ++c) {
        const float* e = st.receiverShade[static_cast<std::size_t>(c)].data();
        for (int X = read.x0; X < read.x1; ++X) eRow[c][X] = e[r0 + X] + ry.f * (e[r1 + X] - e[r0 + X]);
    }
    const std::size_t at = static_cast<std::size_t>(y) * nx;
    const float* occ = st.occlusion.data() + at;
    for (int x = x0; x < x1; ++x) {
        const ReceiverLerp& rx = st.cols[static_cast<std::size_t>(x)];
        const float den = oRow[rx.i0] + rx.f * (oRow[rx.i1] - oRow[rx.i0]);
        // the blockers' mean radiance (E / O, interpolated) times this texel's occlusion
        const float k = den > 0.0f ? occ[x] / den : 0.0f;
        for (int c = 0; c < 3; ++c) {
            const float* e = eRow[c];
            const float num = e[rx.i0] + rx.f * (e[rx.i1] - e[rx.i0]);
            rgb[static_cast<std::size_t>(c)].v[at + static_cast<std::size_t>(x)] =
                (alb[c] ? alb[c][at + x] : 1.0f) * (k * num);
        }
    }
}

}  // namespace

void shadeBlockerRadiance(BlockerRadianceState& st, const AlbedoMap* albedo, const ReceiverTiles* tiles,
                          const TexelRuns* runs, std::array<Grid, 3>& rgb) {
    const int nx = st.nx, ny = st.ny, s = st.subsample, nxr = st.nxr, nyr = st.nyr;
    for (Grid& g : rgb) g.ensureSize(nx, ny);
    const float* alb[3];
    for (int c = 0; c < 3; ++c)
        alb[c] = albedo && !albedo->channel[static_cast<std::size_t>(c)].empty()
                     ? albedo->channel[static_cast<std::size_t>(c)].data()
                     : nullptr;
    if (s == 1) {  // every texel a receiver
        dirtySpans(tiles, nxr, nyr, st.receiverRuns);
        parallelForRows(ny, nx, [&](int y0, int y1) {
            for (int y = y0; y < y1; ++y)
                for (const ColumnSpan& run : st.receiverRuns.ofRow(y))
                    for (int c = 0; c < 3; ++c) {
                        const std::size_t a = static_cast<std::size_t>(y) * nx + run.x0;
                        const std::size_t e = static_cast<std::size_t>(y) * nx + run.x1;
                        const float* in = st.receiverShade[static_cast<std::size_t>(c)].data();
                        float* out = rgb[static_cast<std::size_t>(c)].data();
                        for (std::size_t i = a; i < e; ++i) out[i] = (alb[c] ? alb[c][i] : 1.0f) * in[i];
                    }
        });
        return;
    }
    planRuns(tiles, runs, st);
    const int nBlocks = (ny + kRowsPerBlock - 1) / kRowsPerBlock;
    const std::size_t perBlock = static_cast<std::size_t>(4) * nxr;  // O, E x 3 of a row, between receiver rows
    if (st.scratch.size() < perBlock * nBlocks) st.scratch.resize(perBlock * nBlocks);
    blocksWithRuns(
        &st.texelRuns, nBlocks, [&](int block) { return rowsOfBlock(block, ny); }, st.busyBlocks);
    parallelForEach(st.busyBlocks, [&](int block) {
        float* oRow = st.scratch.data() + perBlock * block;
        float* const eRow[3] = {oRow + nxr, oRow + 2 * nxr, oRow + 3 * nxr};
        const RowSpan rows = rowsOfBlock(block, ny);
        for (int y = rows.y0; y < rows.y1; ++y)
            for (const ColumnSpan& run : st.texelRuns.ofRow(y))
                shadeTexelRun(st, alb, y, run.x0, run.x1, oRow, eRow, rgb);
    });
}

}  // namespace terrain::gi
