// Hydrology maps (definitions and units in sim/hydrology.h).
#include "sim/hydrology.h"

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "core/parallel.h"

namespace terrain {
namespace {

std::size_t cellIndex(int x, int y, int nx) { return static_cast<std::size_t>(y) * nx + x; }

// The accumulated double maps as floats, one per cell.
template <class Fn>
void fillMap(int nx, int ny, Grid& out, Fn&& value) {
    out.ensureSize(nx, ny);
    parallelForRows(ny, nx, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y)
            for (int x = 0; x < nx; ++x) {
                const std::size_t i = cellIndex(x, y, nx);
                out.v[i] = value(i);
            }
    });
}

// Waves: the mean of the two face velocities per axis (faceU is (nx + 1) x ny,
// faceV is nx x (ny + 1)).
void centreVelocity(const TerrainState& s, int x, int y, float& u, float& v) {
    u = (s.faceU(x, y) + s.faceU(x + 1, y)) * 0.5f;
    v = (s.faceV(x, y) + s.faceV(x, y + 1)) * 0.5f;
}

// One row of the ground sums. Both heights are floats, so their difference
// is exact in double and the sums telescope to the total change. Branch-free
// so that the compiler vectorises it: the pass runs every tick.
void addGroundChange(const float* bed, const float* soil, const float* before, double* erosion, double* deposition,
                     int n) {
    for (int x = 0; x < n; ++x) {
        const double change = static_cast<double>(bed[x] + soil[x]) - static_cast<double>(before[x]);
        erosion[x] += std::max(-change, 0.0);
        deposition[x] += std::max(change, 0.0);
    }
}

void countWet(const float* water, std::uint32_t* wetTicks, int n) {
    for (int x = 0; x < n; ++x) wetTicks[x] += water[x] >= kWetDepth ? 1u : 0u;
}

}  // namespace

void HydrologyAccumulator::start(const TerrainState& s, bool trackGround, bool trackWater) {
    nx_ = s.nx;
    ny_ = s.ny;
    ticks_ = 0;
    const std::size_t n = static_cast<std::size_t>(nx_) * static_cast<std::size_t>(ny_);
    erosion_.assign(trackGround ? n : 0, 0.0);
    deposition_.assign(trackGround ? n : 0, 0.0);
    wetTicks_.assign(trackWater && s.hasWater() ? n : 0, 0);
}

void HydrologyAccumulator::accumulateRow(int y, const float* bedrock, const float* soil, const float* groundBefore,
                                         const float* water) {
    const std::size_t row = cellIndex(0, y, nx_);
    if (tracksGround())
        addGroundChange(bedrock, soil, groundBefore, erosion_.data() + row, deposition_.data() + row, nx_);
    if (tracksWater() && water) countWet(water, wetTicks_.data() + row, nx_);
}

void HydrologyAccumulator::erosionMap(Grid& out) const {
    fillMap(nx_, ny_, out, [&](std::size_t i) { return static_cast<float>(erosion_[i]); });
}

void HydrologyAccumulator::depositionMap(Grid& out) const {
    fillMap(nx_, ny_, out, [&](std::size_t i) { return static_cast<float>(deposition_[i]); });
}

void HydrologyAccumulator::netErosionMap(Grid& out) const {
    fillMap(nx_, ny_, out, [&](std::size_t i) { return static_cast<float>(erosion_[i] - deposition_[i]); });
}

void HydrologyAccumulator::wetnessMap(Grid& out) const {
    const double ticks = static_cast<double>(ticks_);
    fillMap(nx_, ny_, out, [&](std::size_t i) {
        return ticks_ > 0 ? static_cast<float>(static_cast<double>(wetTicks_[i]) / ticks) : 0.0f;
    });
}

FaceFlows cellFaceFlows(const TerrainState& s, int x, int y) {
    const std::size_t i = cellIndex(x, y, s.nx);
    const std::size_t row = static_cast<std::size_t>(s.nx);
    const float inL = x > 0 ? s.fluxR.v[i - 1] : 0.0f;
    const float inR = x < s.nx - 1 ? s.fluxL.v[i + 1] : 0.0f;
    const float inU = y > 0 ? s.fluxB.v[i - row] : 0.0f;
    const float inD = y < s.ny - 1 ? s.fluxT.v[i + row] : 0.0f;
    return {inL - s.fluxL.v[i], s.fluxR.v[i] - inR, inU - s.fluxT.v[i], s.fluxB.v[i] - inD};
}

bool hasWaterFlow(const TerrainState& s) { return s.hasWater() && (!s.fluxL.empty() || !s.faceU.empty()); }

void cellDischarge(const TerrainState& s, int x, int y, float& qx, float& qy) {
    if (!s.fluxL.empty()) {
        const FaceFlows f = cellFaceFlows(s, x, y);
        qx = (f.west + f.east) * 0.5f;
        qy = (f.north + f.south) * 0.5f;
        return;
    }
    float u = 0.0f, v = 0.0f;
    centreVelocity(s, x, y, u, v);
    const float widthDepth = s.cellSize * s.water(x, y);
    qx = widthDepth * u;
    qy = widthDepth * v;
}

void dischargeMap(const TerrainState& s, Grid& out) {
    fillMap(s.nx, s.ny, out, [&](std::size_t i) {
        float qx = 0.0f, qy = 0.0f;
        cellDischarge(s, static_cast<int>(i % s.nx), static_cast<int>(i / s.nx), qx, qy);
        return std::sqrt(qx * qx + qy * qy);
    });
}

void velocityMap(const TerrainState& s, Grid& out) {
    fillMap(s.nx, s.ny, out, [&](std::size_t i) {
        float u = 0.0f, v = 0.0f;
        if (!s.velX.empty()) {
            u = s.velX.v[i];
            v = s.velY.v[i];
        } else {
            centreVelocity(s, static_cast<int>(i % s.nx), static_cast<int>(i / s.nx), u, v);
        }
        return std::sqrt(u * u + v * v);
    });
}

void sedimentFluxMap(const TerrainState& s, const Grid& discharge, Grid& out) {
    fillMap(s.nx, s.ny, out, [&](std::size_t i) {
        const float depth = s.water.v[i];
        if (s.suspended.empty() || depth < kWetDepth) return 0.0f;
        return discharge.v[i] * (s.suspended.v[i] / depth);
    });
}

}  // namespace terrain
