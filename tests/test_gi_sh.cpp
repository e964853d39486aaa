// gi/sh, gi/nlp, gi/wedge: the maths, each against an independent slow computation.
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <doctest/doctest.h>

#include "gi/nlp.h"
#include "gi/sh.h"
#include "gi/wedge.h"

using namespace terrain::gi;

namespace {

// Midpoint-rule integral over the sphere of f(x, y, z): dense, independent of
// the Gauss-Legendre code under test.
template <class F>
double sphereIntegral(F&& f, int nTheta = 400, int nPhi = 800) {
    double sum = 0.0;
    for (int a = 0; a < nTheta; ++a) {
        const double theta = kPi * (a + 0.5) / nTheta;
        for (int b = 0; b < nPhi; ++b) {
            const double phi = 2.0 * kPi * (b + 0.5) / nPhi;
            sum +=
                f(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)) * std::sin(theta);
        }
    }
    return sum * (kPi / nTheta) * (2.0 * kPi / nPhi);
}

}  // namespace

TEST_CASE("gi.sh: basis is orthonormal (dense quadrature)") {
    double maxErr = 0.0;
    for (int i = 0; i < kShCount; ++i)
        for (int j = i; j < kShCount; ++j) {
            const double v = sphereIntegral(
                [&](double x, double y, double z) {
                    double yv[kShCount];
                    shEvaluate(x, y, z, yv);
                    return yv[i] * yv[j];
                },
                200, 400);
            maxErr = std::max(maxErr, std::abs(v - (i == j ? 1.0 : 0.0)));
        }
    MESSAGE("max |<Y_i, Y_j> - delta_ij| = " << maxErr);
    CHECK(maxErr < 1e-4);
}

TEST_CASE("gi.sh: separable form matches the cartesian form") {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int n = 0; n < 50; ++n) {
        const double z = 2.0 * u(rng) - 1.0, phi = 2.0 * kPi * u(rng);
        const double s = std::sqrt(1.0 - z * z);
        double y[kShCount];
        shEvaluate(s * std::cos(phi), s * std::sin(phi), z, y);
        for (int i = 0; i < kShCount; ++i)
            CHECK(shAssociated(i, z) * shAzimuthal(i, phi) == doctest::Approx(y[i]).epsilon(1e-12));
    }
}

TEST_CASE("gi.sh: z-rotation preserves norms and matches direct evaluation") {
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    ShVector c{};
    for (double& v : c) v = u(rng);
    double norm0 = 0.0;
    for (double v : c) norm0 += v * v;
    for (double angle : {0.3, -1.7, 2.5, 6.0}) {
        ShVector r = c;
        shRotateZ(angle, r);
        double norm1 = 0.0;
        for (double v : r) norm1 += v * v;
        CHECK(norm1 == doctest::Approx(norm0).epsilon(1e-12));
        // matrix form agrees with the in-place form
        const ShMatrix m = shRotationZ(angle);
        for (int i = 0; i < kShCount; ++i) {
            double s = 0.0;
            for (int k = 0; k < kShCount; ++k)
                s += m[static_cast<std::size_t>(i * kShCount + k)] * c[static_cast<std::size_t>(k)];
            CHECK(s == doctest::Approx(r[static_cast<std::size_t>(i)]).epsilon(1e-12));
        }
        // f_rot(theta, phi) == f(theta, phi - angle) at random directions
        for (int n = 0; n < 20; ++n) {
            const double z = u(rng), phi = 3.0 * u(rng);
            const double s = std::sqrt(1.0 - z * z);
            double y1[kShCount], y0[kShCount];
            shEvaluate(s * std::cos(phi), s * std::sin(phi), z, y1);
            shEvaluate(s * std::cos(phi - angle), s * std::sin(phi - angle), z, y0);
            double f1 = 0.0, f0 = 0.0;
            for (int i = 0; i < kShCount; ++i) {
                f1 += r[static_cast<std::size_t>(i)] * y1[i];
                f0 += c[static_cast<std::size_t>(i)] * y0[i];
            }
            CHECK(f1 == doctest::Approx(f0).epsilon(1e-12));
        }
    }
}

TEST_CASE("gi.sh: zonal rotation matches the projection of the rotated lobe") {
    // Clamped cosine about an arbitrary axis, projected by dense quadrature.
    const double ax = 0.48, ay = -0.6, az = std::sqrt(1.0 - 0.48 * 0.48 - 0.36);
    double rotated[kShCount];
    shRotateZonal(lambertZonal(), ax, ay, az, rotated);
    double norm = 0.0;
    for (int i = 0; i < kShCount; ++i) {
        const double p = sphereIntegral(
            [&](double x, double y, double z) {
                double yv[kShCount];
                shEvaluate(x, y, z, yv);
                return std::max(0.0, x * ax + y * ay + z * az) * yv[i];
            },
            300, 600);
        CHECK(rotated[i] == doctest::Approx(p).epsilon(1e-4).scale(1.0));
        norm += rotated[i] * rotated[i];
    }
    // rotation preserves the per-band norms of a zonal vector
    double zonalNorm = 0.0;
    for (int l = 0; l < kShOrder; ++l) zonalNorm += lambertZonal()[l] * lambertZonal()[l];
    CHECK(norm == doctest::Approx(zonalNorm).epsilon(1e-12));
}

TEST_CASE("gi.sh: product matrix equals the projection of the product") {
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    ShVector a{}, b{};
    for (int i = 0; i < kShCount; ++i) {
        a[static_cast<std::size_t>(i)] = u(rng);
        b[static_cast<std::size_t>(i)] = u(rng);
    }
    const ShMatrix t = shProductMatrix(a);
    for (int i = 0; i < kShCount; ++i) {
        double fast = 0.0;
        for (int k = 0; k < kShCount; ++k)
            fast += t[static_cast<std::size_t>(i * kShCount + k)] * b[static_cast<std::size_t>(k)];
        const double slow = sphereIntegral(
            [&](double x, double y, double z) {
                double yv[kShCount];
                shEvaluate(x, y, z, yv);
                double fa = 0.0, fb = 0.0;
                for (int k = 0; k < kShCount; ++k) {
                    fa += a[static_cast<std::size_t>(k)] * yv[k];
                    fb += b[static_cast<std::size_t>(k)] * yv[k];
                }
                return fa * fb * yv[i];
            },
            200, 400);
        CHECK(fast == doctest::Approx(slow).epsilon(1e-4).scale(1.0));
    }
}

TEST_CASE("gi.nlp: basis is orthonormal on [-1, 1]") {
    const int n = 20000;
    double gram[kNlpCount][kNlpCount] = {};
    for (int q = 0; q < n; ++q) {
        const double z = -1.0 + 2.0 * (q + 0.5) / n;
        double p[kNlpCount];
        nlpEvaluate(z, p);
        for (int i = 0; i < kNlpCount; ++i)
            for (int j = 0; j < kNlpCount; ++j) gram[i][j] += p[i] * p[j] * 2.0 / n;
    }
    for (int i = 0; i < kNlpCount; ++i)
        for (int j = 0; j < kNlpCount; ++j)
            CHECK(gram[i][j] == doctest::Approx(i == j ? 1.0 : 0.0).epsilon(1e-6).scale(1.0));
    // and it is sqrt((2l+1)/2) P_l, not the misprinted vector of Section 4
    double p[kNlpCount];
    nlpEvaluate(0.3, p);
    CHECK(p[2] == doctest::Approx(std::sqrt(2.5) * 0.5 * (3 * 0.09 - 1)));
    CHECK(p[3] == doctest::Approx(std::sqrt(3.5) * 0.5 * (5 * 0.027 - 0.9)));
}

TEST_CASE("gi.nlp: closed-form occlusion vector (Eq. 10) matches quadrature") {
    double maxErr = 0.0;
    for (double sigmaDeg = -89.0; sigmaDeg <= 89.0; sigmaDeg += 7.0) {
        const double s = std::sin(sigmaDeg * kPi / 180.0);
        double closed[kNlpCount], quad[kNlpCount] = {}, vis[kNlpCount];
        nlpOcclusion(s, closed);
        const int n = 20000;
        for (int q = 0; q < n; ++q) {
            const double z = -1.0 + (s + 1.0) * (q + 0.5) / n;
            double p[kNlpCount];
            nlpEvaluate(z, p);
            for (int l = 0; l < kNlpCount; ++l) quad[l] += p[l] * (s + 1.0) / n;
        }
        nlpVisibleAbove(s, vis);
        for (int l = 0; l < kNlpCount; ++l) {
            maxErr = std::max(maxErr, std::abs(closed[l] - quad[l]));
            // Eq. 11: v = v^-(pi/2) - v^-(sigma)
            double full[kNlpCount];
            nlpOcclusion(1.0, full);
            CHECK(vis[l] == doctest::Approx(full[l] - closed[l]).epsilon(1e-12).scale(1.0));
        }
    }
    MESSAGE("max |closed form - quadrature| = " << maxErr);
    CHECK(maxErr < 1e-7);
    // float and slope forms
    float f[kNlpCount];
    nlpVisibleAbove(sinFromSlope(0.5f), f);
    double d[kNlpCount];
    nlpVisibleAbove(std::sin(std::atan(0.5)), d);
    for (int l = 0; l < kNlpCount; ++l) CHECK(f[l] == doctest::Approx(d[l]).epsilon(1e-6));
}

namespace {

// Brute-force SH projection of the azimuthally interpolated NLP function:
// dense midpoint rule in phi, dense midpoint in z, cartesian SH.
void bruteForceWedgeProjection(const FoldedWedgeOperator& op, AzimuthInterp interp, bool fullCircle,
                               const std::vector<double>& nlp, double out[kShCount]) {
    const int m = op.azimuths;
    const int wedges = fullCircle ? m : m - 1;
    const int taps = wedgeTaps(interp);
    const int first = interp == AzimuthInterp::Linear ? 0 : -1;
    const double dphi = fullCircle ? 2.0 * kPi / m : op.phi[1] - op.phi[0];
    const int nSub = 64, nTheta = 200;
    for (int i = 0; i < kShCount; ++i) out[i] = 0.0;
    for (int j = 0; j < wedges; ++j)
        for (int a = 0; a < nSub; ++a) {
            const double frac = (a + 0.5) / nSub;
            const double phi = op.phi[static_cast<std::size_t>(j)] + frac * dphi;
            double w[kNlpCount] = {};
            for (int k = 0; k < taps; ++k) {
                const int sample = ((j + first + k) % m + m) % m;
                for (int l = 0; l < kNlpCount; ++l)
                    w[l] += wedgeTapWeight(interp, k, frac) * nlp[static_cast<std::size_t>(sample * 4 + l)];
            }
            for (int b = 0; b < nTheta; ++b) {
                const double theta = kPi * (b + 0.5) / nTheta;
                const double z = std::cos(theta), s = std::sin(theta);
                double p[kNlpCount], y[kShCount];
                nlpEvaluate(z, p);
                shEvaluate(s * std::cos(phi), s * std::sin(phi), z, y);
                double f = 0.0;
                for (int l = 0; l < kNlpCount; ++l) f += w[l] * p[l];
                for (int i = 0; i < kShCount; ++i) out[i] += f * y[i] * s * (dphi / nSub) * (kPi / nTheta);
            }
        }
}

}  // namespace

TEST_CASE("gi.wedge: folded operators match brute-force integration of the interpolated function") {
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    struct Case {
        int m;
        AzimuthInterp interp;
        bool full;
    };
    for (const Case c : {Case{8, AzimuthInterp::Linear, true}, Case{8, AzimuthInterp::Bspline, true},
                         Case{5, AzimuthInterp::Bspline, true}, Case{3, AzimuthInterp::Linear, false}}) {
        const FoldedWedgeOperator op = c.full ? foldFullCircle(c.m, c.interp) : foldPartialRange(0.4, 1.3, c.m);
        std::vector<double> nlp(static_cast<std::size_t>(4 * c.m));
        for (double& v : nlp) v = u(rng);
        double fast[kShCount], slow[kShCount];
        applyFoldedDense(op, nlp.data(), fast);
        bruteForceWedgeProjection(op, c.interp, c.full, nlp, slow);
        double maxErr = 0.0;
        for (int i = 0; i < kShCount; ++i) maxErr = std::max(maxErr, std::abs(fast[i] - slow[i]));
        MESSAGE("m=" << c.m << std::string(c.interp == AzimuthInterp::Linear ? " linear" : " bspline")
                     << std::string(c.full ? " full" : " partial") << ": max |folded - brute force| = " << maxErr);
        CHECK(maxErr < 1e-4);
        // the sparse pattern reproduces the dense product
        double sparse[kShCount] = {};
        for (int j = 0; j < op.azimuths; ++j)
            for (int e = 0; e < op.patternSize(); ++e)
                sparse[op.patternRow[static_cast<std::size_t>(e)]] +=
                    op.values[static_cast<std::size_t>(j * op.patternSize() + e)] *
                    nlp[static_cast<std::size_t>(j * 4 + op.patternNlp[static_cast<std::size_t>(e)])];
        for (int i = 0; i < kShCount; ++i) CHECK(sparse[i] == doctest::Approx(fast[i]).epsilon(1e-5).scale(1.0));
    }
    // M_lin is 16 x 8; M_bspl is 16 x 16 (4 samples x 4 NLP coefficients, as
    // Appendix A's I_bspl reads; the "16 x 32" in the paper's text does not
    // match its own formula).
    CHECK(wedgeOperator(AzimuthInterp::Linear, 0.2).size() == 16u * 8u);
    CHECK(wedgeOperator(AzimuthInterp::Bspline, 0.2).size() == 16u * 16u);
}

TEST_CASE("gi.wedge: unoccluded upper hemisphere gives the hemisphere's SH projection") {
    // v = visible above the horizon at every azimuth: V must be the (order-4)
    // projection of the upper-hemisphere indicator: Y00 coefficient sqrt(pi),
    // Y10 coefficient sqrt(3 pi)/2, all m != 0 zero.
    for (AzimuthInterp interp : {AzimuthInterp::Linear, AzimuthInterp::Bspline}) {
        const FoldedWedgeOperator op = foldFullCircle(32, interp);
        std::vector<double> nlp(4 * 32);
        for (int j = 0; j < 32; ++j) nlpVisibleAbove(0.0, &nlp[static_cast<std::size_t>(j * 4)]);
        double v[kShCount];
        applyFoldedDense(op, nlp.data(), v);
        CHECK(v[0] == doctest::Approx(std::sqrt(kPi)).epsilon(1e-12));
        CHECK(v[2] == doctest::Approx(std::sqrt(3.0 * kPi) / 2.0).epsilon(1e-12));
        for (int i : {1, 3, 4, 5, 7, 8, 9, 10, 11, 13, 14, 15}) CHECK(std::abs(v[i]) < 1e-12);
    }
}
