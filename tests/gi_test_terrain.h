#pragma once
// Small analytic terrains shared by the GI tests.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <functional>

#include "core/grid.h"
#include "gi/frame.h"

namespace terrain::gi_test {

// A V-shaped valley along y: walls rising at `slope` (m per m) from the floor line.
inline Grid valley(int nx, int ny, float slope) {
    Grid g(nx, ny);
    const float c = 0.5f * static_cast<float>(nx - 1);
    for (int y = 0; y < ny; ++y)
        for (int x = 0; x < nx; ++x) g(x, y) = slope * std::fabs(static_cast<float>(x) - c);
    return g;
}

// Smooth rolling hills (a few sines), heights in metres.
inline Grid hills(int n, float amp) {
    Grid g(n, n);
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const float u = static_cast<float>(x) / static_cast<float>(n),
                        v = static_cast<float>(y) / static_cast<float>(n);
            g(x, y) = amp * (std::sin(6.3f * u) * std::cos(4.1f * v) + 0.5f * std::sin(13.0f * u + 7.0f * v) +
                             0.25f * std::cos(23.0f * v - 3.0f * u));
        }
    return g;
}

/// Mean of g over columns [x0, x1) and rows [y0, y1).
inline double meanOver(const Grid& g, int x0, int x1, int y0, int y1) {
    double sum = 0.0;
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) sum += g(x, y);
    return sum / ((x1 - x0) * (y1 - y0));
}

/// A grid filled with f(x, y).
template <class F>
Grid gridOf(int nx, int ny, F&& f) {
    Grid g(nx, ny);
    for (int y = 0; y < ny; ++y)
        for (int x = 0; x < nx; ++x) g(x, y) = f(x, y);
    return g;
}

/// True when a and b hold the same floats bit for bit (sizes included).
template <class A, class B>
bool sameBits(const A& a, const B& b) {
    return a.size() == b.size() && (a.size() == 0 || std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0);
}

// A smooth field with ridges of several wavelengths.
inline Grid bumpy(int nx, int ny) {
    return gridOf(nx, ny, [](int x, int y) {
        return static_cast<float>(9.0 * std::sin(0.21 * x) * std::cos(0.17 * y) + 3.0 * std::sin(0.8 * x + 0.45 * y) +
                                  1.5 * std::cos(0.05 * x * y));
    });
}

inline gi::GiLighting sunSkyAndKey() {
    gi::GiLighting light;
    light.environment = gi::sunSkyLight();
    gi::KeyLight k;
    k.azimuthDeg = 130.0f;
    k.elevationDeg = 28.0f;
    light.keys.push_back(k);
    return light;
}

inline gi::GiSettings withBounces(gi::GiSettings s, int subsample, int bounces) {
    s.subsample = subsample;
    s.indirect.bounces = bounces;
    return s;
}

/// Full direct-light frames (no bounce, not incremental: every frame's
/// visibility the true one), the engine's or the paper's settings.
inline gi::GiSettings fullDirectFrames(bool paper, int subsample) {
    gi::GiSettings s = withBounces(paper ? gi::paperGiSettings() : gi::GiSettings{}, subsample, 0);
    s.incremental = false;
    return s;
}

// Every output a caller reads: ambient, direct shade, indirect, total and the bounce means.
inline bool sameOutputs(const gi::GiState& a, const gi::GiState& b) {
    bool ok = sameBits(a.shade.ambient.v, b.shade.ambient.v);
    for (int c = 0; c < 3; ++c) {
        const std::size_t i = static_cast<std::size_t>(c);
        ok = ok && sameBits(a.shade.rgb[i].v, b.shade.rgb[i].v) &&
             sameBits(a.indirect.indirect[i].v, b.indirect.indirect[i].v) &&
             sameBits(a.indirect.total[i].v, b.indirect.total[i].v);
    }
    const std::vector<double>&ma = a.indirect.bounceMean, &mb = b.indirect.bounceMean;
    return ok && ma.size() == mb.size() &&
           (ma.empty() || std::memcmp(ma.data(), mb.data(), ma.size() * sizeof(double)) == 0);
}

// Runs one frame of the incremental state `inc` and the same frame on a fresh
// state with incremental frames off; true when every output is the same bit
// for bit.
inline bool incrementalMatchesFull(const Grid& h, float cellSize, const gi::GiLighting& light, const gi::GiSettings& s,
                                   gi::GiState& inc) {
    gi::runGiFrame(h.cview(), cellSize, light, s, inc);
    gi::GiSettings off = s;
    off.incremental = false;
    gi::GiState full;
    gi::runGiFrame(h.cview(), cellSize, light, off, full);
    return sameOutputs(inc, full);
}

// An RGB radiance with change(x, y, channel) added at every texel (clamped
// at 0 when asked), and per texel the largest |change| over the channels.
struct ChangedRadiance {
    std::array<Grid, 3> after;
    Grid dL;
};
inline ChangedRadiance changedRadiance(const std::array<Grid, 3>& base,
                                       const std::function<float(int, int, int)>& change, bool clampAtZero) {
    const int nx = base[0].nx, ny = base[0].ny;
    ChangedRadiance out{base, Grid(nx, ny)};
    for (int y = 0; y < ny; ++y)
        for (int x = 0; x < nx; ++x)
            for (std::size_t c = 0; c < 3; ++c) {
                float& v = out.after[c](x, y);
                v += change(x, y, static_cast<int>(c));
                if (clampAtZero) v = std::max(0.0f, v);
                out.dL(x, y) = std::max(out.dL(x, y), std::fabs(v - base[c](x, y)));
            }
    return out;
}

}  // namespace terrain::gi_test
