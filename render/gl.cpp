#include "render/gl.h"

#include <cstdio>

#include "render/context.h"

namespace terrain::render {

void loadGl(Gl& gl, GlGetProcAddress getProc) {
    if (!getProc) throw ContextError("OpenGL: no get-proc-address callback");
#define TERRAIN_GL_LOAD(name, upper)                                     \
    gl.name = reinterpret_cast<PFNGL##upper##PROC>(getProc("gl" #name)); \
    if (!gl.name) throw ContextError("OpenGL: the context does not provide gl" #name);
    TERRAIN_GL_FUNCTIONS(TERRAIN_GL_LOAD)
#undef TERRAIN_GL_LOAD
    GLint major = 0, minor = 0;
    gl.GetIntegerv(GL_MAJOR_VERSION, &major);
    gl.GetIntegerv(GL_MINOR_VERSION, &minor);
    if (major * 10 + minor < 33)
        throw ContextError("OpenGL 3.3 or newer is needed; the context has " + std::to_string(major) + "." +
                           std::to_string(minor));
}

std::string glDescription(const Gl& gl) {
    auto str = [&](GLenum e) {
        const GLubyte* s = gl.GetString(e);
        return s ? std::string(reinterpret_cast<const char*>(s)) : std::string("?");
    };
    return "OpenGL " + str(GL_VERSION) + ", " + str(GL_RENDERER);
}

void checkGlError(const Gl& gl, const char* what) {
    const GLenum e = gl.GetError();
    if (e != GL_NO_ERROR) {
        char code[16];
        std::snprintf(code, sizeof code, "0x%04x", static_cast<unsigned>(e));
        throw ContextError(std::string("OpenGL error ") + code + " in " + what);
    }
}

}  // namespace terrain::render
