// `terrain_bench gi-bound-diagnosis`: how far the change bounds of
// incremental GI frames are from the true changes, per visibility tile. Per
// frame (full GI frames, uniform unit sky: shade units are the
// tolerance's): the one-frame bound of gi/visibility_cache.h on the change
// of a tile's ambient map (the environment's V at the new normals) against
// the true change (the ambient map shaded at the new normals with the cached
// V against the new V, largest over the tile's texels), and the radiance
// bound of gi/indirect_cache.h against the true change of the one-bounce
// indirect light. An animated scene (the lit surface, ground + water, and the
// ground alone) and the Mont Blanc DEM with pits dropped and filled. Then
// the same at finer granularities (tiles of 16, 8 and 1 receivers): the
// share of the receivers whose one-frame V bound passes the tolerance, and
// the shares an oracle recomputes, which is what finer tiles could save.
// Writes gi_bound_diagnosis.md.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "bench/horizon_aware_bound.h"
#include "bench/suites.h"
#include "core/parallel.h"
#include "gi/change_bound.h"
#include "gi/frame.h"
#include "gi/indirect.h"
#include "gi/indirect_cache.h"
#include "gi/receiver_azimuth_bound.h"
#include "gi/receiver_change_bound.h"
#include "gi/visibility_cache.h"
#include "sim/scene.h"

namespace terrain::bench {
namespace {

struct DiagnosisOptions {
    std::string scene = "erosion";
    int size = 512;
    int frames = 6;
    int ticksPerFrame = 60;
    float tolerance = gi::GiSettings{}.tolerance;  // the engine's default
    std::vector<int> pits = {16, 51};              // then the DEM with a pit of each side
};

double quantile(std::vector<double> v, double q) {
    if (v.empty()) return 0.0;
    const std::size_t k = std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size())));
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
    return v[k];
}

double share(const std::vector<double>& v, double above) {
    double n = 0.0;
    for (double x : v) n += x > above ? 1.0 : 0.0;
    return v.empty() ? 0.0 : n / static_cast<double>(v.size());
}

using GiState = gi::GiState;

// Receivers per tile side of the granularities compared: the visibility
// tiles' first (the engine's), then finer ones.
constexpr std::array<int, 4> kGranularities = {gi::kVisibilityTile, 16, 8, 1};

// Largest |a - b| per tile of T x T receivers over the texels of its receivers (any channel).
std::vector<double> perTile(const std::vector<const Grid*>& a, const std::vector<const Grid*>& b, const GiState& st,
                            int s, int T = gi::kVisibilityTile) {
    const int tilesX = gi::tileCount(st.pyramid.nxr, T);
    std::vector<double> out(static_cast<std::size_t>(tilesX) * gi::tileCount(st.pyramid.nyr, T), 0.0);
    for (std::size_t c = 0; c < a.size(); ++c)
        for (int y = 0; y < a[c]->ny; ++y)
            for (int x = 0; x < a[c]->nx; ++x) {
                const int tx = std::min(x / s, st.pyramid.nxr - 1) / T;
                const int ty = std::min(y / s, st.pyramid.nyr - 1) / T;
                double& t = out[static_cast<std::size_t>(ty) * tilesX + tx];
                t = std::max(t, std::fabs(static_cast<double>((*b[c])(x, y)) - (*a[c])(x, y)));
            }
    return out;
}

// The same over the three channels of two colour fields (a direct shade or an indirect light).
std::vector<double> perTile(const std::array<Grid, 3>& a, const std::array<Grid, 3>& b, const GiState& st, int s,
                            int T = gi::kVisibilityTile) {
    return perTile({&a[0], &a[1], &a[2]}, {&b[0], &b[1], &b[2]}, st, s, T);
}

// One surface sequence (lit or ground only): its GI state and the last frame's.
struct Track {
    std::string name;
    GiState now, last;
    Grid heights, lastHeights;
    std::vector<double> bound, vChange, indirectSampleBound, indirectBound, indirectChange, dh;
    // the indirect light's true change from the geometry alone and from the
    // sources alone (indirectOfLastSources), and its geometry bound (geometryBounds)
    std::vector<double> indirectGeometryChange, indirectSourceChange, indirectGeometryBound;
    // An oracle that knows the true results, per granularity
    // (kGranularities): per tile it keeps its cached V, direct shade and
    // indirect light until they are more than the tolerance from the truth.
    // The share of receivers it recomputes per frame is what any
    // conservative bound on tiles of that size recomputes at least.
    struct Oracle {
        gi::VisibilityField v;
        std::array<Grid, 3> shade, indirect;
        std::vector<double> vShare, shadeShare, indirectShare;
    };
    std::array<Oracle, kGranularities.size()> oracles;
    // per granularity, per frame: the share of the receivers whose tile's
    // one-frame V bound passes the tolerance
    std::array<std::vector<double>, kGranularities.size()> boundShare;
    // the same for receivers alone, counted in the scans' runs of 16 along a row
    std::vector<double> laneRunShare;
    // the same with one slope bound for every azimuth (the geometry tiles' form)
    std::vector<double> isotropicShare;
    // per receiver and azimuth from the samples' own change
    // (gi/receiver_azimuth_bound.h): alone, in runs of 16, and its cost (ms)
    std::vector<double> sampleShare, sampleRunShare, sampleMs;
    gi::ChangeLevels changeLevels;  // its |dh| pyramid, redone from frame to frame as a plan would
    // per variant of bench/horizon_aware_bound.h's bounds, per frame the
    // share of the receivers above the tolerance: alone, in runs of 16, in
    // tiles of 16 x 16 and of 32 x 32 receivers
    std::array<std::array<std::vector<double>, 4>, HorizonAwareBounds::kVariants> horizonShare;
    std::vector<double> idealBound;  // per 32 x 32 tile, the ideal exact-tangent bound's largest
    std::vector<double> trueSigma;   // per 32 x 32 tile, the true sigma moves through the conversion
    std::vector<double> trueSigmaWeighted, idealWeighted;  // the same and the ideal bound, with the elevation weight
    // The same bounds from the heights of frame anchorFrame (an anchor kept while
    // the frames go on) against the true change of its V, per frame: the
    // shares of the 32 x 32 and 16 x 16 tiles above the tolerance
    struct FromAnchor {
        double engine32 = 0, truth32 = 0, truth16 = 0;
        std::array<double, HorizonAwareBounds::kVariants> bound32{}, bound16{};
    };
    std::vector<FromAnchor> fromAnchor;
    int frame = 0, anchorFrame = 0;  // this frame's number; the anchor's (the frames before it settle the scene)
    GiState anchor;
    Grid anchorHeights;
    gi::ChangeLevels anchorLevels;
};

// Copies the receivers (V) or texels (`texels` from `truth`: the direct
// shade or the indirect light) of the tiles of T x T receivers whose
// deviation exceeds the tolerance from the truth into the oracle's cache;
// returns the share of the receivers they hold.
double refreshTiles(const std::vector<double>& deviation, float tolerance, const GiState& now, int s, int T,
                    gi::VisibilityField* v, std::array<Grid, 3>* texels, const std::array<Grid, 3>* truth) {
    const int tilesX = gi::tileCount(now.pyramid.nxr, T);
    double dirty = 0.0;
    for (std::size_t t = 0; t < deviation.size(); ++t) {
        if (!(deviation[t] > tolerance)) continue;
        const int tx = static_cast<int>(t) % tilesX, ty = static_cast<int>(t) / tilesX;
        const int X1 = std::min(now.pyramid.nxr, T * tx + T), Y1 = std::min(now.pyramid.nyr, T * ty + T);
        dirty += static_cast<double>(X1 - T * tx) * (Y1 - T * ty);
        for (int Y = T * ty; Y < Y1; ++Y)
            for (int X = T * tx; X < X1; ++X) {
                if (v)
                    for (int k = 0; k < 16; ++k)
                        v->plane(k)[static_cast<std::size_t>(Y) * v->nxr + X] =
                            now.envVisibility.plane(k)[static_cast<std::size_t>(Y) * v->nxr + X];
                if (!texels) continue;
                // the texels that map to this receiver (the last ones take the edge)
                const int xEnd = X + 1 == now.pyramid.nxr ? now.gradX.nx : s * X + s;
                const int yEnd = Y + 1 == now.pyramid.nyr ? now.gradX.ny : s * Y + s;
                for (std::size_t c = 0; c < 3; ++c)
                    for (int y = s * Y; y < yEnd; ++y)
                        for (int x = s * X; x < xEnd; ++x) (*texels)[c](x, y) = (*truth)[c](x, y);
            }
    }
    return dirty / (static_cast<double>(now.pyramid.nxr) * now.pyramid.nyr);
}

// The SH ambient map of the environment V `v` at the frame's normals: what
// the visibility bounds cover (the frame's own ambient map may be the exact
// one, which does not read V, so both sides of a comparison come from here).
void ambientOfV(const GiState& now, const gi::VisibilityField& v, const gi::GiSettings& settings, gi::ShadeMaps& out) {
    gi::ShadingLight env = now.shadingLights[0];
    env.visibility = &v;
    gi::shadeTexels(now.gradX.cview(), now.gradY.cview(), settings.subsample, v, &env, 1, nullptr, settings.shading,
                    out);
}

// One frame of the oracle (the first frame fills its caches).
// `fresh`: the SH ambient map of this frame's V (ambientOfV).
void oracleFrame(Track& t, const gi::GiSettings& settings, float tolerance, const gi::ShadeMaps& fresh) {
    const int s = settings.subsample;
    for (std::size_t g = 0; g < kGranularities.size(); ++g) {
        Track::Oracle& o = t.oracles[g];
        const int T = kGranularities[g];
        if (o.v.sh.empty()) {
            o.v = t.now.envVisibility;
            o.shade = t.now.shade.rgb;
            o.indirect = t.now.indirect.indirect;
            continue;
        }
        gi::ShadeMaps cached;
        ambientOfV(t.now, o.v, settings, cached);
        const std::vector<double> v = perTile({&cached.ambient}, {&fresh.ambient}, t.now, s, T);
        o.vShare.push_back(refreshTiles(v, tolerance, t.now, s, T, &o.v, nullptr, nullptr));
        const std::vector<double> ind = perTile(o.indirect, t.now.indirect.indirect, t.now, s, T);
        o.indirectShare.push_back(
            refreshTiles(ind, tolerance, t.now, s, T, nullptr, &o.indirect, &t.now.indirect.indirect));
        const std::vector<double> shade = perTile(o.shade, t.now.shade.rgb, t.now, s, T);
        o.shadeShare.push_back(refreshTiles(shade, tolerance, t.now, s, T, nullptr, &o.shade, &t.now.shade.rgb));
    }
}

// One frame's environment V bound per tile of T x T receivers (what
// gi/visibility_cache.h adds to a tile's drift), from the height change `dh`;
// with azimuthsOut and gradientsOut, also the per-azimuth slope bounds and
// the gradient bounds it comes from (gi::boundSlopeChangePerAzimuth,
// gi::boundGradientChange).
std::vector<float> environmentBounds(const gi::MaxChangePyramid& dh, const gi::HeightPyramid& pyr,
                                     const gi::VisibilitySettings& vis, int T,
                                     std::vector<float>* azimuthsOut = nullptr,
                                     std::vector<float>* gradientsOut = nullptr) {
    std::vector<float> ownAzimuths, ownGradients, scratch, bound;
    std::vector<float>& azimuths = azimuthsOut ? *azimuthsOut : ownAzimuths;
    std::vector<float>& gradients = gradientsOut ? *gradientsOut : ownGradients;
    gi::boundSlopeChangePerAzimuth(dh, pyr, T, vis.azimuths, azimuths);
    gi::boundGradientChange(dh, pyr, T, gradients);
    gi::environmentBoundPerTile(azimuths, gradients, vis.azimuths, gi::blockingMaxLipschitz(vis.blockingMax), scratch,
                                bound);
    return bound;
}

// The same per receiver with one slope bound for every azimuth (the form of
// gi/visibility_cache.h's geometry bound), from the max filters of
// gi/receiver_change_bound.h.
std::vector<float> isotropicBounds(const gi::MaxChangePyramid& dh, const gi::HeightPyramid& pyr,
                                   const gi::VisibilitySettings& vis) {
    std::vector<float> slopes, gradients, bound;
    gi::boundSlopeChangePerReceiver(dh, pyr, slopes);
    gi::boundGradientChange(dh, pyr, 1, gradients);
    gi::geometryBoundPerTile(slopes, gradients, gi::blockingMaxLipschitz(vis.blockingMax), bound);
    return bound;
}

// The same per receiver and azimuth from the samples' own change
// (gi/receiver_azimuth_bound.h), every receiver; `ms` gets what it cost
// (the |dh| pyramid redone, the scan, the gradients and the V bound).
std::vector<float> sampleBounds(const gi::MaxChangePyramid& dh, const gi::HeightPyramid& pyr,
                                const gi::VisibilitySettings& vis, gi::ChangeLevels& levels, double& ms) {
    std::vector<float> bound;
    const gi::FoldedWedgeOperator op = gi::foldFullCircle(vis.azimuths, vis.interp);
    const auto t0 = std::chrono::steady_clock::now();
    gi::buildChangeLevels(dh, pyr, levels);
    gi::boundEnvironmentPerReceiver(levels, dh, pyr, op.phi, gi::blockingMaxLipschitz(vis.blockingMax), nullptr, 0.0f,
                                    bound);
    ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return bound;
}

// The share of the receivers that lie in a tile of T x T receivers whose
// bound is above the tolerance; with T = 1 and `run` > 1, in a run of `run`
// receivers of a row (from a multiple of `run`) holding one such receiver.
double shareAbove(const std::vector<float>& bound, int T, int run, int nxr, int nyr, float tolerance) {
    const int tilesX = gi::tileCount(nxr, T);
    double above = 0.0;
    for (int ty = 0; ty < gi::tileCount(nyr, T); ++ty)
        for (int tx0 = 0; tx0 < tilesX; tx0 += run) {
            const int tx1 = std::min(tilesX, tx0 + run);
            bool any = false;
            for (int tx = tx0; tx < tx1; ++tx)
                any = any || bound[static_cast<std::size_t>(ty) * tilesX + tx] > tolerance;
            if (any)
                above += static_cast<double>(std::min(nxr, T * tx1) - T * tx0) * (std::min(nyr, T * ty + T) - T * ty);
        }
    return above / (static_cast<double>(nxr) * nyr);
}

// Per tile, for the change of the direct light from the last frame to this
// one: the largest move of the indirect scan's radiance samples (over the
// indirect azimuths, from the two frames' radiance pyramids) and the
// radiance bound gi/indirect_cache.h adds for it (those moves weighed by the
// last frame's receivers' occlusion shares).
struct IndirectBounds {
    std::vector<double> sampleMove, bound;
};
IndirectBounds indirectBounds(const GiState& now, const GiState& last, int azimuths) {
    gi::IndirectCache cache;
    cache.anchorSource = last.shade.rgb;
    gi::recordAnchorLevels(last.indirect.radiance, cache.levels);
    const gi::FoldedWedgeOperator op = gi::foldFullCircle(azimuths, gi::AzimuthInterp::Linear);
    const gi::IndirectPlanInputs plan{.source = now.shade.rgb,
                                      .heights = now.pyramid,
                                      .pyramid = now.indirect.radiance,
                                      .geometryTiles = nullptr,
                                      .phi = op.phi,
                                      .tolerance = 0.0f,
                                      .blocker = &last.indirect.blocker};
    gi::boundRadianceChange(plan, cache);
    // per visibility tile: the largest bound of the indirect tiles it holds
    const int tilesX = gi::tileCount(now.pyramid.nxr, gi::kVisibilityTile);
    const std::size_t tiles = static_cast<std::size_t>(tilesX) * gi::tileCount(now.pyramid.nyr, gi::kVisibilityTile);
    IndirectBounds out{std::vector<double>(tiles, 0.0), std::vector<double>(tiles, 0.0)};
    const int indirectX = gi::tileCount(now.pyramid.nxr, gi::kIndirectTile);
    for (std::size_t i = 0; i < cache.radianceBound.size(); ++i) {
        const int tx = static_cast<int>(i) % indirectX, ty = static_cast<int>(i) / indirectX;
        const std::size_t t = gi::visibilityTileHolding(tx, ty, now.pyramid.nxr);
        out.bound[t] = std::max(out.bound[t], static_cast<double>(cache.radianceBound[i]));
    }
    if (gi::maxChangeAll(cache.change) == 0.0f) return out;  // no change: no sample moved
    const std::size_t m = static_cast<std::size_t>(azimuths);
    for (std::size_t i = 0; i < cache.azimuthBound.size(); ++i)
        out.sampleMove[i / m] = std::max(out.sampleMove[i / m], static_cast<double>(cache.azimuthBound[i]));
    return out;
}

// The one-bounce indirect light of this frame's geometry lit by the last
// frame's direct light, with the frame's own settings: from the last
// frame's indirect light to it only the geometry moved, from it to this
// frame's only the sources (the direct light it reflects).
std::array<Grid, 3> indirectOfLastSources(const GiState& now, const GiState& last, const gi::GiSettings& settings) {
    const gi::FoldedWedgeOperator op =
        gi::foldFullCircle(gi::indirectScanAzimuths(settings), settings.visibility.interp);
    const gi::IndirectInputs in{.heights = now.pyramid,
                                .gradX = now.gradX.cview(),
                                .gradY = now.gradY.cview(),
                                .op = op,
                                .envVisibility = now.envVisibility,
                                .direct = last.shade.rgb,
                                .directShade = &last.shade,
                                .albedo = nullptr,
                                .shading = settings.shading};
    gi::IndirectState state;
    gi::computeIndirect(in, settings.indirect, state);
    return state.indirect;
}

// Per visibility tile, the bound the plan (gi/visibility_cache.h) puts on
// the geometry's change of the indirect light: V's bound over the indirect
// scan's azimuths where they are every k-th of the environment's (from the
// tiles' per-azimuth slope bounds `azimuthBound` and gradient bounds
// `gradients`, environmentBounds'), else over every direction.
std::vector<float> geometryBounds(const gi::MaxChangePyramid& dh, const gi::HeightPyramid& pyr,
                                  const gi::GiSettings& settings, const std::vector<float>& azimuthBound,
                                  const std::vector<float>& gradients) {
    const gi::VisibilitySettings& vis = settings.visibility;
    const int indirect = gi::indirectScanAzimuths(settings);
    const float lipschitz = gi::blockingMaxLipschitz(vis.blockingMax);
    std::vector<float> scratch, bound;
    if (vis.azimuths % indirect == 0) {
        gi::environmentBoundPerTile(azimuthBound, gradients, vis.azimuths, lipschitz, scratch, bound,
                                    vis.azimuths / indirect);
    } else {
        std::vector<float> slopes;
        gi::boundSlopeChange(dh, pyr, gi::kVisibilityTile, slopes);
        gi::geometryBoundPerTile(slopes, gradients, lipschitz, bound);
    }
    return bound;
}

// Per variant of bench/horizon_aware_bound.h's bounds, the share of the
// receivers above the tolerance alone, in runs of 16 and in tiles of 16 x 16
// and 32 x 32 receivers.
using HorizonShares = std::array<std::array<double, 4>, HorizonAwareBounds::kVariants>;
HorizonShares horizonShares(const HorizonAwareBounds& b, int nxr, int nyr, float tolerance) {
    HorizonShares out{};
    for (std::size_t v = 0; v < out.size(); ++v) {
        const std::vector<float>& r = b.bound[v];
        out[v] = {
            shareAbove(r, 1, 1, nxr, nyr, tolerance),
            shareAbove(r, 1, gi::ReceiverTiles::kTileAlign, nxr, nyr, tolerance),
            shareAbove(tileMaxima(r, nxr, nyr, 16), 16, 1, nxr, nyr, tolerance),
            shareAbove(tileMaxima(r, nxr, nyr, gi::kVisibilityTile), gi::kVisibilityTile, 1, nxr, nyr, tolerance)};
    }
    return out;
}

// The frame against the anchor frame's V (bench/horizon_aware_bound.h with
// that frame's heights as the anchor).
void measureFromAnchor(Track& t, const gi::GiSettings& settings, float tolerance, const gi::ShadeMaps& fresh) {
    gi::VisibilityCache cache;
    gi::planVisibilityTiles(t.anchorHeights.cview(), t.heights.cview(), t.now.pyramid, settings.visibility, {}, 1e30f,
                            cache);
    const gi::FoldedWedgeOperator op = gi::foldFullCircle(settings.visibility.azimuths, settings.visibility.interp);
    gi::buildChangeLevels(cache.change, t.now.pyramid, t.anchorLevels);
    const int nxr = t.now.pyramid.nxr, nyr = t.now.pyramid.nyr, s = settings.subsample, T32 = gi::kVisibilityTile;
    std::vector<float> tileSlopes;
    const std::vector<float> engine =
        environmentBounds(cache.change, t.now.pyramid, settings.visibility, T32, &tileSlopes);
    const HorizonAwareBounds b =
        horizonAwareBounds(t.anchor.pyramid, t.anchor.footprint, t.now.footprint, t.anchorLevels, cache.change, op.phi,
                           gi::blockingMaxLipschitz(settings.visibility.blockingMax), tileSlopes, gi::kVisibilityTile,
                           t.now.gradX.cview(), t.now.gradY.cview());
    gi::ShadeMaps cached;
    ambientOfV(t.now, t.anchor.envVisibility, settings, cached);
    Track::FromAnchor f;
    const auto toFloat = [](const std::vector<double>& v) { return std::vector<float>(v.begin(), v.end()); };
    f.truth32 =
        shareAbove(toFloat(perTile({&cached.ambient}, {&fresh.ambient}, t.now, s, T32)), T32, 1, nxr, nyr, tolerance);
    f.truth16 =
        shareAbove(toFloat(perTile({&cached.ambient}, {&fresh.ambient}, t.now, s, 16)), 16, 1, nxr, nyr, tolerance);
    f.engine32 = shareAbove(engine, T32, 1, nxr, nyr, tolerance);
    for (std::size_t v = 0; v < f.bound32.size(); ++v) {
        f.bound32[v] = shareAbove(tileMaxima(b.bound[v], nxr, nyr, T32), T32, 1, nxr, nyr, tolerance);
        f.bound16[v] = shareAbove(tileMaxima(b.bound[v], nxr, nyr, 16), 16, 1, nxr, nyr, tolerance);
    }
    t.fromAnchor.push_back(f);
}

// One frame's bench/horizon_aware_bound.h bounds from the last frame's
// heights (dh: the change since them, whose |dh| pyramid sampleBounds built
// in t.changeLevels; tileSlopes: its visibility tiles' per-azimuth slope
// bounds), and the true moves of sigma through both weights.
void measureHorizonAware(Track& t, const gi::GiSettings& settings, const gi::MaxChangePyramid& dh,
                         const std::vector<float>& tileSlopes, float tolerance) {
    const int nxr = t.now.pyramid.nxr, nyr = t.now.pyramid.nyr, T32 = gi::kVisibilityTile;
    const gi::FoldedWedgeOperator op = gi::foldFullCircle(settings.visibility.azimuths, settings.visibility.interp);
    const HorizonAwareBounds hb =
        horizonAwareBounds(t.last.pyramid, t.last.footprint, t.now.footprint, t.changeLevels, dh, op.phi,
                           gi::blockingMaxLipschitz(settings.visibility.blockingMax), tileSlopes, T32,
                           t.now.gradX.cview(), t.now.gradY.cview());
    const HorizonShares shares = horizonShares(hb, nxr, nyr, tolerance);
    for (std::size_t v = 0; v < shares.size(); ++v)
        for (std::size_t k = 0; k < 4; ++k) t.horizonShare[v][k].push_back(shares[v][k]);
    const TrueSigmaBounds ts =
        trueSigmaMoveBound(t.last.envVisibility, t.last.footprint, t.now.envVisibility, t.now.footprint, op.phi,
                           t.now.gradX.cview(), t.now.gradY.cview(), settings.subsample);
    const auto addTiles = [&](const std::vector<float>& perReceiver, std::vector<double>& to) {
        const std::vector<float> tiles = tileMaxima(perReceiver, nxr, nyr, T32);
        to.insert(to.end(), tiles.begin(), tiles.end());
    };
    addTiles(hb.bound[HorizonAwareBounds::IdealExactTangent], t.idealBound);
    addTiles(ts.frames, t.trueSigma);
    addTiles(ts.weighted, t.trueSigmaWeighted);
    addTiles(hb.bound[HorizonAwareBounds::IdealExactTangentWeighted], t.idealWeighted);
}

void measureFrame(Track& t, const gi::GiSettings& settings, float cell, float tolerance) {
    const gi::GiLighting sky;  // uniform unit sky
    gi::runGiFrame(t.heights.cview(), cell, sky, settings, t.now);
    gi::ShadeMaps fresh;
    ambientOfV(t.now, t.now.envVisibility, settings, fresh);
    oracleFrame(t, settings, tolerance, fresh);
    if (t.frame++ == t.anchorFrame) {
        t.anchor = t.now;
        t.anchorHeights = t.heights;
    }
    if (t.lastHeights.empty()) return;
    for (std::size_t i = 0; i < t.heights.v.size(); ++i)
        t.dh.push_back(std::fabs(static_cast<double>(t.heights.v[i]) - t.lastHeights.v[i]));
    gi::VisibilityCache cache;  // fresh, anchored at the last heights: one plan's excursion is the frame's bound
    gi::planVisibilityTiles(t.lastHeights.cview(), t.heights.cview(), t.now.pyramid, settings.visibility, {}, 1e30f,
                            cache);
    const int nxr = t.now.pyramid.nxr, nyr = t.now.pyramid.nyr;
    // the per-azimuth bound of every visibility tile (the plan takes it only
    // where the coarse one would use much of the tolerance)
    std::vector<float> tileSlopes, tileGradients;
    const std::vector<float> tileBound = environmentBounds(cache.change, t.now.pyramid, settings.visibility,
                                                           gi::kVisibilityTile, &tileSlopes, &tileGradients);
    for (std::size_t g = 0; g < kGranularities.size(); ++g) {
        const int T = kGranularities[g];
        const std::vector<float> bound = T == gi::kVisibilityTile
                                             ? tileBound
                                             : environmentBounds(cache.change, t.now.pyramid, settings.visibility, T);
        t.boundShare[g].push_back(shareAbove(bound, T, 1, nxr, nyr, tolerance));
        if (T != 1) continue;
        t.laneRunShare.push_back(shareAbove(bound, 1, gi::ReceiverTiles::kTileAlign, nxr, nyr, tolerance));
        t.isotropicShare.push_back(
            shareAbove(isotropicBounds(cache.change, t.now.pyramid, settings.visibility), 1, 1, nxr, nyr, tolerance));
        double ms = 0.0;
        const std::vector<float> samples =
            sampleBounds(cache.change, t.now.pyramid, settings.visibility, t.changeLevels, ms);
        t.sampleShare.push_back(shareAbove(samples, 1, 1, nxr, nyr, tolerance));
        t.sampleRunShare.push_back(shareAbove(samples, 1, gi::ReceiverTiles::kTileAlign, nxr, nyr, tolerance));
        t.sampleMs.push_back(ms);
    }
    measureHorizonAware(t, settings, cache.change, tileSlopes, tolerance);
    if (t.frame > t.anchorFrame + 1) measureFromAnchor(t, settings, tolerance, fresh);
    gi::ShadeMaps cached;
    ambientOfV(t.now, t.last.envVisibility, settings, cached);
    const int s = settings.subsample;
    const std::vector<double> v = perTile({&cached.ambient}, {&fresh.ambient}, t.now, s);
    const std::vector<double> ind = perTile(t.last.indirect.indirect, t.now.indirect.indirect, t.now, s);
    const IndirectBounds ib = indirectBounds(t.now, t.last, gi::indirectScanAzimuths(settings));
    const std::array<Grid, 3> mixed = indirectOfLastSources(t.now, t.last, settings);
    const std::vector<double> geometry = perTile(t.last.indirect.indirect, mixed, t.now, s);
    const std::vector<double> sources = perTile(mixed, t.now.indirect.indirect, t.now, s);
    const std::vector<float> geometryBound =
        geometryBounds(cache.change, t.now.pyramid, settings, tileSlopes, tileGradients);
    t.indirectGeometryChange.insert(t.indirectGeometryChange.end(), geometry.begin(), geometry.end());
    t.indirectSourceChange.insert(t.indirectSourceChange.end(), sources.begin(), sources.end());
    t.indirectGeometryBound.insert(t.indirectGeometryBound.end(), geometryBound.begin(), geometryBound.end());
    t.indirectSampleBound.insert(t.indirectSampleBound.end(), ib.sampleMove.begin(), ib.sampleMove.end());
    t.indirectBound.insert(t.indirectBound.end(), ib.bound.begin(), ib.bound.end());
    t.bound.insert(t.bound.end(), tileBound.begin(), tileBound.end());
    t.vChange.insert(t.vChange.end(), v.begin(), v.end());
    t.indirectChange.insert(t.indirectChange.end(), ind.begin(), ind.end());
}

const char* kIntro =
    "Full GI frames (2x, one bounce, uniform unit sky: shade units are the tolerance's, 2 threads), consecutive "
    "frames compared per visibility tile (32 x 32 receivers). One-frame V bound: the per-azimuth bound "
    "gi/visibility_cache.h takes over the visibility tile (environment, V alone; where its coarse bound over every "
    "direction would take more than a quarter of the tolerance) before it refines it per receiver where it passes "
    "the tolerance. True change of the cached V: "
    "the SH ambient map at the new normals shaded with the last frame's V against the one shaded with the new V "
    "(the frame's own ambient map is the exact one, which does not read V), largest over the tile's "
    "texels. Largest radiance sample move: the largest over the indirect azimuths of the samples' moves "
    "gi/indirect_cache.h reads from the frame's radiance pyramid against the last frame's "
    "(gi/radiance_sample_change.h); radiance bound of the indirect light: what gi/indirect_cache.h "
    "adds for it (the sample moves weighed by each receiver's occlusion shares per azimuth and per distance "
    "group, times the occlusion factor; the largest over the indirect tiles of 16 x 16 receivers the tile holds); "
    "the true change of the indirect light is that of the whole frame (sources and "
    "geometry), largest over the tile's texels and "
    "channels, then split in two through the indirect light of this frame's geometry lit by the last frame's "
    "direct light: from the last frame's indirect light to that one only the geometry moved, from that one to this "
    "frame's only the sources; the plan's geometry bound of the indirect light is V's one-frame bound over the "
    "indirect scan's azimuths (gi/visibility_cache.h re-gathers a tile whose geometry drift passes the tolerance). "
    "Quantiles over every tile of every frame after the first. The oracle knows the true results: per "
    "tile it keeps its cached V (or direct shade, or indirect light) until the tile's texels are more than the "
    "tolerance from the "
    "truth, then takes the truth; the share of tiles it recomputes per frame is about the least any conservative "
    "bound can recompute. The second table of each case compares granularities: per frame, the share of the "
    "receivers whose tile's one-frame V bound passes the tolerance (the same bound taken over tiles of that many "
    "receivers a side, 1: each receiver alone; and, as the scans take receivers in runs of 16 along a row, the share "
    "of the receivers in a run that holds one above; and per receiver with one slope bound for every azimuth, from "
    "max filters of the change pyramid, gi/receiver_change_bound.h; and per receiver and azimuth from the change of "
    "the "
    "very samples its scan reads, gi/receiver_azimuth_bound.h, with what it costs on 2 threads: the |dh| pyramid "
    "redone over the change since the last frame, the scan over every receiver and the V bound) and the shares of the "
    "receivers an oracle with "
    "tiles of that size recomputes, mean over the frames after the first. The rows after the V bound's ratio set the "
    "tightest bound of the third table (ideal, exact tangent) and the true moves of each azimuth's sigma from the two "
    "frames' horizons and tangent planes, through the same weight per unit of slope, and both through the elevation "
    "weight of bench/elevation_weight.h (an estimate, not a bound), against the true change. The third table takes "
    "the per-receiver "
    "bound apart (bench/horizon_aware_bound.h): the same samples' change, then bounds that know each receiver's "
    "horizon (the maximum blocking slope) and its footprint's tangent plane at the last frame, and with the new "
    "frame's tangent planes; the fourth keeps one frame's V (the anchor) while the frames go on and counts the tiles "
    "whose true change, and whose bounds from the anchor, pass the tolerance.\n";

// One row per quantity: its quantiles and the share of tiles (or cells) above the tolerance.
std::string row(const std::string& what, const std::vector<double>& v, double above) {
    char buf[400];
    std::snprintf(buf, sizeof buf, "| %s | %.3g | %.3g | %.3g | %.3g | %.1f %% |\n", what.c_str(), quantile(v, 0.1),
                  quantile(v, 0.5), quantile(v, 0.9), quantile(v, 1.0), 100.0 * share(v, above));
    return buf;
}

double mean(const std::vector<double>& v) {
    double sum = 0.0;
    for (double x : v) sum += x;
    return v.empty() ? 0.0 : sum / static_cast<double>(v.size());
}

// bench/horizon_aware_bound.h's bounds: one frame's, and from the anchor frame on.
std::string horizonTables(const Track& t) {
    std::string out =
        "\n| one-frame V bound per receiver (bench/horizon_aware_bound.h), share of the receivers above the tolerance "
        "| alone | in runs of 16 | in tiles of 16 x 16 | in tiles of 32 x 32 |\n|---|---|---|---|---|\n";
    for (std::size_t v = 0; v < t.horizonShare.size(); ++v) {
        char buf[300];
        std::snprintf(buf, sizeof buf, "| %s | %.2f %% | %.2f %% | %.2f %% | %.2f %% |\n",
                      HorizonAwareBounds::kNames[v], 100.0 * mean(t.horizonShare[v][0]),
                      100.0 * mean(t.horizonShare[v][1]), 100.0 * mean(t.horizonShare[v][2]),
                      100.0 * mean(t.horizonShare[v][3]));
        out += buf;
    }
    char intro[300];
    std::snprintf(intro, sizeof intro,
                  "\nFrom frame %d's V on (an anchor kept while the frames go on; the frames before it let the scene "
                  "settle), the share of the tiles above the tolerance: ",
                  t.anchorFrame);
    out += intro;
    out +=
        "its true change, the engine's tile bound, and the tile maxima of the bounds above (in their order).\n\n"
        "| frames since the anchor | tiles 32²: true change | engine's bound | bounds above | tiles 16²: true change | "
        "bounds above |\n|---|---|---|---|---|---|\n";
    const auto list = [](const auto& shares) {
        std::string s;
        for (double x : shares) {
            char b[32];
            std::snprintf(b, sizeof b, "%s%.1f", s.empty() ? "" : " / ", 100.0 * x);
            s += b;
        }
        return s + " %";
    };
    for (std::size_t n = 0; n < t.fromAnchor.size(); ++n) {
        const Track::FromAnchor& f = t.fromAnchor[n];
        char buf[400];
        std::snprintf(buf, sizeof buf, "| %zu | %.1f %% | %.1f %% | %s | %.1f %% | %s |\n", n + 1, 100 * f.truth32,
                      100 * f.engine32, list(f.bound32).c_str(), 100 * f.truth16, list(f.bound16).c_str());
        out += buf;
    }
    return out;
}

// Per granularity, the mean share per frame of the receivers the one-frame
// V bound marks and of those the oracle recomputes.
std::string granularityTable(const Track& t) {
    std::string out =
        "\n| tiles (receivers) | one-frame V bound above the tolerance | oracle: V recomputed | oracle: direct shade "
        "recomputed | oracle: indirect light recomputed |\n|---|---|---|---|---|\n";
    for (std::size_t g = 0; g < kGranularities.size(); ++g) {
        char buf[200];
        std::snprintf(buf, sizeof buf, "| %d x %d | %.2f %% | %.2f %% | %.2f %% | %.2f %% |\n", kGranularities[g],
                      kGranularities[g], 100.0 * mean(t.boundShare[g]), 100.0 * mean(t.oracles[g].vShare),
                      100.0 * mean(t.oracles[g].shadeShare), 100.0 * mean(t.oracles[g].indirectShare));
        out += buf;
    }
    char buf[200];
    std::snprintf(buf, sizeof buf, "| 1 x 1, in the scans' runs of %d along a row | %.2f %% | | | |\n",
                  gi::ReceiverTiles::kTileAlign, 100.0 * mean(t.laneRunShare));
    out += buf;
    std::snprintf(buf, sizeof buf, "| 1 x 1, one slope bound for every azimuth (max filters) | %.2f %% | | | |\n",
                  100.0 * mean(t.isotropicShare));
    out += buf;
    std::snprintf(buf, sizeof buf,
                  "| 1 x 1, per azimuth from the samples' own change (%.1f ms per frame, median) | %.2f %% | | | |\n",
                  quantile(t.sampleMs, 0.5), 100.0 * mean(t.sampleShare));
    out += buf;
    std::snprintf(buf, sizeof buf, "| the same, in the scans' runs of %d along a row | %.2f %% | | | |\n",
                  gi::ReceiverTiles::kTileAlign, 100.0 * mean(t.sampleRunShare));
    return out + buf + horizonTables(t);
}

std::string report(const Track& t, float tolerance) {
    // per tile, a bound over a true change (V's by default) where that is not 0
    const auto ratioTo = [&](const std::vector<double>& bound, const std::vector<double>* truth = nullptr) {
        const std::vector<double>& change = truth ? *truth : t.vChange;
        std::vector<double> r;
        for (std::size_t i = 0; i < bound.size() && i < change.size(); ++i)
            if (change[i] > 0.0) r.push_back(bound[i] / change[i]);
        return r;
    };
    return "\n### " + t.name +
           "\n\n| quantity | p10 | median | p90 | max | share above the tolerance |\n|---|---|---|---|---|---|\n" +
           row("\\|dh\\| per cell (m; share above 1 cm)", t.dh, 0.01) +
           row("per tile: one-frame bound on the cached V's ambient change", t.bound, tolerance) +
           row("per tile: true change of the cached V's ambient", t.vChange, tolerance) +
           row("per tile: V bound / true change (share above 1)", ratioTo(t.bound), 1.0) +
           row("per tile: the ideal exact-tangent bound (bench/horizon_aware_bound.h), one frame", t.idealBound,
               tolerance) +
           row("per tile: the same / true change", ratioTo(t.idealBound), 1.0) +
           row("per tile: the true moves of sigma through the same conversion (bench/horizon_aware_bound.h)",
               t.trueSigma, tolerance) +
           row("per tile: the same / true change", ratioTo(t.trueSigma), 1.0) +
           row("per tile: the true moves of sigma, elevation weight (bench/elevation_weight.h, an estimate)",
               t.trueSigmaWeighted, tolerance) +
           row("per tile: the same / true change", ratioTo(t.trueSigmaWeighted), 1.0) +
           row("per tile: the ideal exact-tangent bound, elevation weight (an estimate)", t.idealWeighted, tolerance) +
           row("per tile: the same / true change", ratioTo(t.idealWeighted), 1.0) +
           row("per tile: largest radiance sample move of the indirect scan", t.indirectSampleBound, tolerance) +
           row("per tile: one-frame radiance bound of the indirect light", t.indirectBound, tolerance) +
           row("per tile: true change of the indirect light", t.indirectChange, tolerance) +
           row("per tile: the same, from the sources alone (the direct light it reflects)", t.indirectSourceChange,
               tolerance) +
           row("per tile: the same, from the geometry alone", t.indirectGeometryChange, tolerance) +
           row("per tile: the plan's geometry bound of the indirect light (V's over its azimuths)",
               t.indirectGeometryBound, tolerance) +
           row("per tile: the same / the true change from the geometry",
               ratioTo(t.indirectGeometryBound, &t.indirectGeometryChange), 1.0) +
           row("oracle: share of the tiles whose V it recomputes, per frame (share above 0)", t.oracles[0].vShare,
               0.0) +
           row("oracle: share of the tiles whose direct shade it recomputes, per frame (share above 0)",
               t.oracles[0].shadeShare, 0.0) +
           row("oracle: share of the tiles whose indirect light it recomputes, per frame (share above 0)",
               t.oracles[0].indirectShare, 0.0) +
           granularityTable(t);
}

gi::GiSettings diagnosisSettings() {
    gi::GiSettings settings;
    settings.subsample = 2;
    settings.indirect.bounces = 1;
    settings.incremental = false;
    settings.minEnvironmentShRows = gi::kShCount;  // the ambient with the cached V shades with it
    return settings;
}

void runTracks(const std::vector<Track*>& tracks, float cell, int frames, float tolerance,
               const std::function<void(int frame)>& nextSurfaces) {
    const gi::GiSettings settings = diagnosisSettings();
    for (Track* t : tracks) t->anchorFrame = frames / 2;
    withThreads(2, [&] {
        for (int f = 0; f <= frames; ++f) {
            nextSurfaces(f);
            for (Track* t : tracks) {
                measureFrame(*t, settings, cell, tolerance);
                t->last = t->now;
                t->lastHeights = t->heights;
            }
        }
    });
}

// The scene at its pacing: the lit surface and the ground alone.
std::string diagnoseScene(const DiagnosisOptions& o) {
    Simulation sim(builtinScene(o.scene, o.size, 1));
    Track lit{"lit surface (ground + water)"}, ground{"ground alone"};
    runTracks({&lit, &ground}, sim.state().cellSize, o.frames, o.tolerance, [&](int f) {
        if (f > 0)
            for (int k = 0; k < o.ticksPerFrame; ++k) sim.tick();
        const TerrainState& s = sim.state();
        lit.heights.ensureSize(s.nx, s.ny);
        ground.heights.ensureSize(s.nx, s.ny);
        for (int y = 0; y < s.ny; ++y)
            for (int x = 0; x < s.nx; ++x) {
                ground.heights(x, y) = s.ground(x, y);
                lit.heights(x, y) = s.ground(x, y) + (s.hasWater() ? s.water(x, y) : 0.0f);
            }
    });
    char head[200];
    std::snprintf(head, sizeof head, "\n## %s %d², %d frames of %d ticks\n", o.scene.c_str(), o.size, o.frames,
                  o.ticksPerFrame);
    return head + report(lit, o.tolerance) + report(ground, o.tolerance);
}

// The central crop of the Mont Blanc DEM with a square pit of `side` cells
// lowered by 30 m at its centre on odd frames (gi-incremental's pit cases).
std::string diagnosePit(const DiagnosisOptions& o, int side, const BenchContext& ctx) {
    float cell = 0.0f;
    const Grid dem = alpsCentreCrop(ctx.dataDir, o.size, cell);
    side = std::min(side, o.size);
    Track pit{"dem, " + std::to_string(side) + "² pit"};
    runTracks({&pit}, cell, o.frames, o.tolerance, [&](int f) {
        pit.heights = dem;
        const int x0 = (dem.nx - side) / 2, y0 = (dem.ny - side) / 2;
        if (f % 2 == 1)
            for (int y = y0; y < y0 + side; ++y)
                for (int x = x0; x < x0 + side; ++x) pit.heights(x, y) -= 30.0f;
    });
    char head[200];
    std::snprintf(head, sizeof head, "\n## Mont Blanc DEM %d², a %d² pit dropped and filled, %d frames\n", o.size, side,
                  o.frames);
    return head + report(pit, o.tolerance);
}

}  // namespace

Runner addGiBoundDiagnosisSuite(CLI::App& app, const BenchContext& ctx) {
    auto o = std::make_shared<DiagnosisOptions>();
    CLI::App* sub = app.add_subcommand(
        "gi-bound-diagnosis",
        "Per visibility tile of an animated scene: the one-frame change bound against the true change (prints)");
    sub->add_option("--scene", o->scene, "Built-in scene")->capture_default_str();
    sub->add_option("--size", o->size, "Grid side")->check(CLI::Range(64, 2048))->capture_default_str();
    sub->add_option("--frames", o->frames, "Frames measured")->check(CLI::Range(1, 1000))->capture_default_str();
    sub->add_option("--ticks", o->ticksPerFrame, "Simulation ticks per frame")
        ->check(CLI::Range(1, 100000))
        ->capture_default_str();
    sub->add_option("--tolerance", o->tolerance, "Tolerance the shares are counted against")->capture_default_str();
    sub->add_option("--pits", o->pits, "Then the DEM with a square pit of each of these sides (cells, at most --size)")
        ->check(CLI::Range(1, 2048))
        ->capture_default_str();
    return [o, &ctx] {
        std::string text =
            "# Change bounds against true changes, per visibility tile\n\nMachine: " + machineDescription() +
            ".\n\nCommand: `" + ctx.command + "`.\n\n" + kIntro;
        text += diagnoseScene(*o);
        for (int side : o->pits) text += diagnosePit(*o, side, ctx);
        std::fputs(text.c_str(), stdout);
        writeResult(ctx.outDir, "gi_bound_diagnosis.md", text);
        return 0;
    };
}

}  // namespace terrain::bench
