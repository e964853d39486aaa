#include "sim/thermal.h"

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "core/parallel.h"
#include "core/row_driver.h"
#include "core/simd.h"

// Thermal erosion (talus relaxation) in the 8-neighbourhood, with the real
// distance to each neighbour (c along the axes, c * sqrt(2) on the
// diagonals), so the talus angle means the same slope in every direction and
// maxGroundSlope measures what the step enforces.
//
// Per cell, with ground G = bedrock + soil and t = tan(talus):
//   excess_n = max(0, G - G_n - t * dist_n)          (height above the talus)
//   demand   = k * max_n(excess_n) / 2                 (half: the receiver rises
//                                                      as the giver sinks), 0 if
//                                                      max excess is in the dead zone
//   moved    = min(demand, soil)                       (only soil travels)
//   to n     = moved * excess_n / sum(excess)          (shared by excess)
// with k = min(rate * dt, kMaxFraction). With erodeBedrock, the part of the
// demand the soil cannot cover crumbles from bedrock into soil in place and
// travels from the next step on.
//
// Two gather passes: pass 1 writes each cell's ground, moved amount and
// moved / sum(excess); pass 2 lets each cell subtract its own moved amount and
// add share_n * excess_{n -> cell} from each neighbour, recomputed from the
// same stored grounds with the same expression the giver used, so what one
// cell gives is what the others receive (up to the rounding of the sums).
// Only soil moves between cells, so a tiny transfer is never rounded away
// against a large bedrock height.

namespace terrain {

namespace {

// Largest fraction of the half-excess moved per step. A cell in a pit can
// receive from all eight neighbours at once; moving the full half-excess then
// overshoots and the relaxation rings instead of converging.
constexpr float kMaxFraction = 0.5f;
constexpr float kSqrt2 = 1.41421356237f;
// Slope excess (rise over run above tan(talus)) below which nothing moves.
constexpr float kDeadZoneSlope = 1.0e-4f;

struct Fields {
    float* bed;
    float* soil;
    float* ground;  // scratch: G before this step
    float* out;     // scratch: material leaving the cell this step (m)
    float* share;   // scratch: out / sum(excess)
    int nx, ny;
};

struct Coeffs {
    float talusAxis;     // t * c
    float talusDiag;     // t * c * sqrt(2)
    float halfFraction;  // k / 2
    float deadZone;      // m: excess below which a cell does not shed
    bool erodeBedrock;
};

// 4-wide SIMD over GCC vector extensions (as in hydraulic.cpp): the cell
// kernels are templated on the lane type, interior cells run four at a time,
// edge cells one at a time with the same IEEE operations, so a cell's result
// does not depend on the path.
using namespace simd;

// The eight neighbours in a fixed order: L, R, U, D, UL, UR, DL, DR. The
// first four are at distance c, the last four at c * sqrt(2).
struct Nbr8 {
    std::ptrdiff_t idx[8];
    bool has[8];
};

inline Nbr8 edgeNeighbours(int x, int y, int nx, int ny) {
    const std::ptrdiff_t i = static_cast<std::ptrdiff_t>(y) * nx + x;
    const bool l = x > 0, r = x<nx - 1, u = y> 0, d = y < ny - 1;
    Nbr8 n;
    const bool has[8] = {l, r, u, d, u && l, u && r, d && l, d && r};
    const std::ptrdiff_t off[8] = {-1, 1, -nx, nx, -nx - 1, -nx + 1, nx - 1, nx + 1};
    for (int j = 0; j < 8; ++j) {
        n.has[j] = has[j];
        n.idx[j] = has[j] ? i + off[j] : i;
    }
    return n;
}

inline Nbr8 interiorNeighbours(std::ptrdiff_t i, int nx) {
    return Nbr8{{i - 1, i + 1, i - nx, i + nx, i - nx - 1, i - nx + 1, i + nx - 1, i + nx + 1},
                {true, true, true, true, true, true, true, true}};
}

// Height of `drop` above the talus limit over one neighbour, 0 if below it
// or if the neighbour does not exist.
template <class T, bool kEdge>
inline T excessOver(T drop, float talus, const Nbr8& n, int j) {
    const T e = vmax(splat<T>(0.0f), drop - talus);
    if constexpr (kEdge) return n.has[j] ? e : splat<T>(0.0f);
    return e;
}

// Material a cell wants to shed this step: k/2 of its largest excess, or
// nothing inside the dead zone (an endless tail of vanishing moves would only
// add rounding noise).
template <class T>
inline T shedDemand(const T* e, const Coeffs& k) {
    const T maxE = vmax(vmax(vmax(e[0], e[1]), vmax(e[2], e[3])), vmax(vmax(e[4], e[5]), vmax(e[6], e[7])));
    return maxE > k.deadZone ? maxE * k.halfFraction : splat<T>(0.0f);
}

// Pass 1: how much soil leaves each cell, and how it is shared.
template <class T, bool kEdge>
inline void shedCell(const Fields F, const Coeffs& k, std::ptrdiff_t i, const Nbr8& n) {
    const T soil0 = load<T>(F.soil + i);
    const T g0 = load<T>(F.bed + i) + soil0;
    T e[8];
    for (int j = 0; j < 8; ++j) {
        const T gn = load<T>(F.bed + n.idx[j]) + load<T>(F.soil + n.idx[j]);
        e[j] = excessOver<T, kEdge>(g0 - gn, j < 4 ? k.talusAxis : k.talusDiag, n, j);
    }
    const T sumE = ((e[0] + e[1]) + (e[2] + e[3])) + ((e[4] + e[5]) + (e[6] + e[7]));
    const T moved = vmin(shedDemand(e, k), soil0);  // only soil travels
    store(F.ground + i, g0);
    store(F.out + i, moved);
    store(F.share + i, moved / vmax(sumE, splat<T>(1.0e-30f)));
}

// Pass 2: give what pass 1 decided, take what the neighbours give, and (with
// erodeBedrock) crumble the bedrock the soil could not cover into soil in
// place; it travels from the next step on.
template <class T, bool kEdge>
inline void settleCell(const Fields F, const Coeffs& k, std::ptrdiff_t i, const Nbr8& n) {
    const T g0 = load<T>(F.ground + i);
    T eOut[8], r[8];
    for (int j = 0; j < 8; ++j) {
        const float talus = j < 4 ? k.talusAxis : k.talusDiag;
        const T gn = load<T>(F.ground + n.idx[j]);
        // The neighbour's excess towards this cell, exactly as it computed it
        // in pass 1 (same stored grounds, same expression) ...
        r[j] = load<T>(F.share + n.idx[j]) * excessOver<T, kEdge>(gn - g0, talus, n, j);
        // ... and this cell's own excess over it, as this cell computed it.
        eOut[j] = excessOver<T, kEdge>(g0 - gn, talus, n, j);
    }
    const T gained = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]));
    const T moved = load<T>(F.out + i);
    const T soil0 = load<T>(F.soil + i);
    const T bed0 = load<T>(F.bed + i);
    T soil1 = (soil0 - moved) + gained;
    if (k.erodeBedrock) {
        // Crumble exactly what the bedrock loses: bed0 - bed1 is exact
        // (Sterbenz) whenever the crumbled amount is small against the
        // bedrock height, so no material is lost to the rounding of a large
        // bedrock height.
        const T crumble = shedDemand(eOut, k) - moved;
        const T bed1 = bed0 - crumble;
        soil1 = soil1 + (bed0 - bed1);
        store(F.bed + i, bed1);
    }
    store(F.soil + i, soil1);
}

// One pass over the grid, rows in parallel, each row by core/row_driver.h.
template <class Kernel>
void forEachCell8(const Fields& F, const Coeffs& k) {
    const int nx = F.nx, ny = F.ny;
    parallelForRows(ny, nx, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) {
            const std::ptrdiff_t row = static_cast<std::ptrdiff_t>(y) * nx;
            forEachCellOfRow<F4>(y, nx, ny, [&](auto path, int x) {
                using Path = decltype(path);
                if constexpr (Path::edge)
                    Kernel::template run<float, true>(F, k, row + x, edgeNeighbours(x, y, nx, ny));
                else
                    Kernel::template run<typename Path::Lanes, false>(F, k, row + x, interiorNeighbours(row + x, nx));
            });
        }
    });
}

struct ShedPass {
    template <class T, bool kEdge>
    static void run(const Fields& F, const Coeffs& k, std::ptrdiff_t i, const Nbr8& n) {
        shedCell<T, kEdge>(F, k, i, n);
    }
};
struct SettlePass {
    template <class T, bool kEdge>
    static void run(const Fields& F, const Coeffs& k, std::ptrdiff_t i, const Nbr8& n) {
        settleCell<T, kEdge>(F, k, i, n);
    }
};

}  // namespace

void thermalStep(TerrainState& s, const ThermalSettings& settings, float dt, ThermalScratch& scratch) {
    const int nx = s.nx, ny = s.ny;
    if (nx <= 0 || ny <= 0 || !(dt > 0.0f) || !(settings.rate > 0.0f)) return;
    scratch.ground.ensureSize(nx, ny);
    scratch.out.ensureSize(nx, ny);
    scratch.share.ensureSize(nx, ny);

    constexpr float kDegToRad = 3.14159265358979f / 180.0f;
    const float talus = std::clamp(settings.talusAngleDeg, 0.0f, 89.9f) * kDegToRad;
    const float tanTalus = std::tan(talus);
    Coeffs k;
    k.talusAxis = tanTalus * s.cellSize;
    k.talusDiag = tanTalus * s.cellSize * kSqrt2;
    k.halfFraction = 0.5f * std::min(settings.rate * dt, kMaxFraction);
    k.erodeBedrock = settings.erodeBedrock;
    k.deadZone = kDeadZoneSlope * s.cellSize;

    const Fields F{
        s.bedrock.data(), s.soil.data(), scratch.ground.data(), scratch.out.data(), scratch.share.data(), nx, ny};
    forEachCell8<ShedPass>(F, k);    // pass 1
    forEachCell8<SettlePass>(F, k);  // pass 2
}

float maxGroundSlope(const TerrainState& s) {
    const int nx = s.nx, ny = s.ny;
    if (nx <= 0 || ny <= 0) return 0.0f;
    const float invAxis = 1.0f / s.cellSize;
    const float invDiag = 1.0f / (s.cellSize * kSqrt2);
    const float* b = s.bedrock.data();
    const float* so = s.soil.data();
    auto ground = [&](int x, int y) {
        const std::size_t i = static_cast<std::size_t>(y) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(x);
        return b[i] + so[i];
    };
    // Each unordered pair once: right, down, down-left, down-right.
    return deterministicReduce(
        0, ny, 16, 0.0f,
        [&](int y0, int y1) {
            float m = 0.0f;
            for (int y = y0; y < y1; ++y) {
                for (int x = 0; x < nx; ++x) {
                    const float g0 = ground(x, y);
                    if (x + 1 < nx) m = std::max(m, std::fabs(g0 - ground(x + 1, y)) * invAxis);
                    if (y + 1 < ny) {
                        m = std::max(m, std::fabs(g0 - ground(x, y + 1)) * invAxis);
                        if (x > 0) m = std::max(m, std::fabs(g0 - ground(x - 1, y + 1)) * invDiag);
                        if (x + 1 < nx) m = std::max(m, std::fabs(g0 - ground(x + 1, y + 1)) * invDiag);
                    }
                }
            }
            return m;
        },
        [](float a, float c) { return std::max(a, c); });
}

}  // namespace terrain
