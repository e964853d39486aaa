#include "gi/glossy_lobe_gather.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/bfloat16.h"
#include "core/parallel.h"
#include "gi/indirect_scan_tables.h"
#include "gi/phong_lobe_quadrature.h"
#include "gi/sh.h"

namespace terrain::gi {

namespace {

constexpr int kPlanes = 3 * kShCount;  // RGB x 16 SH planes of the exit radiance

// One receiver's lobe: its reflection R (unit), frame and exponent.
struct ReceiverLobe {
    double r[3], t[3], b[3];
    double S;
};

ReceiverLobe receiverLobe(float gx, float gy, const float view[3], double S) {
    ReceiverLobe L;
    const double inv = 1.0 / std::sqrt(1.0 + static_cast<double>(gx) * gx + static_cast<double>(gy) * gy);
    const double n[3] = {-gx * inv, -gy * inv, inv};
    const double d = 2.0 * (n[0] * view[0] + n[1] * view[1] + n[2] * view[2]);
    for (int a = 0; a < 3; ++a) L.r[a] = d * n[a] - view[a];
    const double len = std::sqrt(L.r[0] * L.r[0] + L.r[1] * L.r[1] + L.r[2] * L.r[2]);
    for (double& v : L.r) v /= len;
    lobeFrame(L.r, L.t, L.b);
    L.S = S;
    return L;
}

// The receiver's rays as the walks read them: each lobe direction split
// between the two global azimuths on either side of it (linear weights),
// those above the tangent plane along their azimuth only, sorted by azimuth
// and then slope (insertion sort: a few dozen rays, a fixed order).
void lobeRays(const ReceiverLobe& L, const GlossyLobeState& st, float gx, float gy, GlossyLobeScratch& sc) {
    std::vector<GlossyLobeScratch::Ray>& rays = sc.rays;
    rays.clear();
    sc.quadrature.set(L.S, sc.quadrature.rings());
    const int rings = sc.quadrature.rings(), M = static_cast<int>(st.phi.size());
    const double dphi = 2.0 * kPi / M;
    const float w0 = 1.0f / static_cast<float>(2 * rings * rings);
    for (int i = 0; i < rings; ++i)
        for (int k = 0; k < 2 * rings; ++k) {
            double w[3];
            sc.quadrature.direction(L.r, L.t, L.b, i, k, w);
            const double horizontal = std::sqrt(w[0] * w[0] + w[1] * w[1]);
            if (horizontal < 1e-9) continue;  // straight up: meets nothing
            double a = std::atan2(w[1], w[0]);
            if (a < 0.0) a += 2.0 * kPi;
            const double u = a / dphi;
            const int j0 = std::min(static_cast<int>(u), M - 1);
            const double f = u - j0;
            const float slope = static_cast<float>(w[2] / horizontal);
            const float cosE = static_cast<float>(horizontal), sinE = static_cast<float>(w[2]);
            for (int side = 0; side < 2; ++side) {
                const int j = (j0 + side) % M;
                const float weight = w0 * static_cast<float>(side == 0 ? 1.0 - f : f);
                const float c = st.cosPhi[static_cast<std::size_t>(j)], s = st.sinPhi[static_cast<std::size_t>(j)];
                if (weight <= 0.0f || slope <= gx * c + gy * s) continue;  // below the tangent plane
                rays.push_back({j, slope, weight, {-c * cosE, -s * cosE, -sinE}});
            }
        }
    for (std::size_t a = 1; a < rays.size(); ++a) {
        const GlossyLobeScratch::Ray x = rays[a];
        std::size_t b = a;
        for (; b > 0 &&
               (rays[b - 1].azimuth > x.azimuth || (rays[b - 1].azimuth == x.azimuth && rays[b - 1].slope > x.slope));
             --b)
            rays[b] = rays[b - 1];
        rays[b] = x;
    }
}

// What the member at step i of azimuth j sends along each of `rays` (sorted
// by slope) into acc, weighted: the 48 planes read once, dotted with Y(back).
struct MemberSamples {
    float e[kPlanes];
};

void readMember(const GlossyLobeState& st, std::size_t at, int X, int Y, MemberSamples& m) {
    const ScanStep& ps = st.planeSteps[at];
    const std::uint16_t* const* origins = st.planeOrigins.data() + at * kPlanes;
    const std::ptrdiff_t o = Y * ps.rowStep + X, dB = ps.offB - ps.offA;
    const float wa = ps.w[0][0], wb = ps.w[1][0];
    for (int f = 0; f < kPlanes; ++f) m.e[f] = wa * fromBfloat16(origins[f][o]) + wb * fromBfloat16(origins[f][o + dB]);
}

void addSent(const MemberSamples& m, const GlossyLobeScratch::Ray& ray, bool clamp, double acc[3]) {
    float y[kShCount];
    shBasisLanes<float>(ray.back[0], ray.back[1], ray.back[2], y);
    for (int c = 0; c < 3; ++c) {
        float u = 0.0f;
        for (int f = 0; f < kShCount; ++f) u += m.e[c * kShCount + f] * y[f];
        if (clamp) u = std::max(u, 0.0f);
        acc[c] += static_cast<double>(ray.weight) * u;
    }
}

// Receiver (X, Y)'s rays [begin, end) of one azimuth (sorted by slope):
// the walk over the steps, each ray brought what its first reaching step sends.
void walkAzimuth(const GlossyLobeInputs& in, const GlossyLobeState& st, const GlossyLobeScratch::Ray* begin,
                 const GlossyLobeScratch::Ray* end, int X, int Y, float h0, float margin, double acc[3]) {
    const int j = begin->azimuth, nSteps = static_cast<int>(in.heights.steps.size());
    const int pad = static_cast<int>(st.stepsPerColumn.size() / st.phi.size());
    const int prefix =
        std::min(st.stepsPerColumn[static_cast<std::size_t>(j) * pad + static_cast<std::size_t>(X)],
                 st.stepsPerRow[static_cast<std::size_t>(j) * in.heights.nyr + static_cast<std::size_t>(Y)]);
    const std::size_t base = static_cast<std::size_t>(j) * nSteps;
    const float reach = (in.topHeight - h0) - margin;  // the highest rise any sample can have
    const bool clamp = in.shading.positivity == GlossyPositivity::Clamp;
    const GlossyLobeScratch::Ray* next = begin;
    MemberSamples m;
    for (int i = 0; i < prefix && next != end; ++i) {
        const ScanStep& hs = st.heightSteps[base + static_cast<std::size_t>(i)];
        if (reach * hs.w[2][0] < next->slope) break;  // no sample from here on reaches the lowest ray left
        const std::ptrdiff_t o = Y * hs.rowStep + X;
        const float t =
            ((hs.w[0][0] * hs.field[o + hs.offA] + hs.w[1][0] * hs.field[o + hs.offB] - h0) - margin) * hs.w[2][0];
        if (t < next->slope) continue;
        readMember(st, base + static_cast<std::size_t>(i), X, Y, m);
        for (; next != end && next->slope <= t; ++next) addSent(m, *next, clamp, acc);
    }
}

// Receiver row Y: every receiver's lobe rays and walks into st.gathered.
void gatherRow(const GlossyLobeInputs& in, GlossyLobeState& st, int Y, GlossyLobeScratch& sc) {
    const HeightPyramid& pyr = in.heights;
    const int nxr = pyr.nxr, s = pyr.subsample;
    const std::size_t planeR = static_cast<std::size_t>(nxr) * pyr.nyr;
    const int pad = static_cast<int>(sc.gx.size());
    loadReceiverRow(pyr, in.gradX, in.gradY, Y, pad, sc.gx.data(), sc.gy.data(), sc.h0.data(), sc.margin.data());
    const bool expMap = in.surface && !in.surface->phongExponent.empty();
    for (int X = 0; X < nxr; ++X) {
        const double S = expMap ? in.surface->phongExponent(s * X, s * Y) : in.shading.phongExponent;
        const ReceiverLobe L = receiverLobe(sc.gx[X], sc.gy[X], in.shading.viewDir, S);
        lobeRays(L, st, sc.gx[X], sc.gy[X], sc);
        double acc[3] = {0.0, 0.0, 0.0};
        const GlossyLobeScratch::Ray* rays = sc.rays.data();
        const std::size_t n = sc.rays.size();
        for (std::size_t a = 0; a < n;) {
            std::size_t b = a + 1;
            while (b < n && rays[b].azimuth == rays[a].azimuth) ++b;
            walkAzimuth(in, st, rays + a, rays + b, X, Y, sc.h0[X], sc.margin[X], acc);
            a = b;
        }
        const std::size_t i = static_cast<std::size_t>(Y) * nxr + X;
        for (int c = 0; c < 3; ++c) st.gathered[static_cast<std::size_t>(c) * planeR + i] = static_cast<float>(acc[c]);
    }
}

}  // namespace

void gatherGlossyLobes(const GlossyLobeInputs& in, GlossyLobeState& st) {
    const HeightPyramid& pyr = in.heights;
    const int M = in.azimuths, pad = indirectRowPad(pyr.nxr), nSteps = static_cast<int>(pyr.steps.size());
    const std::size_t table = static_cast<std::size_t>(M) * nSteps;
    st.phi.resize(static_cast<std::size_t>(M));
    st.cosPhi.resize(static_cast<std::size_t>(M));
    st.sinPhi.resize(static_cast<std::size_t>(M));
    for (int j = 0; j < M; ++j) {
        const auto u = static_cast<std::size_t>(j);
        st.phi[u] = 2.0 * kPi * j / M;
        st.cosPhi[u] = static_cast<float>(std::cos(st.phi[u]));
        st.sinPhi[u] = static_cast<float>(std::sin(st.phi[u]));
    }
    st.heightSteps.resize(table);
    st.planeSteps.resize(table);
    st.planeOrigins.resize(table * kPlanes);
    st.stepsPerColumn.resize(static_cast<std::size_t>(M) * pad);
    st.stepsPerRow.resize(static_cast<std::size_t>(M) * pyr.nyr);
    buildGlossyStepTable(pyr, in.exit, st.phi, pad, st.heightSteps, st.stepsPerColumn, st.stepsPerRow, st.planeSteps,
                         st.planeOrigins);
    st.gathered.resize(static_cast<std::size_t>(3) * pyr.nxr * pyr.nyr);
    st.scratch.resize(static_cast<std::size_t>(workerSlots()));
    for (GlossyLobeScratch& sc : st.scratch) {
        for (std::vector<float>* v : {&sc.gx, &sc.gy, &sc.h0, &sc.margin}) v->resize(static_cast<std::size_t>(pad));
        sc.quadrature.set(in.shading.phongExponent, in.rings);
    }
    parallelFor(0, pyr.nyr, 1, [&](int y0, int y1) {
        GlossyLobeScratch& sc = st.scratch[static_cast<std::size_t>(workerSlot())];
        for (int Y = y0; Y < y1; ++Y) gatherRow(in, st, Y, sc);
    });
}

void shadeGlossyLobes(const GlossyLobeState& st, const HeightPyramid& heights, const ShadingSettings& shading,
                      bool addToOut, std::array<Grid, 3>& out) {
    const int nx = heights.nx, ny = heights.ny, nxr = heights.nxr, nyr = heights.nyr, s = heights.subsample;
    const std::size_t planeR = static_cast<std::size_t>(nxr) * nyr;
    const float ws = specularWeightOf(shading);
    const float floor = shading.positivity == GlossyPositivity::Clamp ? 0.0f : -std::numeric_limits<float>::infinity();
    for (Grid& g : out)
        if (!addToOut) g.ensureSize(nx, ny);
    std::vector<ReceiverLerp> columns;
    receiverLerps(nx, s, nxr, columns);
    parallelFor(0, ny, 8, [&](int y0, int y1) {
        std::vector<float> vert(static_cast<std::size_t>(nxr)), row(static_cast<std::size_t>(nx));
        for (int y = y0; y < y1; ++y) {
            const ReceiverLerp ry = receiverLerp(y, s, nyr);
            for (int c = 0; c < 3; ++c) {
                const float* g = st.gathered.data() + static_cast<std::size_t>(c) * planeR;
                const float* a = g + static_cast<std::size_t>(ry.i0) * nxr;
                const float* b = g + static_cast<std::size_t>(ry.i1) * nxr;
                for (int X = 0; X < nxr; ++X) vert[static_cast<std::size_t>(X)] = a[X] + ry.f * (b[X] - a[X]);
                lerpReceiverRow(vert.data(), nxr, s, columns.data(), nx, row.data());
                float* o = out[static_cast<std::size_t>(c)].data() + static_cast<std::size_t>(y) * nx;
                for (int x = 0; x < nx; ++x) {
                    const float v = (addToOut ? o[x] : 0.0f) + ws * row[static_cast<std::size_t>(x)];
                    o[x] = std::isfinite(v) ? std::max(v, floor) : 0.0f;
                }
            }
        }
    });
}

}  // namespace terrain::gi
