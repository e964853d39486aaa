#include "sim/terrain.h"

#include <cmath>
#include <cstdio>
#include <cstring>

#include "core/error.h"
#include "core/parallel.h"
#include "core/size_limits.h"

namespace terrain {

void checkDimensions(int nx, int ny, float cellSize) {
    if (nx < 1 || ny < 1)
        throw InputError("grid size " + std::to_string(nx) + " x " + std::to_string(ny) + " is empty or negative");
    if (nx > kMaxGridSide || ny > kMaxGridSide)
        throw InputError("grid size " + std::to_string(nx) + " x " + std::to_string(ny) + " exceeds the limit of " +
                         std::to_string(kMaxGridSide) + " per side");
    if (!std::isfinite(cellSize) || cellSize <= 0.0f || cellSize > 1e6f)
        throw InputError("cell size " + std::to_string(cellSize) + " m is not a positive finite size up to 1e6 m");
}

void TerrainState::allocate(int w, int h, float cell, const LayerSet& layers) {
    checkDimensions(w, h, cell);
    nx = w;
    ny = h;
    cellSize = cell;
    bedrock.resize(w, h);
    soil.resize(w, h);
    auto opt = [&](Grid& g, bool on, int gw, int gh) {
        if (on)
            g.resize(gw, gh);
        else
            g = Grid();
    };
    opt(water, layers.water || layers.sediment || layers.pipes || layers.faceVelocity, w, h);
    opt(suspended, layers.sediment, w, h);
    for (Grid* g : {&fluxL, &fluxR, &fluxT, &fluxB, &velX, &velY}) opt(*g, layers.pipes, w, h);
    opt(faceU, layers.faceVelocity, w + 1, h);
    opt(faceV, layers.faceVelocity, w, h + 1);
    time = 0.0;
    tick = 0;
}

void TerrainState::groundHeight(Grid& out) const {
    out.ensureSize(nx, ny);
    const float* b = bedrock.data();
    const float* s = soil.data();
    float* o = out.data();
    parallelForRows(ny, nx, [&](int y0, int y1) {
        for (std::size_t i = static_cast<std::size_t>(y0) * nx; i < static_cast<std::size_t>(y1) * nx; ++i)
            o[i] = b[i] + s[i];
    });
}

void checkFinite(const TerrainState& s) {
    const struct {
        const char* name;
        const Grid* g;
    } layers[] = {{"bedrock", &s.bedrock}, {"soil", &s.soil},   {"water", &s.water}, {"suspended", &s.suspended},
                  {"fluxL", &s.fluxL},     {"fluxR", &s.fluxR}, {"fluxT", &s.fluxT}, {"fluxB", &s.fluxB},
                  {"velX", &s.velX},       {"velY", &s.velY},   {"faceU", &s.faceU}, {"faceV", &s.faceV}};
    for (const auto& l : layers) {
        const Grid& g = *l.g;
        for (std::size_t i = 0; i < g.v.size(); ++i) {
            if (!std::isfinite(g.v[i])) {
                const int x = static_cast<int>(i % static_cast<std::size_t>(g.nx));
                const int y = static_cast<int>(i / static_cast<std::size_t>(g.nx));
                throw InputError(std::string("layer '") + l.name + "' has a non-finite value (" +
                                 std::to_string(g.v[i]) + ") at x=" + std::to_string(x) + ", y=" + std::to_string(y));
            }
        }
    }
}

namespace {
// 64-bit FNV-1a over 8-byte words, then a final avalanche (splitmix64).
// Word-wise keeps it fast on 1024^2 grids; the order of words is fixed, so
// the result does not depend on threads.
struct Hasher {
    std::uint64_t h = 0xcbf29ce484222325ull;
    void word(std::uint64_t w) {
        h ^= w;
        h *= 0x100000001b3ull;
    }
    void bytes(const void* p, std::size_t n) {
        const auto* c = static_cast<const unsigned char*>(p);
        std::size_t i = 0;
        for (; i + 8 <= n; i += 8) {
            std::uint64_t w;
            std::memcpy(&w, c + i, 8);
            word(w);
        }
        std::uint64_t tail = 0;
        if (n > i) std::memcpy(&tail, c + i, n - i);  // (c may be null when n == 0)
        word(tail ^ (static_cast<std::uint64_t>(n - i) << 56));
    }
    std::uint64_t finish() const {
        std::uint64_t z = h + 0x9e3779b97f4a7c15ull;
        z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
        z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
        return z ^ (z >> 31);
    }
};
}  // namespace

std::uint64_t hashState(const TerrainState& s) {
    Hasher h;
    h.word(static_cast<std::uint64_t>(s.nx));
    h.word(static_cast<std::uint64_t>(s.ny));
    std::uint32_t cs;
    std::memcpy(&cs, &s.cellSize, 4);
    h.word(cs);
    std::uint64_t t;
    std::memcpy(&t, &s.time, 8);
    h.word(t);
    h.word(static_cast<std::uint64_t>(s.tick));
    for (const Grid* g : {&s.bedrock, &s.soil, &s.water, &s.suspended, &s.fluxL, &s.fluxR, &s.fluxT, &s.fluxB, &s.velX,
                          &s.velY, &s.faceU, &s.faceV}) {
        h.word(g->v.size());
        h.bytes(g->v.data(), g->v.size() * sizeof(float));
    }
    return h.finish();
}

std::string hashHex(std::uint64_t h) {
    char buf[17];
    std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
    return buf;
}

}  // namespace terrain
