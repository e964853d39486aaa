#include "render/deferred_targets.h"

#include <string>

#include "render/context.h"

namespace terrain::render {
namespace {

// A w x h texture of `internal` format, nearest filtering (texels are read
// one per pixel or as the march's samples, never blended).
GLuint newTexture(const Gl& gl, GLenum internal, int w, int h, GLenum format, GLenum type) {
    GLuint tex = 0;
    gl.GenTextures(1, &tex);
    gl.BindTexture(GL_TEXTURE_2D, tex);
    gl.TexImage2D(GL_TEXTURE_2D, 0, static_cast<GLint>(internal), w, h, 0, format, type, nullptr);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    return tex;
}

// A framebuffer with `colors` as its colour attachments 0, 1, ... and the
// shared depth-stencil texture.
GLuint newFramebuffer(const Gl& gl, std::initializer_list<GLuint> colors, GLuint depthStencil, int w, int h) {
    GLuint fbo = 0;
    gl.GenFramebuffers(1, &fbo);
    gl.BindFramebuffer(GL_FRAMEBUFFER, fbo);
    GLenum attachment = GL_COLOR_ATTACHMENT0;
    for (GLuint c : colors) gl.FramebufferTexture2D(GL_FRAMEBUFFER, attachment++, GL_TEXTURE_2D, c, 0);
    gl.FramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_STENCIL_ATTACHMENT, GL_TEXTURE_2D, depthStencil, 0);
    if (gl.CheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        throw ContextError("OpenGL: incomplete deferred framebuffer " + std::to_string(w) + " x " + std::to_string(h));
    return fbo;
}

}  // namespace

void DeferredTargets::ensure(const Gl& gl, int width, int height) {
    if (pointsFbo && w == width && h == height) return;
    release(gl);
    terrainPoints = newTexture(gl, GL_RGBA32F, width, height, GL_RGBA, GL_FLOAT);
    waterPoints = newTexture(gl, GL_RGBA32F, width, height, GL_RGBA, GL_FLOAT);
    terrainColor = newTexture(gl, GL_RGBA16F, width, height, GL_RGBA, GL_FLOAT);
    waterColor = newTexture(gl, GL_RGBA16F, width, height, GL_RGBA, GL_FLOAT);
    displayColor = newTexture(gl, GL_RGBA8, width, height, GL_RGBA, GL_UNSIGNED_BYTE);
    depthStencil = newTexture(gl, GL_DEPTH24_STENCIL8, width, height, GL_DEPTH_STENCIL, GL_UNSIGNED_INT_24_8);
    pointsFbo = newFramebuffer(gl, {terrainPoints, waterPoints}, depthStencil, width, height);
    terrainFbo = newFramebuffer(gl, {terrainColor}, depthStencil, width, height);
    waterFbo = newFramebuffer(gl, {waterColor}, depthStencil, width, height);
    displayFbo = newFramebuffer(gl, {displayColor}, depthStencil, width, height);
    w = width;
    h = height;
}

void DeferredTargets::release(const Gl& gl) {
    const GLuint fbos[] = {pointsFbo, terrainFbo, waterFbo, displayFbo};
    const GLuint textures[] = {terrainPoints, waterPoints, terrainColor, waterColor, displayColor, depthStencil};
    if (pointsFbo) gl.DeleteFramebuffers(4, fbos);
    if (terrainPoints) gl.DeleteTextures(6, textures);
    *this = {};
}

}  // namespace terrain::render
