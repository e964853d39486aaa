#include "bench/horizon_aware_bound.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

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

// The unit normals of the texels whose V blends receiver (X, Y)'s: those
// within s - 1 cells of its cell (Fig. 7), from the heights' gradients.
struct Normal {
    double x, y, z;
};
void texelNormals(ConstGridView gx, ConstGridView gy, int s, int X, int Y, std::vector<Normal>& out) {
    out.clear();
    for (int y = std::max(0, s * Y - (s - 1)); y <= std::min(gx.ny - 1, s * Y + (s - 1)); ++y)
        for (int x = std::max(0, s * X - (s - 1)); x <= std::min(gx.nx - 1, s * X + (s - 1)); ++x) {
            const double a = gx(x, y), b = gy(x, y), n = std::sqrt(1.0 + a * a + b * b);
            out.push_back({-a / n, -b / n, 1.0 / n});
        }
}

double sinOfSlope(double t) { return t / std::sqrt(1.0 + t * t); }

// The directions across the support of each azimuth sample's hat: its
// ends, middle and quarter points (kHatPoints per sample, sample-major),
// taken once per call of the bounds below rather than per receiver.
constexpr int kHatPoints = 5;
struct HatDirections {
    std::vector<double> cosPhi, sinPhi;
};
HatDirections hatDirections(std::span<const double> phi) {
    const double step = 2.0 * std::numbers::pi / static_cast<double>(phi.size());
    HatDirections out;
    for (const double p0 : phi)
        for (int d = -(kHatPoints / 2); d <= kHatPoints / 2; ++d) {
            const double p = p0 + 0.5 * d * step;
            out.cosPhi.push_back(std::cos(p));
            out.sinPhi.push_back(std::sin(p));
        }
    return out;
}

// The ambient change bound of gi/change_bound.h with the elevation weight:
// (2 pi / m) sum_j W_j dU_j, sigma_j (tan) moving within [lo_j, hi_j]; dU_j
// the largest move of sin(sigma_j) over the band, W_j the largest |g| over
// it, the normals, and the directions of sample j's hat.
double weightedAmbientBound(const ElevationWeight& weight, const std::vector<Normal>& normals, const HatDirections& hat,
                            const float* sigma, const float* lo, const float* hi) {
    const int m = static_cast<int>(hat.cosPhi.size()) / kHatPoints;
    double sum = 0.0;
    for (int j = 0; j < m; ++j) {
        const double u = sinOfSlope(sigma[j]), u0 = sinOfSlope(lo[j]), u1 = sinOfSlope(hi[j]);
        const double du = std::max(u1 - u, u - u0);
        if (!(du > 0.0)) continue;
        double w = 0.0;
        for (int d = 0; d < kHatPoints; ++d) {
            const std::size_t k = static_cast<std::size_t>(j * kHatPoints + d);
            const double c = hat.cosPhi[k], sn = hat.sinPhi[k];
            for (const Normal& n : normals) w = std::max(w, weight.largest(n.z, n.x * c + n.y * sn, u0, u1));
        }
        sum += w * du;
    }
    return 2.0 * std::numbers::pi / m * sum;
}

const ElevationWeight& elevationWeight() {
    static const ElevationWeight w;
    return w;
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
                                      const std::vector<float>& tileSlopeBound, int tile, ConstGridView gradX,
                                      ConstGridView gradY) {
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
    const HatDirections hat = hatDirections(phi);
    parallelFor(0, nyr, 4, [&](int Y0, int Y1) {
        constexpr int kV = HorizonAwareBounds::kVariants;
        std::vector<float> gradients(static_cast<std::size_t>(nxr)), columns, perAzimuth(kV * m);
        // the weighted variants' sigma and their bounds (Ideal, TopTwo, Plain, exact tangent)
        constexpr int kWeighted = 3;
        std::vector<float> sigma(m), lo(kWeighted * m), hi(kWeighted * m);
        std::vector<Normal> normals;
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
                    const float moves[kWeighted] = {sigmaMoveExactTangent(b.horizon, lipschitz * b.ideal, T, newT),
                                                    sigmaMoveExactTangent(b.horizon, lipschitz * b.topTwo, T, newT),
                                                    sigmaMoveExactTangent(b.horizon, lipschitz * b.plain, T, newT)};
                    perAzimuth[HorizonAwareBounds::IdealExactTangent * m + k] = moves[0];
                    perAzimuth[HorizonAwareBounds::TopTwoExactTangent * m + k] = moves[1];
                    perAzimuth[HorizonAwareBounds::PlainExactTangent * m + k] = moves[2];
                    sigma[k] = std::max(b.horizon, T);
                    for (int w = 0; w < kWeighted; ++w) {
                        lo[static_cast<std::size_t>(w * m) + k] = sigma[k] - moves[w];
                        hi[static_cast<std::size_t>(w * m) + k] = sigma[k] + moves[w];
                    }
                    const std::size_t t = static_cast<std::size_t>(Y / tile) * gi::tileCount(nxr, tile) +
                                          static_cast<std::size_t>(X / tile);
                    perAzimuth[HorizonAwareBounds::TileExactTangent * m + k] =
                        sigmaMoveExactTangent(b.horizon, lipschitz * tileSlopeBound[t * m + k], T, newT);
                }
                for (int v = 0; v < HorizonAwareBounds::IdealExactTangentWeighted; ++v) {
                    const bool tangentAware = v >= HorizonAwareBounds::IdealTangent;  // dT or T' counted already
                    out.bound[v][r] = gi::ambientChangeBoundPerAzimuth(perAzimuth.data() + v * m, m,
                                                                       tangentAware ? 0.0f : g, 1.0f, false);
                }
                texelNormals(gradX, gradY, s, X, Y, normals);
                for (int w = 0; w < kWeighted; ++w)
                    out.bound[HorizonAwareBounds::IdealExactTangentWeighted + w][r] =
                        static_cast<float>(weightedAmbientBound(elevationWeight(), normals, hat, sigma.data(),
                                                                lo.data() + w * m, hi.data() + w * m));
            }
        }
    });
    return out;
}

TrueSigmaBounds trueSigmaMoveBound(const gi::VisibilityField& last, const gi::FootprintBox& lastBox,
                                   const gi::VisibilityField& now, const gi::FootprintBox& newBox,
                                   std::span<const double> phi, ConstGridView gradX, ConstGridView gradY,
                                   int subsample) {
    const int nxr = now.nxr, nyr = now.nyr, m = static_cast<int>(phi.size());
    const std::size_t plane = static_cast<std::size_t>(nxr) * nyr;
    if (last.nxr != nxr || last.nyr != nyr || last.maxSlope.size() != plane * m || now.maxSlope.size() != plane * m ||
        lastBox.loX.size() != plane || newBox.loX.size() != plane)
        throw InputError("true sigma move: the frames' visibility fields and boxes differ in size");
    TrueSigmaBounds out{std::vector<float>(plane, 0.0f), std::vector<float>(plane, 0.0f)};
    const HatDirections hat = hatDirections(phi);
    std::vector<double> cosPhi, sinPhi;
    for (const double p : phi) {
        cosPhi.push_back(std::cos(p));
        sinPhi.push_back(std::sin(p));
    }
    parallelFor(0, nyr, 8, [&](int Y0, int Y1) {
        std::vector<float> move(m), sigma(m), lo(m), hi(m);
        std::vector<Normal> normals;
        for (int Y = Y0; Y < Y1; ++Y)
            for (int X = 0; X < nxr; ++X) {
                const std::size_t r = static_cast<std::size_t>(Y) * nxr + X;
                for (int j = 0; j < m; ++j) {
                    const std::size_t k = static_cast<std::size_t>(j), at = k * plane + r;
                    const double c = cosPhi[k], sn = sinPhi[k];
                    const float before = std::max(last.maxSlope[at], lowestTangentSlope(lastBox, r, c, sn));
                    const float after = std::max(now.maxSlope[at], lowestTangentSlope(newBox, r, c, sn));
                    move[k] = std::fabs(after - before);
                    sigma[k] = before;
                    lo[k] = std::min(before, after);
                    hi[k] = std::max(before, after);
                }
                out.frames[r] = gi::ambientChangeBoundPerAzimuth(move.data(), m, 0.0f, 1.0f, false);
                texelNormals(gradX, gradY, subsample, X, Y, normals);
                out.weighted[r] = static_cast<float>(
                    weightedAmbientBound(elevationWeight(), normals, hat, sigma.data(), lo.data(), hi.data()));
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
            for (int y = std::max(0, Y - 1); y <= std::min(nyr - 1, Y + 1); ++y)
                for (int x = std::max(0, X - 1); x <= std::min(nxr - 1, X + 1); ++x)
                    t = std::max(t, perReceiver[static_cast<std::size_t>(y) * nxr + x]);
        }
    return out;
}

}  // namespace terrain::bench
