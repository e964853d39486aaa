#include "gi/wedge.h"

#include <cmath>

namespace terrain::gi {

namespace {

// z integrals: Z[r][l] = int_{-1}^{1} NLP_l(z) shAssociated_r(z) dz, done in
// theta (z = cos theta, dz = sin theta dtheta) where the integrand is smooth.
struct ZIntegrals {
    double z[kShCount][kNlpCount];
    ZIntegrals() {
        const int n = 64;
        double x[64], w[64];
        gaussLegendre(n, x, w);
        for (int r = 0; r < kShCount; ++r)
            for (int l = 0; l < kNlpCount; ++l) z[r][l] = 0.0;
        for (int q = 0; q < n; ++q) {
            const double theta = 0.5 * kPi * (x[q] + 1.0);
            const double wt = 0.5 * kPi * w[q] * std::sin(theta);
            double p[kNlpCount];
            nlpEvaluate(std::cos(theta), p);
            for (int r = 0; r < kShCount; ++r) {
                const double a = shAssociated(r, std::cos(theta));
                for (int l = 0; l < kNlpCount; ++l) z[r][l] += wt * a * p[l];
            }
        }
    }
};

const ZIntegrals& zIntegrals() {
    static const ZIntegrals z;
    return z;
}

// Whether NLP_l couples with SH row r at all (parity / m = 0 orthogonality).
bool couples(int r, int l) {
    const int band = shBand(r), m = std::abs(shOrderM(r));
    if (m == 0) return l == band;
    return ((band - m - l) % 2 + 2) % 2 == 0;
}

void buildSparse(FoldedWedgeOperator& op) {
    op.patternRow.clear();
    op.patternNlp.clear();
    for (int r = 0; r < op.shRows; ++r)
        for (int l = 0; l < kNlpCount; ++l)
            if (couples(r, l)) {
                op.patternRow.push_back(static_cast<std::uint8_t>(r));
                op.patternNlp.push_back(static_cast<std::uint8_t>(l));
            }
    const int p = op.patternSize();
    const int cols = 4 * op.azimuths;
    op.values.assign(static_cast<std::size_t>(op.azimuths) * p, 0.0f);
    for (int j = 0; j < op.azimuths; ++j)
        for (int e = 0; e < p; ++e)
            op.values[static_cast<std::size_t>(j * p + e)] = static_cast<float>(
                op.dense[static_cast<std::size_t>(op.patternRow[e] * cols + j * 4 + op.patternNlp[e])]);
}

// dense += R(phi) * M[:, tap block]
void addRotatedBlock(FoldedWedgeOperator& op, const std::vector<double>& m, int taps, int tap, double phi, int sample) {
    const ShMatrix rot = shRotationZ(phi);
    const int cols = 4 * op.azimuths;
    const int mcols = 4 * taps;
    for (int r = 0; r < kShCount; ++r)
        for (int l = 0; l < kNlpCount; ++l) {
            double s = 0.0;
            for (int k = 0; k < kShCount; ++k)
                s += rot[static_cast<std::size_t>(r * kShCount + k)] *
                     m[static_cast<std::size_t>(k * mcols + tap * 4 + l)];
            op.dense[static_cast<std::size_t>(r * cols + sample * 4 + l)] += s;
        }
}

}  // namespace

double wedgeTapWeight(AzimuthInterp interp, int k, double a) {
    if (interp == AzimuthInterp::Linear) return k == 0 ? 1.0 - a : a;
    // Uniform cubic B-spline on samples j-1, j, j+1, j+2 (Nowrouzezahrai & Snyder 2009, Appendix A).
    switch (k) {
        case 0:
            return (1.0 - a) * (1.0 - a) * (1.0 - a) / 6.0;
        case 1:
            return (3.0 * a * a * a - 6.0 * a * a + 4.0) / 6.0;
        case 2:
            return (-3.0 * a * a * a + 3.0 * a * a + 3.0 * a + 1.0) / 6.0;
        default:
            return a * a * a / 6.0;
    }
}

std::vector<double> wedgeOperator(AzimuthInterp interp, double deltaPhi) {
    const int taps = wedgeTaps(interp);
    const int cols = 4 * taps;
    const ZIntegrals& zi = zIntegrals();
    // phi integrals: F[r][k] = int_0^dphi beta_k(phi / dphi) shAzimuthal_r(phi) dphi
    const int n = 32;
    double x[32], w[32];
    gaussLegendre(n, x, w);
    std::vector<double> m(static_cast<std::size_t>(kShCount * cols), 0.0);
    for (int r = 0; r < kShCount; ++r)
        for (int k = 0; k < taps; ++k) {
            double f = 0.0;
            for (int q = 0; q < n; ++q) {
                const double a = 0.5 * (x[q] + 1.0);
                f += 0.5 * deltaPhi * w[q] * wedgeTapWeight(interp, k, a) * shAzimuthal(r, a * deltaPhi);
            }
            for (int l = 0; l < kNlpCount; ++l)
                m[static_cast<std::size_t>(r * cols + k * 4 + l)] = couples(r, l) ? f * zi.z[r][l] : 0.0;
        }
    return m;
}

FoldedWedgeOperator foldFullCircle(int azimuths, AzimuthInterp interp) {
    FoldedWedgeOperator op;
    op.azimuths = azimuths;
    const double dphi = 2.0 * kPi / azimuths;
    for (int j = 0; j < azimuths; ++j) op.phi.push_back(dphi * j);
    op.dense.assign(static_cast<std::size_t>(kShCount * 4 * azimuths), 0.0);
    const int taps = wedgeTaps(interp);
    const std::vector<double> m = wedgeOperator(interp, dphi);
    // Wedge j spans [phi_j, phi_j + dphi]; tap k reads sample j + k (linear)
    // or j - 1 + k (B-spline), indices modulo m.
    const int first = interp == AzimuthInterp::Linear ? 0 : -1;
    for (int j = 0; j < azimuths; ++j)
        for (int k = 0; k < taps; ++k) {
            const int sample = ((j + first + k) % azimuths + azimuths) % azimuths;
            addRotatedBlock(op, m, taps, k, op.phi[static_cast<std::size_t>(j)], sample);
        }
    buildSparse(op);
    return op;
}

FoldedWedgeOperator firstRowOnly(FoldedWedgeOperator op) {
    op.shRows = 1;
    buildSparse(op);
    return op;
}

FoldedWedgeOperator horizonsOnly(FoldedWedgeOperator op) {
    op.shRows = 0;
    buildSparse(op);
    return op;
}

FoldedWedgeOperator foldPartialRange(double phiStart, double phiEnd, int azimuths) {
    FoldedWedgeOperator op;
    op.azimuths = azimuths;
    const double dphi = (phiEnd - phiStart) / std::max(azimuths - 1, 1);
    for (int j = 0; j < azimuths; ++j) op.phi.push_back(phiStart + dphi * j);
    op.dense.assign(static_cast<std::size_t>(kShCount * 4 * azimuths), 0.0);
    const std::vector<double> m = wedgeOperator(AzimuthInterp::Linear, dphi);
    for (int j = 0; j + 1 < azimuths; ++j)
        for (int k = 0; k < 2; ++k) addRotatedBlock(op, m, 2, k, op.phi[static_cast<std::size_t>(j)], j + k);
    buildSparse(op);
    return op;
}

void applyFoldedDense(const FoldedWedgeOperator& op, const double* nlp, double out[kShCount]) {
    const int cols = 4 * op.azimuths;
    for (int r = 0; r < kShCount; ++r) {
        double s = 0.0;
        for (int c = 0; c < cols; ++c) s += op.dense[static_cast<std::size_t>(r * cols + c)] * nlp[c];
        out[r] = s;
    }
}

}  // namespace terrain::gi
