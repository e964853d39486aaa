#include "gi/visibility.h"

#include <algorithm>
#include <cmath>

#include "gi/nlp.h"
#include "sim/parallel.h"

namespace terrain::gi {

namespace {

constexpr int kMaxBlocks = 64;

// ---- algorithm: slopes of one step for a row of receivers -----------------
// Samples `field` (spacing `g` cells, receivers `k` storage texels apart) at
// receiver positions + (dx, dy) cells with one set of bilinear weights, and
// writes the blocking slope (sample - h0) / tau. Receivers whose sample falls
// outside the domain keep the previous step's slope (the ray has left the
// height field, nothing more can block).
void stepSlopes(const float* __restrict field, std::ptrdiff_t fieldStride, int fieldNx, int fieldNy, int k, int Y, double dx,
                double dy, const float* __restrict h0, float invTau, const float* __restrict prev, float* __restrict out, int nxr) {
    const double py = static_cast<double>(k) * Y + dy;
    int xa = nxr, xb = -1;  // valid receivers [xa, xb]
    double fy = 0.0;
    int r0 = 0;
    if (py >= 0.0 && py <= fieldNy - 1) {
        r0 = static_cast<int>(std::floor(py));
        fy = py - r0;
        // k X + dx in [0, fieldNx - 1]
        xa = std::max(0, static_cast<int>(std::ceil(-dx / k)));
        xb = std::min(nxr - 1, static_cast<int>(std::floor((fieldNx - 1 - dx) / k)));
        // guard against rounding at the ends
        while (xa <= xb && k * xa + dx < 0.0) ++xa;
        while (xb >= xa && k * xb + dx > fieldNx - 1) --xb;
    }
    for (int X = 0; X < std::min(xa, nxr); ++X) out[X] = prev ? prev[X] : kNoBlocker;
    for (int X = std::max(xb + 1, 0); X < nxr; ++X) out[X] = prev ? prev[X] : kNoBlocker;
    if (xa > xb) return;
    const int c0 = static_cast<int>(std::floor(dx));
    const float fx = static_cast<float>(dx - c0);
    const float fyf = static_cast<float>(fy);
    const float w00 = (1.0f - fx) * (1.0f - fyf), w01 = fx * (1.0f - fyf), w10 = (1.0f - fx) * fyf, w11 = fx * fyf;
    const float* __restrict a = field + r0 * fieldStride + c0;
    const float* __restrict b = a + fieldStride;  // padded row: in bounds even when fy == 0 at the last row
    if (k == 1) {
        for (int X = xa; X <= xb; ++X) {
            const float v = (w00 * a[X] + w01 * a[X + 1]) + (w10 * b[X] + w11 * b[X + 1]);
            out[X] = (v - h0[X]) * invTau;
        }
    } else {
        for (int X = xa; X <= xb; ++X) {
            const std::ptrdiff_t i = static_cast<std::ptrdiff_t>(k) * X;
            const float v = (w00 * a[i] + w01 * a[i + 1]) + (w10 * b[i] + w11 * b[i + 1]);
            out[X] = (v - h0[X]) * invTau;
        }
    }
}

// ---- algorithm: the maximum blocking slope of each receiver (Eq. 16) --------
void reduceMaxSlope(const float* slopes, int nSteps, int nxr, BlockingMax rule, float* out) {
    if (rule == BlockingMax::Samples || nSteps < 2) {
        for (int X = 0; X < nxr; ++X) out[X] = slopes[X];
        for (int i = 1; i < nSteps; ++i) {
            const float* s = slopes + static_cast<std::size_t>(i) * nxr;
            for (int X = 0; X < nxr; ++X) out[X] = out[X] < s[X] ? s[X] : out[X];
        }
        return;
    }
    // Eq. 16: the maximum of the cubic interpolant through the samples s_i,
    // evaluated at the knots (the samples themselves) and at the midpoints,
    // (-s_{i-1} + 9 s_i + 9 s_{i+1} - s_{i+2}) / 16 (ends replicated). The
    // interpolant can rise between samples, recovering part of a peak that
    // falls between two exponential steps.
    for (int X = 0; X < nxr; ++X) out[X] = slopes[X];
    for (int i = 0; i + 1 < nSteps; ++i) {
        const float* __restrict sm = slopes + static_cast<std::size_t>(std::max(i - 1, 0)) * nxr;
        const float* __restrict s0 = slopes + static_cast<std::size_t>(i) * nxr;
        const float* __restrict s1 = s0 + nxr;
        const float* __restrict s2 = slopes + static_cast<std::size_t>(std::min(i + 2, nSteps - 1)) * nxr;
        for (int X = 0; X < nxr; ++X) {
            const float mid = (9.0f * (s0[X] + s1[X]) - (sm[X] + s2[X])) * (1.0f / 16.0f);
            float m = out[X];
            m = m < s1[X] ? s1[X] : m;
            m = m < mid ? mid : m;
            out[X] = m;
        }
    }
}

// ---- algorithm: Eq. 11 and the folded wedge operator for one azimuth -------
// NLP vectors of a row of receivers (4 rows of nxr), then V += G_j w_j over
// the sparse pattern, each entry a contiguous multiply-add over the row.
void accumulateVisibility(const float* __restrict maxSlope, const float* __restrict gx, const float* __restrict gy,
                          float cosPhi, float sinPhi, const VisibilityTarget& target, const float* opValues,
                          const std::uint8_t* patRow, const std::uint8_t* patNlp, int patSize, float* const* vRows,
                          float* __restrict nlp, int nxr) {
    float* __restrict w0 = nlp;
    float* __restrict w1 = nlp + nxr;
    float* __restrict w2 = nlp + 2 * nxr;
    float* __restrict w3 = nlp + 3 * nxr;
    for (int X = 0; X < nxr; ++X) {
        // omega_min: elevation of the tangent plane along this azimuth
        const float tangent = gx[X] * cosPhi + gy[X] * sinPhi;
        const float t = maxSlope[X] < tangent ? tangent : maxSlope[X];
        const float s = sinFromSlope(t);
        float w[kNlpCount];
        if (target.window) {
            const float lo = s < target.sinLow ? target.sinLow : s;
            const float hi = lo < target.sinHigh ? target.sinHigh : lo;
            nlpVisibleBetween(lo, hi, w);
        } else {
            nlpVisibleAbove(s, w);
        }
        w0[X] = w[0];
        w1[X] = w[1];
        w2[X] = w[2];
        w3[X] = w[3];
    }
    for (int e = 0; e < patSize; ++e) {
        float* __restrict v = vRows[patRow[e]];
        const float* __restrict w = nlp + static_cast<std::size_t>(patNlp[e]) * nxr;
        const float g = opValues[e];
        for (int X = 0; X < nxr; ++X) v[X] += g * w[X];
    }
}

}  // namespace

float maxBlockingSlopeOfSequence(const float* slopes, int count, int stride, BlockingMax rule) {
    (void)stride;
    float out = kNoBlocker;
    reduceMaxSlope(slopes, count, 1, rule, &out);
    return out;
}

void computeVisibility(const HeightPyramid& pyr, ConstGridView gradX, ConstGridView gradY,
                       const VisibilitySettings& settings, const VisibilityTarget& target, VisibilityState& state,
                       VisibilityField& out) {
    (void)settings.interp;
    const FoldedWedgeOperator& op = *target.op;
    const int nxr = pyr.nxr, nyr = pyr.nyr, s = pyr.subsample;
    const int m = op.azimuths;
    const int nSteps = static_cast<int>(pyr.steps.size());
    const std::size_t planeSize = static_cast<std::size_t>(nxr) * nyr;
    out.nxr = nxr;
    out.nyr = nyr;
    out.sh.resize(planeSize * kShCount);
    out.maxSlope.resize(planeSize * m);

    const int nBlocks = std::max(1, std::min(nyr, kMaxBlocks));
    state.blocks.resize(static_cast<std::size_t>(nBlocks));
    for (VisibilityScratch& b : state.blocks) {
        b.slopes.resize(static_cast<std::size_t>(nSteps) * nxr);
        b.gradX.resize(static_cast<std::size_t>(nxr));
        b.gradY.resize(static_cast<std::size_t>(nxr));
        b.h0.resize(static_cast<std::size_t>(nxr));
        b.nlp.resize(static_cast<std::size_t>(4) * nxr);
    }
    // ---- schedule: fixed row blocks in parallel, rows serially within a block
    parallelFor(0, nBlocks, 1, [&](int b0, int b1) {
        for (int block = b0; block < b1; ++block) {
            VisibilityScratch& sc = state.blocks[static_cast<std::size_t>(block)];
            const int yBegin = static_cast<int>(static_cast<long long>(nyr) * block / nBlocks);
            const int yEnd = static_cast<int>(static_cast<long long>(nyr) * (block + 1) / nBlocks);
            for (int Y = yBegin; Y < yEnd; ++Y) {
                // receiver heights and height gradients of this row
                const float* rawRow = pyr.raw.row(s * Y);
                for (int X = 0; X < nxr; ++X) {
                    sc.h0[static_cast<std::size_t>(X)] = rawRow[static_cast<std::size_t>(s) * X];
                    sc.gradX[static_cast<std::size_t>(X)] = gradX(s * X, s * Y);
                    sc.gradY[static_cast<std::size_t>(X)] = gradY(s * X, s * Y);
                }
                float* vRows[kShCount];
                for (int i = 0; i < kShCount; ++i) {
                    vRows[i] = out.plane(i) + static_cast<std::size_t>(Y) * nxr;
                    std::fill(vRows[i], vRows[i] + nxr, 0.0f);
                }
                for (int j = 0; j < m; ++j) {
                    const double c = std::cos(op.phi[static_cast<std::size_t>(j)]);
                    const double sn = std::sin(op.phi[static_cast<std::size_t>(j)]);
                    for (int i = 0; i < nSteps; ++i) {
                        const PyramidStep& st = pyr.steps[static_cast<std::size_t>(i)];
                        const double dxCells = st.tauCells * c, dyCells = st.tauCells * sn;
                        float* outRow = sc.slopes.data() + static_cast<std::size_t>(i) * nxr;
                        const float* prevRow = i > 0 ? outRow - nxr : nullptr;
                        if (st.level < 0) {
                            // unfiltered heights: spacing 1, receivers s texels apart
                            stepSlopes(pyr.raw.v.data(), pyr.raw.stride, pyr.nx, pyr.ny, s, Y, dxCells, dyCells,
                                       sc.h0.data(), st.invTauWorld, prevRow, outRow, nxr);
                        } else {
                            // level blown out to the receiver grid: spacing s
                            const PaddedField& f = pyr.levels[static_cast<std::size_t>(st.level)];
                            stepSlopes(f.v.data(), f.stride, f.nx, f.ny, 1, Y, dxCells / s, dyCells / s, sc.h0.data(),
                                       st.invTauWorld, prevRow, outRow, nxr);
                        }
                    }
                    float* maxRow = out.maxSlope.data() + planeSize * j + static_cast<std::size_t>(Y) * nxr;
                    reduceMaxSlope(sc.slopes.data(), nSteps, nxr, settings.blockingMax, maxRow);
                    accumulateVisibility(maxRow, sc.gradX.data(), sc.gradY.data(), static_cast<float>(c),
                                         static_cast<float>(sn), target,
                                         op.values.data() + static_cast<std::size_t>(j) * op.patternSize(),
                                         op.patternRow.data(), op.patternNlp.data(), op.patternSize(), vRows, sc.nlp.data(), nxr);
                }
            }
        }
    });
}

}  // namespace terrain::gi
