#include "sim/waves.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "sim/error.h"
#include "sim/parallel.h"

// ---------------------------------------------------------------------------
// The algorithm
// ---------------------------------------------------------------------------
// Shallow-water equations in non-conservative velocity form,
//
//   (1)  h_t + (h u)_x + (h v)_y = 0
//   (2)  u_t + u u_x + v u_y = -g eta_x - g n^2 |u| u / h^(4/3)
//        (and the same for v),            eta = h + b,  b = bedrock + soil,
//
// on an Arakawa C grid: h at cell centres, u on vertical faces (faceU,
// (nx+1) x ny), v on horizontal faces (faceV, nx x (ny+1)). Gravity waves on
// this grid have the semi-discrete speed c sin(k dx/2) / (k dx/2) with
// c = sqrt(g h), i.e. sqrt(g h) up to O((k dx)^2) (GUIDE 3).
//
// One step is forward-backward (symplectic Euler), as in Stelling &
// Duinmeijer 2003 ("A staggered conservative scheme for every Froude number
// in rapidly varied shallow water flows", IJNMF 43), sections 2-3:
//
//   P1 (cells)  outflow rate o_i = sum of the outgoing face velocities / dx and
//               per-row maxima of h and |u| for the CFL check.
//   P2 (faces)  volume fluxes q = u * h_up * r_up with the upwind reconstructed
//               depth h_up (S&D eq. 8 with hydrostatic reconstruction, below)
//               and the positivity limiter r = 1 / max(1, dt o_donor): a cell
//               never gives away more than it holds (the donor's depth bounds
//               every h_up it feeds, so dt * sum(out q) / dx <= h).
//   P3 (cells)  continuity (1): h += -dt/dx (q_E - q_W + q_N - q_S). Every face
//               flux is stored once and read by both neighbours, so the volume
//               leaving one cell is bit-for-bit the volume entering the other.
//   P4 (faces)  momentum (2) with the new depth h^{n+1} (the "backward" half):
//               pressure gradient from the reconstructed depths, upwind
//               momentum-conservative advection built from the P2 fluxes,
//               semi-implicit Manning friction, wet/dry rule; writes new
//               velocities into scratch, which are then swapped in.
//
// No pass reads what it writes (P3 updates h in place but reads h only at
// the cell it writes).
//
// Wet/dry and well balancing: hydrostatic reconstruction (Audusse, Bouchut,
// Bristeau, Klein & Perthame 2004, eq. 2.8) at every face between cells A and
// B with grounds bA, bB and depths hA, hB:
//
//   b* = max(bA, bB),  hA* = max(0, eta_A - b*),  hB* = max(0, eta_B - b*).
//
// The face pressure gradient is g (max(eta_B, b*) - max(eta_A, b*)) / dx:
//   - both wet: g (eta_B - eta_A) / dx, the difference of one per-cell
//     potential eta. So the discrete force is curl-free: rounding in eta
//     cannot drive a circulation that grows forever around islands (a form
//     like hB* - hA* with b differences rounds differently on every face and
//     does: 1e-3 m/s after 10^4 ticks in the rest test). At rest
//     eta_A = eta_B exactly up to the rounding of h = level - b;
//   - a wet cell beside dry ground higher than its surface: both terms are
//     b*, no force, and h_up = 0 gives no flux;
//   - a wet cell beside lower dry ground pushes with its full depth (a dam
//     break over the edge).
// Elevations are taken relative to a reference level (the ground at the
// centre cell), so eta keeps float precision on terrain far from 0 m.
// A face whose reconstructed depths are both <= dryDepth carries no velocity.
//
// Momentum advection, momentum-conservative form (S&D eq. 12): with the cell
// centred flux qc_i = (q_{i-1/2} + q_{i+1/2}) / 2 and the upwind velocity
// u*_i = (qc_i > 0 ? u_{i-1/2} : u_{i+1/2}),
//
//   u u_x |_{i+1/2} = [ (qc_{i+1} u*_{i+1} - qc_i u*_i) - u_{i+1/2} (qc_{i+1} - qc_i) ] / (dx hbar),
//
// hbar = (h_i + h_{i+1}) / 2, which is exactly the depth whose rate of change
// the fluxes qc describe; it follows from (hu)_t + (q u)_x = -g h eta_x minus
// u times (1), so momentum is conserved across a bore (right bore and
// dam-break speeds). The cross term v u_y uses the same form with the corner
// fluxes (average of the two neighbouring v-face fluxes) and upwind u.
//
// Friction (Manning, semi-implicit so it never reverses the flow):
//   u <- u / (1 + dt g n^2 |u| / h_f^(4/3)),  h_f = max(hA*, hB*).
//
// Stability: the gravity-wave part is stable for c dt sqrt(2) / dx <= 1; the
// upwind advection for |u| dt / dx <= 1. waveMaxDt returns
// courant * dx / (sqrt(g h_max) + |u|_max); waveStep sub-steps internally
// when the state exceeds maxCourant, and clamps face velocities to
// maxCourant dx / dt so a thin film racing down a cliff cannot run away.
//
// Boundaries: closed walls (u = 0 on the outer faces). A swell edge uses a
// Flather condition (Flather 1976) around the still-water depth h0 at the
// boundary cell: the incoming linear wave has u_in = sqrt(g/h0) eta_in, an
// outgoing one u_out = -sqrt(g/h0) eta_out, so with the boundary cell's
// anomaly eta_b = h - h0 the inward normal velocity is
//   u_n = sqrt(g / h0) (2 eta_in - eta_b),
// which passes the incoming wave and lets outgoing waves leave.
// ---------------------------------------------------------------------------

namespace terrain {

namespace {

// Hydrostatic reconstruction at a face (see above). bA, bB: grounds relative
// to the step's reference level. Returns the pressure difference
// max(eta_B, b*) - max(eta_A, b*) and the reconstructed depths.
inline float reconstruct(float hA, float hB, float bA, float bB, float& hAs, float& hBs) {
    const float etaA = hA + bA;
    const float etaB = hB + bB;
    const float bStar = std::max(bA, bB);
    hAs = std::max(0.0f, etaA - bStar);
    hBs = std::max(0.0f, etaB - bStar);
    return std::max(etaB, bStar) - std::max(etaA, bStar);
}

struct StepConsts {
    float dt = 0.0f;
    float dx = 0.0f;
    float invDx = 0.0f;
    float k = 0.0f;          // dt / dx
    float gk = 0.0f;         // g dt / dx
    float dry = 0.0f;        // dryDepth
    float vmax = 0.0f;       // velocity clamp, m/s
    float frictionK = 0.0f;  // dt g n^2
    bool advection = true;
    // swell
    bool swell = false;
    int edge = 0;
    float etaIn = 0.0f;      // incoming elevation at the velocity time level
    float etaInFlux = 0.0f;  // incoming elevation at the flux time level
    float seaLevel = 0.0f;
    float gravity = 9.81f;
    float bref = 0.0f;       // m, reference level subtracted from the ground (precision at large offsets)
};

struct Views {
    int nx = 0, ny = 0;
    float* h = nullptr;
    const float* bed = nullptr;
    const float* soil = nullptr;
    const float* u = nullptr;   // faceU, stride nx + 1
    const float* v = nullptr;   // faceV, stride nx
    float* out = nullptr;       // outflow, stride nx
    float* qu = nullptr;        // fluxU, stride nx + 1
    float* qv = nullptr;        // fluxV, stride nx
    float* nu = nullptr;        // nextU
    float* nv = nullptr;        // nextV
    std::size_t su() const { return static_cast<std::size_t>(nx) + 1; }
    std::size_t sc() const { return static_cast<std::size_t>(nx); }
};

// eta_in(t): the incoming swell elevation, ramped in from t = 0.
float swellElevation(const WaveSwell& sw, double t) {
    if (!sw.enabled || !(sw.period > 0.0f)) return 0.0f;
    const double omega = 2.0 * 3.14159265358979323846 / static_cast<double>(sw.period);
    double ramp = 1.0;
    if (sw.rampPeriods > 0.0f) ramp = std::clamp(t / (static_cast<double>(sw.rampPeriods) * sw.period), 0.0, 1.0);
    return static_cast<float>(static_cast<double>(sw.amplitude) * ramp * std::sin(omega * t));
}

// Sign of the inward normal velocity on a swell edge (0: -x, 1: +x, 2: -y, 3: +y).
inline float inwardSign(int edge) { return (edge == 0 || edge == 2) ? 1.0f : -1.0f; }

// Flux through a swell boundary face: upwind between the exterior still water
// plus the incoming elevation (inflow) and the limited boundary cell (outflow).
inline float swellFlux(const StepConsts& c, float un, float hCell, float gCell, float outCell) {
    const float sgn = inwardSign(c.edge);
    if (sgn * un > 0.0f) return un * std::max(0.0f, c.seaLevel + c.etaInFlux - gCell);
    return un * hCell / std::max(c.dt * outCell, 1.0f);
}

// Flather velocity on a swell boundary face (see the header comment).
inline float swellVelocity(const StepConsts& c, float hCell, float gCell) {
    const float h0 = c.seaLevel - gCell;
    if (!(h0 > c.dry)) return 0.0f;
    const float un = inwardSign(c.edge) * std::sqrt(c.gravity / h0) * (2.0f * c.etaIn - (hCell - h0));
    return std::clamp(un, -c.vmax, c.vmax);
}

// --- P1: outflow rate per cell and per-row maxima ---------------------------
void outflowRows(const Views& w, int y0, int y1, float invDx, float* rowMaxDepth, float* rowMaxSpeed) {
    const std::size_t su = w.su(), sc = w.sc();
    for (int y = y0; y < y1; ++y) {
        const float* u = w.u + y * su;
        const float* vS = w.v + y * sc;
        const float* vN = vS + sc;
        const float* h = w.h + y * sc;
        float* o = w.out + y * sc;
        float mh = 0.0f, mv = 0.0f;
        for (int x = 0; x < w.nx; ++x) {
            const float outgoing = std::max(u[x + 1], 0.0f) + std::max(-u[x], 0.0f) + std::max(vN[x], 0.0f) +
                                   std::max(-vS[x], 0.0f);
            o[x] = outgoing * invDx;
            mh = std::max(mh, h[x]);
            mv = std::max(mv, std::max(std::fabs(u[x]), std::fabs(vS[x])));
        }
        mv = std::max(mv, std::fabs(u[w.nx]));
        if (y == w.ny - 1)
            for (int x = 0; x < w.nx; ++x) mv = std::max(mv, std::fabs(vN[x]));
        rowMaxDepth[y] = mh;
        rowMaxSpeed[y] = mv;
    }
}

// --- P2: face fluxes ----------------------------------------------------------
// Interior faces between cells A = a[x] and B = b[x] (A west/south of B).
inline void faceFluxes(int n, const float* hA, const float* hB, const float* bedA, const float* bedB,
                       const float* soilA, const float* soilB, const float* oA, const float* oB, const float* vel,
                       float dt, float bref, float* q) {
    for (int x = 0; x < n; ++x) {
        float hAs, hBs;
        reconstruct(hA[x], hB[x], (bedA[x] + soilA[x]) - bref, (bedB[x] + soilB[x]) - bref, hAs, hBs);
        const float un = vel[x];
        const bool fromA = un > 0.0f;
        const float hUp = fromA ? hAs : hBs;
        const float oUp = fromA ? oA[x] : oB[x];
        q[x] = un * hUp / std::max(dt * oUp, 1.0f);
    }
}

void fluxRows(const Views& w, const StepConsts& c, int y0, int y1) {
    const std::size_t su = w.su(), sc = w.sc();
    const int nx = w.nx, ny = w.ny;
    for (int y = y0; y < y1; ++y) {
        const std::size_t r = static_cast<std::size_t>(y) * sc;
        const float* h = w.h + r;
        const float* bed = w.bed + r;
        const float* soil = w.soil + r;
        const float* o = w.out + r;
        // x faces of row y: face x between cells x-1 and x.
        float* qu = w.qu + y * su;
        const float* u = w.u + y * su;
        if (nx > 1) faceFluxes(nx - 1, h, h + 1, bed, bed + 1, soil, soil + 1, o, o + 1, u + 1, c.dt, c.bref, qu + 1);
        qu[0] = (c.swell && c.edge == 0) ? swellFlux(c, u[0], h[0], bed[0] + soil[0], o[0]) : 0.0f;
        qu[nx] = (c.swell && c.edge == 1) ? swellFlux(c, u[nx], h[nx - 1], bed[nx - 1] + soil[nx - 1], o[nx - 1])
                                          : 0.0f;
        // y faces of row y: between cells (x, y-1) and (x, y).
        float* qv = w.qv + r;
        const float* v = w.v + r;
        if (y > 0) {
            faceFluxes(nx, h - sc, h, bed - sc, bed, soil - sc, soil, o - sc, o, v, c.dt, c.bref, qv);
        } else {
            for (int x = 0; x < nx; ++x)
                qv[x] = (c.swell && c.edge == 2) ? swellFlux(c, v[x], h[x], bed[x] + soil[x], o[x]) : 0.0f;
        }
        if (y == ny - 1) {  // the last face row, y = ny
            float* qvN = qv + sc;
            const float* vN = v + sc;
            for (int x = 0; x < nx; ++x)
                qvN[x] = (c.swell && c.edge == 3) ? swellFlux(c, vN[x], h[x], bed[x] + soil[x], o[x]) : 0.0f;
        }
    }
}

// --- P3: continuity -----------------------------------------------------------
void continuityRows(const Views& w, float k, int y0, int y1) {
    const std::size_t su = w.su(), sc = w.sc();
    for (int y = y0; y < y1; ++y) {
        float* h = w.h + y * sc;
        const float* qu = w.qu + y * su;
        const float* qvS = w.qv + y * sc;
        const float* qvN = qvS + sc;
        for (int x = 0; x < w.nx; ++x) {
            const float div = (qu[x + 1] - qu[x]) + (qvN[x] - qvS[x]);
            h[x] = std::max(0.0f, h[x] - k * div);
        }
    }
}

// --- P4: momentum ---------------------------------------------------------------
// One face between cells A and B along the face normal. vel: this face's
// velocity; velM / velP: the previous / next face along the normal;
// qM, q0, qP: their fluxes. Cross direction: velLo / velHi the parallel faces
// on either side; qLo = the two fluxes through the low corner summed, qHi the
// same at the high corner.
struct FaceIn {
    float hA, hB, bA, bB;
    float vel, velM, velP, qM, q0, qP;
    float velLo, velHi, qLo, qHi;
};

inline float momentum(const FaceIn& f, const StepConsts& c, bool friction) {
    float hAs, hBs;
    const float dEta = reconstruct(f.hA, f.hB, f.bA, f.bB, hAs, hBs);
    float un = f.vel - c.gk * dEta;
    if (c.advection) {
        // Along the normal: cell-centred fluxes and upwind velocities (S&D eq. 12).
        const float qcA = 0.5f * (f.qM + f.q0);
        const float qcB = 0.5f * (f.q0 + f.qP);
        const float usA = qcA > 0.0f ? f.velM : f.vel;
        const float usB = qcB > 0.0f ? f.vel : f.velP;
        float adv = (qcB * usB - qcA * usA) - f.vel * (qcB - qcA);
        // Across: corner fluxes and upwind velocities.
        const float qLo = 0.5f * f.qLo;
        const float qHi = 0.5f * f.qHi;
        const float usLo = qLo > 0.0f ? f.velLo : f.vel;
        const float usHi = qHi > 0.0f ? f.vel : f.velHi;
        adv += (qHi * usHi - qLo * usLo) - f.vel * (qHi - qLo);
        const float hbar = 0.5f * (f.hA + f.hB);
        float advection = adv / std::max(hbar, c.dry);
        // Where the flow accelerates along itself (a contraction in S&D's
        // terms: the rarefaction of a dam break, the run towards a dry
        // front) use the velocity (energy-head) form u (u - u_upwind) / dx for
        // the normal part: the momentum form above over-advects there, by
        // the ratio of upwind to centred depth, and would slow the front.
        const bool fwd = f.vel >= 0.0f;
        const float du = fwd ? f.vel - f.velM : f.velP - f.vel;
        const bool accelerating = fwd ? f.vel > f.velM : f.vel < f.velP;
        const float crossOnly = ((qHi * usHi - qLo * usLo) - f.vel * (qHi - qLo)) / std::max(hbar, c.dry);
        advection = accelerating ? f.vel * du + crossOnly : advection;
        un -= c.k * advection;
    }
    const float hf = std::max(hAs, hBs);
    if (friction) {
        const float hfc = std::max(hf, c.dry);
        un = un / (1.0f + c.frictionK * std::fabs(un) / (hfc * std::cbrt(hfc)));
    }
    un = std::clamp(un, -c.vmax, c.vmax);
    return hf > c.dry ? un : 0.0f;
}

template <bool kFriction>
void momentumRows(const Views& w, const StepConsts& c, int y0, int y1) {
    const std::size_t su = w.su(), sc = w.sc();
    const int nx = w.nx, ny = w.ny;
    for (int y = y0; y < y1; ++y) {
        const std::size_t r = static_cast<std::size_t>(y) * sc;
        const float* h = w.h + r;
        const float* bed = w.bed + r;
        const float* soil = w.soil + r;

        // ---- u faces of row y ----
        const float* u = w.u + y * su;
        const float* uS = w.u + (y > 0 ? y - 1 : y) * su;       // clamped: qv on a closed wall is 0 anyway
        const float* uN = w.u + (y < ny - 1 ? y + 1 : y) * su;
        const float* qu = w.qu + y * su;
        const float* qvS = w.qv + r;       // face row y: the south corners
        const float* qvN = w.qv + r + sc;  // face row y + 1: the north corners
        float* nu = w.nu + y * su;
        for (int x = 1; x < nx; ++x) {
            FaceIn f;
            f.hA = h[x - 1];
            f.hB = h[x];
            f.bA = (bed[x - 1] + soil[x - 1]) - c.bref;
            f.bB = (bed[x] + soil[x]) - c.bref;
            f.vel = u[x];
            f.velM = u[x - 1];
            f.velP = u[x + 1];
            f.qM = qu[x - 1];
            f.q0 = qu[x];
            f.qP = qu[x + 1];
            f.velLo = uS[x];
            f.velHi = uN[x];
            f.qLo = qvS[x - 1] + qvS[x];
            f.qHi = qvN[x - 1] + qvN[x];
            nu[x] = momentum(f, c, kFriction);
        }
        nu[0] = (c.swell && c.edge == 0) ? swellVelocity(c, h[0], bed[0] + soil[0]) : 0.0f;
        nu[nx] = (c.swell && c.edge == 1) ? swellVelocity(c, h[nx - 1], bed[nx - 1] + soil[nx - 1]) : 0.0f;

        // ---- v faces of row y (between cell rows y-1 and y) ----
        float* nv = w.nv + r;
        if (y > 0) {
            const float* hS = h - sc;
            const float* bedS = bed - sc;
            const float* soilS = soil - sc;
            const float* v = w.v + r;
            const float* vS = v - sc;
            const float* vN = v + sc;
            const float* qv = w.qv + r;
            const float* qvSS = qv - sc;
            const float* qvNN = qv + sc;
            const float* quS = w.qu + (y - 1) * su;  // x faces of the cell row below
            const float* quN = w.qu + y * su;        // and of this row
            auto face = [&](int x, int xm, int xp) {
                FaceIn f;
                f.hA = hS[x];
                f.hB = h[x];
                f.bA = (bedS[x] + soilS[x]) - c.bref;
                f.bB = (bed[x] + soil[x]) - c.bref;
                f.vel = v[x];
                f.velM = vS[x];
                f.velP = vN[x];
                f.qM = qvSS[x];
                f.q0 = qv[x];
                f.qP = qvNN[x];
                f.velLo = v[xm];
                f.velHi = v[xp];
                f.qLo = quS[x] + quN[x];
                f.qHi = quS[x + 1] + quN[x + 1];
                return momentum(f, c, kFriction);
            };
            // Edge columns clamp the missing neighbour (its corner flux is 0
            // on a closed wall; zero gradient on a swell edge).
            nv[0] = face(0, 0, nx > 1 ? 1 : 0);
            for (int x = 1; x < nx - 1; ++x) nv[x] = face(x, x - 1, x + 1);
            if (nx > 1) nv[nx - 1] = face(nx - 1, nx - 2, nx - 1);
        } else {
            for (int x = 0; x < nx; ++x)
                nv[x] = (c.swell && c.edge == 2) ? swellVelocity(c, h[x], bed[x] + soil[x]) : 0.0f;
        }
        if (y == ny - 1) {
            float* nvN = nv + sc;
            for (int x = 0; x < nx; ++x)
                nvN[x] = (c.swell && c.edge == 3) ? swellVelocity(c, h[x], bed[x] + soil[x]) : 0.0f;
        }
    }
}

// --- Drops: Gaussian sources ------------------------------------------------
void applyDrop(TerrainState& s, const WaveDrop& d) {
    const float dx = s.cellSize;
    const float sigma = std::max(d.radius, 1e-3f * dx);
    const float reach = 4.0f * sigma;  // exp(-8) ~ 3e-4 of the height beyond
    const int x0 = std::max(0, static_cast<int>(std::floor((d.x - reach) / dx)));
    const int x1 = std::min(s.nx - 1, static_cast<int>(std::ceil((d.x + reach) / dx)));
    const int y0 = std::max(0, static_cast<int>(std::floor((d.y - reach) / dx)));
    const int y1 = std::min(s.ny - 1, static_cast<int>(std::ceil((d.y + reach) / dx)));
    if (x0 > x1 || y0 > y1) return;
    const float inv2s2 = 1.0f / (2.0f * sigma * sigma);
    float* h = s.water.data();
    const int nx = s.nx;
    parallelFor(y0, y1 + 1, std::max(1, 16384 / std::max(x1 - x0 + 1, 1)), [&](int ya, int yb) {
        for (int y = ya; y < yb; ++y) {
            const float ry = static_cast<float>(y) * dx - d.y;
            for (int x = x0; x <= x1; ++x) {
                const float rx = static_cast<float>(x) * dx - d.x;
                float& cell = h[static_cast<std::size_t>(y) * nx + x];
                cell = std::max(0.0f, cell + d.height * std::exp(-(rx * rx + ry * ry) * inv2s2));
            }
        }
    });
}

void ensure(Grid& g, int w, int h) {
    if (g.nx != w || g.ny != h || g.v.size() != static_cast<std::size_t>(w) * static_cast<std::size_t>(h))
        g.resize(w, h);
}

void checkLayers(const TerrainState& s) {
    if (s.water.nx != s.nx || s.water.ny != s.ny || s.faceU.nx != s.nx + 1 || s.faceU.ny != s.ny ||
        s.faceV.nx != s.nx || s.faceV.ny != s.ny + 1)
        throw InputError("waves need the water and faceVelocity layers (water " + std::to_string(s.water.nx) + "x" +
                         std::to_string(s.water.ny) + ", faceU " + std::to_string(s.faceU.nx) + "x" +
                         std::to_string(s.faceU.ny) + " for a " + std::to_string(s.nx) + "x" +
                         std::to_string(s.ny) + " grid)");
}

struct Maxima {
    float depth = 0.0f;
    float speed = 0.0f;
};

}  // namespace

float waveMaxDt(const TerrainState& s, const WaveSettings& settings) {
    checkLayers(s);
    const int nx = s.nx, ny = s.ny;
    const std::size_t su = static_cast<std::size_t>(nx) + 1, sc = static_cast<std::size_t>(nx);
    const float* h = s.water.data();
    const float* u = s.faceU.data();
    const float* v = s.faceV.data();
    // max is exact, so any chunking gives the same answer; deterministicReduce keeps it obviously so.
    const Maxima m = deterministicReduce(
        0, ny, std::max(1, 16384 / std::max(nx, 1)), Maxima{},
        [&](int y0, int y1) {
            Maxima r;
            for (int y = y0; y < y1; ++y) {
                for (int x = 0; x < nx; ++x) {
                    r.depth = std::max(r.depth, h[y * sc + x]);
                    r.speed = std::max(r.speed, std::max(std::fabs(u[y * su + x]), std::fabs(v[y * sc + x])));
                }
                r.speed = std::max(r.speed, std::fabs(u[y * su + nx]));
                if (y == ny - 1)
                    for (int x = 0; x < nx; ++x) r.speed = std::max(r.speed, std::fabs(v[(y + 1) * sc + x]));
            }
            return r;
        },
        [](Maxima a, Maxima b) { return Maxima{std::max(a.depth, b.depth), std::max(a.speed, b.speed)}; });
    // Sources still to come raise the depth the step must survive.
    float extra = 0.0f;
    for (const WaveDrop& d : settings.drops)
        if (d.time >= s.time) extra = std::max(extra, d.height);
    if (settings.swell.enabled) extra += 2.0f * std::fabs(settings.swell.amplitude);
    const float depth = std::max(m.depth + extra, std::max(settings.dryDepth, 1e-6f));
    const float speed = std::sqrt(settings.gravity * depth) + m.speed;
    const float courant = std::clamp(settings.courant, 1e-3f, settings.maxCourant);
    const float dt = courant * s.cellSize / speed;
    return std::isfinite(dt) && dt > 0.0f ? dt : 1e-3f;
}

void waveStep(TerrainState& s, const WaveSettings& settings, float dt, WaveScratch& scratch) {
    checkLayers(s);
    if (!(dt > 0.0f) || !std::isfinite(dt)) return;
    const int nx = s.nx, ny = s.ny;
    ensure(scratch.outflow, nx, ny);
    ensure(scratch.fluxU, nx + 1, ny);
    ensure(scratch.fluxV, nx, ny + 1);
    ensure(scratch.nextU, nx + 1, ny);
    ensure(scratch.nextV, nx, ny + 1);
    if (scratch.rowMaxDepth.size() != static_cast<std::size_t>(ny)) {
        scratch.rowMaxDepth.assign(static_cast<std::size_t>(ny), 0.0f);
        scratch.rowMaxSpeed.assign(static_cast<std::size_t>(ny), 0.0f);
    }

    const float dx = s.cellSize;
    const float g = settings.gravity;
    const float maxCourant = std::clamp(settings.maxCourant, 0.05f, 1.0f);
    constexpr int kMaxSubsteps = 64;

    double t = s.time;
    double remaining = dt;
    int taken = 0;
    while (remaining > 0.0) {
        Views w;
        w.nx = nx;
        w.ny = ny;
        w.h = s.water.data();
        w.bed = s.bedrock.data();
        w.soil = s.soil.data();
        w.u = s.faceU.data();
        w.v = s.faceV.data();
        w.out = scratch.outflow.data();
        w.qu = scratch.fluxU.data();
        w.qv = scratch.fluxV.data();
        w.nu = scratch.nextU.data();
        w.nv = scratch.nextV.data();

        // P1, and the CFL check on the state at the start of this sub-step.
        parallelForRows(ny, nx, [&](int y0, int y1) {
            outflowRows(w, y0, y1, 1.0f / dx, scratch.rowMaxDepth.data(), scratch.rowMaxSpeed.data());
        });
        float hMax = 0.0f, vMax = 0.0f;
        for (int y = 0; y < ny; ++y) {
            hMax = std::max(hMax, scratch.rowMaxDepth[static_cast<std::size_t>(y)]);
            vMax = std::max(vMax, scratch.rowMaxSpeed[static_cast<std::size_t>(y)]);
        }
        const double speed = std::sqrt(static_cast<double>(g) * hMax) + vMax;
        const double stable = speed > 0.0 ? maxCourant * dx / speed : remaining;
        int n = 1;
        if (stable < remaining) n = static_cast<int>(std::min<double>(std::ceil(remaining / stable), kMaxSubsteps - taken));
        n = std::max(n, 1);
        const double h = n == 1 ? remaining : remaining / n;

        StepConsts c;
        c.dt = static_cast<float>(h);
        c.dx = dx;
        c.invDx = 1.0f / dx;
        c.k = c.dt / dx;
        c.gk = g * c.dt / dx;
        c.dry = settings.dryDepth;
        c.vmax = maxCourant * dx / c.dt;
        c.frictionK = c.dt * g * settings.friction * settings.friction;
        c.advection = settings.advection;
        c.swell = settings.swell.enabled && settings.swell.edge >= 0 && settings.swell.edge <= 3;
        c.edge = settings.swell.edge;
        c.etaInFlux = swellElevation(settings.swell, t);
        c.etaIn = swellElevation(settings.swell, t + h);
        c.seaLevel = settings.swell.seaLevel;
        c.gravity = g;
        // Any constant reference level gives the same physics; the ground at the
        // centre keeps eta - bref small where the terrain sits far from 0 m
        // (heights of 1e5 m), so the surface is resolved to float precision.
        c.bref = s.bedrock(nx / 2, ny / 2) + s.soil(nx / 2, ny / 2);

        parallelForRows(ny, nx, [&](int y0, int y1) { fluxRows(w, c, y0, y1); });          // P2
        parallelForRows(ny, nx, [&](int y0, int y1) { continuityRows(w, c.k, y0, y1); });  // P3
        for (const WaveDrop& d : settings.drops)
            if (d.time >= t && d.time < t + h) applyDrop(s, d);
        if (settings.friction > 0.0f)                                                       // P4
            parallelForRows(ny, nx, [&](int y0, int y1) { momentumRows<true>(w, c, y0, y1); });
        else
            parallelForRows(ny, nx, [&](int y0, int y1) { momentumRows<false>(w, c, y0, y1); });
        std::swap(s.faceU, scratch.nextU);
        std::swap(s.faceV, scratch.nextV);

        t += h;
        ++taken;
        remaining = n == 1 ? 0.0 : remaining - h;
    }
    scratch.lastSubsteps = taken;
}

}  // namespace terrain
