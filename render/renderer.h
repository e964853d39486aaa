#pragma once
// The OpenGL 3.3 core renderer shared by the window and the headless path.
//
// Per frame: upload the heights (one RG32F texture: ground, water depth) and
// the GI textures of FrameData; draw the terrain mesh (chunks whose
// resolution follows the screen-space error, render/terrain_lod.h; positions
// fetched from the height texture by gl_VertexID) and the water as a second
// surface (ground + depth, the same chunks) with deferred shading
// (render/deferred_targets.h): the mesh passes record only the surface point
// each pixel sees, then one full-screen pass lights the terrain's pixels and
// one the water's (which reflects the lit terrain); tone map and encode sRGB
// with the sky behind.
//
// Materials (Heidrich & Seidel 1999): Torrance-Sparrow specular for the key light
// (Beckmann distribution, Smith geometry term, Schlick's Fresnel), modulated
// by the key light's visibility (the engine's soft visibility, or a classic
// shadow map); water reflects a prefiltered environment map (the
// sky's order-4 SH, a band-limited hence prefiltered map, baked to a small
// equirectangular texture) weighted by Fresnel: L = F L_m + (1 - F) L_d
// (Section 4.4), L_d the water body and the lit terrain seen through it.
#include <array>
#include <cstdint>
#include <map>
#include <vector>

#include "engine/frame_data.h"
#include "render/deferred_targets.h"
#include "render/gl.h"
#include "render/sky.h"
#include "render/terrain_lod.h"

namespace terrain::render {

enum class ShadowMode { SoftVisibility, ShadowMap, None };

enum class DebugView {
    None,
    Ambient,           // gi/ ambient map (normal-weighted sky-view factor)
    SkyVisibility,     // V: visible fraction of the sky hemisphere (V's constant term), receiver grid
    KeyVisibility,     // the key light's soft visibility
    Normals,           // full-resolution normals
    PyramidLevel,      // one height-pyramid level, receiver grid
    ShadeMap,          // the GI's diffuse result: sky, key light and indirect light, with the albedo
    IndirectRadiance,  // U: mean incident indirect radiance (U's constant term, or E / pi without U), receiver grid
    Albedo,            // the materials' albedo map: the GI's albedo and the base colour
    // the hydrology maps (sim/hydrology.h), each over its largest magnitude
    // in the frame; they need PipelineSettings::hydrologyMaps
    Discharge,   // sqrt(discharge / max): black to blue, so small streams show beside rivers
    Velocity,    // velocity / max, grey
    NetErosion,  // net erosion / max |net erosion|: white unchanged, red eroded, blue deposited
    Wetness,     // fraction of ticks wet: sand to blue
};

struct OrbitCamera {
    float yawDeg = 235.0f;   // azimuth of the eye around the terrain centre, from +x towards +y
    float pitchDeg = 34.0f;  // elevation of the eye
    float distance = 1.35f;  // in terrain extents
    float fovYDeg = 40.0f;
    // the point looked at: fractions of the extent along x and y, of the relief along z
    float targetX = 0.5f, targetY = 0.5f, targetZ = 0.5f;
};

struct RenderSettings {
    ShadowMode shadow = ShadowMode::SoftVisibility;
    DebugView debug = DebugView::None;
    float exposure = 1.0f;
    bool water = true;
    bool specular = true;
    int shadowMapSize = 2048;
    // Level of detail: the largest screen-space error of the mesh, in pixels
    // (render/terrain_lod.h), in [0, kMaxLodPixelError]; 0: the full grid,
    // one vertex per grid point everywhere. The shading is full resolution
    // either way.
    float lodPixelError = 1.0f;
    OrbitCamera camera;
};

/// What the last draw() drew of the terrain mesh.
struct DrawStats {
    std::int64_t triangles = 0;         // every mesh pass: shadow map, terrain, water
    std::int64_t terrainTriangles = 0;  // the terrain pass alone
    int terrainChunks = 0;              // chunks the terrain pass drew (0: the full grid in one draw)
};

class Renderer {
public:
    /// Compiles the shaders; throws ContextError on a GL failure.
    explicit Renderer(const Gl& gl);
    ~Renderer();
    Renderer(const Renderer&) = delete;
    Renderer& operator=(const Renderer&) = delete;

    /// Streams the frame's heights and GI textures to the GPU.
    void upload(const engine::FrameData& frame);
    /// Draws the last uploaded frame into `framebuffer` (0: the window) of size w x h.
    void draw(const RenderSettings& settings, int width, int height, GLuint framebuffer);
    /// Headless: draws into an own 8-bit target and reads it back as RGB, row 0 at the top.
    void drawToImage(const RenderSettings& settings, int width, int height, std::vector<std::uint8_t>& rgb);
    /// Where the eye of `camera` is (world metres, z exaggerated) for the
    /// uploaded frame: never under the terrain, whatever the camera asks.
    std::array<float, 3> eyeOf(const OrbitCamera& camera) const;
    /// Triangles and chunks of the last draw().
    const DrawStats& lastDrawStats() const { return stats_; }

private:
    struct Target {
        GLuint fbo = 0, color = 0, depth = 0;
        int w = 0, h = 0;
    };
    void ensureTarget(Target& t, int w, int h, GLenum colorFormat, bool depth);
    void releaseTarget(Target& t);
    void ensureTexture(GLuint& tex, int& w, int& h, int nw, int nh, GLenum internal, GLenum format, bool linear);
    /// ensureTexture (linear) and the texels of `data` (nw x nh float texels of `format`).
    void streamTexture(GLuint& tex, int& w, int& h, int nw, int nh, GLenum internal, GLenum format, const float* data);
    // The passes of draw().
    struct FrameViews;
    FrameViews frameViews(const OrbitCamera& camera, int width, int height) const;
    float lowestEye(float x, float y, float nearPlane) const;
    void drawShadowMap(const FrameViews& v, bool lod);
    struct MeshCount {
        std::int64_t triangles = 0;
        int chunks = 0;
    };
    /// The terrain mesh with `program`: the full grid, or (lod) the selected
    /// chunks inside the clip volume of `cullViewProj` (column-major 4 x 4).
    MeshCount drawMesh(GLuint program, const float* cullViewProj, bool lod);
    /// The same mesh's triangles that can show water (render/water_triangles.h).
    MeshCount drawWaterMesh(GLuint program, const float* cullViewProj, bool lod);
    /// The full grid's index buffer, bound to the vertex array of draw().
    void ensureFullGrid();
    void drawSurfacePoints(const FrameViews& v, bool lod, bool water);
    void shadeSurfaces(const RenderSettings& s, const FrameViews& v, bool wantShadowMap, bool water);
    /// The terrain's or the water's shading program for these settings,
    /// compiled on first use.
    GLuint shadingProgram(bool water, const RenderSettings& s, bool wantShadowMap);
    void shadingUniforms(GLuint p, const FrameViews& v);
    /// Every pass of draw(); the image is left in deferred_.displayColor.
    void drawFrame(const RenderSettings& s, int width, int height);
    void drawDisplay(const RenderSettings& s, const FrameViews& v, bool water);

    const Gl& gl_;
    // pointsProgram_: the mesh passes; shadingPrograms_: the shading passes' variants
    GLuint pointsProgram_ = 0, shadowProgram_ = 0, displayProgram_ = 0, skyProgram_ = 0;
    std::map<int, GLuint> shadingPrograms_;
    GLuint vao_ = 0, indexBuffer_ = 0;
    std::int64_t indexCount_ = 0;  // of the full grid, built on its first draw
    int meshNx_ = 0, meshNy_ = 0;
    // Chunked LOD: the 16 stitch variants of one chunk's indices (16 bits,
    // one after another), the uploaded heights' chunk tree, the frame's chunks.
    GLuint chunkIndexBuffer_ = 0;
    std::vector<std::uint16_t> chunkIndices_;  // what chunkIndexBuffer_ holds
    int chunkFirst_[kStitchVariants] = {}, chunkCount_[kStitchVariants] = {};
    // The water pass's triangles: where the uploaded heights show water, and
    // the frame's triangles (one draw per chunk, or the full grid's).
    std::vector<std::uint8_t> shownWater_;
    GLuint waterIndexBuffer_ = 0;
    std::vector<std::uint16_t> waterChunkIndices_;
    std::vector<std::uint32_t> waterGridIndices_;
    // Level of detail per mesh pass: the ground's chunks (terrain, shadow map)
    // and the water surface's (only with water), each following its own surface.
    ChunkTree groundTree_, waterTree_;
    ChunkSelection groundChunks_, waterChunks_;
    DrawStats stats_;
    GLuint heightTex_ = 0, shadeTex_ = 0, keyTex_ = 0, receiverTex_ = 0, albedoTex_ = 0, hydrologyTex_ = 0;
    int heightW_ = 0, heightH_ = 0, shadeW_ = 0, shadeH_ = 0, keyW_ = 0, keyH_ = 0, recvW_ = 0, recvH_ = 0,
        albedoW_ = 0, albedoH_ = 0, hydrologyW_ = 0, hydrologyH_ = 0;
    // FrameData's versions of what was uploaded last
    std::int64_t heightsVersion_ = -1, albedoVersion_ = -1, shadeVersion_ = -1, hydrologyVersion_ = -1;
    Target shadow_;
    DeferredTargets deferred_;
    engine::FrameData meta_;  // the uploaded frame's sizes, lights and modes (no per-texel arrays)
    Sky sky_;
};

/// FNV-1a 64-bit hash of image bytes (for determinism checks).
std::uint64_t hashBytes(const std::vector<std::uint8_t>& bytes);

/// How two 8-bit RGB images of one size differ: per pixel the largest
/// |a - b| over R, G, B, its mean over the pixels and the fraction of pixels
/// where it exceeds `levels`.
struct ImageDifference {
    double mean = 0.0, fractionAbove = 0.0;
};
ImageDifference compareImages(const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b, int levels);

}  // namespace terrain::render
