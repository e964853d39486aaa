// The Phong lobe quadrature (gi/phong_lobe_quadrature.h) shared by the lobe
// gather and the glossy reference: n rings in t = cos^(S + 1), 2n azimuths
// about R, every other ring turned by half an azimuth step.
#include <cmath>

#include <doctest/doctest.h>

#include "gi/phong_lobe_quadrature.h"
#include "gi/sh.h"

using namespace terrain::gi;

namespace {

double dot(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// A unit vector away from every axis, so that lobeFrame's choice is not special.
void tiltedR(double r[3]) {
    r[0] = 0.3;
    r[1] = -0.5;
    r[2] = 0.8;
    const double len = std::sqrt(dot(r, r));
    for (int k = 0; k < 3; ++k) r[k] /= len;
}

}  // namespace

TEST_CASE("gi.lobe_quadrature: the cached directions are lobeDirection's, bit for bit") {
    double r[3], t[3], b[3];
    tiltedR(r);
    lobeFrame(r, t, b);
    LobeQuadrature q;
    for (int n : {1, 2, 3, 5})
        for (double S : {1.0, 8.0, 64.0, 300.0}) {
            q.set(S, n);
            for (int i = 0; i < n; ++i)
                for (int j = 0; j < 2 * n; ++j) {
                    double cached[3], direct[3];
                    q.direction(r, t, b, i, j, cached);
                    lobeDirection(r, t, b, S, n, i, j, direct);
                    for (int k = 0; k < 3; ++k) CHECK(cached[k] == direct[k]);
                }
        }
}

TEST_CASE("gi.lobe_quadrature: odd rings are turned by half an azimuth step about R") {
    double r[3], t[3], b[3];
    tiltedR(r);
    lobeFrame(r, t, b);
    const int n = 3;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < 2 * n; ++j) {
            double w[3];
            lobeDirection(r, t, b, 16.0, n, i, j, w);
            double psi = std::atan2(dot(w, b), dot(w, t));
            if (psi < 0.0) psi += 2.0 * kPi;
            const double expected = kPi * (j + 0.5 + 0.5 * (i % 2)) / n;
            CHECK(psi == doctest::Approx(expected).epsilon(1e-12));
        }
}

namespace {

// Moments of the lobe by the n-ring quadrature: E[w . R], E[(w . R)^2],
// E[w . t + w . b], E[(w . t)^2], E[(w . b)^2] and E[|w|^2].
struct Moments {
    double cosine = 0.0, cos2 = 0.0, across = 0.0, alongT2 = 0.0, alongB2 = 0.0, unit = 0.0;
};

Moments lobeMoments(double S, int n) {
    double r[3], t[3], b[3];
    tiltedR(r);
    lobeFrame(r, t, b);
    Moments m;
    const double weight = 1.0 / (2.0 * n * n);
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < 2 * n; ++j) {
            double w[3];
            lobeDirection(r, t, b, S, n, i, j, w);
            const double c = dot(w, r), ct = dot(w, t), cb = dot(w, b);
            m.unit += weight * dot(w, w);
            m.cosine += weight * c;
            m.cos2 += weight * c * c;
            m.across += weight * (ct + cb);
            m.alongT2 += weight * ct * ct;
            m.alongB2 += weight * cb * cb;
        }
    return m;
}

}  // namespace

TEST_CASE("gi.lobe_quadrature: integrates the normalised lobe's moments") {
    // Under f(w) = (S + 1) / (2 pi) (w . R)^S: E[w . R] = (S + 1) / (S + 2),
    // E[(w . R)^2] = (S + 1) / (S + 3); the components across R average to 0
    // on every ring, and each carries half of E[1 - (w . R)^2]. The midpoint
    // rule in t = (w . R)^(S + 1) converges slowly at the lobe's rim, where
    // w . R = t^(1 / (S + 1)) is steep: the error must shrink with the rings.
    for (double S : {8.0, 64.0}) {
        const double cosine = (S + 1.0) / (S + 2.0), cos2 = (S + 1.0) / (S + 3.0), sin2 = 1.0 - cos2;
        const Moments coarse = lobeMoments(S, 16), fine = lobeMoments(S, 64);
        MESSAGE("S = " << S << ": E[w.R] " << coarse.cosine << " (16 rings), " << fine.cosine << " (64), exact "
                       << cosine << "; E[(w.R)^2] " << coarse.cos2 << ", " << fine.cos2 << ", exact " << cos2);
        for (const Moments& m : {coarse, fine}) {
            CHECK(m.unit == doctest::Approx(1.0).epsilon(1e-12));
            CHECK(std::fabs(m.across) < 1e-12);
            CHECK(m.alongT2 == doctest::Approx(m.alongB2).epsilon(1e-9));
            CHECK(m.alongT2 + m.alongB2 == doctest::Approx(1.0 - m.cos2).epsilon(1e-9));
        }
        CHECK(coarse.cosine == doctest::Approx(cosine).epsilon(5e-3));
        CHECK(coarse.cos2 == doctest::Approx(cos2).epsilon(5e-3));
        CHECK(std::fabs(fine.cosine - cosine) < std::fabs(coarse.cosine - cosine) / 3.0);
        CHECK(std::fabs(fine.cos2 - cos2) < std::fabs(coarse.cos2 - cos2) / 3.0);
        CHECK(fine.alongT2 == doctest::Approx(0.5 * sin2).epsilon(0.01));
    }
}
