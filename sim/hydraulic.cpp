#include "sim/hydraulic.h"

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "core/parallel.h"
#include "core/row_driver.h"
#include "core/simd.h"

// Hydraulic erosion, virtual-pipe model (Mei, Decaudin & Hu 2007), written as
// two gather passes over the grid:
//
//   pass A ("pipes"):  reads ground + water of the 4-neighbourhood and the
//                      cell's own old fluxes; writes the cell's own new
//                      fluxes, its sediment-per-unit-outflow and sin^2(tilt).
//   pass B ("update"): reads the neighbours' new fluxes and
//                      sediment-per-unit-outflow; writes the cell's own water,
//                      velocity, suspended sediment, soil and bedrock.
//
// No pass reads a value another cell writes in the same pass, so the result
// is the same for any thread count and any chunking. Rain is uniform, so it
// cancels in every head difference and pass A need not add it before
// comparing heads.
//
// Notation (per cell, SI units): b bedrock, s soil, d water depth, m suspended
// sediment (a material thickness), f_L/R/T/B outflow fluxes (m^3/s), c cell
// size, A = pipeArea * c^2 pipe cross-section, l = c pipe length.

namespace terrain {

namespace {

// The K-scaling of the outflow (Mei et al. Eq. 5) aims at draining a cell to
// (1 - 4e-6) of its water rather than to exactly zero, so rounding in
// the flux sums can never push a depth below zero (which a clamp would turn
// into created water).
constexpr float kDrainKeep = 1.0f - 4.0e-6f;
// m: below this mean depth a cell counts as dry for the velocity (the velocity
// of a vanishing film is 0/0).
constexpr float kDryDepth = 1.0e-6f;

/// Everything pass A and pass B read, as raw row-major pointers (stride nx).
struct Fields {
    float* bed;
    float* soil;
    float* water;
    float* susp;
    float* fL;
    float* fR;
    float* fT;
    float* fB;
    float* velX;
    float* velY;
    float* conc;  // scratch: suspended * dt / (d1 * c^2), sediment per m^3/s of outflow
    float* sin2;  // scratch: max(sin^2(tilt), minTilt^2)
    int nx, ny;
};

struct Coeffs {
    float dt;
    float fluxGain;      // dt * g * A / l = dt * g * pipeArea * c   (m^2/s per metre of head)
    float rainDt;        // m of rain this step
    float cellArea;      // c^2
    float dtOverArea;    // dt / c^2
    float invCell;       // 1 / c
    float halfInvCell;   // 0.5 / c
    float minSin2;       // minTilt^2
    float capacity;      // Kc
    float maxDepth;      // depth limiter of the capacity
    float dissolveFrac;  // min(1, Ks dt)
    float depositFrac;   // min(1, Kd dt)
    float hardness;      // bedrock dissolution multiplier
    float evapKeep;      // max(0, 1 - Ke dt)
    bool open;           // open boundary: water (and its sediment) may leave the domain
};

/// Neighbour indices and which of them exist, for one cell. Interior cells
/// take the fast path (every neighbour exists, no masks).
struct Nbr {
    std::ptrdiff_t iL, iR, iU, iD;  // clamped to the cell itself where missing
    bool hasL, hasR, hasU, hasD;
    float gxScale, gyScale;  // 1 / (run of the central/one-sided difference), 0 on a 1-wide axis
};

inline Nbr edgeNeighbours(int x, int y, int nx, int ny, float invCell) {
    Nbr n;
    const std::ptrdiff_t i = static_cast<std::ptrdiff_t>(y) * nx + x;
    n.hasL = x > 0;
    n.hasR = x < nx - 1;
    n.hasU = y > 0;
    n.hasD = y < ny - 1;
    n.iL = n.hasL ? i - 1 : i;
    n.iR = n.hasR ? i + 1 : i;
    n.iU = n.hasU ? i - nx : i;
    n.iD = n.hasD ? i + nx : i;
    const int spanX = (n.hasL ? 1 : 0) + (n.hasR ? 1 : 0);
    const int spanY = (n.hasU ? 1 : 0) + (n.hasD ? 1 : 0);
    n.gxScale = spanX == 0 ? 0.0f : invCell / static_cast<float>(spanX);
    n.gyScale = spanY == 0 ? 0.0f : invCell / static_cast<float>(spanY);
    return n;
}

// ---------------------------------------------------------------------------
// 4-wide SIMD over GCC vector extensions. The cell kernels below are written
// once, templated on the lane type T (float or F4): interior cells run four at
// a time, edge cells one at a time with the same arithmetic. Every lane op is
// an IEEE-754 correctly rounded add/sub/mul/div/sqrt or a select, so a cell's
// result does not depend on which path computed it. Explicit vectors (rather
// than auto-vectorisation) because the build keeps -fmath-errno and
// -ftrapping-math, which stop GCC from vectorising sqrt and guarded divisions.
// ---------------------------------------------------------------------------
using namespace simd;

// ---------------------------------------------------------------------------
// Pass A: outflow fluxes (Mei et al., "flow simulation": pipe acceleration and
// the K-scaling), local tilt, sediment per unit outflow.
// ---------------------------------------------------------------------------
template <class T, bool kEdge>
inline void pipeCell(const Fields F, const Coeffs& k, std::ptrdiff_t i, const Nbr& n) {
    const T g0 = load<T>(F.bed + i) + load<T>(F.soil + i);
    const T gL = load<T>(F.bed + n.iL) + load<T>(F.soil + n.iL);
    const T gR = load<T>(F.bed + n.iR) + load<T>(F.soil + n.iR);
    const T gU = load<T>(F.bed + n.iU) + load<T>(F.soil + n.iU);
    const T gD = load<T>(F.bed + n.iD) + load<T>(F.soil + n.iD);
    const T w0 = load<T>(F.water + i);
    const T zero = splat<T>(0.0f);

    // Head difference to each neighbour, ground and water apart so that a
    // thin film on a 1e5 m plateau keeps its precision.
    T hL = (g0 - gL) + (w0 - load<T>(F.water + n.iL));
    T hR = (g0 - gR) + (w0 - load<T>(F.water + n.iR));
    T hU = (g0 - gU) + (w0 - load<T>(F.water + n.iU));
    T hD = (g0 - gD) + (w0 - load<T>(F.water + n.iD));
    if constexpr (kEdge) {
        // Outside the domain: an open edge sits at the cell's own ground
        // level (the water column pours out); a closed wall gets no flux below.
        const T outside = k.open ? w0 : zero;
        if (!n.hasL) hL = outside;
        if (!n.hasR) hR = outside;
        if (!n.hasU) hU = outside;
        if (!n.hasD) hD = outside;
    }
    // f <- max(0, f + dt * g * A / l * dh)
    T fl = vmax(zero, load<T>(F.fL + i) + k.fluxGain * hL);
    T fr = vmax(zero, load<T>(F.fR + i) + k.fluxGain * hR);
    T ft = vmax(zero, load<T>(F.fT + i) + k.fluxGain * hU);
    T fb = vmax(zero, load<T>(F.fB + i) + k.fluxGain * hD);
    if constexpr (kEdge) {
        if (!k.open) {
            if (!n.hasL) fl = zero;
            if (!n.hasR) fr = zero;
            if (!n.hasU) ft = zero;
            if (!n.hasD) fb = zero;
        }
    }
    // K = min(1, d1 c^2 / (sum f dt)): at most the water present (after
    // rain) leaves in this step, so depths never go negative.
    const T d1 = w0 + k.rainDt;
    const T outVolume = ((fl + fr) + (ft + fb)) * k.dt;
    const T available = d1 * (k.cellArea * kDrainKeep);
    const T scale = vmin(splat<T>(1.0f), available / vmax(outVolume, splat<T>(1.0e-30f)));
    store(F.fL + i, fl * scale);
    store(F.fR + i, fr * scale);
    store(F.fT + i, ft * scale);
    store(F.fB + i, fb * scale);

    // Sediment carried per unit outflow over this step: concentration m / d1
    // times dt / c^2. With the K-scaling, conc * sum(f) <= m, so a cell never
    // sends away more sediment than it holds.
    store(F.conc + i, load<T>(F.susp + i) * k.dtOverArea / vmax(d1, splat<T>(kDryDepth)));

    // Local tilt of the ground from central differences (one-sided at the
    // edges): sin^2 = |grad|^2 / (1 + |grad|^2), floored at minTilt^2.
    const float sx = kEdge ? n.gxScale : k.halfInvCell;
    const float sy = kEdge ? n.gyScale : k.halfInvCell;
    const T gx = (gR - gL) * sx;
    const T gy = (gD - gU) * sy;
    const T grad2 = gx * gx + gy * gy;
    store(F.sin2 + i, vmax(splat<T>(k.minSin2), grad2 / (grad2 + 1.0f)));
}

// ---------------------------------------------------------------------------
// Pass B: water update, velocity field, flux-form sediment transport,
// capacity, dissolution/deposition, evaporation.
// ---------------------------------------------------------------------------
template <class T, bool kEdge>
inline void updateCell(const Fields F, const Coeffs& k, std::ptrdiff_t i, const Nbr& n) {
    const T zero = splat<T>(0.0f);
    const T outL = load<T>(F.fL + i), outR = load<T>(F.fR + i);
    const T outT = load<T>(F.fT + i), outB = load<T>(F.fB + i);
    // What each neighbour sends towards this cell (0 across the domain edge).
    T inL = load<T>(F.fR + n.iL);
    T inR = load<T>(F.fL + n.iR);
    T inU = load<T>(F.fB + n.iU);
    T inD = load<T>(F.fT + n.iD);
    if constexpr (kEdge) {
        if (!n.hasL) inL = zero;
        if (!n.hasR) inR = zero;
        if (!n.hasU) inU = zero;
        if (!n.hasD) inD = zero;
    }
    const T out = (outL + outR) + (outT + outB);
    const T in = (inL + inR) + (inU + inD);

    // Depth change from the net volume through the four pipes.
    const T d1 = load<T>(F.water + i) + k.rainDt;
    const T d2 = vmax(zero, d1 + (in - out) * k.dtOverArea);

    // Mean volume per second through the cell along x and y, and the velocity
    // it implies in the mean water column (0 where the cell is dry).
    const T dbar = (d1 + d2) * 0.5f;
    const T passX = ((inL - outL) + (outR - inR)) * 0.5f;
    const T passY = ((inU - outT) + (outB - inD)) * 0.5f;
    const T invCrossWet = splat<T>(k.invCell) / vmax(dbar, splat<T>(kDryDepth));
    const T invCross = dbar > kDryDepth ? invCrossWet : zero;
    const T u = passX * invCross;
    const T v = passY * invCross;

    // Flux-form transport: keep what is not sent away, receive exactly what
    // the neighbours computed they send here (their conc times the same flux).
    const T sedIn = (load<T>(F.conc + n.iL) * inL + load<T>(F.conc + n.iR) * inR) +
                    (load<T>(F.conc + n.iU) * inU + load<T>(F.conc + n.iD) * inD);
    const T m1 = vmax(zero, (load<T>(F.susp + i) - load<T>(F.conc + i) * out) + sedIn);

    // Capacity C = Kc * sin(tilt) * |v| * min(d, dmax). |v| * d is the unit
    // discharge, which stays bounded for a thin film.
    const T capacity = sqrtv(load<T>(F.sin2 + i) * (u * u + v * v)) * vmin(dbar, splat<T>(k.maxDepth)) * k.capacity;

    // Dissolve a fraction of the deficit (soil first, then bedrock at the
    // reduced rate) or deposit a fraction of the excess.
    const T deficit = capacity - m1;
    const T dissolve = vmax(deficit, zero) * k.dissolveFrac;
    const T deposit = vmax(zero - deficit, zero) * k.depositFrac;
    const T soil0 = load<T>(F.soil + i);
    const T fromSoil = vmin(dissolve, soil0);
    const T fromRock = (dissolve - fromSoil) * k.hardness;

    // The suspended load takes exactly what soil and bedrock lost (or gave):
    // the realised differences, so a tiny exchange that a large bedrock or
    // soil height rounds away is not created in the water.
    const T bed0 = load<T>(F.bed + i);
    const T soil1 = (soil0 - fromSoil) + deposit;
    const T bed1 = bed0 - fromRock;
    store(F.soil + i, soil1);
    store(F.bed + i, bed1);
    store(F.susp + i, vmax(zero, m1 + ((soil0 - soil1) + (bed0 - bed1))));
    store(F.water + i, d2 * k.evapKeep);  // evaporation
    store(F.velX + i, u);
    store(F.velY + i, v);
}

/// One row of a pass (core/row_driver.h): edge cells on the scalar path,
/// interior cells four at a time, the interior remainder one at a time.
template <class Kernel>
void runRow(const Fields& F, const Coeffs& k, int y) {
    const int nx = F.nx, ny = F.ny;
    const std::ptrdiff_t row = static_cast<std::ptrdiff_t>(y) * nx;
    forEachCellOfRow<F4>(y, nx, ny, [&](auto path, int x) {
        using Path = decltype(path);
        const std::ptrdiff_t i = row + x;
        if constexpr (Path::edge)
            Kernel::template run<float, true>(F, k, i, edgeNeighbours(x, y, nx, ny, k.invCell));
        else
            Kernel::template run<typename Path::Lanes, false>(
                F, k, i, Nbr{i - 1, i + 1, i - nx, i + nx, true, true, true, true, 0, 0});
    });
}

struct PipePass {
    template <class T, bool kEdge>
    static void run(const Fields& F, const Coeffs& k, std::ptrdiff_t i, const Nbr& n) {
        pipeCell<T, kEdge>(F, k, i, n);
    }
};
struct UpdatePass {
    template <class T, bool kEdge>
    static void run(const Fields& F, const Coeffs& k, std::ptrdiff_t i, const Nbr& n) {
        updateCell<T, kEdge>(F, k, i, n);
    }
};

/// Rows per block of the pipelined schedule: about 32k cells, at least 4 rows.
int blockRows(int nx, int ny) { return std::clamp(32768 / std::max(nx, 1), 4, std::max(ny, 4)); }

}  // namespace

// ---------------------------------------------------------------------------
// Stable time step.
//
// Linearise the pipe update around a lake at rest. Per step (symplectic
// Euler: fluxes first, then depths with the new fluxes)
//     f   += dt * g * A / l * (h_i - h_j)          (Mei et al. Eq. 2)
//     h_i -= dt / c^2 * sum_j f_ij                 (Mei et al. Eq. 6)
// which is a discrete wave equation h'' = (g A / (l c^2)) * L h with L the
// un-normalised 5-point Laplacian (eigenvalues in [-8, 0]). Symplectic Euler
// on h'' = -w^2 h is stable iff dt * w <= 2; with w^2 = 8 g A / (l c^2) and
// A = a c^2, l = c:
//     dt <= 2 / sqrt(8 g a / c) = sqrt(c / (2 g a)).
// The water depth does not enter: in the pipe model the "wave speed" is
// sqrt(g A / l) = sqrt(g a c), set by the pipe, not sqrt(g d). Depth enters
// only through the K-scaling (Mei et al. Eq. 5), which caps the volume a cell
// sends in one step at the water it holds. That cap keeps depths
// non-negative for any dt, but once it is active the update is no longer the
// linear scheme above (a shallow film on a slope drains every step), so we
// keep half of the linear limit as margin. The state argument is unused
// beyond the cell size: the bound holds for any depth.
// ---------------------------------------------------------------------------
float hydraulicMaxDt(const TerrainState& s, const HydraulicSettings& settings) {
    const float c = s.cellSize;
    const float a = std::max(settings.pipeArea, 1.0e-6f);
    const float g = std::max(settings.gravity, 1.0e-6f);
    constexpr float kSafety = 0.5f;
    return kSafety * std::sqrt(c / (2.0f * g * a));
}

void hydraulicStep(TerrainState& s, const HydraulicSettings& settings, float dt, HydraulicScratch& scratch) {
    const int nx = s.nx, ny = s.ny;
    if (nx <= 0 || ny <= 0 || !(dt > 0.0f)) return;
    scratch.conc.ensureSize(nx, ny);
    scratch.sin2.ensureSize(nx, ny);

    const float c = s.cellSize;
    Coeffs k;
    k.dt = dt;
    k.fluxGain = dt * settings.gravity * settings.pipeArea * c;
    k.rainDt = std::max(0.0f, settings.rainRate) * dt;
    k.cellArea = c * c;
    k.dtOverArea = dt / (c * c);
    k.invCell = 1.0f / c;
    k.halfInvCell = 0.5f / c;
    k.minSin2 = settings.minTilt * settings.minTilt;
    k.capacity = settings.capacity;
    k.maxDepth = settings.maxErosionDepth;
    k.dissolveFrac = std::clamp(settings.dissolve * dt, 0.0f, 1.0f);
    k.depositFrac = std::clamp(settings.deposit * dt, 0.0f, 1.0f);
    k.hardness = std::clamp(settings.bedrockHardness, 0.0f, 1.0f);
    k.evapKeep = std::clamp(1.0f - settings.evaporation * dt, 0.0f, 1.0f);
    k.open = !settings.closedBoundary;

    const Fields F{s.bedrock.data(),
                   s.soil.data(),
                   s.water.data(),
                   s.suspended.data(),
                   s.fluxL.data(),
                   s.fluxR.data(),
                   s.fluxT.data(),
                   s.fluxB.data(),
                   s.velX.data(),
                   s.velY.data(),
                   scratch.conc.data(),
                   scratch.sin2.data(),
                   nx,
                   ny};

    // Schedule (apart from the algorithm above): rows are cut into fixed
    // blocks (independent of the thread count). Phase 1 runs pass A on the
    // first and last row of every block. Phase 2 walks each block top-down,
    // running pass A on row y + 1 just before pass B on row y, so the rows a
    // pass B reads are still in cache from its pass A. This is hazard-free:
    // pass A on row y + 1 reads ground and water of rows y..y + 2 before pass
    // B touches row y, and a block's pass A never reads a row of another
    // block (its edge rows were done in phase 1), while pass B reads only
    // fluxes and concentrations, which phase 1 or the block itself wrote.
    const int rows = blockRows(nx, ny);
    const int blocks = (ny + rows - 1) / rows;
    parallelFor(0, blocks, 1, [&](int b0, int b1) {
        for (int b = b0; b < b1; ++b) {
            const int y0 = b * rows, y1 = std::min(ny, y0 + rows);
            runRow<PipePass>(F, k, y0);
            if (y1 - 1 != y0) runRow<PipePass>(F, k, y1 - 1);
        }
    });
    parallelFor(0, blocks, 1, [&](int b0, int b1) {
        for (int b = b0; b < b1; ++b) {
            const int y0 = b * rows, y1 = std::min(ny, y0 + rows);
            for (int y = y0; y < y1; ++y) {
                if (y + 1 < y1 - 1) runRow<PipePass>(F, k, y + 1);
                runRow<UpdatePass>(F, k, y);
            }
        }
    });
}

}  // namespace terrain
