// The Phong lobe quadrature (gi/phong_lobe_quadrature.h) shared by the lobe
// gather and the glossy reference: rings in t = cos^(S + 1), each ring's slab
// its share of the equally weighted directions, every other ring turned by
// half of its own azimuth step; the reference's uniform layout (n rings of
// 2n) and the gather's growing one (the i-th ring from the axis holds i k).
#include <cmath>
#include <vector>

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

const LobeLayout kLayouts[] = {LobeLayout::uniform(1),    LobeLayout::uniform(3),    LobeLayout::uniform(5),
                               LobeLayout::growing(1, 4), LobeLayout::growing(2, 5), LobeLayout::growing(3, 3),
                               LobeLayout::growing(4, 6)};

// The azimuth about R and the cosine from R of direction w.
double psiOf(const double w[3], const double t[3], const double b[3]) {
    const double psi = std::atan2(dot(w, b), dot(w, t));
    return psi < 0.0 ? psi + 2.0 * kPi : psi;
}

}  // namespace

TEST_CASE("gi.lobe_quadrature: the layouts count their directions ring by ring") {
    CHECK(LobeLayout::uniform(3).directions() == 18);
    CHECK(LobeLayout::growing(2, 5).directions() == 15);
    CHECK(LobeLayout::growing(3, 3).directions() == 18);
    for (const LobeLayout& layout : kLayouts) {
        int before = 0;
        for (int i = 0; i < layout.rings; ++i) {
            CHECK(layout.directionsBefore(i) == before);
            before += layout.ringDirections(i);
        }
        CHECK(layout.directions() == before);
    }
    // growing: the ring nearest R (the last) holds k, each ring outwards k more
    const LobeLayout g = LobeLayout::growing(4, 6);
    for (int i = 0; i < 4; ++i) CHECK(g.ringDirections(i) == (4 - i) * 6);
}

TEST_CASE("gi.lobe_quadrature: the cached directions are lobeDirection's, bit for bit") {
    double r[3], t[3], b[3];
    tiltedR(r);
    lobeFrame(r, t, b);
    LobeQuadrature q;
    for (const LobeLayout& layout : kLayouts)
        for (double S : {1.0, 8.0, 64.0, 300.0}) {
            q.set(S, layout);
            REQUIRE(q.directions() == layout.directions());
            for (int i = 0, d = 0; i < layout.rings; ++i)
                for (int j = 0; j < layout.ringDirections(i); ++j, ++d) {
                    double cached[3], direct[3];
                    q.direction(r, t, b, d, cached);
                    lobeDirection(r, t, b, S, layout, i, j, direct);
                    for (int k = 0; k < 3; ++k) CHECK(cached[k] == direct[k]);
                }
            CHECK(q.widestCos() <= 1.0);
        }
}

TEST_CASE("gi.lobe_quadrature: rings sit at their slab's midpoint in t, odd rings turned by half a step") {
    double r[3], t[3], b[3];
    tiltedR(r);
    lobeFrame(r, t, b);
    const double S = 16.0;
    for (const LobeLayout& layout : kLayouts) {
        const double N = layout.directions();
        for (int i = 0; i < layout.rings; ++i) {
            const int c = layout.ringDirections(i);
            const double slabMid = (layout.directionsBefore(i) + 0.5 * c) / N;
            for (int j = 0; j < c; ++j) {
                double w[3];
                lobeDirection(r, t, b, S, layout, i, j, w);
                CHECK(std::pow(dot(w, r), S + 1.0) == doctest::Approx(slabMid).epsilon(1e-9));
                const double expected = 2.0 * kPi * (j + 0.5 + 0.5 * (i % 2)) / c;
                CHECK(std::fabs(std::remainder(psiOf(w, t, b) - expected, 2.0 * kPi)) < 1e-12);
            }
        }
    }
    // the uniform layout is the reference's n rings x 2n azimuths
    const LobeLayout u = LobeLayout::uniform(3);
    for (int i = 0; i < 3; ++i) {
        CHECK(u.ringDirections(i) == 6);
        double w[3];
        lobeDirection(r, t, b, S, u, i, 0, w);
        CHECK(std::pow(dot(w, r), S + 1.0) == doctest::Approx((i + 0.5) / 3.0).epsilon(1e-9));
    }
}

namespace {

// Moments of the lobe by a quadrature layout: E[w . R], E[(w . R)^2],
// E[w . t + w . b], E[(w . t)^2], E[(w . b)^2] and E[|w|^2].
struct Moments {
    double cosine = 0.0, cos2 = 0.0, across = 0.0, alongT2 = 0.0, alongB2 = 0.0, unit = 0.0;
};

Moments lobeMoments(double S, const LobeLayout& layout) {
    double r[3], t[3], b[3];
    tiltedR(r);
    lobeFrame(r, t, b);
    Moments m;
    const double weight = 1.0 / layout.directions();
    for (int i = 0; i < layout.rings; ++i)
        for (int j = 0; j < layout.ringDirections(i); ++j) {
            double w[3];
            lobeDirection(r, t, b, S, layout, i, j, w);
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
    // on every ring of at least 3 directions, and each carries half of
    // E[1 - (w . R)^2]. The midpoint rule in t = (w . R)^(S + 1) converges
    // slowly at the lobe's rim, where w . R = t^(1 / (S + 1)) is steep: the
    // error must shrink with the rings, in both layouts.
    struct Pair {
        LobeLayout coarse, fine;
    };
    for (const Pair& p : {Pair{LobeLayout::uniform(16), LobeLayout::uniform(64)},
                          Pair{LobeLayout::growing(16, 3), LobeLayout::growing(64, 3)}})
        for (double S : {8.0, 64.0}) {
            const double cosine = (S + 1.0) / (S + 2.0), cos2 = (S + 1.0) / (S + 3.0), sin2 = 1.0 - cos2;
            const Moments coarse = lobeMoments(S, p.coarse), fine = lobeMoments(S, p.fine);
            MESSAGE("S = " << S << ", " << p.coarse.directions() << " / " << p.fine.directions()
                           << " directions: E[w.R] " << coarse.cosine << ", " << fine.cosine << ", exact " << cosine
                           << "; E[(w.R)^2] " << coarse.cos2 << ", " << fine.cos2 << ", exact " << cos2);
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

TEST_CASE("gi.lobe_quadrature: the gather's layout for narrow lobes and the lobe's spread") {
    // 2 rings of 5 and 10 (the gather's from S = 16 up): the midpoint rule in t with two slabs (1/3 and
    // 2/3 of the mass) places the outer ring at t = 1/3, the inner at 5/6, so
    // E[w . R] = (2/3) (1/3)^(1/(S+1)) + (1/3) (5/6)^(1/(S+1)). The rule
    // narrows the lobe: its spread 1 - E[w . R] is 17-20 % short of the
    // true 1 / (S + 2) at S = 8-64 (the rim, t < 1/3, is sampled at t =
    // 1/3), where the uniform layout's 3 rings of 6 are 8-11 % short.
    const LobeLayout g = LobeLayout::growing(2, 5);
    for (double S : {8.0, 32.0, 64.0}) {
        const Moments m = lobeMoments(S, g), u = lobeMoments(S, LobeLayout::uniform(3));
        const double e = 1.0 / (S + 1.0);
        const double expected = (2.0 / 3.0) * std::pow(1.0 / 3.0, e) + (1.0 / 3.0) * std::pow(5.0 / 6.0, e);
        CHECK(m.cosine == doctest::Approx(expected).epsilon(1e-12));
        CHECK(m.unit == doctest::Approx(1.0).epsilon(1e-12));
        CHECK(std::fabs(m.across) < 1e-12);
        CHECK(m.alongT2 == doctest::Approx(m.alongB2).epsilon(1e-9));
        const double spread = 1.0 / (S + 2.0);
        const double shortG = 1.0 - (1.0 - m.cosine) / spread, shortU = 1.0 - (1.0 - u.cosine) / spread;
        MESSAGE("S = " << S << ": spread short by " << shortG << " (2 rings of 5, 10), " << shortU
                       << " (3 rings of 6)");
        CHECK(shortG > 0.16);
        CHECK(shortG < 0.21);
        CHECK(shortU > 0.08);
        CHECK(shortU < 0.11);
    }
}
