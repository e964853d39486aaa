#include "gi/horizon_angles.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"
#include "core/parallel.h"
#include "gi/near_field.h"
#include "gi/reference.h"
#include "gi/sh.h"
#include "gi/shading.h"

namespace terrain::gi {

namespace {

constexpr double kDegreesPerRadian = 180.0 / kPi;

// The receivers' angles of one azimuth plane (nxr x nyr), in degrees.
void receiverDegrees(const float* slopes, std::size_t count, std::vector<float>& out) {
    out.resize(count);
    for (std::size_t i = 0; i < count; ++i) out[i] = static_cast<float>(horizonDegrees(slopes[i]));
}

// The bilinear blend of the receivers' angles a..d (weights wa..wd) over
// those that have terrain in the direction: a receiver with none (-90, a
// border receiver looking out) says nothing about the texels between it and
// a receiver that has, which do have terrain before them. -90 when none has.
float blendWithTerrain(const float (&angle)[4], const float (&weight)[4]) {
    float sum = 0.0f, total = 0.0f;
    for (int k = 0; k < 4; ++k)
        if (angle[k] > -90.0f) {
            sum += weight[k] * angle[k];
            total += weight[k];
        }
    return total > 0.0f ? sum / total : -90.0f;
}

// Bilinear from the receivers' angles to the texels of one plane.
void interpolateToTexels(const std::vector<float>& receivers, int nxr, int nyr, int subsample, Grid& out) {
    const int nx = out.nx;
    std::vector<ReceiverLerp> columns;
    receiverLerps(nx, subsample, nxr, columns);
    parallelForRows(out.ny, nx, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) {
            const ReceiverLerp ry = receiverLerp(y, subsample, nyr);
            const float* r0 = receivers.data() + static_cast<std::size_t>(ry.i0) * nxr;
            const float* r1 = receivers.data() + static_cast<std::size_t>(ry.i1) * nxr;
            for (int x = 0; x < nx; ++x) {
                const ReceiverLerp& rx = columns[static_cast<std::size_t>(x)];
                const float angle[4] = {r0[rx.i0], r0[rx.i1], r1[rx.i0], r1[rx.i1]};
                const float weight[4] = {(1.0f - rx.f) * (1.0f - ry.f), rx.f * (1.0f - ry.f), (1.0f - rx.f) * ry.f,
                                         rx.f * ry.f};
                out(x, y) = blendWithTerrain(angle, weight);
            }
        }
    });
}

}  // namespace

std::vector<double> scanAzimuths(int m) {
    if (m < 1) throw InputError("horizon angles: at least one azimuth");
    std::vector<double> phi;
    const double dphi = 2.0 * kPi / m;
    for (int j = 0; j < m; ++j) phi.push_back(dphi * j);
    return phi;
}

double horizonDegrees(double slope) { return slope <= kNoBlocker ? -90.0 : std::atan(slope) * kDegreesPerRadian; }

void horizonAnglesFromScan(const VisibilityField& env, const std::vector<double>& azimuths, int subsample, int nx,
                           int ny, HorizonAngles& out) {
    const int s = subsample, nxr = env.nxr, nyr = env.nyr;
    const std::size_t plane = static_cast<std::size_t>(nxr) * nyr;
    if (s < 1 || nxr != (nx + s - 1) / s || nyr != (ny + s - 1) / s || plane == 0 ||
        env.maxSlope.size() != azimuths.size() * plane)
        throw InputError("horizon angles: the horizons are not of this grid, sub-sampling and azimuth count");
    out.azimuths = azimuths;
    out.degrees.resize(azimuths.size());
    std::vector<float> receivers;
    for (std::size_t j = 0; j < azimuths.size(); ++j) {
        Grid& g = out.degrees[j];
        g.resize(nx, ny);
        receiverDegrees(env.maxSlope.data() + j * plane, plane, receivers);
        if (s == 1)
            std::copy(receivers.begin(), receivers.end(), g.data());
        else
            interpolateToTexels(receivers, nxr, nyr, s, g);
    }
}

void raiseHorizonAnglesToNearField(ConstGridView heights, float cellSize, int subsample, HorizonAngles& angles) {
    if (subsample <= 1) return;
    const int nx = heights.nx, ny = heights.ny;
    std::vector<float> cosSin;
    for (double phi : angles.azimuths) {
        cosSin.push_back(static_cast<float>(std::cos(phi)));
        cosSin.push_back(static_cast<float>(std::sin(phi)));
    }
    std::vector<NearFieldStep> steps;
    buildNearFieldSteps(cosSin, subsample, cellSize, steps);
    for (std::size_t j = 0; j < angles.azimuths.size(); ++j) {
        Grid& g = angles.degrees[j];
        if (g.nx != nx || g.ny != ny) throw InputError("horizon angles: not of this grid");
        const std::span<const NearFieldStep> mine(steps.data() + j * subsample, static_cast<std::size_t>(subsample));
        parallelForRows(ny, nx, [&](int y0, int y1) {
            std::vector<float> near(static_cast<std::size_t>(nx));
            for (int y = y0; y < y1; ++y) {
                std::fill(near.begin(), near.end(), -std::numeric_limits<float>::infinity());
                raiseToNearField(heights, y, mine, near.data());
                for (int x = 0; x < nx; ++x)
                    g(x, y) = std::max(g(x, y), static_cast<float>(horizonDegrees(near[static_cast<std::size_t>(x)])));
            }
        });
    }
}

void referenceHorizonAngles(ConstGridView heights, float cellSize, const std::vector<double>& azimuths,
                            HorizonAngles& out) {
    const int nx = heights.nx, ny = heights.ny;
    double heightMax = -HUGE_VAL;
    for (int y = 0; y < ny; ++y)
        for (int x = 0; x < nx; ++x) heightMax = std::max(heightMax, static_cast<double>(heights(x, y)));
    out.azimuths = azimuths;
    out.degrees.resize(azimuths.size());
    for (std::size_t j = 0; j < azimuths.size(); ++j) {
        Grid& g = out.degrees[j];
        g.resize(nx, ny);
        const double c = std::cos(azimuths[j]), sn = std::sin(azimuths[j]);
        parallelForRows(ny, nx * 64, [&](int y0, int y1) {
            for (int y = y0; y < y1; ++y)
                for (int x = 0; x < nx; ++x)
                    g(x, y) = static_cast<float>(
                        horizonDegrees(referenceMaxSlope(heights, cellSize, x, y, c, sn, heightMax)));
        });
    }
}

double compassAzimuthDegrees(double phi, double eastPerColumn, double northPerRow) {
    const double east = (eastPerColumn >= 0.0 ? 1.0 : -1.0) * std::cos(phi);
    const double north = (northPerRow >= 0.0 ? 1.0 : -1.0) * std::sin(phi);
    double bearing = std::atan2(east, north) * kDegreesPerRadian;
    if (bearing < 0.0) bearing += 360.0;
    // exact compass points stay exact (atan2 of a cos that should be 0 is not)
    const double rounded = std::round(bearing * 1.0e9) / 1.0e9;
    return rounded >= 360.0 ? rounded - 360.0 : rounded;
}

}  // namespace terrain::gi
