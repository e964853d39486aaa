// The glossy ground truth (gi/reference_gi.h, renderReferenceGlossy): exact
// visibility and first hits, the fast path's BRDFs; the Phong lobes of the
// direct light and of the first bounce integrated by quadrature against the
// exact incident radiance (gi/reference_glossy_lobe.h).
// Sections: Nowrouzezahrai & Snyder 2009.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <vector>

#include "core/error.h"
#include "core/parallel.h"
#include "gi/frame.h"
#include "gi/reference_gi.h"
#include "gi/reference_glossy_lobe.h"

namespace terrain::gi {

namespace {

// PP_ij(lo) = int_lo^{pi/2} A_i(sin w) A_j(sin w) cos w dw over lo in
// [-pi/2, pi/2] (A_i the z part of Y_i, gi/sh.h): the elevation integral of a
// product of two harmonics over the visible part of an azimuth. Tabulated
// once (8-point Gauss-Legendre per interval), interpolated linearly between
// the kN + 1 tabulated angles.
struct PairTables {
    static constexpr int kN = 2048;
    std::vector<double> t;  // (kN + 1) x 256
    PairTables() : t(static_cast<std::size_t>(kN + 1) * kShCount * kShCount) {
        double x[8], w[8];
        gaussLegendre(8, x, w);
        const double h = kPi / kN;
        std::vector<double> acc(kShCount * kShCount, 0.0);
        for (int k = kN; k >= 0; --k) {
            if (k < kN) {
                const double a = -0.5 * kPi + k * h;
                for (int g = 0; g < 8; ++g) {
                    const double om = a + 0.5 * h + 0.5 * h * x[g];
                    const double wt = 0.5 * h * w[g] * std::cos(om), sw = std::sin(om);
                    double A[kShCount];
                    for (int i = 0; i < kShCount; ++i) A[i] = shAssociated(i, sw);
                    for (int i = 0; i < kShCount; ++i)
                        for (int j = 0; j < kShCount; ++j)
                            acc[static_cast<std::size_t>(i * kShCount + j)] += wt * A[i] * A[j];
                }
            }
            std::copy(acc.begin(), acc.end(), t.begin() + static_cast<std::ptrdiff_t>(k) * kShCount * kShCount);
        }
    }
    // out[i * 16 + j] = PP_ij(lo)
    void lookup(double lo, double* out) const {
        const double u = std::clamp((lo + 0.5 * kPi) / (kPi / kN), 0.0, static_cast<double>(kN));
        const int k = std::min(static_cast<int>(u), kN - 1);
        const double f = u - k;
        const double* a = &t[static_cast<std::size_t>(k) * kShCount * kShCount];
        const double* b = a + kShCount * kShCount;
        for (int i = 0; i < kShCount * kShCount; ++i) out[i] = (1.0 - f) * a[i] + f * b[i];
    }
};

const PairTables& pairTables() {
    static const PairTables t;
    return t;
}

// Bilinear sample of plane p at (px, py) cells (clamped to the grid).
struct Bilinear {
    std::size_t i00, i10, i01, i11;
    float fx, fy;
    Bilinear(int nx, int ny, float px, float py) {
        int x0 = std::clamp(static_cast<int>(px), 0, std::max(nx - 2, 0));
        int y0 = std::clamp(static_cast<int>(py), 0, std::max(ny - 2, 0));
        const int x1 = std::min(x0 + 1, nx - 1), y1 = std::min(y0 + 1, ny - 1);
        fx = std::clamp(px - static_cast<float>(x0), 0.0f, 1.0f);
        fy = std::clamp(py - static_cast<float>(y0), 0.0f, 1.0f);
        i00 = static_cast<std::size_t>(y0) * nx + x0;
        i10 = static_cast<std::size_t>(y0) * nx + x1;
        i01 = static_cast<std::size_t>(y1) * nx + x0;
        i11 = static_cast<std::size_t>(y1) * nx + x1;
    }
    float operator()(const float* v) const {
        const float a = v[i00] + fx * (v[i10] - v[i00]);
        const float b = v[i01] + fx * (v[i11] - v[i01]);
        return a + fy * (b - a);
    }
};

// Order-4 SH basis at a unit direction (double, gi/sh.h conventions).
inline void basis(double x, double y, double z, double* o) { shEvaluate(x, y, z, o); }

// The Phong part towards w of a texel with lobe factors ph and incident SH I
// (one channel, planes `stride` apart): sum_lm ph_l I_lm Y_lm(R_N(w)), yR = Y(R_N(w)) (Section 7).
inline double phongTowards(const double ph[kShOrder], const double* yR, const float* I, std::size_t stride) {
    double s = 0.0;
    for (int i = 0; i < kShCount; ++i) s += ph[shBand(i)] * yR[i] * I[static_cast<std::size_t>(i) * stride];
    return s;
}

void reflect(const double n[3], const double w[3], double r[3]) {
    const double d = 2.0 * (n[0] * w[0] + n[1] * w[1] + n[2] * w[2]);
    for (int a = 0; a < 3; ++a) r[a] = d * n[a] - w[a];
}

// The surface as the glossy reference reads it at a texel: normal from the
// gradients, albedo and Phong lobe factors (uniform where the maps are empty).
struct GlossySurface {
    const Grid& gx;
    const Grid& gy;
    const AlbedoMap* surface;
    double phUniform[kShOrder];
    bool lobeMap, expMap;
    double uniformExponent;
    GlossySurface(const Grid& gradX, const Grid& gradY, const AlbedoMap* map, const ShadingSettings& sh)
        : gx(gradX),
          gy(gradY),
          surface(map),
          lobeMap(map && !map->phongLobe[0].empty()),
          expMap(map && !map->phongExponent.empty()),
          uniformExponent(sh.phongExponent) {
        float f[kShOrder];
        phongLobeFactors(sh.phongExponent, f);
        for (int l = 0; l < kShOrder; ++l) phUniform[l] = f[l];
    }
    float albedoAt(int c, std::size_t i) const {
        const std::size_t ch = static_cast<std::size_t>(c);
        return surface && !surface->channel[ch].empty() ? surface->channel[ch].v[i] : 1.0f;
    }
    void lobeAt(std::size_t i, double ph[kShOrder]) const {
        for (int l = 0; l < kShOrder; ++l)
            ph[l] = l > 0 && lobeMap ? surface->phongLobe[static_cast<std::size_t>(l - 1)].v[i] : phUniform[l];
    }
    // the lobe factors at a bilinear sample (a first hit)
    void lobeAt(const Bilinear& bl, double ph[kShOrder]) const {
        for (int l = 0; l < kShOrder; ++l)
            ph[l] = l > 0 && lobeMap ? bl(surface->phongLobe[static_cast<std::size_t>(l - 1)].data()) : phUniform[l];
    }
    // the exponent S (the map's, bilinear at a first hit, or the uniform one)
    double exponentAt(std::size_t i) const { return expMap ? surface->phongExponent.v[i] : uniformExponent; }
    double exponentAt(const Bilinear& bl) const { return expMap ? bl(surface->phongExponent.data()) : uniformExponent; }
    void normalAt(std::size_t i, double n[3]) const {
        const double ddx = gx.v[i], ddy = gy.v[i];
        const double inv = 1.0 / std::sqrt(1.0 + ddx * ddx + ddy * ddy);
        n[0] = -ddx * inv;
        n[1] = -ddy * inv;
        n[2] = inv;
    }
};

// Bounce 0 at every texel: the exact Lambert part and the exact-cap key
// lights (D_0); with `withIncident` also the exact SH incident radiance (I_0,
// read by the SH-projected bounces after the first); out.ambient from the
// direct reference, out.direct / indirect sized (indirect zeroed).
void directBounce(ConstGridView heights, float cellSize, const ShRgb& lighting, const AlbedoMap* surface,
                  const ReferenceGiSettings& s, double wd, bool withIncident, ReferenceGiResult& out,
                  std::array<Grid, 3>& prevD, std::vector<float>& prevI) {
    const int nx = heights.nx, ny = heights.ny;
    const std::size_t plane = static_cast<std::size_t>(nx) * ny;
    ReferenceResult d;
    renderDirectReference(heights, cellSize, lighting, surface, s, d);
    out.ambient = d.ambient;
    std::array<Grid, 3> keys;
    for (Grid& g : keys) g.resize(nx, ny, 0.0f);
    for (const KeyLight& k : s.keys) addReferenceKeyLight(heights, cellSize, k, surface, s.keyAzimuths, keys);
    if (withIncident) referenceIncidentSh(heights, cellSize, lighting, s.azimuths, prevI);
    for (int c = 0; c < 3; ++c) {
        prevD[c].resize(nx, ny);
        out.direct[c].resize(nx, ny);
        out.indirect[c].resize(nx, ny, 0.0f);
        for (std::size_t i = 0; i < plane; ++i) prevD[c].v[i] = static_cast<float>(wd * d.rgb[c].v[i] + keys[c].v[i]);
    }
}

// Exit radiance towards the viewer of (D, I) at every texel, written to dst
// (add: added to it): the SH-projected bounces after the first.
void towardsViewer(const GlossySurface& surf, const double view[3], double ws, const std::array<Grid, 3>& D,
                   const std::vector<float>& I, std::array<Grid, 3>& dst, bool add) {
    const int nx = surf.gx.nx, ny = surf.gx.ny;
    const std::size_t plane = static_cast<std::size_t>(nx) * ny;
    parallelFor(0, ny, 1, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y)
            for (int x = 0; x < nx; ++x) {
                const std::size_t i = static_cast<std::size_t>(y) * nx + x;
                double n[3], r[3], ph[kShOrder], yR[kShCount];
                surf.normalAt(i, n);
                reflect(n, view, r);
                basis(r[0], r[1], r[2], yR);
                surf.lobeAt(i, ph);
                for (int c = 0; c < 3; ++c) {
                    const float* Ic = I.data() + static_cast<std::size_t>(c * kShCount) * plane + i;
                    const double v = D[c].v[i] + ws * phongTowards(ph, yR, Ic, plane);
                    dst[c].v[i] = static_cast<float>(add ? dst[c].v[i] + v : v);
                }
            }
    });
}

// Bounce 0 towards the viewer, exact: D_0 + w_s (the Phong lobe about the
// viewer's reflection against the exact sky, gi/reference_glossy_lobe.h).
void directTowardsViewer(const GlossySurface& surf, const SkyHorizons& hz, const ShRgb& lighting, const double view[3],
                         double ws, const LobeLayout& lobe, const std::array<Grid, 3>& D, std::array<Grid, 3>& dst) {
    const int nx = surf.gx.nx, ny = surf.gx.ny;
    parallelFor(0, ny, 1, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y)
            for (int x = 0; x < nx; ++x) {
                const std::size_t i = static_cast<std::size_t>(y) * nx + x;
                double n[3], r[3], e[3] = {0.0, 0.0, 0.0};
                surf.normalAt(i, n);
                reflect(n, view, r);
                if (ws != 0.0)
                    exactLobeRadiance(hz, lighting, static_cast<float>(x), static_cast<float>(y), n, r,
                                      surf.exponentAt(i), lobe, e);
                for (int c = 0; c < 3; ++c) dst[c].v[i] = static_cast<float>(D[c].v[i] + ws * e[c]);
            }
    });
}

// What one gathering bounce reads: the surface, the height field for the
// first hits, the fixed directions and their SH basis, weights, and the exact
// sky (horizons, lighting, lobe quadrature) of the first bounce.
struct GlossyGather {
    const GlossySurface& surf;
    const Grid& heights;
    float hMax;
    float cellSize;
    const ReferenceGiSettings& s;
    const std::vector<std::array<float, 3>>& dirs;
    const std::vector<double>& dirBasis;  // Y(dirs[k]), kShCount each
    double weight;                        // 4 pi / directions
    double ws, wd;                        // specular and diffuse weights
    const SkyHorizons& horizons;
    const ShRgb& lighting;
};

// Radiance L[c] leaving the first hit (qx, qy) towards the texel (direction
// -dir) under the previous bounce: D bilinear at the hit plus the Phong part,
// against the exact sky for the first bounce (prevI null), else from the
// previous bounce's SH incident radiance prevI.
void radianceFromHit(const GlossyGather& g, float qx, float qy, const double dir[3], const std::array<Grid, 3>& prevD,
                     const std::vector<float>* prevI, double L[3]) {
    const std::size_t plane = static_cast<std::size_t>(g.heights.nx) * g.heights.ny;
    const Bilinear bl(g.heights.nx, g.heights.ny, qx, qy);
    // q's normal, lobe and radiance towards p (direction -w)
    const double ddx = bl(g.surf.gx.data()), ddy = bl(g.surf.gy.data());
    const double inv = 1.0 / std::sqrt(1.0 + ddx * ddx + ddy * ddy);
    const double nq[3] = {-ddx * inv, -ddy * inv, inv};
    const double back[3] = {-dir[0], -dir[1], -dir[2]};
    double r[3];
    reflect(nq, back, r);
    for (int c = 0; c < 3; ++c) L[c] = bl(prevD[c].data());
    if (g.ws == 0.0) return;
    if (!prevI && g.s.membersWindowed) {
        double yR[kShCount], ph[kShOrder];
        basis(r[0], r[1], r[2], yR);
        g.surf.lobeAt(bl, ph);
        const double eR = std::asin(std::clamp(r[2], -1.0, 1.0));
        const double eH = std::atan(g.horizons.at(qx, qy, std::atan2(r[1], r[0])));
        const double open = 0.5 * std::erfc((eH - eR) * std::sqrt(0.5 * (g.surf.exponentAt(bl) + 1.0)));
        for (std::size_t c = 0; c < 3; ++c) {
            double sp = 0.0;
            for (int j = 0; j < kShCount; ++j)
                sp += ph[shBand(j)] * yR[j] * g.lighting.c[c][static_cast<std::size_t>(j)];
            L[c] += g.ws * open * sp;
        }
        return;
    }
    if (!prevI) {
        double e[3];
        exactLobeRadiance(g.horizons, g.lighting, qx, qy, nq, r, g.surf.exponentAt(bl), g.s.lobe, e);
        for (int c = 0; c < 3; ++c) L[c] += g.ws * e[c];
        return;
    }
    double yR[kShCount], ph[kShOrder];
    basis(r[0], r[1], r[2], yR);
    g.surf.lobeAt(bl, ph);
    for (int c = 0; c < 3; ++c) {
        double sp = 0.0;
        for (int j = 0; j < kShCount; ++j)
            sp += ph[shBand(j)] * yR[j] * bl(prevI->data() + static_cast<std::size_t>(c * kShCount + j) * plane);
        L[c] += g.ws * sp;
    }
}

// One gathering bounce at texel (x, y) over the fixed directions: the
// previous bounce's radiance from the first hits integrated against the
// cosine (the Lambert part, nextD) and, when nextI is given, projected to SH
// (the incident radiance the next bounce reads).
void gatherTexel(const GlossyGather& g, const std::array<Grid, 3>& prevD, const std::vector<float>* prevI, int x, int y,
                 std::array<Grid, 3>& nextD, std::vector<float>* nextI) {
    const int nx = g.heights.nx, ny = g.heights.ny;
    const std::size_t plane = static_cast<std::size_t>(nx) * ny;
    const std::size_t i = static_cast<std::size_t>(y) * nx + x;
    double n[3];
    g.surf.normalAt(i, n);
    double I[3][kShCount] = {}, E[3] = {};
    for (std::size_t k = 0; k < g.dirs.size(); ++k) {
        const auto& dir = g.dirs[k];
        const double cosine = n[0] * dir[0] + n[1] * dir[1] + n[2] * dir[2];
        if (cosine <= 0.0) continue;
        float qx, qy;
        if (!referenceFirstHit(g.heights.data(), nx, ny, g.hMax, g.cellSize, x, y, dir, g.s.marchStep, qx, qy))
            continue;
        const double d[3] = {dir[0], dir[1], dir[2]};
        double L[3];
        radianceFromHit(g, qx, qy, d, prevD, prevI, L);
        const double* yw = &g.dirBasis[k * kShCount];
        for (int c = 0; c < 3; ++c) {
            for (int j = 0; j < kShCount && nextI; ++j) I[c][j] += L[c] * yw[j];
            E[c] += L[c] * cosine;
        }
    }
    for (int c = 0; c < 3; ++c) {
        for (int j = 0; j < kShCount && nextI; ++j)
            (*nextI)[static_cast<std::size_t>(c * kShCount + j) * plane + i] = static_cast<float>(g.weight * I[c][j]);
        nextD[c].v[i] = static_cast<float>(g.wd * g.surf.albedoAt(c, i) / kPi * g.weight * E[c]);
    }
}

// The radiance arriving at texel (x, y) from direction w (the first hit's,
// 0 for a ray below the tangent plane or one that escapes to the sky), added
// to acc times `weight`.
void addRayRadiance(const GlossyGather& g, const std::array<Grid, 3>& prevD, const std::vector<float>* prevI,
                    const double nrm[3], const double w[3], int x, int y, double weight, double acc[3]) {
    if (nrm[0] * w[0] + nrm[1] * w[1] + nrm[2] * w[2] <= 0.0) return;
    const std::array<float, 3> dir = {static_cast<float>(w[0]), static_cast<float>(w[1]), static_cast<float>(w[2])};
    float qx, qy;
    if (!referenceFirstHit(g.heights.data(), g.heights.nx, g.heights.ny, g.hMax, g.cellSize, x, y, dir, g.s.marchStep,
                           qx, qy))
        return;
    double L[3];
    radianceFromHit(g, qx, qy, w, prevD, prevI, L);
    for (int c = 0; c < 3; ++c) acc[c] += weight * L[c];
}

// The lobe ray w seen along m azimuths only (ReferenceGiSettings::
// receiverAzimuths): the rays at w's elevation along the two azimuths
// phi_j = 2 pi j / m on either side of w's, weighted linearly.
void addAzimuthSnappedRadiance(const GlossyGather& g, const std::array<Grid, 3>& prevD, const std::vector<float>* prevI,
                               const double nrm[3], const double w[3], int x, int y, double acc[3]) {
    const int m = g.s.receiverAzimuths;
    const double dphi = 2.0 * kPi / m;
    double phi = std::atan2(w[1], w[0]);
    if (phi < 0.0) phi += 2.0 * kPi;
    const double u = phi / dphi;
    const int j0 = std::min(static_cast<int>(u), m - 1);
    const double f = u - j0;
    const double horizontal = std::sqrt(w[0] * w[0] + w[1] * w[1]);
    for (int k = 0; k < 2; ++k) {
        const double phiJ = dphi * ((j0 + k) % m);
        const double wj[3] = {horizontal * std::cos(phiJ), horizontal * std::sin(phiJ), w[2]};
        addRayRadiance(g, prevD, prevI, nrm, wj, x, y, k == 0 ? 1.0 - f : f, acc);
    }
}

// The first bounce's Phong part towards the viewer at texel (x, y), exact:
// the texel's lobe about the viewer's reflection sampled by the lobe
// quadrature (gi/reference_glossy_lobe.h), each ray's first hit sending its
// exact exit radiance (prevI null; else from I_0 in SH, the membersSh
// diagnostic); rays below the tangent plane carry nothing, rays that escape
// see the sky (direct light, bounce 0). With receiverAzimuths, each ray as the
// scan's azimuths see it (addAzimuthSnappedRadiance).
void firstBouncePhong(const GlossyGather& g, const std::array<Grid, 3>& prevD, const std::vector<float>* prevI,
                      const double view[3], int x, int y, double out[3]) {
    const int nx = g.heights.nx;
    const LobeLayout& layout = g.s.lobe;
    const std::size_t i = static_cast<std::size_t>(y) * nx + x;
    double nrm[3], r[3], t[3], b[3], acc[3] = {0.0, 0.0, 0.0};
    g.surf.normalAt(i, nrm);
    reflect(nrm, view, r);
    lobeFrame(r, t, b);
    const double S = g.surf.exponentAt(i);
    for (int a = 0; a < layout.rings; ++a)
        for (int j = 0; j < layout.ringDirections(a); ++j) {
            double w[3];
            lobeDirection(r, t, b, S, layout, a, j, w);
            if (g.s.receiverAzimuths > 0)
                addAzimuthSnappedRadiance(g, prevD, prevI, nrm, w, x, y, acc);
            else
                addRayRadiance(g, prevD, prevI, nrm, w, x, y, 1.0, acc);
        }
    for (int c = 0; c < 3; ++c) out[c] = g.ws * acc[c] / layout.directions();
}

}  // namespace

void referenceIncidentSh(ConstGridView heights, float cellSize, const ShRgb& lighting, int azimuths,
                         std::vector<float>& out) {
    const int nx = heights.nx, ny = heights.ny, M = std::max(azimuths, 1);
    const std::size_t plane = static_cast<std::size_t>(nx) * ny;
    out.assign(plane * 3 * kShCount, 0.0f);
    Grid gx, gy;
    computeGradient(heights, cellSize, gx, gy);
    double heightMax = -1e300;
    for (int y = 0; y < ny; ++y)
        for (int x = 0; x < nx; ++x) heightMax = std::max(heightMax, static_cast<double>(heights(x, y)));
    // lambda_cj(a) = T_j(phi_a) L_cj, only the j with some non-zero L_cj
    std::vector<int> js;
    for (int j = 0; j < kShCount; ++j)
        for (int c = 0; c < 3; ++c)
            if (lighting.c[static_cast<std::size_t>(c)][static_cast<std::size_t>(j)] != 0.0) {
                js.push_back(j);
                break;
            }
    const int nj = static_cast<int>(js.size());
    std::vector<double> lam(static_cast<std::size_t>(M) * 3 * kShCount), Ti(static_cast<std::size_t>(M) * kShCount);
    std::vector<double> cs(static_cast<std::size_t>(M)), sn(static_cast<std::size_t>(M));
    for (int a = 0; a < M; ++a) {
        const double phi = 2.0 * kPi * (a + 0.5) / M;
        cs[static_cast<std::size_t>(a)] = std::cos(phi);
        sn[static_cast<std::size_t>(a)] = std::sin(phi);
        for (int i = 0; i < kShCount; ++i) Ti[static_cast<std::size_t>(a * kShCount + i)] = shAzimuthal(i, phi);
        for (int c = 0; c < 3; ++c)
            for (int q = 0; q < nj; ++q)
                lam[(static_cast<std::size_t>(a) * 3 + c) * kShCount + q] =
                    shAzimuthal(js[static_cast<std::size_t>(q)], phi) *
                    lighting.c[static_cast<std::size_t>(c)][static_cast<std::size_t>(js[static_cast<std::size_t>(q)])];
    }
    const PairTables& tables = pairTables();
    const double dphi = 2.0 * kPi / M;
    parallelFor(0, ny, 1, [&](int y0, int y1) {
        std::vector<double> pp(kShCount * kShCount);
        for (int y = y0; y < y1; ++y)
            for (int x = 0; x < nx; ++x) {
                double I[3][kShCount] = {};
                for (int a = 0; a < M; ++a) {
                    const double c = cs[static_cast<std::size_t>(a)], s = sn[static_cast<std::size_t>(a)];
                    const double slope = referenceMaxSlope(heights, cellSize, x, y, c, s, heightMax);
                    const double lo = std::atan(std::max(slope, static_cast<double>(gx(x, y)) * c + gy(x, y) * s));
                    tables.lookup(lo, pp.data());
                    const double* la = &lam[static_cast<std::size_t>(a) * 3 * kShCount];
                    for (int i = 0; i < kShCount; ++i) {
                        const double ti = Ti[static_cast<std::size_t>(a * kShCount + i)] * dphi;
                        for (int ch = 0; ch < 3; ++ch) {
                            double acc = 0.0;
                            for (int q = 0; q < nj; ++q)
                                acc += pp[static_cast<std::size_t>(i * kShCount + js[static_cast<std::size_t>(q)])] *
                                       la[ch * kShCount + q];
                            I[ch][i] += ti * acc;
                        }
                    }
                }
                for (int ch = 0; ch < 3; ++ch)
                    for (int i = 0; i < kShCount; ++i)
                        out[static_cast<std::size_t>(ch * kShCount + i) * plane + static_cast<std::size_t>(y) * nx +
                            x] = static_cast<float>(I[ch][i]);
            }
    });
}

void renderReferenceGlossy(ConstGridView heights, float cellSize, const ShRgb& lighting, const AlbedoMap* surface,
                           const ReferenceGiSettings& s, ReferenceGiResult& out) {
    const int nx = heights.nx, ny = heights.ny;
    const std::size_t plane = static_cast<std::size_t>(nx) * ny;
    const ShadingSettings& sh = s.shading;
    const double ws = specularWeightOf(sh);
    const double wd = sh.brdf == Brdf::Phong ? 0.0 : 1.0;
    const double view[3] = {sh.viewDir[0], sh.viewDir[1], sh.viewDir[2]};
    if (s.lobe.rings < 1 || s.lobe.innermost < 1 || s.lobe.growth < 0)
        throw InputError("glossy reference: the lobe quadrature needs a ring and a direction on each");
    if (s.receiverAzimuths < 0) throw InputError("glossy reference: receiverAzimuths must not be negative");
    Grid gx, gy;
    computeGradient(heights, cellSize, gx, gy);
    const GlossySurface surf(gx, gy, surface, sh);
    SkyHorizons horizons;
    buildSkyHorizons(heights, cellSize, s.azimuths, horizons);

    // ---- bounce 0: exact Lambert part + exact-cap keys (D_0), exact Phong part
    // towards the viewer; I_0 (SH) only for the bounces after the first and
    // the membersSh diagnostic
    std::vector<float> prevI, nextI;
    std::array<Grid, 3> prevD, nextD;
    directBounce(heights, cellSize, lighting, surface, s, wd, s.bounces >= 2 || s.membersSh, out, prevD, prevI);
    for (int c = 0; c < 3; ++c) nextD[c].resize(nx, ny, 0.0f);
    directTowardsViewer(surf, horizons, lighting, view, ws, s.lobe, prevD, out.direct);

    // ---- bounce 1 exact; bounces 2..B gather (D, I) of the previous bounce in SH
    if (nx >= 2 && ny >= 2 && s.bounces > 0) {
        Grid hCopy(nx, ny);
        for (int y = 0; y < ny; ++y)
            for (int x = 0; x < nx; ++x) hCopy(x, y) = heights(x, y);
        const float hMax = *std::max_element(hCopy.v.begin(), hCopy.v.end());
        std::vector<std::array<float, 3>> dirs;
        referenceDirections(s.directions, dirs);
        std::vector<double> dirBasis(dirs.size() * kShCount);
        for (std::size_t k = 0; k < dirs.size(); ++k)
            basis(dirs[k][0], dirs[k][1], dirs[k][2], &dirBasis[k * kShCount]);
        const GlossyGather gather{surf, hCopy, hMax,     cellSize, s, dirs, dirBasis, 4.0 * kPi / s.directions,
                                  ws,   wd,    horizons, lighting};
        for (int b = 1; b <= s.bounces; ++b) {
            if (s.progress) std::printf("glossy reference: bounce %d of %d\n", b, s.bounces);
            // SH incident radiance: for the next bounce, and for towardsViewer after the first
            const bool exact = b == 1, needI = b < s.bounces || !exact || s.receiverSh;
            if (needI) nextI.assign(plane * 3 * kShCount, 0.0f);
            // the first hits' exit radiance: exact, or from I_0 in SH (membersSh)
            const std::vector<float>* hitsI = exact && !s.membersSh ? nullptr : &prevI;
            parallelFor(0, ny, 1, [&](int y0, int y1) {
                for (int y = y0; y < y1; ++y)
                    for (int x = 0; x < nx; ++x) {
                        if (wd != 0.0 || needI)
                            gatherTexel(gather, prevD, hitsI, x, y, nextD, needI ? &nextI : nullptr);
                        if (!exact || s.receiverSh) continue;
                        double phong[3] = {0.0, 0.0, 0.0};
                        if (ws != 0.0) firstBouncePhong(gather, prevD, hitsI, view, x, y, phong);
                        const std::size_t i = static_cast<std::size_t>(y) * nx + x;
                        for (int c = 0; c < 3; ++c)
                            out.indirect[c].v[i] += static_cast<float>(nextD[c].v[i] + phong[c]);
                    }
            });
            if (!exact || s.receiverSh) towardsViewer(surf, view, ws, nextD, nextI, out.indirect, true);
            std::swap(prevI, nextI);
            std::swap(prevD, nextD);
        }
    }
    for (int c = 0; c < 3; ++c) {
        out.total[c].resize(nx, ny);
        for (std::size_t i = 0; i < plane; ++i) out.total[c].v[i] = out.direct[c].v[i] + out.indirect[c].v[i];
    }
}

}  // namespace terrain::gi
