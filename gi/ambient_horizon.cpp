#include "gi/ambient_horizon.h"

#include <algorithm>

#include "core/error.h"
#include "core/parallel.h"
#include "core/simd.h"
#include "gi/near_field.h"
#include "gi/shading.h"

namespace terrain::gi {

namespace {

using simd::atanv;
using simd::load;
using simd::splat;
using simd::sqrtv;
using simd::store;

constexpr float kHalfPi = 1.57079632679489661923f;
constexpr int kRowsPerSlot = 5;  // row buffers: three integrals, horizon, the receivers' vertical blend

// What one row block needs, fixed for the frame.
struct AmbientJob {
    const AmbientInputs& in;
    int nx, ny, nxr, nyr, m;
    int rowFloats;                   // scratch floats per row buffer (nx rounded up, or nxr)
    float* scratch;                  // per worker slot: kRowsPerSlot rows, then the raised window
    const ReceiverLerp* columns;     // per texel column: the receivers it lies between
    const NearFieldStep* nearSteps;  // azimuths x subsample
    const TexelRuns* runs;           // null: every texel
    const AmbientOutputs& out;
};

// Per texel of [x0, x1) and one azimuth (c, sn), t the texels' horizon
// slopes before the tangent plane is applied (sin sigma cos sigma =
// t / (1 + t^2), cos^2 sigma = 1 / (1 + t^2)):
//   acc[0] += -g (pi/2 - sigma - sin sigma cos sigma) + cos^2 sigma,
// evaluated as (cos^2 sigma + g (t cos^2 sigma - pi/2)) + g sigma, so that the
// atan's long chain ends in one multiply-add; and with the sky gradient's
// parts (gi/ambient_horizon.h), a = max(sigma, 0):
//   acc[1] += that minus its value at sigma = 0 (1 - g pi/2) when sigma < 0,
//   acc[2] += 2/3 (1 - sin^3 a - g cos^3 a).
// K vectors at a time, each step over all K before the next: their chains
// are independent, and interleaved the out-of-order core overlaps them (one
// vector's chain alone keeps its scheduler waiting on the divisions).
template <class V, bool Parts, int K>
[[gnu::always_inline]] inline void addAzimuthVectors(const float* gx, const float* gy, const float* horizon, V vc, V vs,
                                                     float* const acc[3], int x) {
    constexpr int L = simd::kLaneCount<V>;
    const V one = splat<V>(1.0f), halfPi = splat<V>(kHalfPi);
    V g[K], t[K], r2[K], sigma[K];
    for (int k = 0; k < K; ++k) {
        g[k] = load<V>(gx + x + k * L) * vc + load<V>(gy + x + k * L) * vs;
        const V h = load<V>(horizon + x + k * L);
        t[k] = h > g[k] ? h : g[k];
    }
    for (int k = 0; k < K; ++k) r2[k] = one / (one + t[k] * t[k]);
    for (int k = 0; k < K; ++k) sigma[k] = atanv(t[k]);
    for (int k = 0; k < K; ++k) {
        float* const out = acc[0] + x + k * L;
        const V term = (r2[k] + g[k] * (t[k] * r2[k] - halfPi)) + g[k] * sigma[k];
        store(out, load<V>(out) + term);
        if constexpr (Parts) {
            const V zero = splat<V>(0.0f), twoThirds = splat<V>(2.0f / 3.0f);
            const V below = t[k] < zero ? term - (one - g[k] * halfPi) : zero;
            const V ta = t[k] > zero ? t[k] : zero;
            const V cos2a = t[k] > zero ? r2[k] : one;
            const V cos3a = cos2a * sqrtv(cos2a);
            const V rising = twoThirds * (one - ta * ta * ta * cos3a - g[k] * cos3a);
            store(acc[1] + x + k * L, load<V>(acc[1] + x + k * L) + below);
            store(acc[2] + x + k * L, load<V>(acc[2] + x + k * L) + rising);
        }
    }
}

// The whole vectors of [x0, x1): eight at a time (the more chains in
// flight, the more of the divisions' latency is hidden), then two, then one.
template <class V, bool Parts>
[[gnu::always_inline]] inline void addAzimuth(const float* gx, const float* gy, const float* horizon, float c, float sn,
                                              float* const acc[3], int x0, int x1) {
    constexpr int L = simd::kLaneCount<V>;
    const V vc = splat<V>(c), vs = splat<V>(sn);
    int x = x0;
    for (; x + 8 * L <= x1; x += 8 * L) addAzimuthVectors<V, Parts, 8>(gx, gy, horizon, vc, vs, acc, x);
    for (; x + 2 * L <= x1; x += 2 * L) addAzimuthVectors<V, Parts, 2>(gx, gy, horizon, vc, vs, acc, x);
    for (; x + L <= x1; x += L) addAzimuthVectors<V, Parts, 1>(gx, gy, horizon, vc, vs, acc, x);
}

// The texel range [x0, x1) of a row: whole vectors, then the rest through
// one zero-padded vector (the same lane arithmetic, so a texel's value does
// not depend on where it falls).
template <class V, bool Parts>
[[gnu::always_inline]] inline void addAzimuthRun(const float* gx, const float* gy, const float* horizon, float c,
                                                 float sn, float* const acc[3], int x0, int x1) {
    constexpr int L = simd::kLaneCount<V>;
    const int vecEnd = x0 + (x1 - x0) / L * L, nx = x1;
    addAzimuth<V, Parts>(gx, gy, horizon, c, sn, acc, x0, vecEnd);
    if (vecEnd == nx) return;
    alignas(32) float tail[6][L] = {};
    const int n = nx - vecEnd, rows = Parts ? 3 : 1;
    std::copy(gx + vecEnd, gx + nx, tail[0]);
    std::copy(gy + vecEnd, gy + nx, tail[1]);
    std::copy(horizon + vecEnd, horizon + nx, tail[2]);
    float* const tailAcc[3] = {tail[3], tail[4], tail[5]};
    for (int r = 0; r < rows; ++r) std::copy(acc[r] + vecEnd, acc[r] + nx, tailAcc[r]);
    addAzimuth<V, Parts>(tail[0], tail[1], tail[2], c, sn, tailAcc, 0, L);
    for (int r = 0; r < rows; ++r) std::copy(tailAcc[r], tailAcc[r] + n, acc[r] + vecEnd);
}

// out[r][x] = acc[r][x] / (m n) over a row, n = sqrt(1 + gx^2 + gy^2): the
// midpoint rule's weight and the normal's length (gi/ambient_horizon.h);
// whole vectors, then the rest one by one (the same IEEE operations).
template <class V, int Maps>
[[gnu::always_inline]] inline void normaliseRow(const float* const acc[3], const float* gx, const float* gy,
                                                float perAzimuth, float* const out[3], int nx) {
    constexpr int L = simd::kLaneCount<V>;
    const V one = splat<V>(1.0f), w = splat<V>(perAzimuth);
    int x = 0;
    for (; x + L <= nx; x += L) {
        const V gxv = load<V>(gx + x), gyv = load<V>(gy + x);
        const V n = sqrtv(one + gxv * gxv + gyv * gyv);
        for (int r = 0; r < Maps; ++r) store(out[r] + x, load<V>(acc[r] + x) * w / n);
    }
    for (; x < nx; ++x) {
        const float n = std::sqrt(1.0f + gx[x] * gx[x] + gy[x] * gy[x]);
        for (int r = 0; r < Maps; ++r) out[r][x] = acc[r][x] * perAzimuth / n;
    }
}

// The horizon slopes of receiver row Y along azimuth a (c, sn) at the
// receivers `cols`, each raised to the receiver's lowest tangent slope: the
// footprint box's when there is one, else its own.
void receiverRowHorizons(const AmbientJob& j, int Y, int a, float c, float sn, ColumnSpan cols, float* out) {
    const std::size_t row = static_cast<std::size_t>(Y) * j.nxr;
    const float* h = j.in.env->maxSlope.data() + static_cast<std::size_t>(a) * j.nxr * j.nyr + row;
    if (const FootprintBox* f = j.in.footprint) {
        const float* tx = (c >= 0.0f ? f->loX.data() : f->hiX.data()) + row;
        const float* ty = (sn >= 0.0f ? f->loY.data() : f->hiY.data()) + row;
        for (int X = cols.x0; X < cols.x1; ++X) out[X] = std::max(h[X], tx[X] * c + ty[X] * sn);
        return;
    }
    const int s = j.in.subsample, y = std::min(s * Y, j.ny - 1);
    const float* gx = j.in.gradX.row(y);
    const float* gy = j.in.gradY.row(y);
    for (int X = cols.x0; X < cols.x1; ++X) {
        const int x = std::min(s * X, j.nx - 1);
        out[X] = std::max(h[X], gx[x] * c + gy[x] * sn);
    }
}

// The two receiver rows a texel row interpolates between, every azimuth's
// horizons raised (receiverRowHorizons), in a worker slot's scratch: azimuth
// a's two rows at rows + 2 a nxr and rows + (2 a + 1) nxr, `first` saying
// which of them holds row i0. The rows a block's texel rows read change
// every s texel rows, and then the last i1 is the new i0: it is kept, and
// only the new i1 is raised. Only the receivers `cols` (the block's texels
// read no others) are raised.
struct RaisedWindow {
    float* rows;
    int nxr = 0;
    ColumnSpan cols;
    int i0 = -1, i1 = -1;
    int first = 0;
    float f = 0.0f;  // the covered texel row's fraction from row i0 towards row i1

    float* slot(int a, int k) const { return rows + (2 * static_cast<std::size_t>(a) + k) * nxr; }
    const float* row0(int a) const { return slot(a, first); }
    const float* row1(int a) const { return slot(a, 1 - first); }

    void cover(const AmbientJob& j, int y) {
        const ReceiverLerp ry = receiverLerp(y, j.in.subsample, j.nyr);
        f = ry.f;
        if (ry.i0 == i0 && ry.i1 == i1) return;
        const bool shift = ry.i0 == i1;  // the old i1's rows are the new i0's
        if (shift) first = 1 - first;
        i0 = ry.i0;
        i1 = ry.i1;
        for (int a = 0; a < j.m; ++a) {
            const float c = j.in.cosSin[2 * static_cast<std::size_t>(a)];
            const float sn = j.in.cosSin[2 * static_cast<std::size_t>(a) + 1];
            if (!shift) receiverRowHorizons(j, i0, a, c, sn, cols, slot(a, first));
            receiverRowHorizons(j, i1, a, c, sn, cols, slot(a, 1 - first));
        }
    }
};

// Horizon slopes of azimuth a at the texels of a run of the row the window
// covers, bilinear from the raised receivers (Fig. 7): the vertical mix of
// the receivers the run reads, then along the row (lerpReceiverSpan: the
// same operations over a whole row or a part of one). vert: nxr floats of
// scratch.
void interpolatedHorizons(const AmbientJob& j, const RaisedWindow& window, int a, ColumnSpan run, float* vert,
                          float* out) {
    const bool wholeRow = run.x0 == 0 && run.x1 == j.nx;
    const ColumnSpan read =
        wholeRow ? ColumnSpan{0, j.nxr} : receiversReadBy(j.columns[run.x0].i0, j.columns[run.x1 - 1].i0, j.nxr);
    const float* t0 = window.row0(a);
    const float* t1 = window.row1(a);
    for (int X = read.x0; X < read.x1; ++X) vert[X] = t0[X] + window.f * (t1[X] - t0[X]);
    lerpReceiverSpan(vert, j.nxr, j.in.subsample, j.columns, run.x0, run.x1, out);
}

// One texel row's runs: every azimuth's horizons (at sub-sampling
// interpolated and raised to the near field) into the integrals of the runs'
// texels, V the lane type.
template <class V, bool Parts>
[[gnu::always_inline]] inline void ambientRowWith(const AmbientJob& j, int y, std::span<const ColumnSpan> runs,
                                                  float* buffers, const RaisedWindow& window) {
    float* const acc[3] = {buffers, buffers + j.rowFloats, buffers + 2 * static_cast<std::size_t>(j.rowFloats)};
    float* horizon = buffers + 3 * static_cast<std::size_t>(j.rowFloats);
    float* vert = buffers + 4 * static_cast<std::size_t>(j.rowFloats);
    for (int r = 0; r < (Parts ? 3 : 1); ++r)
        for (const ColumnSpan& run : runs) std::fill(acc[r] + run.x0, acc[r] + run.x1, 0.0f);
    const float* gx = j.in.gradX.row(y);
    const float* gy = j.in.gradY.row(y);
    for (int a = 0; a < j.m; ++a) {
        const float c = j.in.cosSin[2 * static_cast<std::size_t>(a)];
        const float sn = j.in.cosSin[2 * static_cast<std::size_t>(a) + 1];
        const float* h;
        if (j.in.subsample == 1) {
            h = j.in.env->maxSlope.data() + (static_cast<std::size_t>(a) * j.ny + y) * j.nx;
        } else {
            const std::span<const NearFieldStep> near{j.nearSteps + static_cast<std::size_t>(a) * j.in.subsample,
                                                      static_cast<std::size_t>(j.in.subsample)};
            for (const ColumnSpan& run : runs) {
                interpolatedHorizons(j, window, a, run, vert, horizon);
                raiseToNearField(j.in.heights, y, near, horizon, run.x0, run.x1);
            }
            h = horizon;
        }
        for (const ColumnSpan& run : runs) addAzimuthRun<V, Parts>(gx, gy, h, c, sn, acc, run.x0, run.x1);
    }
    Grid* const maps[3] = {&j.out.ambient, j.out.below, j.out.rising};
    for (const ColumnSpan& run : runs) {
        const std::size_t at = static_cast<std::size_t>(y) * j.nx + run.x0;
        float* const out[3] = {maps[0]->data() + at, Parts ? maps[1]->data() + at : nullptr,
                               Parts ? maps[2]->data() + at : nullptr};
        const float* const runAcc[3] = {acc[0] + run.x0, acc[1] + run.x0, acc[2] + run.x0};
        normaliseRow<V, Parts ? 3 : 1>(runAcc, gx + run.x0, gy + run.x0, 1.0f / static_cast<float>(j.m), out,
                                       run.x1 - run.x0);
    }
}

// The AVX2 builds of the row: 8-wide lanes in the integrals and the
// compiler's 32-byte vectors in the interpolation and the near field
// (element-wise float arithmetic in the same order: the same bits as the
// SSE2 build).
using Runs = std::span<const ColumnSpan>;
[[gnu::target("avx2"), gnu::flatten]] void ambientRowAvx2(const AmbientJob& j, int y, Runs runs, float* buffers,
                                                          const RaisedWindow& window) {
    ambientRowWith<simd::F8, false>(j, y, runs, buffers, window);
}
[[gnu::target("avx2"), gnu::flatten]] void ambientPartsRowAvx2(const AmbientJob& j, int y, Runs runs, float* buffers,
                                                               const RaisedWindow& window) {
    ambientRowWith<simd::F8, true>(j, y, runs, buffers, window);
}

// The runs of one texel row; at sub-sampling `window` covers it (RaisedWindow::cover).
void ambientRow(const AmbientJob& j, int y, Runs runs, float* buffers, const RaisedWindow& window) {
    const bool parts = j.out.below != nullptr;
    if (simd::wideEnabled())
        (parts ? ambientPartsRowAvx2 : ambientRowAvx2)(j, y, runs, buffers, window);
    else
        (parts ? ambientRowWith<simd::F4, true> : ambientRowWith<simd::F4, false>)(j, y, runs, buffers, window);
}

void checkInputs(const AmbientInputs& in, int m, const TexelRuns* runs) {
    const VisibilityField& env = *in.env;
    const int s = in.subsample;
    if (in.gradY.nx != in.gradX.nx || in.gradY.ny != in.gradX.ny || s < 1 || env.nxr != (in.gradX.nx + s - 1) / s ||
        env.nyr != (in.gradX.ny + s - 1) / s ||
        env.maxSlope.size() != static_cast<std::size_t>(m) * env.nxr * env.nyr || in.cosSin.size() != 2u * m)
        throw InputError("ambient: the horizons are not of this grid, sub-sampling and azimuth count");
    if (s > 1 && (in.heights.nx != in.gradX.nx || in.heights.ny != in.gradX.ny || !(in.cellSize > 0.0f)))
        throw InputError("ambient: sub-sampling needs the field's heights and cell size");
    if (runs && runs->ny != in.gradX.ny) throw InputError("ambient: texel runs of another grid");
}

}  // namespace

void ambientFromHorizons(const AmbientInputs& in, const AmbientOutputs& out, AmbientScratch& scratch,
                         const TexelRuns* runs) {
    const int m = static_cast<int>(in.cosSin.size() / 2);
    checkInputs(in, m, runs);
    if ((out.below == nullptr) != (out.rising == nullptr))
        throw InputError("ambient: the sky gradient's parts come together (below and rising)");
    const int nx = in.gradX.nx, ny = in.gradX.ny;
    out.ambient.ensureSize(nx, ny);
    if (out.below) {
        out.below->ensureSize(nx, ny);
        out.rising->ensureSize(nx, ny);
    }
    const int nBlocks = std::max(1, std::min(ny, 64));
    const int rowFloats = std::max(nx, in.env->nxr);
    const int s = in.subsample, nxr = in.env->nxr, nyr = in.env->nyr;
    // per worker slot: the row buffers, then (sub-sampling) the raised window
    const std::size_t slotFloats =
        kRowsPerSlot * static_cast<std::size_t>(rowFloats) + (s > 1 ? 2 * static_cast<std::size_t>(m) * nxr : 0);
    scratch.rows.resize(static_cast<std::size_t>(workerSlots()) * slotFloats);
    receiverLerps(nx, s, nxr, scratch.columns);
    if (s > 1) buildNearFieldSteps(in.cosSin, s, in.cellSize, scratch.nearSteps);
    const AmbientJob job{
        in,   nx, ny, nxr, nyr, m, rowFloats, scratch.rows.data(), scratch.columns.data(), scratch.nearSteps.data(),
        runs, out};
    // a row keeps nothing in the scratch but the window, which a block
    // starts afresh; only the blocks with runs are handed out
    const auto blockRows = [&](int block) {
        return RowSpan{static_cast<int>(static_cast<long long>(ny) * block / nBlocks),
                       static_cast<int>(static_cast<long long>(ny) * (block + 1) / nBlocks)};
    };
    blocksWithRuns(runs, nBlocks, blockRows, scratch.busyBlocks);
    parallelForEach(scratch.busyBlocks, [&](int block) {
        float* buffers = job.scratch + static_cast<std::size_t>(workerSlot()) * slotFloats;
        const RowSpan rows = blockRows(block);
        const ColumnSpan read =
            receiverColumnsRead(runs, rows.y0, rows.y1, nxr, [&](int x) { return job.columns[x].i0; });
        RaisedWindow window{buffers + kRowsPerSlot * static_cast<std::size_t>(rowFloats), nxr, read};
        const ColumnSpan wholeRow{0, nx};
        for (int y = rows.y0; y < rows.y1; ++y) {
            const Runs rowRuns = runsOfRow(runs, y, wholeRow);
            if (rowRuns.empty()) continue;
            if (s > 1) window.cover(job, y);
            ambientRow(job, y, rowRuns, buffers, window);
        }
    });
}

namespace {

// shade[c] += albedo[c] x value(c, i) at every texel i of the runs (`runs`
// as for ambientFromHorizons; albedo 1 where the map has no channel).
template <class Value>
void addLambertSky(int nx, int ny, const AlbedoMap* albedo, std::array<Grid, 3>& shade, const TexelRuns* runs,
                   Value value) {
    const ColumnSpan wholeRow{0, nx};
    parallelForRows(ny, nx, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) {
            const std::size_t row = static_cast<std::size_t>(y) * nx;
            for (const ColumnSpan& run : runsOfRow(runs, y, wholeRow))
                for (std::size_t c = 0; c < 3; ++c) {
                    const bool mapped = albedo && !albedo->channel[c].empty();
                    float* out = shade[c].data() + row;
                    for (int x = run.x0; x < run.x1; ++x) {
                        const float a = mapped ? albedo->channel[c].v[row + x] : 1.0f;
                        out[x] += a * value(c, row + x);
                    }
                }
        }
    });
}

}  // namespace

void addConstantSky(const Grid& ambient, const float radiance[3], const AlbedoMap* albedo, std::array<Grid, 3>& shade,
                    const TexelRuns* runs) {
    addLambertSky(ambient.nx, ambient.ny, albedo, shade, runs,
                  [&](std::size_t c, std::size_t i) { return radiance[c] * ambient.v[i]; });
}

void addGradientSky(const AmbientOutputs& parts, const SkyGradient& sky, const AlbedoMap* albedo,
                    std::array<Grid, 3>& shade, const TexelRuns* runs) {
    addLambertSky(parts.ambient.nx, parts.ambient.ny, albedo, shade, runs, [&](std::size_t c, std::size_t i) {
        const float below = parts.below->v[i];
        return sky.horizon[c] * (parts.ambient.v[i] - below) + sky.ground[c] * below +
               (sky.zenith[c] - sky.horizon[c]) * parts.rising->v[i];
    });
}

}  // namespace terrain::gi
