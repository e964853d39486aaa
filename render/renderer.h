#pragma once
// The OpenGL 3.3 core renderer shared by the window and the headless path.
//
// Per frame: upload the heights (one RG32F texture: ground, water depth) and
// the GI textures of FrameData; draw the terrain mesh (one vertex per grid
// point, positions fetched from the height texture by gl_VertexID, two
// triangles per quad) into an HDR target; draw water as a second surface
// (ground + depth) blended over the lit terrain; tone map and encode sRGB.
//
// Materials (Heidrich & Seidel 1999): Torrance-Sparrow specular for the key light
// (Beckmann distribution, Smith geometry term, Schlick's Fresnel), modulated
// by the key light's visibility (the engine's soft visibility, or a classic
// shadow map); water reflects a prefiltered environment map (the
// sky's order-4 SH, a band-limited hence prefiltered map, baked to a small
// equirectangular texture) weighted by Fresnel: L = F L_m + (1 - F) L_d
// (Section 4.4), L_d the water body and the lit terrain seen through it.
#include <cstdint>
#include <vector>

#include "engine/frame_data.h"
#include "render/gl.h"

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
};

struct OrbitCamera {
    float yawDeg = 235.0f;   // azimuth of the eye around the terrain centre, from +x towards +y
    float pitchDeg = 34.0f;  // elevation of the eye
    float distance = 1.35f;  // in terrain extents
    float fovYDeg = 40.0f;
};

struct RenderSettings {
    ShadowMode shadow = ShadowMode::SoftVisibility;
    DebugView debug = DebugView::None;
    float exposure = 1.0f;
    bool water = true;
    bool specular = true;
    int shadowMapSize = 2048;
    OrbitCamera camera;
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
    void drawShadowMap(const FrameViews& v);
    void drawSurfaces(const RenderSettings& s, const FrameViews& v, int width, int height, bool wantShadowMap);
    void surfaceUniforms(GLuint p, int water, const RenderSettings& s, const FrameViews& v, bool wantShadowMap);
    void drawPost(const RenderSettings& s, const FrameViews& v, int width, int height, GLuint framebuffer);

    const Gl& gl_;
    GLuint terrainProgram_ = 0, waterProgram_ = 0, shadowProgram_ = 0, postProgram_ = 0;
    GLuint vao_ = 0, indexBuffer_ = 0;
    std::int64_t indexCount_ = 0;
    int meshNx_ = 0, meshNy_ = 0;
    GLuint heightTex_ = 0, shadeTex_ = 0, keyTex_ = 0, receiverTex_ = 0, envTex_ = 0, albedoTex_ = 0;
    int heightW_ = 0, heightH_ = 0, shadeW_ = 0, shadeH_ = 0, keyW_ = 0, keyH_ = 0, recvW_ = 0, recvH_ = 0, envW_ = 0,
        envH_ = 0, albedoW_ = 0, albedoH_ = 0;
    std::int64_t albedoVersion_ = -1;  // FrameData::albedoVersion of the uploaded albedo
    Target hdr_, ldr_, shadow_;
    engine::FrameData meta_;  // the uploaded frame's sizes, lights and modes (no per-texel arrays)
    std::vector<float> envPixels_;
};

/// FNV-1a 64-bit hash of image bytes (for determinism checks).
std::uint64_t hashBytes(const std::vector<std::uint8_t>& bytes);

}  // namespace terrain::render
