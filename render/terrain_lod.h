#pragma once
// Chunked level of detail for the terrain mesh, after Ulrich 2002 ("Rendering
// massive terrains using chunked level of detail control").
//
// A quadtree of square chunks: a chunk of level k has quads x quads quads
// that sample every 2^k-th grid point, so it covers quads * 2^k grid quads a
// side and the one root covers the grid. Every chunk of every level is drawn
// with the same index patterns, one draw per chunk with its first grid point
// and step as uniforms; positions still come from the height texture, so
// nothing per vertex is uploaded per frame. A quadtree rather than a fixed
// grid of chunks with per-chunk levels: far terrain costs one draw per large
// chunk instead of many draws of a few triangles each. Vertices past the
// grid's last row or column are clamped onto it (the shader does the same),
// so any grid size works; power-of-two sizes waste at most one quad column.
//
// Level choice. Each chunk of each level carries a geometric error: the
// largest vertical distance, over every grid point it covers, between the
// full-resolution surface and the chunk's triangles, made monotonic (a chunk's
// error is at least its children's) so that a refined selection never has a
// larger error; and per side the same for the triangles that side adds when
// it is stitched. Both are computed exactly on the CPU when the heights are
// uploaded: every grid point once per level, in parallel. Per frame a chunk is
// split while its error projected from its bounding box exceeds the threshold
// in pixels: Ulrich's rho = delta K / D (K = viewport height / (2 tan(fovY /
// 2)), D the distance to the box) times cos(phi), phi the elevation of the
// view ray, bounded over the box: a vertical error seen from above moves the
// surface across the ray by only that much, and the shading follows the
// surface point (normals come from the height texture at full resolution).
// Where a stitched side's error would exceed it, the coarser neighbour is
// split instead, so that the side needs no stitch.
//
// One tree per drawn surface (LodSurface): the ground, and the water surface
// as the vertex shader places it. Each mesh pass selects its own chunks, so
// a choppy sea does not refine the flat bed under it, nor a rough bed a calm
// sea.
//
// Cracks: neighbouring chunks differ by at most one level (a restricted
// quadtree: the selection is refined until it is), and a chunk beside a
// coarser one draws that side with its odd vertices collapsed onto an even
// neighbour (one of 16 index variants, one per set of stitched sides). The
// shared edge then has exactly the coarser chunk's vertices, fetched from the
// same texels by the same shader, so the mesh is watertight for the terrain,
// the water surface and the shadow pass alike, and no extra geometry is
// drawn. Skirts would hang below every edge and show through the water
// surface, which is drawn without depth writes; geomorphing (Strugar 2009,
// "Continuous distance-dependent level of detail for rendering heightmaps")
// ties each level to a distance band rather than to an error bound.
#include <array>
#include <cstdint>
#include <vector>

namespace terrain::render {

/// Quads per chunk side at every level (even; (quads + 1)^2 vertex ids fit 16
/// bits). Smaller chunks follow the error more closely (fewer triangles) but
/// cost more draws and a longer error pass: 32 was the fastest of 16, 32 and
/// 64 for 1024^2 and 2048^2 fields (bench/results/render.md).
inline constexpr int kChunkQuads = 32;
/// RenderSettings::lodPixelError is in [0, kMaxLodPixelError].
inline constexpr float kMaxLodPixelError = 64.0f;

/// Sides of a chunk: the bits of a stitch mask (LodChunk::stitched, chunkTriangles).
inline constexpr int kSideLeft = 1, kSideRight = 2, kSideBottom = 4, kSideTop = 8;
inline constexpr int kStitchVariants = 16;

/// A triangle of a chunk pattern: local vertex ids j * (quads + 1) + i for the
/// vertex i steps along x and j along y from the chunk's first grid point.
using ChunkTriangle = std::array<std::uint16_t, 3>;

/// The triangles of a quads x quads chunk whose `stitched` sides are collapsed
/// to every other vertex, in quad row order; degenerate ones are left out.
/// With no side stitched: two triangles (a, b, d), (a, d, c) per quad, the
/// full mesh's split.
std::vector<ChunkTriangle> chunkTriangles(int quads, int stitched);

/// The surface a chunk tree follows: the ground, or the water surface as the
/// vertex shader places it (the ground plus the depth where wet, just under
/// the ground where dry).
enum class LodSurface { Ground, Water };

/// Bounds of every chunk of every level, computed from the heights on upload.
struct ChunkTree {
    struct Level {
        int nodesX = 0, nodesY = 0;  // chunks of this level along x and y
        // per chunk (row-major), world units (heights x exaggeration):
        std::vector<float> error;       // geometric error, monotonic towards the root
        std::vector<float> sideError;   // 4 per chunk (left, right, bottom, top): of the triangles a stitched side adds
        std::vector<float> zMin, zMax;  // range of the surface
        std::vector<std::uint8_t> wet;  // 1: some grid point is under water (water tree only; ground: 0)
    };
    int nx = 0, ny = 0;
    int quads = kChunkQuads;
    float cellSize = 1.0f;
    std::vector<Level> levels;  // [0] full resolution ... back(): the root, one chunk
    // scratch of buildChunkTree: the drawn surface in world units, row-major
    std::vector<float> surface;
};

/// Fills `tree` for an nx x ny grid of `heights` (2 per texel: ground, water
/// depth, m) with chunks of `quads` quads (even, 4..254: with 2, a chunk
/// stitched on every side folds onto a fin), its errors and bounds those of
/// `surface`; the wet flags are set in the water surface's tree only (the
/// water pass skips dry chunks). Parallel; bit-identical for any thread count.
void buildChunkTree(const std::vector<float>& heights, int nx, int ny, float cellSize, float exaggeration,
                    LodSurface surface, int quads, ChunkTree& tree);

/// The camera as the level choice sees it.
struct LodView {
    float eye[3] = {0, 0, 0};  // world
    float pixelsPerUnit = 1;   // viewport height / (2 tan(fovY / 2))
    float pixelError = 1;      // largest projected error, pixels (> 0)
};

/// One chunk of a selection.
struct LodChunk {
    int level = 0;                // samples every 2^level-th grid point
    int x0 = 0, y0 = 0;           // first grid point
    int stitched = 0;             // sides drawn with the coarser neighbour's vertices
    bool wet = false;             // the water surface shows somewhere on it
    float boxMin[3] = {0, 0, 0};  // world bounding box of the drawn surfaces
    float boxMax[3] = {0, 0, 0};
};

/// A frame's chunks, and the selection's working state.
struct ChunkSelection {
    std::vector<LodChunk> chunks;        // cover the grid once, nearest first
    std::vector<std::int8_t> cellLevel;  // level per finest chunk (scratch)
};

/// Chooses the chunks for `view`: a pure function of the tree and the view.
/// Every chunk's projected error, with its stitched sides', is within
/// view.pixelError (unless it is at full resolution and unstitched), and
/// neighbours differ by at most one level.
void selectChunks(const ChunkTree& tree, const LodView& view, ChunkSelection& out);

/// Whether the box can intersect the clip volume of `viewProj` (column-major
/// 4 x 4, OpenGL clip space): false only when it lies outside one plane.
bool boxInClipVolume(const float viewProj[16], const float boxMin[3], const float boxMax[3]);

}  // namespace terrain::render
