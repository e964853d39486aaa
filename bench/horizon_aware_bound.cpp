#include "bench/horizon_aware_bound.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"
#include "core/parallel.h"
#include "gi/receiver_tiles.h"
#include "gi/visibility.h"

namespace terrain::bench {
namespace {

// One step of one azimuth in both fields: the anchor's heights and the |dh|
// bound pyramid (the same layout), and the receivers inside the domain at
// this step and every earlier one (a receiver's valid prefix).
struct StepPair {
    gi::ScanStep heights, change;
    int x0, x1, y0, y1;
};

std::vector<std::vector<StepPair>> stepPairs(const gi::HeightPyramid& anchor, const gi::HeightPyramid& change,
                                             std::span<const double> phi) {
    std::vector<std::vector<StepPair>> out(phi.size());
    for (std::size_t j = 0; j < phi.size(); ++j) {
        const double c = std::cos(phi[j]), sn = std::sin(phi[j]);
        int x0 = 0, x1 = anchor.nxr - 1, y0 = 0, y1 = anchor.nyr - 1;
        for (int i = 0; i < static_cast<int>(anchor.steps.size()); ++i) {
            const gi::ScanStepInfo a = gi::scanStepInfo(anchor, i, c, sn);
            const gi::ScanStepInfo d = gi::scanStepInfo(change, i, c, sn);
            x0 = std::max(x0, a.xFirst);
            x1 = std::min(x1, a.xLast);
            y0 = std::max(y0, a.yFirst);
            y1 = std::min(y1, a.yLast);
            if (x0 > x1 || y0 > y1) break;
            out[j].push_back({a.step, d.step, x0, x1, y0, y1});
        }
    }
    return out;
}

// |sigma' - sigma| for sigma = max(H, T), from bounds dH and dT on the moves of H and T.
float sigmaMove(float H, float dH, float T, float dT) {
    if (H >= T) return std::max(dH, std::max(0.0f, T + dT - H));
    return std::max(dT, std::max(0.0f, H + dH - T));
}

// The same with the new tangent slope T' itself: sigma' = max(H', T') is
// monotone in H', so its farthest values lie at H' = H +- dH.
float sigmaMoveExactTangent(float H, float dH, float T, float newT) {
    const float sigma = std::max(H, T);
    return std::max(std::fabs(std::max(H + dH, newT) - sigma), std::fabs(std::max(H - dH, newT) - sigma));
}

// The footprint box's lowest tangent slope along (c, sn) (gi/visibility.h).
float lowestTangentSlope(const gi::FootprintBox& b, std::size_t r, double c, double sn) {
    return static_cast<float>((c >= 0.0 ? b.loX[r] : b.hiX[r]) * c + (sn >= 0.0 ? b.loY[r] : b.hiY[r]) * sn);
}

// The slope bounds of receiver (X, Y) along one azimuth's steps, and its
// anchor horizon H (-infinity without a step inside the domain).
struct SlopeBounds {
    float plain = 0.0f, ideal = 0.0f, topTwo = 0.0f;
    float horizon = -std::numeric_limits<float>::infinity();
};
SlopeBounds receiverSlopeBounds(const std::vector<StepPair>& steps, int X, int Y, float h0, float d0) {
    float best = -std::numeric_limits<float>::infinity(), second = best;
    float moveAtBest = 0.0f, risen = best, largestMove = 0.0f, largestOtherMove = 0.0f;
    for (const StepPair& p : steps) {
        if (X < p.x0 || X > p.x1 || Y < p.y0 || Y > p.y1) break;
        const float inv = p.heights.w[2][0];
        const float s = (gi::stepSample(p.heights, Y * p.heights.rowStep + X) - h0) * inv;
        const float move = (gi::stepSample(p.change, Y * p.change.rowStep + X) + d0) * inv;
        risen = std::max(risen, s + move);
        largestMove = std::max(largestMove, move);
        if (s > best) {
            // the old best becomes one of the others
            second = best;
            largestOtherMove = std::max(largestOtherMove, moveAtBest);
            best = s;
            moveAtBest = move;
        } else {
            second = std::max(second, s);
            largestOtherMove = std::max(largestOtherMove, move);
        }
    }
    if (best == -std::numeric_limits<float>::infinity()) return {};
    SlopeBounds b;
    b.horizon = best;
    b.plain = largestMove;
    b.ideal = std::max(moveAtBest, risen - best);
    const float gap =
        second == -std::numeric_limits<float>::infinity() ? std::numeric_limits<float>::infinity() : best - second;
    b.topTwo = std::max(moveAtBest, std::max(0.0f, largestOtherMove - gap));
    return b;
}

}  // namespace

HorizonAwareBounds horizonAwareBounds(const gi::HeightPyramid& anchor, const gi::FootprintBox& box,
                                      const gi::FootprintBox& newBox, const gi::ChangeLevels& levels,
                                      const gi::MaxChangePyramid& dh, std::span<const double> phi, float lipschitz,
                                      const std::vector<float>& tileSlopeBound, int tile) {
    const gi::HeightPyramid& change = levels.bound;
    if (!levels.valid || change.nxr != anchor.nxr || change.nyr != anchor.nyr ||
        change.steps.size() != anchor.steps.size() || box.nxr != anchor.nxr || box.nyr != anchor.nyr ||
        newBox.nxr != anchor.nxr || newBox.nyr != anchor.nyr)
        throw InputError("horizon-aware bound: the change levels were not built for this pyramid");
    const int nxr = anchor.nxr, nyr = anchor.nyr, s = anchor.subsample, m = static_cast<int>(phi.size());
    const std::vector<std::vector<StepPair>> steps = stepPairs(anchor, change, phi);
    HorizonAwareBounds out;
    const std::size_t plane = static_cast<std::size_t>(nxr) * nyr;
    for (std::vector<float>& v : out.bound) v.assign(plane, 0.0f);
    std::vector<double> c(phi.size()), sn(phi.size());
    for (std::size_t j = 0; j < phi.size(); ++j) {
        c[j] = std::cos(phi[j]);
        sn[j] = std::sin(phi[j]);
    }
    parallelFor(0, nyr, 4, [&](int Y0, int Y1) {
        constexpr int kV = HorizonAwareBounds::kVariants;
        std::vector<float> gradients(static_cast<std::size_t>(nxr)), columns, perAzimuth(kV * m);
        for (int Y = Y0; Y < Y1; ++Y) {
            gi::receiverGradientBounds(dh, anchor, Y, 0, nxr, gradients.data(), columns);
            const float* h0 = anchor.rawPhaseRow(0, s * Y);
            const float* d0 = change.rawPhaseRow(0, s * Y);
            for (int X = 0; X < nxr; ++X) {
                const std::size_t r = static_cast<std::size_t>(Y) * nxr + X;
                const float g = gradients[static_cast<std::size_t>(X)];
                for (int j = 0; j < m; ++j) {
                    const SlopeBounds b = receiverSlopeBounds(steps[static_cast<std::size_t>(j)], X, Y, h0[X], d0[X]);
                    const std::size_t k = static_cast<std::size_t>(j);
                    const float T = lowestTangentSlope(box, r, c[k], sn[k]);
                    const float newT = lowestTangentSlope(newBox, r, c[k], sn[k]);
                    const float dT = static_cast<float>((std::fabs(c[k]) + std::fabs(sn[k])) * g);
                    perAzimuth[HorizonAwareBounds::Plain * m + k] = lipschitz * b.plain;
                    perAzimuth[HorizonAwareBounds::Ideal * m + k] = lipschitz * b.ideal;
                    perAzimuth[HorizonAwareBounds::TopTwo * m + k] = lipschitz * b.topTwo;
                    perAzimuth[HorizonAwareBounds::IdealTangent * m + k] =
                        sigmaMove(b.horizon, lipschitz * b.ideal, T, dT);
                    perAzimuth[HorizonAwareBounds::TopTwoTangent * m + k] =
                        sigmaMove(b.horizon, lipschitz * b.topTwo, T, dT);
                    perAzimuth[HorizonAwareBounds::IdealExactTangent * m + k] =
                        sigmaMoveExactTangent(b.horizon, lipschitz * b.ideal, T, newT);
                    perAzimuth[HorizonAwareBounds::TopTwoExactTangent * m + k] =
                        sigmaMoveExactTangent(b.horizon, lipschitz * b.topTwo, T, newT);
                    perAzimuth[HorizonAwareBounds::PlainExactTangent * m + k] =
                        sigmaMoveExactTangent(b.horizon, lipschitz * b.plain, T, newT);
                    const std::size_t t = static_cast<std::size_t>(Y / tile) * gi::tileCount(nxr, tile) +
                                          static_cast<std::size_t>(X / tile);
                    perAzimuth[HorizonAwareBounds::TileExactTangent * m + k] =
                        sigmaMoveExactTangent(b.horizon, lipschitz * tileSlopeBound[t * m + k], T, newT);
                }
                for (int v = 0; v < kV; ++v) {
                    const bool tangentAware = v >= HorizonAwareBounds::IdealTangent;  // dT or T' counted already
                    out.bound[v][r] = gi::ambientChangeBoundPerAzimuth(perAzimuth.data() + v * m, m,
                                                                       tangentAware ? 0.0f : g, 1.0f, false);
                }
            }
        }
    });
    return out;
}

std::vector<float> tileMaxima(const std::vector<float>& perReceiver, int nxr, int nyr, int T) {
    const int tilesX = gi::tileCount(nxr, T);
    std::vector<float> out(static_cast<std::size_t>(tilesX) * gi::tileCount(nyr, T), 0.0f);
    for (int Y = 0; Y < nyr; ++Y)
        for (int X = 0; X < nxr; ++X) {
            float& t = out[static_cast<std::size_t>(Y / T) * tilesX + X / T];
            t = std::max(t, perReceiver[static_cast<std::size_t>(Y) * nxr + X]);
        }
    return out;
}

}  // namespace terrain::bench
