#include "gi/glossy_lobe_gather.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/bfloat16.h"
#include "core/parallel.h"
#include "core/simd.h"
#include "gi/azimuth.h"
#include "gi/indirect_scan_tables.h"
#include "gi/phong_lobe_quadrature.h"
#include "gi/sh.h"

namespace terrain::gi {

namespace {

constexpr int kPlanes = 3 * kShCount;  // RGB x 16 SH planes of the exit radiance
constexpr int kBandTopsChunk = 64;     // receivers whose walks' band maxima are taken together

// One receiver's lobe: its reflection R (unit), frame and exponent.
struct ReceiverLobe {
    double r[3], t[3], b[3];
    double S;
};

ReceiverLobe receiverLobe(float gx, float gy, const float view[3], double S) {
    ReceiverLobe L;
    const double inv = 1.0 / std::sqrt(1.0 + static_cast<double>(gx) * gx + static_cast<double>(gy) * gy);
    const double n[3] = {-gx * inv, -gy * inv, inv};
    const double d = 2.0 * (n[0] * view[0] + n[1] * view[1] + n[2] * view[2]);
    for (int a = 0; a < 3; ++a) L.r[a] = d * n[a] - view[a];
    const double len = std::sqrt(L.r[0] * L.r[0] + L.r[1] * L.r[1] + L.r[2] * L.r[2]);
    for (double& v : L.r) v /= len;
    lobeFrame(L.r, L.t, L.b);
    L.S = S;
    return L;
}

// How far texel f stands ahead of its receiver along the azimuth (c, sn),
// in cells: the walk's distances from it and the bands' clearance from it
// (BandClearance) take the same value.
double texelAlong(const GlossyLobeScratch::TexelFrame& f, double c, double sn) { return f.ox * c + f.oy * sn; }

// Receiver X's highest samples of azimuth j (GlossyLobeScratch::bandTops):
// band k's at [k * kBandTopsChunk].
const float* bandTopsOf(const GlossyLobeState& st, const GlossyLobeScratch& sc, int X, int j) {
    return sc.bandTops.data() + static_cast<std::size_t>(j * st.bands) * kBandTopsChunk +
           static_cast<std::size_t>(X % kBandTopsChunk);
}

// Receiver X's walk along azimuth j seen from texel f, band by band: each
// band's samples lie at most GlossyLobeScratch::bandTops high (rise, over the
// texel less its margin) and at least the band's nearest step ahead of the
// texel (run; the walk reads none nearer than half a cell), so a ray of slope
// t >= 0 passes above them where t run > rise, in the walk's own double
// arithmetic (its steps' runs and rises are no shorter and no higher).
struct BandClearance {
    const float* tops;    // band k's at tops[k * kBandTopsChunk]
    const double* start;  // band k's nearest step (cells)
    double along, h, margin, cell;
    int bands;
    double run(int k) const { return std::max(0.5, start[k] - along) * cell; }
    double rise(int k) const {
        return (static_cast<double>(tops[static_cast<std::size_t>(k * kBandTopsChunk)]) - h) - margin;
    }
};

BandClearance bandClearance(const GlossyLobeState& st, const GlossyLobeScratch& sc,
                            const GlossyLobeScratch::TexelFrame& f, int X, int j, double cell) {
    const auto ju = static_cast<std::size_t>(j);
    const double c = st.cosPhi[ju], sn = st.sinPhi[ju];
    return {bandTopsOf(st, sc, X, j),
            st.bandStart.data() + static_cast<std::size_t>(j * st.bands),
            texelAlong(f, c, sn),
            f.h,
            f.margin,
            cell,
            st.bands};
}

// The slope above which a ray leaving texel f along azimuth j meets no
// sample of receiver X's walk: the highest rise / run over the bands that
// hold one (BandClearance), raised by 1e-9 of itself (far more than the
// division's and the walk's product's rounding); -inf where none does.
// Taken once per texel and azimuth.
double escapeSlope(const GlossyLobeState& st, GlossyLobeScratch& sc, const GlossyLobeScratch::TexelFrame& f, int X,
                   int j, double cell) {
    const auto ju = static_cast<std::size_t>(j);
    if (sc.escapeStamp[ju] == sc.texelSerial) return sc.escape[ju];
    const BandClearance bc = bandClearance(st, sc, f, X, j, cell);
    double escape = -std::numeric_limits<double>::infinity();
    for (int k = 0; k < bc.bands; ++k) {
        const double rise = bc.rise(k);
        if (rise > -std::numeric_limits<double>::infinity())  // a band with no sample bounds nothing
            escape = std::max(escape, rise / bc.run(k));
    }
    if (!std::isinf(escape)) escape += std::fabs(escape) * 1e-9;
    sc.escape[ju] = escape;
    sc.escapeStamp[ju] = sc.texelSerial;
    return escape;
}

// Whether every ray of the lobe L of a texel clears its walks
// (BandClearance; the escape slope's bound without its divisions, which
// across every azimuth of a lobe about the zenith cost more than the test
// saves) along every azimuth its directions reach, so that it has none: the directions lie within the widest ring's angle theta of R, so
// none is lower than elevation(R) - theta (its slope is lowered by 1e-6 of
// itself, beyond the directions' rounding and the rays' float slopes), and
// their azimuths within asin(sin theta / cos elevation(R)) of R's (every
// azimuth where the lobe holds the zenith). asin(x) <= x + (pi / 2 - 1) x^3
// on [0, 1]; the span is widened by 0.05 azimuths for azimuthOf's error
// (1e-5 radians, 0.013 azimuths at the most azimuths allowed), and by the
// azimuth after it, which takes the linear weight of the rays between the
// two.
bool lobeEscapes(const ReceiverLobe& L, const GlossyLobeState& st, const GlossyLobeScratch::TexelFrame& frame, int X,
                 double cell, const GlossyLobeScratch& sc) {
    const double cosT = sc.quadrature.widestCos(), sinT = std::sqrt(std::max(0.0, 1.0 - cosT * cosT));
    const double rz = L.r[2], rh = std::sqrt(L.r[0] * L.r[0] + L.r[1] * L.r[1]);
    const double lowZ = rz * cosT - rh * sinT;  // sin(elevation(R) - theta)
    if (!(lowZ > 1e-6)) return false;           // the lobe reaches the horizon
    const double lowH = rh * cosT + rz * sinT;  // its cosine
    const double lowest = lowZ / lowH * (1.0 - 1e-6);
    const int M = static_cast<int>(st.phi.size());
    int first = 0, last = M - 1;
    if (rh > sinT) {
        const double dphi = 2.0 * kPi / M, x = sinT / rh;
        const double half = (x + (0.5 * kPi - 1.0) * x * x * x) / dphi + 0.05;
        const double u = azimuthOf(L.r[0], L.r[1]) / dphi;
        first = static_cast<int>(std::floor(u - half));
        last = std::min(static_cast<int>(std::floor(u + half)) + 1, first + M - 1);
    }
    for (int j = first; j <= last; ++j) {
        const BandClearance bc = bandClearance(st, sc, frame, X, (j % M + M) % M, cell);
        for (int k = 0; k < bc.bands; ++k)
            if (!(lowest * bc.run(k) > bc.rise(k))) return false;
    }
    return true;
}

// A texel's rays as the walks read them, appended to sc.rays: each lobe
// direction split between the two global azimuths on either side of it
// (linear weights), those above the texel's tangent plane along their azimuth
// and below its escape slope there only (a ray above it meets nothing, and
// the rays a walk meets come in the same order without it). The directions
// go through each stage together (loops the compiler vectorises), the rays
// are appended one by one.
void appendLobeRays(const ReceiverLobe& L, const GlossyLobeState& st, float gx, float gy, int X, double cell, int texel,
                    GlossyLobeScratch& sc) {
    const GlossyLobeScratch::TexelFrame& frame = sc.texelFrames[static_cast<std::size_t>(texel)];
    ++sc.texelSerial;
    if (lobeEscapes(L, st, frame, X, cell, sc)) return;
    const int count = sc.quadrature.directions(), M = static_cast<int>(st.phi.size());
    const double dphi = 2.0 * kPi / M;
    const float w0 = 1.0f / static_cast<float>(count);
    GlossyLobeScratch::Directions& dir = sc.directions;
    dir.resize(count);
    for (int d = 0; d < count; ++d) {
        double w[3];
        sc.quadrature.direction(L.r, L.t, L.b, d, w);
        dir.x[d] = w[0];
        dir.y[d] = w[1];
        dir.z[d] = w[2];
    }
    for (int d = 0; d < count; ++d) dir.horizontal[d] = std::sqrt(dir.x[d] * dir.x[d] + dir.y[d] * dir.y[d]);
    for (int d = 0; d < count; ++d) dir.u[d] = azimuthOf(dir.x[d], dir.y[d]) / dphi;
    for (int d = 0; d < count; ++d) dir.slope[d] = dir.z[d] / dir.horizontal[d];
    for (int d = 0; d < count; ++d) {
        if (dir.horizontal[d] < 1e-9) continue;  // straight up: meets nothing
        const double u = dir.u[d];
        const int j0 = std::min(static_cast<int>(u), M - 1);
        const double f = u - j0;
        const float slope = static_cast<float>(dir.slope[d]);
        const float cosE = static_cast<float>(dir.horizontal[d]), sinE = static_cast<float>(dir.z[d]);
        for (int side = 0; side < 2; ++side) {
            const int j = (j0 + side) % M;
            const float weight = w0 * static_cast<float>(side == 0 ? 1.0 - f : f);
            const float c = st.cosPhi[static_cast<std::size_t>(j)], s = st.sinPhi[static_cast<std::size_t>(j)];
            if (weight <= 0.0f || slope <= gx * c + gy * s) continue;  // below the tangent plane
            if (slope >= 0.0f && static_cast<double>(slope) > escapeSlope(st, sc, frame, X, j, cell)) continue;
            sc.rays.push_back({j, texel, slope, weight, {-c * cosE, -s * cosE, -sinE}});
        }
    }
}

// sc.rays by azimuth into sc.byAzimuth (a stable counting sort: each azimuth's
// rays stay texel by texel, in the order they were appended).
void bucketRays(int M, GlossyLobeScratch& sc) {
    std::vector<int>& start = sc.bucketStart;
    start.assign(static_cast<std::size_t>(M + 1), 0);
    for (const GlossyLobeScratch::Ray& r : sc.rays) ++start[static_cast<std::size_t>(r.azimuth) + 1];
    for (int j = 0; j < M; ++j) start[static_cast<std::size_t>(j + 1)] += start[static_cast<std::size_t>(j)];
    sc.byAzimuth.resize(sc.rays.size());
    for (const GlossyLobeScratch::Ray& r : sc.rays)
        sc.byAzimuth[static_cast<std::size_t>(start[static_cast<std::size_t>(r.azimuth)]++)] = r;
}

// The lowest slope of the rays [first, end) not yet met (+inf when none is
// left: a met ray's slope is set to +inf).
double lowestSlope(const GlossyLobeScratch::Ray* first, const GlossyLobeScratch::Ray* end) {
    float lowest = std::numeric_limits<float>::infinity();
    for (const GlossyLobeScratch::Ray* r = first; r != end; ++r) lowest = std::min(lowest, r->slope);
    return lowest;
}

// The exit radiance E (48 planes) where a ray meets the surface.
struct MemberSamples {
    float e[kPlanes];
};

// Asks for the cache lines of a tap's texels (two runs of two texels, 2 x 96
// bytes) well before readExit reads them: the rays meet the surface anywhere,
// and E at 512^2 is 25 MB, so the receiver's hits are read after its walks.
void prefetchExit(const std::uint16_t* exit, const BilinearTap& t) {
    constexpr int kTexelBytes = kPlanes * static_cast<int>(sizeof(std::uint16_t));
    const auto* a = reinterpret_cast<const char*>(exit + t.i00 * kPlanes);
    const std::size_t row = t.dy * kTexelBytes;
    for (int k = 0; k < 2 * kTexelBytes; k += 64) {
        __builtin_prefetch(a + k);
        __builtin_prefetch(a + row + k);
    }
}

// E bilinear between a tap's four texels.
[[gnu::always_inline]] inline void readExit(const std::uint16_t* exit, const BilinearTap& t, MemberSamples& m) {
    const std::size_t dx = t.dx * kPlanes, dy = t.dy * kPlanes;
    const std::uint16_t* a = exit + t.i00 * kPlanes;
    for (int f = 0; f < kPlanes; ++f)
        m.e[f] = t.w00 * fromBfloat16(a[f]) + t.w10 * fromBfloat16(a[f + dx]) + t.w01 * fromBfloat16(a[f + dy]) +
                 t.w11 * fromBfloat16(a[f + dx + dy]);
}

// Where along its azimuth a ray of slope `slope` meets the surface, as a
// horizontal distance from where it leaves: between the last step below it
// (a sample riseBefore over the ray's start, runBefore away) and the first
// that reaches it (rise, run), where the ray's height above the linearly
// interpolated samples crosses zero. Before the first step (runBefore 0: the
// ray leaves the surface there, and nothing says where it rises again)
// halfway to it.
double crossingDistance(double riseBefore, double runBefore, double rise, double run, float slope) {
    if (runBefore <= 0.0) return 0.5 * run;
    const double below = slope * runBefore - riseBefore;  // > 0
    const double above = rise - slope * run;              // >= 0
    const double alpha = below + above > 0.0 ? below / (below + above) : 1.0;
    return runBefore + alpha * (run - runBefore);
}

// What the member sends back along `ray`, E . Y(back) (max(0, .) with the
// clamp), weighted into the accumulator of the ray's texel (3 per texel).
void addSent(const MemberSamples& m, const GlossyLobeScratch::Ray& ray, bool clamp, double* acc) {
    float y[kShCount];
    shBasisLanes<float>(ray.back[0], ray.back[1], ray.back[2], y);
    for (int c = 0; c < 3; ++c) {
        float u = 0.0f;
        for (int f = 0; f < kShCount; ++f) u += m.e[c * kShCount + f] * y[f];
        if (clamp) u = std::max(u, 0.0f);
        acc[3 * ray.texel + c] += static_cast<double>(ray.weight) * u;
    }
}

// Whether any lane of a comparison's mask is set.
template <class Mask>
inline bool anyLane(Mask m) {
    std::int64_t any = 0;
    for (std::size_t l = 0; l < sizeof(Mask) / sizeof(std::int64_t); ++l) any |= m[l];
    return any != 0;
}

// The scratch's lane blocks of width N.
template <int N>
std::vector<TexelLanes<N>>& laneBlocks(GlossyLobeScratch& sc) {
    if constexpr (N == 4)
        return sc.wideLanes;
    else
        return sc.narrowLanes;
}

// Receiver (X, Y)'s rays [begin, end) of one azimuth (texel by texel, as
// appended): the walk over the receiver's steps. Each texel sees the samples
// from where it stands, its own height and its distance along the azimuth
// (the samples lie on the receiver's ray, at most s / 2 cells beside its
// own), and each of its rays brings what the surface sends back where it
// crosses it, between its first reaching step and the step before, into the
// texel's acc (3 per texel; through sc.hits, read after the walks). The
// texels go N to a block of lanes (TexelLanes): a step tests every lane of a
// block at once, in the same double arithmetic as one texel at a time, and
// only a lane whose texel stops or whose lowest ray left meets the step
// there goes on alone.
template <int N>
[[gnu::always_inline]] inline void walkAzimuth(const GlossyLobeInputs& in, const GlossyLobeState& st,
                                               GlossyLobeScratch::Ray* begin, GlossyLobeScratch::Ray* end, int X, int Y,
                                               GlossyLobeScratch& sc) {
    const HeightPyramid& pyr = in.heights;
    const int j = begin->azimuth, nSteps = st.stepStride;
    const int pad = static_cast<int>(st.stepsPerColumn.size() / st.phi.size());
    const int prefix = std::min(st.stepsPerColumn[static_cast<std::size_t>(j) * pad + static_cast<std::size_t>(X)],
                                st.stepsPerRow[static_cast<std::size_t>(j) * pyr.nyr + static_cast<std::size_t>(Y)]);
    const std::size_t base = static_cast<std::size_t>(j) * nSteps;
    const double x0 = static_cast<double>(pyr.subsample) * X, y0 = static_cast<double>(pyr.subsample) * Y;
    const double c = st.cosPhi[static_cast<std::size_t>(j)], sn = st.sinPhi[static_cast<std::size_t>(j)];
    const double cell = pyr.cellSize;
    std::vector<GlossyLobeScratch::TexelWalk>& walks = sc.walks;
    walks.clear();
    for (GlossyLobeScratch::Ray* r = begin; r != end;) {
        GlossyLobeScratch::Ray* e = r;
        while (e != end && e->texel == r->texel) ++e;
        walks.push_back({r, e, &sc.texelFrames[static_cast<std::size_t>(r->texel)]});
        r = e;
    }
    // the lanes: a lane past the last texel, or whose texel is done, stands
    // infinitely far back (every step lies behind it)
    using Block = TexelLanes<N>;
    std::vector<Block>& blocks = laneBlocks<N>(sc);
    const int nBlocks = (static_cast<int>(walks.size()) + N - 1) / N;
    blocks.resize(static_cast<std::size_t>(nBlocks));
    constexpr double kDone = std::numeric_limits<double>::infinity();
    for (int k = 0; k < nBlocks * N; ++k) {
        Block& L = blocks[static_cast<std::size_t>(k / N)];
        const int l = k % N;
        L.riseBefore[l] = L.runBefore[l] = 0.0;
        if (k >= static_cast<int>(walks.size())) {
            L.along[l] = kDone;
            L.h[l] = L.margin[l] = L.slope[l] = 0.0;
            continue;
        }
        const GlossyLobeScratch::TexelWalk& w = walks[static_cast<std::size_t>(k)];
        L.along[l] = texelAlong(*w.frame, c, sn);
        L.h[l] = w.frame->h;
        L.margin[l] = w.frame->margin;
        L.slope[l] = lowestSlope(w.first, w.end);
    }
    int active = static_cast<int>(walks.size());
    // the highest sample of each band on, of this receiver's walk
    const float* own = bandTopsOf(st, sc, X, j);
    std::vector<float>& ahead = sc.topsAhead;
    ahead.resize(static_cast<std::size_t>(st.bands));
    float highest = -std::numeric_limits<float>::infinity();
    for (int k = st.bands - 1; k >= 0; --k)
        ahead[static_cast<std::size_t>(k)] = highest =
            std::max(highest, own[static_cast<std::size_t>(k * kBandTopsChunk)]);
    // block b's lanes L at a step: sample v, tau cells from the receiver, in
    // band `band`
    const auto step = [&](Block& L, int b, float v, double tau, int band) {
        const typename Block::Lanes dist = tau - L.along;  // from the texel, along the azimuth (cells)
        const typename Block::Mask valid = dist >= 0.5;    // not beside or behind the texel
        const typename Block::Lanes run = dist * cell;     // metres
        const typename Block::Lanes reached = L.slope * run;
        // no sample from here on rises to its lowest ray left: the highest
        // of this band on is below it here, and farther on a rising ray is
        // higher still (a falling one may yet meet one)
        const double top = ahead[static_cast<std::size_t>(band)];
        const typename Block::Mask stop = valid & (L.slope >= 0.0) & (reached > (top - L.h) - L.margin);
        const typename Block::Lanes rise = (static_cast<double>(v) - L.h) - L.margin;  // over the texel, metres
        const typename Block::Mask meets = valid & ~stop & (reached <= rise);
        if (anyLane(stop | meets)) {
            for (int l = 0; l < N; ++l) {
                if (!(stop[l] | meets[l])) continue;
                GlossyLobeScratch::TexelWalk& w = walks[static_cast<std::size_t>(b * N + l)];
                double lowest = stop[l] ? kDone : L.slope[l];
                if (meets[l]) {
                    // the rays met here, in the order of their slopes (equal
                    // slopes in the order appended, so the sums are fixed)
                    std::vector<GlossyLobeScratch::Ray*>& met = sc.met;
                    met.clear();
                    for (GlossyLobeScratch::Ray* r = w.first; r != w.end; ++r) {
                        if (!(r->slope * run[l] <= rise[l])) continue;
                        std::size_t k = met.size();
                        met.push_back(r);
                        for (; k > 0 && met[k - 1]->slope > r->slope; --k) met[k] = met[k - 1];
                        met[k] = r;
                    }
                    const GlossyLobeScratch::TexelFrame& f = *w.frame;
                    for (GlossyLobeScratch::Ray* r : met) {
                        const double d =
                            crossingDistance(L.riseBefore[l], L.runBefore[l], rise[l], run[l], r->slope) / cell;
                        const double px = x0 + f.ox + d * c, py = y0 + f.oy + d * sn;
                        if (in.members) {
                            sc.memberHits.push(*in.members, px, py, r->back);
                        } else {
                            prefetchExit(in.exit, bilinearTap(pyr.nx, pyr.ny, px, py));
                        }
                        sc.hits.push_back({px, py, r});
                        r->slope = std::numeric_limits<float>::infinity();
                    }
                    lowest = lowestSlope(w.first, w.end);
                }
                if (lowest == kDone) {
                    L.along[l] = kDone;
                    --active;
                } else {
                    L.slope[l] = lowest;
                }
            }
        }
        L.riseBefore = valid ? rise : L.riseBefore;
        L.runBefore = valid ? run : L.runBefore;
    };
    const auto sample = [&](int i) {
        const ScanStep& hs = st.heightSteps[base + static_cast<std::size_t>(i)];
        return stepSample(hs, Y * hs.rowStep + X);
    };
    if (nBlocks == 1) {  // one block (1x, 2x): its lanes held in registers
        Block L = blocks[0];
        for (int i = 0; i < prefix && active > 0; ++i)
            step(L, 0, sample(i), st.stepCells[base + static_cast<std::size_t>(i)],
                 st.stepBand[base + static_cast<std::size_t>(i)]);
        return;
    }
    for (int i = 0; i < prefix && active > 0; ++i) {
        const float v = sample(i);
        for (int b = 0; b < nBlocks; ++b)
            step(blocks[static_cast<std::size_t>(b)], b, v, st.stepCells[base + static_cast<std::size_t>(i)],
                 st.stepBand[base + static_cast<std::size_t>(i)]);
    }
}

// sc.bandTops of the receivers [X0, X0 + kBandTopsChunk) of row Y (those
// inside the field): per azimuth, band and receiver the highest height
// sample of its walk in that band, each sample as the walk reads it (the
// same floats), the receivers side by side. A chunk at a time, so the memory
// does not grow with the row times the azimuths.
void chunkBandTops(const GlossyLobeState& st, int Y, int X0, GlossyLobeScratch& sc) {
    const int M = static_cast<int>(st.phi.size()), bands = st.bands;
    constexpr std::size_t kStride = kBandTopsChunk;
    sc.bandTops.assign(static_cast<std::size_t>(M * bands) * kStride, -std::numeric_limits<float>::infinity());
    for (int j = 0; j < M; ++j) {
        float* tops = sc.bandTops.data() + static_cast<std::size_t>(j * bands) * kStride;
        const std::size_t base = static_cast<std::size_t>(j) * st.stepStride;
        for (int i = 0; i < st.stepCounts[static_cast<std::size_t>(j)]; ++i) {
            const ValidPrefix::Receivers& r = st.stepReceivers[base + static_cast<std::size_t>(i)];
            const int x0 = std::max(r.x0, X0), x1 = std::min(r.x1, X0 + kBandTopsChunk - 1);
            if (Y < r.y0 || Y > r.y1 || x0 > x1) break;  // the boxes only narrow
            // a copy: the stores to top cannot then alias the step's weights
            // and pointer, and the loop vectorises
            const ScanStep hs = st.heightSteps[base + static_cast<std::size_t>(i)];
            const std::ptrdiff_t row = Y * hs.rowStep;
            float* top = tops + static_cast<std::size_t>(st.stepBand[base + static_cast<std::size_t>(i)]) * kStride;
            for (int X = x0; X <= x1; ++X) top[X - X0] = std::max(top[X - X0], stepSample(hs, row + X));
        }
    }
}

// The texels [first, last] along one axis of n that receiver i of nr owns:
// those nearer to it than to the next (ties to the later one), the last
// receiver to the end.
struct OwnedSpan {
    int first, last;
};
OwnedSpan ownedTexels(int i, int s, int nr, int n) {
    const int first = std::max(0, s * i - s / 2);
    const int last = i == nr - 1 ? n - 1 : std::min(n - 1, s * i + s - s / 2 - 1);
    return {first, last};
}

// Receiver row Y: the lobes of the texels every receiver of it owns, along
// the receiver's walks, into st.gathered.
template <int N>
[[gnu::always_inline]] inline void gatherRowImpl(const GlossyLobeInputs& in, GlossyLobeState& st, int Y,
                                                 GlossyLobeScratch& sc) {
    const HeightPyramid& pyr = in.heights;
    const int nxr = pyr.nxr, nx = pyr.nx, s = pyr.subsample;
    const std::size_t plane = static_cast<std::size_t>(nx) * pyr.ny;
    const bool expMap = in.surface && !in.surface->phongExponent.empty();
    const bool clamp = in.shading.positivity == GlossyPositivity::Clamp;
    const OwnedSpan rows = ownedTexels(Y, s, pyr.nyr, pyr.ny);
    for (int X = 0; X < nxr; ++X) {
        if (X % kBandTopsChunk == 0) chunkBandTops(st, Y, X, sc);
        const OwnedSpan cols = ownedTexels(X, s, nxr, nx);
        const int width = cols.last - cols.first + 1;
        const int texels = width * (rows.last - rows.first + 1);
        sc.rays.clear();
        sc.texelFrames.clear();
        for (int y = rows.first; y <= rows.last; ++y)
            for (int x = cols.first; x <= cols.last; ++x) {
                const float h = pyr.rawPhaseRow(x % s, y)[x / s];
                const float margin = std::fabs(h) * kHeightMarginRel;
                sc.texelFrames.push_back({h, margin, static_cast<double>(x - s * X), static_cast<double>(y - s * Y)});
                const double S = expMap ? in.surface->phongExponent(x, y) : in.shading.phongExponent;
                const float gx = in.gradX(x, y), gy = in.gradY(x, y);
                const ReceiverLobe L = receiverLobe(gx, gy, in.shading.viewDir, S);
                sc.quadrature.set(S, gatherLobeLayout(S, in.rings, in.innerDirections));
                appendLobeRays(L, st, gx, gy, X, pyr.cellSize, (y - rows.first) * width + (x - cols.first), sc);
            }
        bucketRays(static_cast<int>(st.phi.size()), sc);
        sc.hits.clear();
        sc.memberHits.clear();
        GlossyLobeScratch::Ray* rays = sc.byAzimuth.data();
        const std::size_t n = sc.byAzimuth.size();
        for (std::size_t a = 0; a < n;) {
            std::size_t b = a + 1;
            while (b < n && rays[b].azimuth == rays[a].azimuth) ++b;
            walkAzimuth<N>(in, st, rays + a, rays + b, X, Y, sc);
            a = b;
        }
        // what the surface sends back where each ray met it, in the walks'
        // order (so the sums are fixed)
        sc.acc.assign(static_cast<std::size_t>(3 * texels), 0.0);
        if (in.members) {
            LobeMemberHits& mh = sc.memberHits;
            lobeMembersSend<std::conditional_t<N == 4, simd::F8, simd::F4>>(*in.members, mh);
            for (std::size_t k = 0; k < sc.hits.size(); ++k) {
                const GlossyLobeScratch::Ray& ray = *sc.hits[k].ray;
                for (int c = 0; c < 3; ++c) {
                    const float u = mh.sent[c][k];
                    sc.acc[static_cast<std::size_t>(3 * ray.texel + c)] +=
                        static_cast<double>(ray.weight) * (clamp ? std::max(u, 0.0f) : u);
                }
            }
        } else
            for (const GlossyLobeScratch::Hit& hit : sc.hits) {
                MemberSamples m;
                readExit(in.exit, bilinearTap(nx, pyr.ny, hit.px, hit.py), m);
                addSent(m, *hit.ray, clamp, sc.acc.data());
            }
        for (int t = 0; t < texels; ++t) {
            const std::size_t i = static_cast<std::size_t>(rows.first + t / width) * nx + cols.first + t % width;
            for (int c = 0; c < 3; ++c)
                st.gathered[static_cast<std::size_t>(c) * plane + i] =
                    static_cast<float>(sc.acc[static_cast<std::size_t>(3 * t + c)]);
        }
    }
}

void gatherRowSse(const GlossyLobeInputs& in, GlossyLobeState& st, int Y, GlossyLobeScratch& sc) {
    gatherRowImpl<2>(in, st, Y, sc);
}
[[gnu::target("avx2"), gnu::flatten]] void gatherRowAvx2(const GlossyLobeInputs& in, GlossyLobeState& st, int Y,
                                                         GlossyLobeScratch& sc) {
    gatherRowImpl<4>(in, st, Y, sc);
}

// The walks' steps: raw steps (the full-resolution heights, exact between
// grid lines) from the pyramid's first step out to 2^nearOctaves cells at
// perOctave steps per octave, then the pyramid's steps beyond. Where a ray
// meets the surface and what it reads there follow the steps' spacing, so
// near, where most rays meet it, they are denser than the pyramid's.
std::vector<PyramidStep> walkSteps(const HeightPyramid& pyr, int perOctave, int nearOctaves) {
    std::vector<PyramidStep> steps;
    if (pyr.steps.empty()) return steps;
    const double first = pyr.steps.front().tauCells, limit = std::ldexp(1.0, nearOctaves);
    for (int k = 0;; ++k) {
        const double tau = first * std::exp2(static_cast<double>(k) / perOctave);
        if (tau >= limit) break;
        steps.push_back({tau, static_cast<float>(1.0 / (tau * pyr.cellSize)), -1});
    }
    for (const PyramidStep& ps : pyr.steps)
        if (ps.tauCells >= limit) steps.push_back(ps);
    return steps;
}

bool sameSample(const ScanStep& a, const ScanStep& b) {
    return a.field == b.field && a.offA == b.offA && a.offB == b.offB && a.w[0][0] == b.w[0][0] &&
           a.w[2][0] == b.w[2][0];
}

// st's step table (azimuth j's steps from j * stepStride, a step whose moved
// sample is the one before's left out: near the receiver several distances
// round to the same grid line), the valid prefixes and the steps' distances.
void buildWalkTable(const HeightPyramid& pyr, int perOctave, int nearOctaves, int pad, GlossyLobeState& st) {
    const std::vector<PyramidStep> steps = walkSteps(pyr, perOctave, nearOctaves);
    const int M = static_cast<int>(st.phi.size());
    st.stepStride = static_cast<int>(steps.size());
    const std::size_t table = static_cast<std::size_t>(M) * steps.size();
    st.heightSteps.resize(table);
    st.stepCells.resize(table);
    st.stepBand.resize(table);
    st.stepReceivers.resize(table);
    st.stepCounts.resize(static_cast<std::size_t>(M));
    st.stepsPerColumn.resize(static_cast<std::size_t>(M) * pad);
    st.stepsPerRow.resize(static_cast<std::size_t>(M) * pyr.nyr);
    parallelFor(0, M, 1, [&](int j0, int j1) {
        for (int j = j0; j < j1; ++j) {
            const auto ju = static_cast<std::size_t>(j);
            const std::size_t base = ju * steps.size();
            ValidPrefix prefix(pyr.nxr, pyr.nyr, pad, st.stepsPerColumn.data() + ju * pad,
                               st.stepsPerRow.data() + ju * pyr.nyr);
            int n = 0;
            for (const PyramidStep& ps : steps) {
                const ScanStepInfo info = scanStepInfoAt(pyr, ps, std::cos(st.phi[ju]), std::sin(st.phi[ju]));
                if (n > 0 && sameSample(info.step, st.heightSteps[base + static_cast<std::size_t>(n - 1)])) continue;
                const std::size_t at = base + static_cast<std::size_t>(n);
                const double tau = 1.0 / (static_cast<double>(info.step.w[2][0]) * pyr.cellSize);
                st.heightSteps[at] = info.step;
                st.stepCells[at] = tau;
                st.stepBand[at] = static_cast<std::uint8_t>(tau <= 1.0 ? 0 : std::ceil(std::log2(tau)));
                prefix.narrow(info);
                prefix.commit(n);
                st.stepReceivers[at] = prefix.receivers();
                ++n;
            }
            st.stepCounts[ju] = n;
        }
    });
    st.bands = 0;
    for (int j = 0; j < M; ++j) {
        const int n = st.stepCounts[static_cast<std::size_t>(j)];
        if (n > 0) st.bands = std::max(st.bands, st.stepBand[static_cast<std::size_t>(j) * steps.size() + n - 1] + 1);
    }
    st.bandStart.assign(static_cast<std::size_t>(M * st.bands), std::numeric_limits<double>::infinity());
    for (int j = 0; j < M; ++j)
        for (int i = 0; i < st.stepCounts[static_cast<std::size_t>(j)]; ++i) {
            const std::size_t at = static_cast<std::size_t>(j) * steps.size() + static_cast<std::size_t>(i);
            double& start = st.bandStart[static_cast<std::size_t>(j * st.bands + st.stepBand[at])];
            start = std::min(start, st.stepCells[at]);
        }
}

}  // namespace

LobeLayout gatherLobeLayout(double S, int rings, int innerDirections) {
    return LobeLayout::growing(rings > 0 ? rings : (S < kWideLobeExponent ? 3 : 2), innerDirections);
}

void gatherGlossyLobes(const GlossyLobeInputs& in, GlossyLobeState& st) {
    const HeightPyramid& pyr = in.heights;
    const int M = in.azimuths, pad = indirectRowPad(pyr.nxr);
    st.phi.resize(static_cast<std::size_t>(M));
    st.cosPhi.resize(static_cast<std::size_t>(M));
    st.sinPhi.resize(static_cast<std::size_t>(M));
    for (int j = 0; j < M; ++j) {
        const auto u = static_cast<std::size_t>(j);
        st.phi[u] = 2.0 * kPi * j / M;
        st.cosPhi[u] = static_cast<float>(std::cos(st.phi[u]));
        st.sinPhi[u] = static_cast<float>(std::sin(st.phi[u]));
    }
    buildWalkTable(pyr, in.nearStepsPerOctave, in.nearOctaves, pad, st);
    st.gathered.resize(static_cast<std::size_t>(3) * pyr.nx * pyr.ny);
    st.scratch.resize(static_cast<std::size_t>(workerSlots()));
    for (GlossyLobeScratch& sc : st.scratch) {
        sc.escape.resize(static_cast<std::size_t>(M));
        sc.escapeStamp.assign(static_cast<std::size_t>(M), 0);
        sc.texelSerial = 0;
    }
    parallelFor(0, pyr.nyr, 1, [&](int y0, int y1) {
        GlossyLobeScratch& sc = st.scratch[static_cast<std::size_t>(workerSlot())];
        for (int Y = y0; Y < y1; ++Y) (simd::wideEnabled() ? gatherRowAvx2 : gatherRowSse)(in, st, Y, sc);
    });
}

void shadeGlossyLobes(const GlossyLobeState& st, const HeightPyramid& heights, const ShadingSettings& shading,
                      bool addToOut, std::array<Grid, 3>& out) {
    const int nx = heights.nx, ny = heights.ny;
    const std::size_t plane = static_cast<std::size_t>(nx) * ny;
    const float ws = specularWeightOf(shading);
    const float floor = shading.positivity == GlossyPositivity::Clamp ? 0.0f : -std::numeric_limits<float>::infinity();
    for (Grid& g : out)
        if (!addToOut) g.ensureSize(nx, ny);
    parallelFor(0, ny, 8, [&](int y0, int y1) {
        for (int c = 0; c < 3; ++c) {
            const float* g = st.gathered.data() + static_cast<std::size_t>(c) * plane;
            float* o = out[static_cast<std::size_t>(c)].data();
            for (std::size_t i = static_cast<std::size_t>(y0) * nx; i < static_cast<std::size_t>(y1) * nx; ++i) {
                const float v = (addToOut ? o[i] : 0.0f) + ws * g[i];
                o[i] = std::isfinite(v) ? std::max(v, floor) : 0.0f;
            }
        }
    });
}

}  // namespace terrain::gi
