#include "render/terrain_lod.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <utility>

#include "core/error.h"
#include "core/parallel.h"
#include "core/simd.h"

namespace terrain::render {
namespace {

int ceilDiv(int a, int b) { return (a + b - 1) / b; }

// ---- index patterns ---------------------------------------------------------------------

// The vertex id a stitched side moves (i, j) to. Odd vertices of a stitched
// side collapse onto the even neighbour at the end of the quads' (a, d)
// diagonal: towards lower ids on the left and bottom sides, higher on the
// right and top. The two triangles of the pair of quads then become a fan
// from that vertex, with the side's middle vertex gone.
int stitchedId(int i, int j, int quads, int stitched) {
    if ((stitched & kSideBottom) && j == 0 && (i & 1)) --i;
    if ((stitched & kSideTop) && j == quads && (i & 1)) ++i;
    if ((stitched & kSideLeft) && i == 0 && (j & 1)) --j;
    if ((stitched & kSideRight) && i == quads && (j & 1)) ++j;
    return j * (quads + 1) + i;
}

// Appends quad (i, j)'s two triangles (a, b, d), (a, d, c) with `stitched`
// applied, leaving out those two of whose vertices collapsed onto one.
void appendQuad(int quads, int stitched, int i, int j, std::vector<ChunkTriangle>& out) {
    const auto id = [&](int di, int dj) {
        return static_cast<std::uint16_t>(stitchedId(i + di, j + dj, quads, stitched));
    };
    const std::uint16_t a = id(0, 0), b = id(1, 0), c = id(0, 1), d = id(1, 1);
    for (const ChunkTriangle& t : {ChunkTriangle{a, b, d}, ChunkTriangle{a, d, c}})
        if (t[0] != t[1] && t[1] != t[2] && t[0] != t[2]) out.push_back(t);
}

// A triangle that some stitch variant draws and the plain pattern does not,
// with the sides that every variant drawing it stitches.
struct StitchTriangle {
    ChunkTriangle v;
    int sides;
};

// Only the outer ring of quads changes with the stitched sides.
std::vector<StitchTriangle> stitchTriangles(int quads) {
    const auto ringTriangles = [quads](int stitched) {
        std::vector<ChunkTriangle> out;
        for (int j = 0; j < quads; ++j)
            for (int i = 0; i < quads; ++i)
                if (i == 0 || j == 0 || i == quads - 1 || j == quads - 1) appendQuad(quads, stitched, i, j, out);
        std::sort(out.begin(), out.end());
        return out;
    };
    const std::vector<ChunkTriangle> plain = ringTriangles(0);
    std::vector<StitchTriangle> all;
    for (int stitched = 1; stitched < kStitchVariants; ++stitched)
        for (const ChunkTriangle& t : ringTriangles(stitched))
            if (!std::binary_search(plain.begin(), plain.end(), t)) all.push_back({t, stitched});
    std::sort(all.begin(), all.end(), [](const StitchTriangle& a, const StitchTriangle& b) { return a.v < b.v; });
    std::vector<StitchTriangle> merged;
    for (const StitchTriangle& t : all) {
        if (!merged.empty() && merged.back().v == t.v)
            merged.back().sides &= t.sides;
        else
            merged.push_back(t);
    }
    return merged;
}

// ---- the drawn surfaces -----------------------------------------------------------------

// Depth (m) above which kMeshVertex puts a point of the water surface on the
// water; drier points sit 0.2 m under the ground, and kWaterFragment discards
// them (its threshold is larger), so a chunk with no deeper point shows no water.
constexpr float kWetDepth = 0.01f;

// One drawn surface in world units, row-major, nx wide.
struct Plane {
    const float* v;
    int nx;
    float operator()(int x, int y) const { return v[static_cast<std::size_t>(y) * nx + x]; }
    const float* row(int y) const { return v + static_cast<std::size_t>(y) * nx; }
};

// The surface as kMeshVertex places it, heights times the exaggeration, in
// the same float operations.
void fillSurface(const std::vector<float>& heights, float exag, LodSurface surface, ChunkTree& t) {
    const std::size_t n = static_cast<std::size_t>(t.nx) * t.ny;
    t.surface.resize(n);
    const bool water = surface == LodSurface::Water;
    parallelForRows(t.ny, t.nx, [&](int y0, int y1) {
        for (std::size_t i = static_cast<std::size_t>(y0) * t.nx; i < static_cast<std::size_t>(y1) * t.nx; ++i) {
            const float g = heights[2 * i], d = heights[2 * i + 1];
            t.surface[i] = water ? (d > kWetDepth ? g + d : g - 0.2f) * exag : g * exag;
        }
    });
}

// Largest |row[x] - (base + (x - xb) slope)| over x in [x0, x1): the deviation
// from one triangle along a grid row, four lanes at a time where it is long.
[[gnu::always_inline]] inline float segmentDeviation(const float* row, int x0, int x1, int xb, float base,
                                                     float slope) {
    using simd::F4;
    float m = 0.0f;
    int x = x0;
    if (x1 - x0 >= 8) {
        const F4 lane = {0.0f, 1.0f, 2.0f, 3.0f}, b4 = simd::splat<F4>(base), s4 = simd::splat<F4>(slope);
        F4 m4 = simd::splat<F4>(0.0f);
        for (; x + 4 <= x1; x += 4) {
            const F4 d = simd::load<F4>(row + x) - (b4 + (simd::splat<F4>(static_cast<float>(x - xb)) + lane) * s4);
            m4 = simd::vmax(m4, simd::vmax(d, -d));
        }
        m = std::max(std::max(m4[0], m4[1]), std::max(m4[2], m4[3]));
    }
    for (; x < x1; ++x) m = std::max(m, std::abs(row[x] - (base + static_cast<float>(x - xb) * slope)));
    return m;
}

// Smallest and largest of p[x] over x in [0, n), into lo and hi.
void rowRange(const float* p, int n, float& lo, float& hi) {
    using simd::F4;
    int x = 0;
    if (n >= 4) {
        F4 lo4 = simd::load<F4>(p), hi4 = lo4;
        for (x = 4; x + 4 <= n; x += 4) {
            const F4 v = simd::load<F4>(p + x);
            lo4 = simd::vmin(lo4, v);
            hi4 = simd::vmax(hi4, v);
        }
        lo = std::min({lo, lo4[0], lo4[1], lo4[2], lo4[3]});
        hi = std::max({hi, hi4[0], hi4[1], hi4[2], hi4[3]});
    }
    for (; x < n; ++x) {
        lo = std::min(lo, p[x]);
        hi = std::max(hi, p[x]);
    }
}

long long floorDiv(long long a, long long b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }  // b > 0

// Calls visit(y, lo, hi) for each row y of the triangle (px, py) with the
// grid points x in [lo, hi] inside it, edges included (none: lo > hi).
template <class Visit>
void forEachTriangleRow(const int (&px)[3], const int (&py)[3], Visit&& visit) {
    const long long area = static_cast<long long>(px[1] - px[0]) * (py[2] - py[0]) -
                           static_cast<long long>(py[1] - py[0]) * (px[2] - px[0]);
    const long long sign = area > 0 ? 1 : -1;
    for (int y = std::min({py[0], py[1], py[2]}); y <= std::max({py[0], py[1], py[2]}); ++y) {
        // inside: sign * cross(p_j - p_i, p - p_i) >= 0 for each edge, i.e. A x + B >= 0
        long long lo = std::min({px[0], px[1], px[2]}), hi = std::max({px[0], px[1], px[2]});
        for (int i = 0; i < 3; ++i) {
            const int j = (i + 1) % 3;
            const long long A = -sign * (py[j] - py[i]);
            const long long B = sign * (static_cast<long long>(px[j] - px[i]) * (y - py[i]) +
                                        static_cast<long long>(py[j] - py[i]) * px[i]);
            if (A > 0) lo = std::max(lo, -floorDiv(B, A));  // x >= ceil(-B / A)
            if (A < 0) hi = std::min(hi, floorDiv(B, -A));  // x <= floor(B / -A)
            if (A == 0 && B < 0) hi = lo - 1;
        }
        visit(y, static_cast<int>(lo), static_cast<int>(hi));
    }
}

// The plane through a triangle's vertices on surface s: h0 + beta (x - x0) + gamma (y - y0).
struct TrianglePlane {
    float h0 = 0, beta = 0, gamma = 0;
    int x0 = 0, y0 = 0;
    TrianglePlane() = default;
    TrianglePlane(const Plane& s, const int (&px)[3], const int (&py)[3]) : x0(px[0]), y0(py[0]) {
        const float area = static_cast<float>(static_cast<long long>(px[1] - px[0]) * (py[2] - py[0]) -
                                              static_cast<long long>(py[1] - py[0]) * (px[2] - px[0]));
        h0 = s(px[0], py[0]);
        const float dh1 = s(px[1], py[1]) - h0, dh2 = s(px[2], py[2]) - h0;
        beta = (dh1 * static_cast<float>(py[2] - py[0]) - dh2 * static_cast<float>(py[1] - py[0])) / area;
        gamma = (dh2 * static_cast<float>(px[1] - px[0]) - dh1 * static_cast<float>(px[2] - px[0])) / area;
    }
    float rowDeviation(const Plane& s, int y, int lo, int hi) const {
        return segmentDeviation(s.row(y), lo, hi + 1, x0, h0 + gamma * static_cast<float>(y - y0), beta);
    }
};

// A stitch triangle's vertices for the chunk at (x0, y0) of a level with
// `step`, clamped to the grid; false when it has no area there.
bool placeTriangle(const StitchTriangle& tri, int quads, int x0, int y0, int step, int nx, int ny, int (&px)[3],
                   int (&py)[3]) {
    for (std::size_t v = 0; v < 3; ++v) {
        px[v] = std::min(x0 + (tri.v[v] % (quads + 1)) * step, nx - 1);
        py[v] = std::min(y0 + (tri.v[v] / (quads + 1)) * step, ny - 1);
    }
    return static_cast<long long>(px[1] - px[0]) * (py[2] - py[0]) !=
           static_cast<long long>(py[1] - py[0]) * (px[2] - px[0]);
}

// Where the stitch triangles cover grid points other than their vertices
// (there they deviate by nothing), for the unclamped chunks of one level:
// per triangle its vertices and plane weights relative to the chunk's first
// grid point, and rows of x intervals. Shared by every chunk of the level, so
// a chunk's stitch error is one pass over them.
struct StitchSpan {
    int dy, dx0, dx1;
};
struct StitchPattern {
    struct Triangle {
        int sides;             // the stitched sides it needs
        int vx[3], vy[3];      // vertices, grid points from the chunk's first
        float b1, b2, g1, g2;  // beta = b1 dh1 + b2 dh2, gamma = g1 dh1 + g2 dh2 (dh_i = h_i - h_0)
        int first, count;      // its spans
    };
    std::vector<Triangle> triangles;
    std::vector<StitchSpan> spans;
};
StitchPattern stitchPattern(const std::vector<StitchTriangle>& tris, int quads, int step) {
    StitchPattern p;
    const int big = (quads + 1) * step;  // no clamping
    for (const StitchTriangle& tri : tris) {
        StitchPattern::Triangle t{};
        if (!placeTriangle(tri, quads, 0, 0, step, big, big, t.vx, t.vy)) continue;
        const float area = static_cast<float>(static_cast<long long>(t.vx[1] - t.vx[0]) * (t.vy[2] - t.vy[0]) -
                                              static_cast<long long>(t.vy[1] - t.vy[0]) * (t.vx[2] - t.vx[0]));
        t.sides = tri.sides;
        t.b1 = static_cast<float>(t.vy[2] - t.vy[0]) / area;
        t.b2 = -static_cast<float>(t.vy[1] - t.vy[0]) / area;
        t.g1 = -static_cast<float>(t.vx[2] - t.vx[0]) / area;
        t.g2 = static_cast<float>(t.vx[1] - t.vx[0]) / area;
        t.first = static_cast<int>(p.spans.size());
        forEachTriangleRow(t.vx, t.vy, [&](int y, int lo, int hi) {
            // a vertex in this row is an end of its interval (triangles are convex)
            for (int pass = 0; pass < 2; ++pass)
                for (int v = 0; v < 3; ++v) {
                    if (t.vy[v] == y && t.vx[v] == lo) ++lo;
                    if (t.vy[v] == y && t.vx[v] == hi) --hi;
                }
            if (lo <= hi) p.spans.push_back({y, lo, hi});
        });
        t.count = static_cast<int>(p.spans.size()) - t.first;
        if (t.count > 0) p.triangles.push_back(t);
    }
    return p;
}

// ---- the tree ---------------------------------------------------------------------------

// Lays out the levels: level k has ceil((n - 1) / (quads 2^k)) chunks a side,
// up to the first level with one chunk.
void layOut(ChunkTree& t) {
    t.levels.clear();
    if (t.nx < 2 || t.ny < 2) return;
    for (int k = 0;; ++k) {
        ChunkTree::Level L;
        const int span = t.quads << k;
        L.nodesX = ceilDiv(t.nx - 1, span);
        L.nodesY = ceilDiv(t.ny - 1, span);
        const std::size_t n = static_cast<std::size_t>(L.nodesX) * L.nodesY;
        L.error.assign(n, 0.0f);
        L.sideError.assign(4 * n, 0.0f);
        L.zMin.assign(n, 0.0f);
        L.zMax.assign(n, 0.0f);
        L.wet.assign(n, 0);
        t.levels.push_back(std::move(L));
        if (t.levels.back().nodesX == 1 && t.levels.back().nodesY == 1) return;
    }
}

// Level 0: each chunk's height range over its grid points and, for the water
// surface's tree, whether one of them is under water.
void rangesLevel0(const std::vector<float>& heights, LodSurface surface, ChunkTree& t) {
    const bool water = surface == LodSurface::Water;
    ChunkTree::Level& L = t.levels[0];
    parallelFor(0, L.nodesX * L.nodesY, 1, [&](int b, int e) {
        for (int n = b; n < e; ++n) {
            const int x0 = (n % L.nodesX) * t.quads, y0 = (n / L.nodesX) * t.quads;
            const int x1 = std::min(x0 + t.quads, t.nx - 1), y1 = std::min(y0 + t.quads, t.ny - 1);
            float lo = t.surface[static_cast<std::size_t>(y0) * t.nx + x0], hi = lo;
            bool wet = false;
            for (int y = y0; y <= y1; ++y) {
                rowRange(Plane{t.surface.data(), t.nx}.row(y) + x0, x1 - x0 + 1, lo, hi);
                for (int x = x0; x <= x1 && water && !wet; ++x)
                    wet = heights[2 * (static_cast<std::size_t>(y) * t.nx + x) + 1] > kWetDepth;
            }
            L.zMin[static_cast<std::size_t>(n)] = lo;
            L.zMax[static_cast<std::size_t>(n)] = hi;
            L.wet[static_cast<std::size_t>(n)] = wet ? 1 : 0;
        }
    });
}

// Level k >= 1, plain pattern: the largest deviation over each chunk's grid
// points (its last row and column included), into L.error. Along each grid row
// the level's triangles are linear between the quad's columns and its split
// point: (a, d, c) where u < v, i.e. (x - qx0) h < (y - qy0) w, and (a, b, d)
// elsewhere (a = (qx0, qy0), d = (qx1, qy1); quads clamped at the grid's end
// are narrower). Rows of coarse quads run in parallel, each writing its own
// row of per-chunk maxima; the rows are then folded per chunk.
void plainErrors(const std::vector<Plane>& surfaces, ChunkTree& t, int k, std::vector<float>& rowMax) {
    ChunkTree::Level& L = t.levels[static_cast<std::size_t>(k)];
    const int step = 1 << k, span = t.quads << k, rows = ceilDiv(t.ny - 1, step), nx = t.nx;
    rowMax.assign(static_cast<std::size_t>(rows) * L.nodesX, 0.0f);
    parallelFor(0, rows, std::max(1, 16384 / (nx * step)), [&](int rb, int re) {
        for (int r = rb; r < re; ++r) {
            const int qy0 = r * step, qy1 = std::min(qy0 + step, t.ny - 1), h = qy1 - qy0;
            const int chunkTop = std::min((qy0 / span + 1) * span, t.ny - 1);
            const int yEnd = qy1 == chunkTop ? qy1 + 1 : qy1;  // a chunk's last row is its own too
            float* m = rowMax.data() + static_cast<std::size_t>(r) * L.nodesX;
            const float ih = 1.0f / static_cast<float>(h);
            for (const Plane& s : surfaces) {
                const float *r0 = s.row(qy0), *r1 = s.row(qy1);
                for (int i = 0; i < L.nodesX; ++i) {
                    const int cx0 = i * span, cx1 = std::min(cx0 + span, nx - 1);
                    float dev = 0.0f;
                    for (int qx0 = cx0; qx0 < cx1; qx0 += step) {
                        const int qx1 = std::min(qx0 + step, cx1), w = qx1 - qx0;
                        const int xEnd = qx1 == cx1 ? qx1 + 1 : qx1;  // a chunk's last column is its own too
                        const float a = r0[qx0], b = r0[qx1], c = r1[qx0], d = r1[qx1];
                        const float iw = 1.0f / static_cast<float>(w);
                        const float upperSlope = (d - c) * iw, lowerSlope = (b - a) * iw;
                        for (int y = qy0; y < yEnd; ++y) {
                            const int dy = y - qy0;
                            const float v = static_cast<float>(dy) * ih;
                            const int split = std::min(qx1, qx0 + (w == h ? dy : ceilDiv(dy * w, h)));
                            const float* row = s.row(y);
                            dev = std::max({dev, segmentDeviation(row, qx0, split, qx0, a + v * (c - a), upperSlope),
                                            segmentDeviation(row, split, xEnd, qx0, a + v * (d - b), lowerSlope)});
                        }
                    }
                    m[i] = std::max(m[i], dev);
                }
            }
        }
    });
    for (int r = 0; r < rows; ++r) {
        const std::size_t j = static_cast<std::size_t>(r * step / span);
        for (int i = 0; i < L.nodesX; ++i) {
            float& e = L.error[j * L.nodesX + i];
            e = std::max(e, rowMax[static_cast<std::size_t>(r) * L.nodesX + i]);
        }
    }
}

// Level 1, the plain pattern's deviation as a stencil (what plainErrors gives
// for step 2, without its per-quad set-up): a grid point off the vertices of
// every other row and column lies midway along a quad's edge or its (a, d)
// diagonal. The grid's last row and column are vertices (clamped), and points
// beside them lie on a vertical or horizontal edge.
void levelOneErrors(const std::vector<Plane>& surfaces, ChunkTree& t, std::vector<float>& rowMax) {
    using simd::F4;
    ChunkTree::Level& L = t.levels[1];
    const int nx = t.nx, ny = t.ny, span = 2 * t.quads;
    rowMax.assign(static_cast<std::size_t>(ny) * L.nodesX, 0.0f);
    parallelForRows(ny, nx, [&](int yb, int ye) {
        std::vector<float> dev(static_cast<std::size_t>(nx));
        for (int y = yb; y < ye; ++y) {
            float* m = rowMax.data() + static_cast<std::size_t>(y) * L.nodesX;
            for (const Plane& s : surfaces) {
                const float* row = s.row(y);
                dev[0] = dev[static_cast<std::size_t>(nx - 1)] = 0.0f;
                if (y % 2 == 0 || y == ny - 1) {  // a row of vertices: odd points mid-edge
                    for (int x = 1; x < nx - 1; ++x)
                        dev[static_cast<std::size_t>(x)] =
                            x % 2 ? std::abs(row[x] - 0.5f * (row[x - 1] + row[x + 1])) : 0.0f;
                } else {  // between: even points mid vertical edge, odd ones mid diagonal
                    const float *below = s.row(y - 1), *above = s.row(y + 1);
                    const auto vertical = [&](int x) { return std::abs(row[x] - 0.5f * (below[x] + above[x])); };
                    dev[0] = vertical(0);
                    dev[static_cast<std::size_t>(nx - 1)] = vertical(nx - 1);
                    const F4 half = simd::splat<F4>(0.5f);
                    const auto odd = F4{0.0f, 1.0f, 0.0f, 1.0f} > simd::splat<F4>(0.5f);  // x0 even
                    int x = 2;
                    for (; x + 4 <= nx - 1; x += 4) {
                        const F4 h = simd::load<F4>(row + x);
                        const F4 v = h - half * (simd::load<F4>(below + x) + simd::load<F4>(above + x));
                        const F4 d = h - half * (simd::load<F4>(below + x - 1) + simd::load<F4>(above + x + 1));
                        const F4 e = odd ? d : v;
                        simd::store(dev.data() + x, simd::vmax(e, -e));
                    }
                    if (nx > 2) dev[1] = std::abs(row[1] - 0.5f * (below[0] + above[2]));
                    for (; x < nx - 1; ++x)
                        dev[static_cast<std::size_t>(x)] =
                            x % 2 ? std::abs(row[x] - 0.5f * (below[x - 1] + above[x + 1])) : vertical(x);
                }
                for (int i = 0; i < L.nodesX; ++i) {
                    const int x0 = i * span, x1 = std::min(x0 + span, nx - 1);
                    float mi = m[i];
                    for (int x = x0; x <= x1; ++x) mi = std::max(mi, dev[static_cast<std::size_t>(x)]);
                    m[i] = mi;
                }
            }
        }
    });
    for (int y = 0; y < ny; ++y)
        for (int j = std::max(0, (y - 1) / span); j <= std::min(y / span, L.nodesY - 1); ++j)
            if (y >= j * span && y <= std::min((j + 1) * span, ny - 1))
                for (int i = 0; i < L.nodesX; ++i) {
                    float& e = L.error[static_cast<std::size_t>(j) * L.nodesX + i];
                    e = std::max(e, rowMax[static_cast<std::size_t>(y) * L.nodesX + i]);
                }
}

// Every level below the root: per side, the deviation of the triangles the
// stitch variants add with that side stitched (a corner's, with two sides, to
// both), into L.sideError; a side on the grid's border is never stitched.
// Chunks clamped at the grid's end scan their own triangles; the others use
// the level's spans.
void stitchErrors(const std::vector<Plane>& surfaces, ChunkTree& t, const std::vector<StitchTriangle>& tris) {
    std::vector<StitchPattern> patterns;
    std::vector<std::pair<int, int>> chunks;  // (level, chunk)
    for (int k = 0; k + 1 < static_cast<int>(t.levels.size()); ++k) {
        patterns.push_back(stitchPattern(tris, t.quads, 1 << k));
        const ChunkTree::Level& L = t.levels[static_cast<std::size_t>(k)];
        for (int n = 0; n < L.nodesX * L.nodesY; ++n) chunks.emplace_back(k, n);
    }
    parallelFor(0, static_cast<int>(chunks.size()), 16, [&](int b, int e) {
        for (int c = b; c < e; ++c) {
            const auto [k, n] = chunks[static_cast<std::size_t>(c)];
            ChunkTree::Level& L = t.levels[static_cast<std::size_t>(k)];
            const int step = 1 << k, span = t.quads << k;
            const int x0 = (n % L.nodesX) * span, y0 = (n / L.nodesX) * span;
            const bool clamped = x0 + span > t.nx - 1 || y0 + span > t.ny - 1;
            const int border = (x0 == 0 ? kSideLeft : 0) | (y0 == 0 ? kSideBottom : 0) |
                               (x0 + span >= t.nx - 1 ? kSideRight : 0) | (y0 + span >= t.ny - 1 ? kSideTop : 0);
            float dev[4] = {0.0f, 0.0f, 0.0f, 0.0f};
            const auto raise = [&dev](int sides, float d) {
                for (int side = 0; side < 4; ++side)
                    if (sides & (1 << side)) dev[side] = std::max(dev[side], d);
            };
            for (const Plane& s : surfaces) {
                if (clamped) {
                    for (const StitchTriangle& tri : tris) {
                        int px[3], py[3];
                        if ((tri.sides & border) || !placeTriangle(tri, t.quads, x0, y0, step, t.nx, t.ny, px, py))
                            continue;
                        const TrianglePlane plane(s, px, py);
                        float d = 0.0f;
                        forEachTriangleRow(
                            px, py, [&](int y, int lo, int hi) { d = std::max(d, plane.rowDeviation(s, y, lo, hi)); });
                        raise(tri.sides, d);
                    }
                    continue;
                }
                const StitchPattern& p = patterns[static_cast<std::size_t>(k)];
                for (const StitchPattern::Triangle& tri : p.triangles) {
                    if (tri.sides & border) continue;
                    const float h0 = s(x0 + tri.vx[0], y0 + tri.vy[0]);
                    const float dh1 = s(x0 + tri.vx[1], y0 + tri.vy[1]) - h0;
                    const float dh2 = s(x0 + tri.vx[2], y0 + tri.vy[2]) - h0;
                    const float beta = tri.b1 * dh1 + tri.b2 * dh2, gamma = tri.g1 * dh1 + tri.g2 * dh2;
                    float d = 0.0f;
                    for (int i = tri.first; i < tri.first + tri.count; ++i) {
                        const StitchSpan& sp = p.spans[static_cast<std::size_t>(i)];
                        const float base = h0 + gamma * static_cast<float>(sp.dy - tri.vy[0]);
                        d = std::max(d, segmentDeviation(s.row(y0 + sp.dy), x0 + sp.dx0, x0 + sp.dx1 + 1,
                                                         x0 + tri.vx[0], base, beta));
                    }
                    raise(tri.sides, d);
                }
            }
            for (int side = 0; side < 4; ++side)
                L.sideError[4 * static_cast<std::size_t>(n) + static_cast<std::size_t>(side)] = dev[side];
        }
    });
}

// Coarser levels: ranges and water from the children; errors made monotonic.
void foldLevels(ChunkTree& t) {
    for (std::size_t k = 1; k < t.levels.size(); ++k) {
        const ChunkTree::Level& C = t.levels[k - 1];
        ChunkTree::Level& L = t.levels[k];
        for (int j = 0; j < L.nodesY; ++j)
            for (int i = 0; i < L.nodesX; ++i) {
                const std::size_t n = static_cast<std::size_t>(j) * L.nodesX + i;
                bool first = true;
                for (int cj = 2 * j; cj < std::min(2 * j + 2, C.nodesY); ++cj)
                    for (int ci = 2 * i; ci < std::min(2 * i + 2, C.nodesX); ++ci) {
                        const std::size_t c = static_cast<std::size_t>(cj) * C.nodesX + ci;
                        L.zMin[n] = first ? C.zMin[c] : std::min(L.zMin[n], C.zMin[c]);
                        L.zMax[n] = first ? C.zMax[c] : std::max(L.zMax[n], C.zMax[c]);
                        L.error[n] = std::max(L.error[n], C.error[c]);
                        L.wet[n] = L.wet[n] | C.wet[c];
                        first = false;
                    }
            }
    }
}

// ---- selection --------------------------------------------------------------------------

void chunkBox(const ChunkTree& t, int k, int i, int j, float (&lo)[3], float (&hi)[3]) {
    const ChunkTree::Level& L = t.levels[static_cast<std::size_t>(k)];
    const int span = t.quads << k;
    const std::size_t n = static_cast<std::size_t>(j) * L.nodesX + i;
    lo[0] = static_cast<float>(i * span) * t.cellSize;
    lo[1] = static_cast<float>(j * span) * t.cellSize;
    hi[0] = static_cast<float>(std::min((i + 1) * span, t.nx - 1)) * t.cellSize;
    hi[1] = static_cast<float>(std::min((j + 1) * span, t.ny - 1)) * t.cellSize;
    lo[2] = L.zMin[n];
    hi[2] = L.zMax[n];
}

float distanceToBox(const float (&eye)[3], const float (&lo)[3], const float (&hi)[3]) {
    float d2 = 0.0f;
    for (int a = 0; a < 3; ++a) {
        const float d = std::max({lo[a] - eye[a], 0.0f, eye[a] - hi[a]});
        d2 += d * d;
    }
    return std::sqrt(d2);
}

// The largest angle (radians, small-angle) that a vertical segment of unit
// length subtends anywhere in the box: cos(phi) / D at horizontal distance h
// and height v below the eye, phi the ray's elevation, i.e. h / (h^2 + v^2)
// (render/terrain_lod.h says why only this part of a vertical error shows).
// 1 / (distance to the box) bounds it too.
float angularSizeBound(const float (&eye)[3], const float (&lo)[3], const float (&hi)[3]) {
    const float d = distanceToBox(eye, lo, hi);
    const float below = eye[2] - hi[2];  // the eye's height over the box's top
    if (below <= 0.0f) return d > 0.0f ? 1.0f / d : std::numeric_limits<float>::infinity();
    float near2 = 0.0f, far2 = 0.0f;
    for (int a = 0; a < 2; ++a) {
        const float n = std::max({lo[a] - eye[a], 0.0f, eye[a] - hi[a]});
        const float f = std::max(std::abs(eye[a] - lo[a]), std::abs(eye[a] - hi[a]));
        near2 += n * n;
        far2 += f * f;
    }
    // h / (h^2 + v^2) falls with v and peaks at h = v
    const float h = std::clamp(below, std::sqrt(near2), std::sqrt(far2));
    return std::min(1.0f / d, h / (h * h + below * below));
}

// Sets the finest chunks (cells) under chunk (k, i, j) to the level the
// screen-space error asks for, splitting from the root down.
void chooseLevels(const ChunkTree& t, const LodView& v, int k, int i, int j, std::vector<std::int8_t>& cells) {
    const ChunkTree::Level& L = t.levels[static_cast<std::size_t>(k)];
    if (i >= L.nodesX || j >= L.nodesY) return;
    float lo[3], hi[3];
    chunkBox(t, k, i, j, lo, hi);
    const float error = L.error[static_cast<std::size_t>(j) * L.nodesX + i];
    if (k > 0 && error * v.pixelsPerUnit * angularSizeBound(v.eye, lo, hi) > v.pixelError) {
        for (int c = 0; c < 4; ++c) chooseLevels(t, v, k - 1, 2 * i + (c & 1), 2 * j + (c >> 1), cells);
        return;
    }
    const ChunkTree::Level& fine = t.levels[0];
    for (int cy = j << k; cy < std::min((j + 1) << k, fine.nodesY); ++cy)
        for (int cx = i << k; cx < std::min((i + 1) << k, fine.nodesX); ++cx)
            cells[static_cast<std::size_t>(cy) * fine.nodesX + cx] = static_cast<std::int8_t>(k);
}

// Refines until neighbours differ by at most one level: a chunk beside one
// two levels finer is split into its four children, and the scan repeats.
void balance(int cellsX, int cellsY, std::vector<std::int8_t>& cells) {
    const auto at = [&](int x, int y) -> std::int8_t& { return cells[static_cast<std::size_t>(y) * cellsX + x]; };
    for (bool changed = true; changed;) {
        changed = false;
        for (int cy = 0; cy < cellsY; ++cy)
            for (int cx = 0; cx < cellsX; ++cx) {
                const int k = at(cx, cy);
                const bool tooCoarse = (cx > 0 && k > at(cx - 1, cy) + 1) || (cy > 0 && k > at(cx, cy - 1) + 1) ||
                                       (cx + 1 < cellsX && k > at(cx + 1, cy) + 1) ||
                                       (cy + 1 < cellsY && k > at(cx, cy + 1) + 1);
                if (!tooCoarse) continue;
                const int bx = (cx >> k) << k, by = (cy >> k) << k;
                for (int y = by; y < std::min(by + (1 << k), cellsY); ++y)
                    for (int x = bx; x < std::min(bx + (1 << k), cellsX); ++x)
                        at(x, y) = static_cast<std::int8_t>(k - 1);
                changed = true;
            }
    }
}

// The cell across `side` of the chunk of level k whose first cell is (cx, cy).
void cellAcross(int side, int cx, int cy, int k, int& x, int& y) {
    x = side == kSideLeft ? cx - 1 : (side == kSideRight ? cx + (1 << k) : cx);
    y = side == kSideBottom ? cy - 1 : (side == kSideTop ? cy + (1 << k) : cy);
}

// Where a stitched side's error, projected from its chunk, exceeds the bound,
// splits the coarser neighbour across it, so that the side needs no stitch.
// Returns whether it split any.
bool splitCoarseNeighbours(const ChunkTree& t, const LodView& v, std::vector<std::int8_t>& cells) {
    const int cellsX = t.levels[0].nodesX, cellsY = t.levels[0].nodesY;
    const auto at = [&](int x, int y) -> std::int8_t& { return cells[static_cast<std::size_t>(y) * cellsX + x]; };
    bool split = false;
    for (int cy = 0; cy < cellsY; ++cy)
        for (int cx = 0; cx < cellsX; ++cx) {
            const int k = at(cx, cy);
            if ((cx & ((1 << k) - 1)) || (cy & ((1 << k) - 1))) continue;  // not the chunk's first cell
            const ChunkTree::Level& L = t.levels[static_cast<std::size_t>(k)];
            const std::size_t n = static_cast<std::size_t>(cy >> k) * L.nodesX + static_cast<std::size_t>(cx >> k);
            float lo[3], hi[3];
            chunkBox(t, k, cx >> k, cy >> k, lo, hi);
            const float pixelsPerUnitError = v.pixelsPerUnit * angularSizeBound(v.eye, lo, hi);
            for (int bit = 0; bit < 4; ++bit) {
                int x, y;
                cellAcross(1 << bit, cx, cy, k, x, y);
                if (x < 0 || y < 0 || x >= cellsX || y >= cellsY || at(x, y) != k + 1) continue;
                if (L.sideError[4 * n + static_cast<std::size_t>(bit)] * pixelsPerUnitError <= v.pixelError) continue;
                const int bx = (x >> (k + 1)) << (k + 1), by = (y >> (k + 1)) << (k + 1);
                for (int yy = by; yy < std::min(by + (2 << k), cellsY); ++yy)
                    for (int xx = bx; xx < std::min(bx + (2 << k), cellsX); ++xx)
                        at(xx, yy) = static_cast<std::int8_t>(k);
                split = true;
            }
        }
    return split;
}

}  // namespace

std::vector<ChunkTriangle> chunkTriangles(int quads, int stitched) {
    std::vector<ChunkTriangle> out;
    out.reserve(static_cast<std::size_t>(quads) * quads * 2);
    for (int j = 0; j < quads; ++j)
        for (int i = 0; i < quads; ++i) appendQuad(quads, stitched, i, j, out);
    return out;
}

void buildChunkTree(const std::vector<float>& heights, int nx, int ny, float cellSize, float exaggeration,
                    LodSurface surface, int quads, ChunkTree& tree) {
    if (quads < 4 || quads > 254 || quads % 2 != 0) throw InputError("LOD chunks need an even 4..254 quads a side");
    if (heights.size() != 2 * static_cast<std::size_t>(std::max(nx, 0)) * static_cast<std::size_t>(std::max(ny, 0)))
        throw InputError("LOD: the heights are not 2 per texel of the grid");
    tree.nx = nx;
    tree.ny = ny;
    tree.quads = quads;
    tree.cellSize = cellSize;
    layOut(tree);
    if (tree.levels.empty()) return;
    fillSurface(heights, exaggeration, surface, tree);
    const std::vector<Plane> surfaces{{tree.surface.data(), nx}};
    rangesLevel0(heights, surface, tree);
    std::vector<float> rowMax;
    for (int k = 1; k < static_cast<int>(tree.levels.size()); ++k) {
        if (k == 1)
            levelOneErrors(surfaces, tree, rowMax);
        else
            plainErrors(surfaces, tree, k, rowMax);
    }
    stitchErrors(surfaces, tree, stitchTriangles(quads));
    foldLevels(tree);
}

void selectChunks(const ChunkTree& t, const LodView& v, ChunkSelection& out) {
    out.chunks.clear();
    if (t.levels.empty()) return;
    const int cellsX = t.levels[0].nodesX, cellsY = t.levels[0].nodesY;
    out.cellLevel.assign(static_cast<std::size_t>(cellsX) * cellsY, 0);
    chooseLevels(t, v, static_cast<int>(t.levels.size()) - 1, 0, 0, out.cellLevel);
    balance(cellsX, cellsY, out.cellLevel);
    while (splitCoarseNeighbours(t, v, out.cellLevel)) balance(cellsX, cellsY, out.cellLevel);
    const auto at = [&](int x, int y) {
        return static_cast<int>(out.cellLevel[static_cast<std::size_t>(y) * cellsX + x]);
    };
    std::vector<std::pair<float, std::size_t>> order;
    for (int cy = 0; cy < cellsY; ++cy)
        for (int cx = 0; cx < cellsX; ++cx) {
            const int k = at(cx, cy), size = 1 << k;
            if ((cx & (size - 1)) || (cy & (size - 1))) continue;  // not the chunk's first cell
            LodChunk c;
            c.level = k;
            c.x0 = cx * t.quads;
            c.y0 = cy * t.quads;
            // a side beside a coarser chunk takes its vertices (that chunk spans the whole side)
            for (int side : {kSideLeft, kSideRight, kSideBottom, kSideTop}) {
                int x, y;
                cellAcross(side, cx, cy, k, x, y);
                if (x >= 0 && y >= 0 && x < cellsX && y < cellsY && at(x, y) == k + 1) c.stitched |= side;
            }
            float lo[3], hi[3];
            chunkBox(t, k, cx >> k, cy >> k, lo, hi);
            const ChunkTree::Level& L = t.levels[static_cast<std::size_t>(k)];
            c.wet = L.wet[static_cast<std::size_t>(cy >> k) * L.nodesX + static_cast<std::size_t>(cx >> k)] != 0;
            std::copy(lo, lo + 3, c.boxMin);
            std::copy(hi, hi + 3, c.boxMax);
            order.emplace_back(distanceToBox(v.eye, lo, hi), out.chunks.size());
            out.chunks.push_back(c);
        }
    // nearest first, so that the depth test rejects what nearer chunks hide
    std::sort(order.begin(), order.end());
    std::vector<LodChunk> sorted;
    sorted.reserve(order.size());
    for (const auto& [d, n] : order) sorted.push_back(out.chunks[n]);
    out.chunks.swap(sorted);
}

bool boxInClipVolume(const float m[16], const float lo[3], const float hi[3]) {
    // The planes w +- x_r >= 0 of clip space (Gribb & Hartmann 2001): row r of
    // the column-major matrix is m[r], m[4 + r], m[8 + r], m[12 + r].
    for (int p = 0; p < 6; ++p) {
        const int r = p / 2;
        const double sign = (p & 1) ? -1.0 : 1.0;
        double n[4];
        for (int c = 0; c < 4; ++c) n[c] = static_cast<double>(m[4 * c + 3]) + sign * m[4 * c + r];
        // the corner furthest along the plane's normal
        double dot = n[3];
        for (int a = 0; a < 3; ++a) dot += n[a] * (n[a] >= 0 ? hi[a] : lo[a]);
        if (dot < 0) return false;
    }
    return true;
}

}  // namespace terrain::render
