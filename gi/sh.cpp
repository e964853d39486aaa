#include "gi/sh.h"

#include <cmath>
#include <mutex>
#include <vector>

namespace terrain::gi {

namespace {

// Normalisation constants of the cartesian forms.
const double kY00 = 0.5 * std::sqrt(1.0 / kPi);
const double kY1 = std::sqrt(3.0 / (4.0 * kPi));
const double kY2a = 0.5 * std::sqrt(15.0 / kPi);   // xy, yz, xz
const double kY20 = 0.25 * std::sqrt(5.0 / kPi);   // 3z^2 - 1
const double kY22 = 0.25 * std::sqrt(15.0 / kPi);  // x^2 - y^2
const double kY33 = 0.25 * std::sqrt(35.0 / (2.0 * kPi));
const double kY32a = 0.5 * std::sqrt(105.0 / kPi);  // xyz
const double kY31 = 0.25 * std::sqrt(21.0 / (2.0 * kPi));
const double kY30 = 0.25 * std::sqrt(7.0 / kPi);
const double kY32b = 0.25 * std::sqrt(105.0 / kPi);  // z (x^2 - y^2)

template <class T>
void evaluateCartesian(T x, T y, T z, double* out) {
    const double X = x, Y = y, Z = z;
    out[0] = kY00;
    out[1] = kY1 * Y;
    out[2] = kY1 * Z;
    out[3] = kY1 * X;
    out[4] = kY2a * X * Y;
    out[5] = kY2a * Y * Z;
    out[6] = kY20 * (3.0 * Z * Z - 1.0);
    out[7] = kY2a * X * Z;
    out[8] = kY22 * (X * X - Y * Y);
    out[9] = kY33 * Y * (3.0 * X * X - Y * Y);
    out[10] = kY32a * X * Y * Z;
    out[11] = kY31 * Y * (5.0 * Z * Z - 1.0);
    out[12] = kY30 * (5.0 * Z * Z * Z - 3.0 * Z);
    out[13] = kY31 * X * (5.0 * Z * Z - 1.0);
    out[14] = kY32b * Z * (X * X - Y * Y);
    out[15] = kY33 * X * (X * X - 3.0 * Y * Y);
}

}  // namespace

void shEvaluate(double x, double y, double z, double out[kShCount]) { evaluateCartesian(x, y, z, out); }
void shEvaluate(float x, float y, float z, double out[kShCount]) { evaluateCartesian(x, y, z, out); }

double shAssociated(int i, double z) {
    // Y_i at phi = 0 (m >= 0) or at |m| phi = pi/2 (m < 0) share K_l|m| P_l^|m|:
    // evaluate the m >= 0 partner at phi = 0.
    const int l = shBand(i);
    const int m = std::abs(shOrderM(i));
    const double s = std::sqrt(std::max(0.0, 1.0 - z * z));
    double y[kShCount];
    evaluateCartesian(s, 0.0, z, y);
    return y[shIndex(l, m)];
}

double shAzimuthal(int i, double phi) {
    const int m = shOrderM(i);
    if (m > 0) return std::cos(m * phi);
    if (m < 0) return std::sin(-m * phi);
    return 1.0;
}

ShMatrix shRotationZ(double angle) {
    ShMatrix r{};
    for (int l = 0; l < kShOrder; ++l) {
        r[shIndex(l, 0) * kShCount + shIndex(l, 0)] = 1.0;
        for (int m = 1; m <= l; ++m) {
            const double c = std::cos(m * angle), s = std::sin(m * angle);
            const int ip = shIndex(l, m), in = shIndex(l, -m);
            // f(phi - a): cos(m(phi-a)) = cos cos + sin sin; sin(m(phi-a)) = sin cos - cos sin
            r[ip * kShCount + ip] = c;
            r[ip * kShCount + in] = -s;
            r[in * kShCount + ip] = s;
            r[in * kShCount + in] = c;
        }
    }
    return r;
}

void shRotateZ(double angle, ShVector& v) {
    for (int l = 1; l < kShOrder; ++l) {
        for (int m = 1; m <= l; ++m) {
            const double c = std::cos(m * angle), s = std::sin(m * angle);
            const int ip = shIndex(l, m), in = shIndex(l, -m);
            const double a = v[static_cast<std::size_t>(ip)], b = v[static_cast<std::size_t>(in)];
            v[static_cast<std::size_t>(ip)] = c * a - s * b;
            v[static_cast<std::size_t>(in)] = s * a + c * b;
        }
    }
}

void shRotateZonal(const double zh[kShOrder], double ax, double ay, double az, double out[kShCount]) {
    double y[kShCount];
    evaluateCartesian(ax, ay, az, y);
    for (int i = 0; i < kShCount; ++i) {
        const int l = shBand(i);
        out[i] = std::sqrt(4.0 * kPi / (2.0 * l + 1.0)) * zh[l] * y[i];
    }
}

const double* lambertZonal() {
    // Exact ZH projection of max(cos theta, 0): sqrt(pi)/2, sqrt(pi/3), sqrt(5 pi)/8, 0.
    static const double zh[kShOrder] = {std::sqrt(kPi) / 2.0, std::sqrt(kPi / 3.0), std::sqrt(5.0 * kPi) / 8.0, 0.0};
    return zh;
}

void phongZonal(double exponent, double zh[kShOrder]) {
    for (int l = 0; l < kShOrder; ++l)
        zh[l] = std::exp(-static_cast<double>(l * l) / (2.0 * exponent)) / std::sqrt(4.0 * kPi / (2.0 * l + 1.0));
}

namespace {

// P_n(x) by the three-term recurrence k P_k = (2k - 1) x P_{k-1} - (k - 1) P_{k-2},
// and its derivative P_n'(x) = n (x P_n - P_{n-1}) / (x^2 - 1).
struct LegendreAt {
    double p, dp;
};
LegendreAt legendreAt(int n, double x) {
    double p0 = 1.0, p1 = x;
    for (int k = 2; k <= n; ++k) {
        const double p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
    }
    return {p1, n * (x * p1 - p0) / (x * x - 1.0)};
}

}  // namespace

void gaussLegendre(int n, double* nodes, double* weights) {
    // Newton iteration on P_n from Chebyshev starting points.
    for (int i = 0; i < n; ++i) {
        double x = std::cos(kPi * (i + 0.75) / (n + 0.5));
        for (int it = 0; it < 100; ++it) {
            const LegendreAt l = legendreAt(n, x);
            const double dx = l.p / l.dp;
            x -= dx;
            if (std::abs(dx) < 1e-16) break;
        }
        const double dp = legendreAt(n, x).dp;
        nodes[i] = x;
        weights[i] = 2.0 / ((1.0 - x * x) * dp * dp);
    }
}

const double* shTripleProductTensor() {
    static std::vector<double> tensor;
    static std::once_flag once;
    std::call_once(once, [] {
        // Products of three band <= 3 harmonics are polynomials of degree <= 9
        // on the sphere: 16 Gauss-Legendre nodes in z and 32 uniform phi
        // samples integrate them exactly.
        const int nz = 16, nphi = 32;
        double zs[16], ws[16];
        gaussLegendre(nz, zs, ws);
        tensor.assign(static_cast<std::size_t>(kShCount) * kShCount * kShCount, 0.0);
        for (int a = 0; a < nz; ++a) {
            const double s = std::sqrt(std::max(0.0, 1.0 - zs[a] * zs[a]));
            for (int b = 0; b < nphi; ++b) {
                const double phi = 2.0 * kPi * b / nphi;
                const double w = ws[a] * 2.0 * kPi / nphi;
                double y[kShCount];
                evaluateCartesian(s * std::cos(phi), s * std::sin(phi), zs[a], y);
                for (int i = 0; i < kShCount; ++i)
                    for (int j = 0; j < kShCount; ++j)
                        for (int k = 0; k < kShCount; ++k)
                            tensor[static_cast<std::size_t>((i * kShCount + j) * kShCount + k)] +=
                                w * y[i] * y[j] * y[k];
            }
        }
        for (double& t : tensor)
            if (std::abs(t) < 1e-13) t = 0.0;
    });
    return tensor.data();
}

ShMatrix shProductMatrix(const ShVector& light) {
    const double* c = shTripleProductTensor();
    ShMatrix t{};
    for (int i = 0; i < kShCount; ++i)
        for (int k = 0; k < kShCount; ++k) {
            double s = 0.0;
            for (int j = 0; j < kShCount; ++j)
                s += c[(i * kShCount + j) * kShCount + k] * light[static_cast<std::size_t>(j)];
            t[static_cast<std::size_t>(i * kShCount + k)] = s;
        }
    return t;
}

}  // namespace terrain::gi
