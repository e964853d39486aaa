#include "gi/reference.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <limits>
#include <mutex>
#include <vector>

#include "core/error.h"
#include "core/parallel.h"
#include "gi/frame.h"
#include "gi/visibility.h"

namespace terrain::gi {

namespace {

inline double bilinear(ConstGridView h, double px, double py) {
    int x0 = static_cast<int>(std::floor(px)), y0 = static_cast<int>(std::floor(py));
    x0 = std::clamp(x0, 0, std::max(h.nx - 2, 0));
    y0 = std::clamp(y0, 0, std::max(h.ny - 2, 0));
    const int x1 = std::min(x0 + 1, h.nx - 1), y1 = std::min(y0 + 1, h.ny - 1);
    const double fx = std::clamp(px - x0, 0.0, 1.0), fy = std::clamp(py - y0, 0.0, 1.0);
    return (1.0 - fy) * ((1.0 - fx) * h(x0, y0) + fx * h(x1, y0)) + fy * ((1.0 - fx) * h(x0, y1) + fx * h(x1, y1));
}

// Tables of P_i(lo) = int_lo^{pi/2} A_i(sin w) cos^2 w dw and
// Q_i(lo) = int_lo^{pi/2} A_i(sin w) sin w cos w dw over lo in [-pi/2, pi/2].
struct ElevationTables {
    static constexpr int kN = 4096;
    std::vector<double> p, q;  // (kN + 1) x 16
    ElevationTables() : p(static_cast<std::size_t>(kN + 1) * kShCount), q(static_cast<std::size_t>(kN + 1) * kShCount) {
        double x[8], w[8];
        gaussLegendre(8, x, w);
        const double h = kPi / kN;
        double accP[kShCount] = {}, accQ[kShCount] = {};
        // integrate from the top (pi/2) downwards
        for (int k = kN; k >= 0; --k) {
            if (k < kN) {
                const double a = -0.5 * kPi + k * h, b = a + h;
                for (int g = 0; g < 8; ++g) {
                    const double om = 0.5 * (a + b) + 0.5 * h * x[g];
                    const double wt = 0.5 * h * w[g];
                    const double sw = std::sin(om), cw = std::cos(om);
                    for (int i = 0; i < kShCount; ++i) {
                        const double A = shAssociated(i, sw);
                        accP[i] += wt * A * cw * cw;
                        accQ[i] += wt * A * sw * cw;
                    }
                }
            }
            for (int i = 0; i < kShCount; ++i) {
                p[static_cast<std::size_t>(k * kShCount + i)] = accP[i];
                q[static_cast<std::size_t>(k * kShCount + i)] = accQ[i];
            }
        }
    }
    void lookup(double lo, double* P, double* Q) const {
        const double u = std::clamp((lo + 0.5 * kPi) / (kPi / kN), 0.0, static_cast<double>(kN));
        const int k = std::min(static_cast<int>(u), kN - 1);
        const double f = u - k;
        const double* p0 = &p[static_cast<std::size_t>(k * kShCount)];
        const double* q0 = &q[static_cast<std::size_t>(k * kShCount)];
        for (int i = 0; i < kShCount; ++i) {
            P[i] = (1.0 - f) * p0[i] + f * p0[i + kShCount];
            Q[i] = (1.0 - f) * q0[i] + f * q0[i + kShCount];
        }
    }
};

const ElevationTables& elevationTables() {
    static const ElevationTables t;
    return t;
}

// The M azimuths phi_a = 2 pi (a + 0.5) / M: cos, sin and T_i(phi_a).
struct ReferenceAzimuths {
    int M;
    std::vector<double> cosA, sinA;
    std::vector<std::array<double, kShCount>> azim;
    explicit ReferenceAzimuths(int count)
        : M(count),
          cosA(static_cast<std::size_t>(M)),
          sinA(static_cast<std::size_t>(M)),
          azim(static_cast<std::size_t>(M)) {
        for (int a = 0; a < M; ++a) {
            const double phi = 2.0 * kPi * (a + 0.5) / M;
            cosA[static_cast<std::size_t>(a)] = std::cos(phi);
            sinA[static_cast<std::size_t>(a)] = std::sin(phi);
            for (int i = 0; i < kShCount; ++i)
                azim[static_cast<std::size_t>(a)][static_cast<std::size_t>(i)] = shAzimuthal(i, phi);
        }
    }
};

// What every texel of renderReference reads and writes.
struct ReferenceTexels {
    ConstGridView heights;
    float cellSize;
    const Grid& gx;
    const Grid& gy;
    double heightMax;
    const ReferenceAzimuths& az;
    const ElevationTables* tables;  // SH lighting (null: none)
    const ShRgb* lighting;
    const SunSkySettings* gradient;  // the sky gradient's function (null: none)
    const AlbedoMap* albedo;
    double dphi;  // 2 pi / M
    ReferenceResult& out;
};

// Adds the integral over the visible elevations [lo, pi/2] of the sky
// gradient's radiance L(w) times (N . d) cos w, d = (cos w cos phi,
// cos w sin phi, sin w), N . d = nh cos w + nz sin w, per channel
// (antiderivatives in gi/reference.h, renderReferenceSkyGradient).
void addGradientElevationIntegral(const SunSkySettings& sky, double lo, double nh, double nz, double rgb[3]) {
    auto cos2 = [](double w) { return 0.5 * w + 0.25 * std::sin(2.0 * w); };
    auto sinCos = [](double w) { return 0.5 * std::sin(w) * std::sin(w); };
    auto cube = [](double v) { return v * v * v; };
    auto sinCos2 = [&](double w) { return -cube(std::cos(w)) / 3.0; };
    auto sin2Cos = [&](double w) { return cube(std::sin(w)) / 3.0; };
    const double top = 0.5 * kPi, a = std::max(lo, 0.0), b = std::min(lo, 0.0);
    // above the horizontal: horizon + (zenith - horizon) sin w; below: ground
    const double flat = nh * (cos2(top) - cos2(a)) + nz * (sinCos(top) - sinCos(a));
    const double rising = nh * (sinCos2(top) - sinCos2(a)) + nz * (sin2Cos(top) - sin2Cos(a));
    const double below = nh * (cos2(0.0) - cos2(b)) + nz * (sinCos(0.0) - sinCos(b));
    for (int ch = 0; ch < 3; ++ch)
        rgb[ch] += sky.horizon[ch] * flat + (sky.zenith[ch] - sky.horizon[ch]) * rising + sky.ground[ch] * below;
}

// The Lambert shade of texel (x, y) from its azimuth sums: albedo x sum x dphi / pi.
void writeReferenceShade(const ReferenceTexels& t, int x, int y, const double sum[3]) {
    for (int ch = 0; ch < 3; ++ch) {
        const float alb = t.albedo && !t.albedo->channel[static_cast<std::size_t>(ch)].empty()
                              ? t.albedo->channel[static_cast<std::size_t>(ch)](x, y)
                              : 1.0f;
        t.out.rgb[static_cast<std::size_t>(ch)](x, y) = static_cast<float>(alb * sum[ch] * t.dphi / kPi);
    }
}

// The ambient (and, with lighting, the Lambert shade) of texel (x, y): per
// azimuth the exact blocking slope, then the elevation integrals above
// lo = max(omega_max, tangent plane).
void shadeReferenceTexel(const ReferenceTexels& t, int x, int y) {
    const int M = t.az.M;
    const double gxv = t.gx(x, y), gyv = t.gy(x, y);
    const double inv = 1.0 / std::sqrt(1.0 + gxv * gxv + gyv * gyv);
    const double nxv = -gxv * inv, nyv = -gyv * inv, nzv = inv;
    double amb = 0.0;
    double transfer[kShCount] = {};
    double skyRgb[3] = {};
    for (int a = 0; a < M; ++a) {
        const double c = t.az.cosA[static_cast<std::size_t>(a)], s = t.az.sinA[static_cast<std::size_t>(a)];
        const double slope = referenceMaxSlope(t.heights, t.cellSize, x, y, c, s, t.heightMax);
        const double tangent = gxv * c + gyv * s;
        const double lo = std::atan(std::max(slope, tangent));
        const double horiz = nxv * c + nyv * s;
        const double sl = std::sin(lo), cl = std::cos(lo);
        amb += horiz * (0.5 * kPi - lo - sl * cl) * 0.5 + nzv * cl * cl * 0.5;
        if (t.gradient) addGradientElevationIntegral(*t.gradient, lo, horiz, nzv, skyRgb);
        if (t.tables) {
            double P[kShCount], Q[kShCount];
            t.tables->lookup(lo, P, Q);
            const auto& az = t.az.azim[static_cast<std::size_t>(a)];
            for (int i = 0; i < kShCount; ++i)
                transfer[i] += az[static_cast<std::size_t>(i)] * (horiz * P[i] + nzv * Q[i]);
        }
    }
    t.out.ambient(x, y) = static_cast<float>(amb * t.dphi / kPi);
    if (t.tables)
        for (int ch = 0; ch < 3; ++ch)
            for (int i = 0; i < kShCount; ++i)
                skyRgb[ch] += t.lighting->c[static_cast<std::size_t>(ch)][static_cast<std::size_t>(i)] * transfer[i];
    if (t.tables || t.gradient) writeReferenceShade(t, x, y, skyRgb);
}

// Prints "reference: N%" to stdout every 5 % of the rows.
class RowProgress {
public:
    explicit RowProgress(int rowsTotal) : rowsTotal_(rowsTotal) {}
    void rowDone() {
        const int done = ++rowsDone_;
        const int pct = static_cast<int>(100LL * done / std::max(rowsTotal_, 1));
        const int prevPct = static_cast<int>(100LL * (done - 1) / std::max(rowsTotal_, 1));
        if (pct / 5 != prevPct / 5) {
            std::lock_guard<std::mutex> lock(printMutex_);
            std::printf("reference: %d%%\n", pct);
        }
    }

private:
    int rowsTotal_;
    std::atomic<int> rowsDone_{0};
    std::mutex printMutex_;
};

}  // namespace

double referenceMaxSlope(ConstGridView h, float cellSize, int x, int y, double c, double s, double heightMax) {
    const double h0 = h(x, y);
    const double xmax = h.nx - 1, ymax = h.ny - 1;
    double best = kNoBlocker;
    const double ac = std::abs(c), as = std::abs(s);
    const double dtx = ac > 1e-12 ? 1.0 / ac : std::numeric_limits<double>::infinity();
    const double dty = as > 1e-12 ? 1.0 / as : std::numeric_limits<double>::infinity();
    double tx = dtx, ty = dty, tPrev = 0.0;
    const double invCell = 1.0 / cellSize;
    for (;;) {
        const double t = std::min(tx, ty);
        if (!std::isfinite(t)) break;
        // midpoint of the previous segment, then the crossing
        for (int k = 0; k < 2; ++k) {
            const double tt = k == 0 ? 0.5 * (tPrev + t) : t;
            const double px = x + tt * c, py = y + tt * s;
            if (px < -1e-9 || py < -1e-9 || px > xmax + 1e-9 || py > ymax + 1e-9) return best;
            if (tt < 1e-9) continue;
            const double slope = (bilinear(h, px, py) - h0) * invCell / tt;
            if (slope > best) best = slope;
        }
        // nothing farther can beat the current slope
        if (best > 0.0 && heightMax - h0 <= best * t * cellSize) return best;
        tPrev = t;
        if (tx <= ty)
            tx += dtx;
        else
            ty += dty;
        if (t > 4.0 * (xmax + ymax + 2.0)) break;
    }
    return best;
}

namespace {

// Every texel of the interior (settings' border and stride), rows in parallel.
void renderTexels(ConstGridView heights, float cellSize, const ShRgb* lighting, const SunSkySettings* gradient,
                  const AlbedoMap* albedo, const ReferenceSettings& rs, ReferenceResult& out) {
    const int nx = heights.nx, ny = heights.ny;
    const int M = std::max(rs.azimuths, 1);
    out.ambient.resize(nx, ny, 0.0f);
    if (lighting || gradient)
        for (Grid& g : out.rgb) g.resize(nx, ny, 0.0f);
    Grid gx, gy;
    computeGradient(heights, cellSize, gx, gy);  // the fast path's normals
    double heightMax = -std::numeric_limits<double>::infinity();
    for (int y = 0; y < ny; ++y)
        for (int x = 0; x < nx; ++x) heightMax = std::max(heightMax, static_cast<double>(heights(x, y)));
    const ReferenceAzimuths azimuths(M);
    const ReferenceTexels texels{heights,
                                 cellSize,
                                 gx,
                                 gy,
                                 heightMax,
                                 azimuths,
                                 lighting ? &elevationTables() : nullptr,
                                 lighting,
                                 gradient,
                                 albedo,
                                 2.0 * kPi / M,
                                 out};
    const int stride = std::max(rs.stride, 1);
    const int yBegin = rs.border, yEnd = ny - rs.border;
    const int rowsTotal = std::max(0, (yEnd - yBegin + stride - 1) / stride);
    RowProgress progress(rowsTotal);

    parallelFor(0, rowsTotal, 1, [&](int r0, int r1) {
        for (int r = r0; r < r1; ++r) {
            const int y = yBegin + r * stride;
            for (int x = rs.border; x < nx - rs.border; x += stride) shadeReferenceTexel(texels, x, y);
            if (rs.progress) progress.rowDone();
        }
    });
}

}  // namespace

void renderReference(ConstGridView heights, float cellSize, const ShRgb* lighting, const AlbedoMap* albedo,
                     const ReferenceSettings& rs, ReferenceResult& out) {
    renderTexels(heights, cellSize, lighting, nullptr, albedo, rs, out);
}

void renderReferenceSkyGradient(ConstGridView heights, float cellSize, const SunSkySettings& sky,
                                const AlbedoMap* albedo, const ReferenceSettings& rs, ReferenceResult& out) {
    for (float s : sky.sun)
        if (s != 0.0f)
            throw InputError("sky reference: the gradient has a sun lobe; integrate the sun as a key light instead");
    renderTexels(heights, cellSize, nullptr, &sky, albedo, rs, out);
}

}  // namespace terrain::gi
