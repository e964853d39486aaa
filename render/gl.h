#pragma once
// The OpenGL function table. Every entry point the renderer uses is
// loaded once through a get-proc-address callback (glfwGetProcAddress or
// OSMesaGetProcAddress) into one struct typed with the PFN typedefs of
// <GL/glcorearb.h>; both platforms share it. Nothing here links against libGL.
#include <string>

#include <GL/glcorearb.h>

namespace terrain::render {

/// A platform's get-proc-address: name -> entry point (null when missing).
using GlProc = void (*)();
using GlGetProcAddress = GlProc (*)(const char* name);  // same alias as in render/context.h

// X(member, PFN name part): member `Clear` is loaded from "glClear" with type PFNGLCLEARPROC.
// clang-format off (one entry a line, sorted; the formatter would reflow the list)
#define TERRAIN_GL_FUNCTIONS(X)                       \
    X(ActiveTexture, ACTIVETEXTURE)                   \
    X(AttachShader, ATTACHSHADER)                     \
    X(BindBuffer, BINDBUFFER)                         \
    X(BindFramebuffer, BINDFRAMEBUFFER)               \
    X(BindTexture, BINDTEXTURE)                       \
    X(BindVertexArray, BINDVERTEXARRAY)               \
    X(BlendFunc, BLENDFUNC)                           \
    X(BlitFramebuffer, BLITFRAMEBUFFER)               \
    X(BufferData, BUFFERDATA)                         \
    X(CheckFramebufferStatus, CHECKFRAMEBUFFERSTATUS) \
    X(Clear, CLEAR)                                   \
    X(ClearColor, CLEARCOLOR)                         \
    X(ClearDepth, CLEARDEPTH)                         \
    X(ClearStencil, CLEARSTENCIL)                     \
    X(CompileShader, COMPILESHADER)                   \
    X(CreateProgram, CREATEPROGRAM)                   \
    X(CreateShader, CREATESHADER)                     \
    X(CullFace, CULLFACE)                             \
    X(DeleteBuffers, DELETEBUFFERS)                   \
    X(DeleteFramebuffers, DELETEFRAMEBUFFERS)         \
    X(DeleteProgram, DELETEPROGRAM)                   \
    X(DeleteShader, DELETESHADER)                     \
    X(DeleteTextures, DELETETEXTURES)                 \
    X(DeleteVertexArrays, DELETEVERTEXARRAYS)         \
    X(DepthFunc, DEPTHFUNC)                           \
    X(DepthMask, DEPTHMASK)                           \
    X(Disable, DISABLE)                               \
    X(DrawArrays, DRAWARRAYS)                         \
    X(DrawBuffers, DRAWBUFFERS)                       \
    X(DrawElements, DRAWELEMENTS)                     \
    X(Enable, ENABLE)                                 \
    X(Finish, FINISH)                                 \
    X(FramebufferTexture2D, FRAMEBUFFERTEXTURE2D)     \
    X(GenBuffers, GENBUFFERS)                         \
    X(GenFramebuffers, GENFRAMEBUFFERS)               \
    X(GenTextures, GENTEXTURES)                       \
    X(GenVertexArrays, GENVERTEXARRAYS)               \
    X(GetError, GETERROR)                             \
    X(GetIntegerv, GETINTEGERV)                       \
    X(GetProgramInfoLog, GETPROGRAMINFOLOG)           \
    X(GetProgramiv, GETPROGRAMIV)                     \
    X(GetShaderInfoLog, GETSHADERINFOLOG)             \
    X(GetShaderiv, GETSHADERIV)                       \
    X(GetString, GETSTRING)                           \
    X(GetUniformLocation, GETUNIFORMLOCATION)         \
    X(LinkProgram, LINKPROGRAM)                       \
    X(PixelStorei, PIXELSTOREI)                       \
    X(PolygonOffset, POLYGONOFFSET)                   \
    X(ReadBuffer, READBUFFER)                         \
    X(ReadPixels, READPIXELS)                         \
    X(ShaderSource, SHADERSOURCE)                     \
    X(StencilFunc, STENCILFUNC)                       \
    X(StencilOp, STENCILOP)                           \
    X(TexImage2D, TEXIMAGE2D)                         \
    X(TexParameterfv, TEXPARAMETERFV)                 \
    X(TexParameteri, TEXPARAMETERI)                   \
    X(TexSubImage2D, TEXSUBIMAGE2D)                   \
    X(Uniform1f, UNIFORM1F)                           \
    X(Uniform1i, UNIFORM1I)                           \
    X(Uniform2f, UNIFORM2F)                           \
    X(Uniform2i, UNIFORM2I)                           \
    X(Uniform3f, UNIFORM3F)                           \
    X(Uniform3fv, UNIFORM3FV)                         \
    X(Uniform4f, UNIFORM4F)                           \
    X(UniformMatrix4fv, UNIFORMMATRIX4FV)             \
    X(UseProgram, USEPROGRAM)                         \
    X(Viewport, VIEWPORT)
// clang-format on

/// Every GL entry point the renderer calls: gl.Clear(...) is glClear(...).
struct Gl {
#define TERRAIN_GL_MEMBER(name, upper) PFNGL##upper##PROC name = nullptr;
    TERRAIN_GL_FUNCTIONS(TERRAIN_GL_MEMBER)
#undef TERRAIN_GL_MEMBER
};

/// Loads every entry point through `getProc` (with a context current).
/// Throws ContextError naming the first missing function, and when the
/// context is older than OpenGL 3.3.
void loadGl(Gl& gl, GlGetProcAddress getProc);

/// "OpenGL 4.5 (Core Profile) Mesa 22.3.6, llvmpipe (LLVM 15.0.6, 256 bits)".
std::string glDescription(const Gl& gl);

/// Throws ContextError with `what` and the GL error code when glGetError reports one.
void checkGlError(const Gl& gl, const char* what);

}  // namespace terrain::render
