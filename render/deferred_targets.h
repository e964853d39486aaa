#pragma once
// The off-screen targets of the renderer's deferred shading (render/shaders.h):
// the mesh passes write surface points, the shading passes read them and
// write HDR colour, the display passes tone map it and draw the sky into the
// displayed 8-bit image, and one depth-stencil buffer ties them together.
//
// The stencil says which surface a pixel shows: kTerrainStencil where the
// terrain was drawn, kWaterStencil where water was drawn over it, 0 for the
// sky. Each shading and display pass draws one full-screen triangle under a
// stencil test, so the rasteriser skips the pixels it has nothing to do on.
#include "render/gl.h"

namespace terrain::render {

inline constexpr int kTerrainStencil = 1;
inline constexpr int kWaterStencil = 2;

struct DeferredTargets {
    GLuint pointsFbo = 0;      // colour 0: terrain points, colour 1: water points; depth-stencil
    GLuint terrainFbo = 0;     // colour: terrain HDR; the same depth-stencil (stencil test only)
    GLuint waterFbo = 0;       // colour: water HDR; the same depth-stencil (stencil test only)
    GLuint displayFbo = 0;     // colour: the displayed image; the same depth-stencil (stencil test only)
    GLuint terrainPoints = 0;  // RGBA32F: grid x, grid y, world z, 1 (0: nothing drawn)
    GLuint waterPoints = 0;    // RGBA32F: as terrainPoints, for the water surface
    GLuint terrainColor = 0;   // RGBA16F: the lit terrain (where the terrain's stencil is)
    GLuint waterColor = 0;     // RGBA16F: the lit water (where the water's stencil is)
    GLuint displayColor = 0;   // RGBA8: tone mapped, sRGB encoded
    GLuint depthStencil = 0;   // DEPTH24_STENCIL8
    int w = 0, h = 0;

    /// Creates (or re-creates at a new size) every target; throws
    /// ContextError if a framebuffer is incomplete. Binds textures to the
    /// active unit.
    void ensure(const Gl& gl, int width, int height);
    void release(const Gl& gl);
};

}  // namespace terrain::render
