#include "render/renderer.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <optional>
#include <string>

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>

#include "render/context.h"
#include "render/shaders.h"
#include "render/water_triangles.h"

namespace terrain::render {
namespace {

constexpr float kDeg = 0.017453292519943295f;

// When the shader or program `object` failed (its `status` is false): deletes
// it and returns its info log; otherwise nothing. Shaders and programs have
// entry points of the same types (glGetShaderiv / glGetProgramiv, ...).
std::optional<std::string> failureLog(PFNGLGETSHADERIVPROC getiv, PFNGLGETSHADERINFOLOGPROC getInfoLog,
                                      PFNGLDELETESHADERPROC del, GLuint object, GLenum status) {
    GLint ok = 0;
    getiv(object, status, &ok);
    if (ok) return std::nullopt;
    char log[2048] = {};
    getInfoLog(object, sizeof log, nullptr, log);
    del(object);
    return std::string(log);
}

GLuint compile(const Gl& gl, GLenum type, const std::vector<const char*>& sources, const char* name) {
    const GLuint s = gl.CreateShader(type);
    gl.ShaderSource(s, static_cast<GLsizei>(sources.size()), sources.data(), nullptr);
    gl.CompileShader(s);
    if (const auto log = failureLog(gl.GetShaderiv, gl.GetShaderInfoLog, gl.DeleteShader, s, GL_COMPILE_STATUS)) {
        std::string line(*log);
        for (char& c : line)
            if (c == '\n') c = ' ';
        throw ContextError(std::string("shader ") + name + " does not compile: " + line);
    }
    return s;
}

GLuint link(const Gl& gl, const std::vector<const char*>& vs, const std::vector<const char*>& fs, const char* name) {
    const GLuint v = compile(gl, GL_VERTEX_SHADER, vs, name);
    const GLuint f = compile(gl, GL_FRAGMENT_SHADER, fs, name);
    const GLuint p = gl.CreateProgram();
    gl.AttachShader(p, v);
    gl.AttachShader(p, f);
    gl.LinkProgram(p);
    gl.DeleteShader(v);
    gl.DeleteShader(f);
    if (const auto log = failureLog(gl.GetProgramiv, gl.GetProgramInfoLog, gl.DeleteProgram, p, GL_LINK_STATUS))
        throw ContextError(std::string("shader program ") + name + " does not link: " + *log);
    return p;
}

// Binds `tex` and gives it w x h texels of the `internal` format (contents
// undefined) and one filter for minification and magnification.
void defineTexture(const Gl& gl, GLuint tex, GLenum internal, int w, int h, GLenum format, GLenum type, GLint filter) {
    gl.BindTexture(GL_TEXTURE_2D, tex);
    gl.TexImage2D(GL_TEXTURE_2D, 0, static_cast<GLint>(internal), w, h, 0, format, type, nullptr);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, filter);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, filter);
}

struct Uniforms {
    const Gl& gl;
    GLuint p;
    GLint at(const char* n) const { return gl.GetUniformLocation(p, n); }
    void i(const char* n, int v) const { gl.Uniform1i(at(n), v); }
    void i2(const char* n, int a, int b) const { gl.Uniform2i(at(n), a, b); }
    void f(const char* n, float v) const { gl.Uniform1f(at(n), v); }
    void f2(const char* n, float a, float b) const { gl.Uniform2f(at(n), a, b); }
    void v3(const char* n, const glm::vec3& v) const { gl.Uniform3f(at(n), v.x, v.y, v.z); }
    void m4(const char* n, const glm::mat4& m) const { gl.UniformMatrix4fv(at(n), 1, GL_FALSE, glm::value_ptr(m)); }
};

glm::vec3 keyDirection(const gi::KeyLight& k) {
    const float ce = std::cos(k.elevationDeg * kDeg);
    return {ce * std::cos(k.azimuthDeg * kDeg), ce * std::sin(k.azimuthDeg * kDeg), std::sin(k.elevationDeg * kDeg)};
}

// The first key light (the sun) has the specular highlights and the shadow
// map; with none, a black light overhead.
gi::KeyLight sunOf(const engine::SceneLights& l) {
    if (!l.keys.empty()) return l.keys[0];
    gi::KeyLight dark;
    dark.elevationDeg = 90.0f;
    dark.rgb[0] = dark.rgb[1] = dark.rgb[2] = 0.0f;
    return dark;
}

}  // namespace

std::uint64_t hashBytes(const std::vector<std::uint8_t>& bytes) {
    std::uint64_t h = 1469598103934665603ull;
    for (std::uint8_t b : bytes) {
        h ^= b;
        h *= 1099511628211ull;
    }
    return h;
}

ImageDifference compareImages(const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b, int levels) {
    if (a.size() != b.size() || a.size() % 3 != 0) throw InputError("compareImages: two RGB images of one size");
    double sum = 0.0;
    std::size_t above = 0;
    for (std::size_t i = 0; i < a.size(); i += 3) {
        int d = 0;
        for (std::size_t c = 0; c < 3; ++c) d = std::max(d, std::abs(int(a[i + c]) - int(b[i + c])));
        sum += d;
        above += d > levels ? 1 : 0;
    }
    const double pixels = std::max<double>(1.0, static_cast<double>(a.size() / 3));
    return {sum / pixels, static_cast<double>(above) / pixels};
}

Renderer::Renderer(const Gl& gl) : gl_(gl), sky_(gl) {
    using namespace shaders;
    pointsProgram_ = link(gl_, {kMeshVertex}, {kSurfacePointFragment}, "surface points");
    shadowProgram_ = link(gl_, {kMeshVertex}, {kShadowFragment}, "shadow");
    const char* version = "#version 330 core\n";
    displayProgram_ = link(gl_, {kFullScreenVertex}, {version, kToneMap, kDisplayFragment}, "display");
    skyProgram_ = link(gl_, {kFullScreenVertex}, {version, kToneMap, kSkyFragment}, "sky");
    gl_.GenVertexArrays(1, &vao_);
    gl_.GenBuffers(1, &indexBuffer_);
    // One chunk's 16 stitch variants, one after another (render/terrain_lod.h).
    for (int stitched = 0; stitched < kStitchVariants; ++stitched) {
        chunkFirst_[stitched] = static_cast<int>(chunkIndices_.size());
        for (const ChunkTriangle& t : chunkTriangles(kChunkQuads, stitched))
            chunkIndices_.insert(chunkIndices_.end(), t.begin(), t.end());
        chunkCount_[stitched] = static_cast<int>(chunkIndices_.size()) - chunkFirst_[stitched];
    }
    gl_.GenBuffers(1, &chunkIndexBuffer_);
    gl_.GenBuffers(1, &waterIndexBuffer_);
    gl_.BindVertexArray(vao_);
    gl_.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, chunkIndexBuffer_);
    gl_.BufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(chunkIndices_.size() * sizeof(std::uint16_t)),
                   chunkIndices_.data(), GL_STATIC_DRAW);
    gl_.BindVertexArray(0);
    checkGlError(gl_, "renderer set-up");
}

Renderer::~Renderer() {
    deferred_.release(gl_);
    releaseTarget(shadow_);
    const GLuint textures[] = {heightTex_, shadeTex_, keyTex_, receiverTex_, albedoTex_, hydrologyTex_};
    gl_.DeleteTextures(6, textures);
    gl_.DeleteBuffers(1, &indexBuffer_);
    gl_.DeleteBuffers(1, &chunkIndexBuffer_);
    gl_.DeleteBuffers(1, &waterIndexBuffer_);
    gl_.DeleteVertexArrays(1, &vao_);
    for (GLuint p : {pointsProgram_, shadowProgram_, displayProgram_, skyProgram_}) gl_.DeleteProgram(p);
    for (const auto& [key, p] : shadingPrograms_) gl_.DeleteProgram(p);
}

void Renderer::ensureTexture(GLuint& tex, int& w, int& h, int nw, int nh, GLenum internal, GLenum format, bool linear) {
    if (tex && w == nw && h == nh) return;
    if (!tex) gl_.GenTextures(1, &tex);
    defineTexture(gl_, tex, internal, nw, nh, format, GL_FLOAT, linear ? GL_LINEAR : GL_NEAREST);
    gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    w = nw;
    h = nh;
}

void Renderer::streamTexture(GLuint& tex, int& w, int& h, int nw, int nh, GLenum internal, GLenum format,
                             const float* data) {
    ensureTexture(tex, w, h, nw, nh, internal, format, true);
    gl_.BindTexture(GL_TEXTURE_2D, tex);
    gl_.TexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, nw, nh, format, GL_FLOAT, data);
}

void Renderer::upload(const engine::FrameData& f) {
    gl_.PixelStorei(GL_UNPACK_ALIGNMENT, 4);
    // only what changed since the last upload (a paused or static scene: nothing)
    const bool newHeights = f.heightsVersion != heightsVersion_ || heightW_ != f.nx || heightH_ != f.ny;
    if (newHeights) {
        streamTexture(heightTex_, heightW_, heightH_, f.nx, f.ny, GL_RG32F, GL_RG, f.heights.data());
        heightsVersion_ = f.heightsVersion;
        if (f.hasWater) markShownWater(f.heights, shownWater_);
    }
    if (f.shadeVersion != shadeVersion_ || shadeW_ != f.nx || shadeH_ != f.ny || recvW_ != f.nxr || recvH_ != f.nyr) {
        streamTexture(shadeTex_, shadeW_, shadeH_, f.nx, f.ny, GL_RGBA32F, GL_RGBA, f.shade.data());
        streamTexture(keyTex_, keyW_, keyH_, f.nx, f.ny, GL_RGBA32F, GL_RGBA, f.key.data());
        streamTexture(receiverTex_, recvW_, recvH_, f.nxr, f.nyr, GL_RGBA32F, GL_RGBA, f.receiver.data());
        shadeVersion_ = f.shadeVersion;
    }
    if (f.albedoVersion != albedoVersion_ || albedoW_ != f.nx || albedoH_ != f.ny) {
        streamTexture(albedoTex_, albedoW_, albedoH_, f.nx, f.ny, GL_RGBA32F, GL_RGBA, f.albedo.data());
        albedoVersion_ = f.albedoVersion;
    }
    if (!f.hydrology.empty() &&
        (f.hydrologyVersion != hydrologyVersion_ || hydrologyW_ != f.nx || hydrologyH_ != f.ny)) {
        streamTexture(hydrologyTex_, hydrologyW_, hydrologyH_, f.nx, f.ny, GL_RGBA32F, GL_RGBA, f.hydrology.data());
        hydrologyVersion_ = f.hydrologyVersion;
    }

    sky_.upload(f.lights);

    // The chunks' errors and bounds follow the heights as drawn (render/terrain_lod.h).
    if (newHeights || groundTree_.levels.empty() || f.exaggeration != meta_.exaggeration ||
        f.hasWater != meta_.hasWater) {
        buildChunkTree(f.heights, f.nx, f.ny, f.cellSize, f.exaggeration, LodSurface::Ground, kChunkQuads, groundTree_);
        if (f.hasWater)
            buildChunkTree(f.heights, f.nx, f.ny, f.cellSize, f.exaggeration, LodSurface::Water, kChunkQuads,
                           waterTree_);
        else
            waterTree_ = ChunkTree{};
    }
    meta_.nx = f.nx;
    meta_.ny = f.ny;
    meta_.nxr = f.nxr;
    meta_.nyr = f.nyr;
    meta_.subsample = f.subsample;
    meta_.cellSize = f.cellSize;
    meta_.zMin = f.zMin;
    meta_.zMax = f.zMax;
    meta_.hasWater = f.hasWater;
    meta_.exaggeration = f.exaggeration;
    meta_.lights = f.lights;
    meta_.lighting = f.lighting;
    meta_.hydrologyMax = f.hydrologyMax;
    checkGlError(gl_, "upload");
}

void Renderer::ensureTarget(Target& t, int w, int h, GLenum colorFormat, bool depth) {
    if (t.fbo && t.w == w && t.h == h) return;
    releaseTarget(t);
    gl_.GenFramebuffers(1, &t.fbo);
    gl_.BindFramebuffer(GL_FRAMEBUFFER, t.fbo);
    if (colorFormat) {
        gl_.GenTextures(1, &t.color);
        const GLenum type = colorFormat == GL_RGBA8 ? GL_UNSIGNED_BYTE : GL_FLOAT;
        defineTexture(gl_, t.color, colorFormat, w, h, GL_RGBA, type, GL_NEAREST);
        gl_.FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, t.color, 0);
    }
    if (depth) {
        gl_.GenTextures(1, &t.depth);
        defineTexture(gl_, t.depth, GL_DEPTH_COMPONENT24, w, h, GL_DEPTH_COMPONENT, GL_FLOAT, GL_LINEAR);
        gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_BORDER);
        gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_BORDER);
        const float border[4] = {1.0f, 1.0f, 1.0f, 1.0f};
        gl_.TexParameterfv(GL_TEXTURE_2D, GL_TEXTURE_BORDER_COLOR, border);
        gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
        gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
        gl_.FramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, t.depth, 0);
    }
    if (!colorFormat) {
        const GLenum none = GL_NONE;
        gl_.DrawBuffers(1, &none);
        gl_.ReadBuffer(GL_NONE);
    }
    if (gl_.CheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        throw ContextError("OpenGL: incomplete framebuffer " + std::to_string(w) + " x " + std::to_string(h));
    t.w = w;
    t.h = h;
}

// Two triangles per quad, rebuilt only when the size changes.
void Renderer::ensureFullGrid() {
    if (meshNx_ == meta_.nx && meshNy_ == meta_.ny) return;
    const int nx = meta_.nx, ny = meta_.ny;
    std::vector<std::uint32_t> idx;
    idx.reserve(static_cast<std::size_t>(std::max(nx - 1, 0)) * std::max(ny - 1, 0) * 6);
    for (int y = 0; y + 1 < ny; ++y)
        for (int x = 0; x + 1 < nx; ++x) {
            const std::uint32_t a = static_cast<std::uint32_t>(y * nx + x), b = a + 1,
                                c = a + static_cast<std::uint32_t>(nx), d = c + 1;
            idx.insert(idx.end(), {a, b, d, a, d, c});
        }
    gl_.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, indexBuffer_);
    gl_.BufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(idx.size() * sizeof(std::uint32_t)), idx.data(),
                   GL_STATIC_DRAW);
    indexCount_ = static_cast<std::int64_t>(idx.size());
    meshNx_ = nx;
    meshNy_ = ny;
}

Renderer::MeshCount Renderer::drawMesh(GLuint program, const float* cullViewProj, bool lod) {
    const GLint origin = gl_.GetUniformLocation(program, "uOrigin"), step = gl_.GetUniformLocation(program, "uStep"),
                row = gl_.GetUniformLocation(program, "uRow");
    MeshCount n;
    if (!lod) {
        ensureFullGrid();
        gl_.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, indexBuffer_);
        gl_.Uniform2i(origin, 0, 0);
        gl_.Uniform1i(step, 1);
        gl_.Uniform1i(row, meta_.nx);
        gl_.DrawElements(GL_TRIANGLES, static_cast<GLsizei>(indexCount_), GL_UNSIGNED_INT, nullptr);
        n.triangles = indexCount_ / 3;
    } else {
        gl_.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, chunkIndexBuffer_);
        gl_.Uniform1i(row, kChunkQuads + 1);
        for (const LodChunk& c : groundChunks_.chunks) {
            if (!boxInClipVolume(cullViewProj, c.boxMin, c.boxMax)) continue;
            gl_.Uniform2i(origin, c.x0, c.y0);
            gl_.Uniform1i(step, 1 << c.level);
            const auto offset = static_cast<std::uintptr_t>(chunkFirst_[c.stitched]) * sizeof(std::uint16_t);
            gl_.DrawElements(GL_TRIANGLES, chunkCount_[c.stitched], GL_UNSIGNED_SHORT,
                             reinterpret_cast<const void*>(offset));
            n.triangles += chunkCount_[c.stitched] / 3;
            ++n.chunks;
        }
    }
    stats_.triangles += n.triangles;
    return n;
}

// The chunks' (or the full grid's) triangles that can show water, gathered
// into one stream index buffer, drawn in the same order as drawMesh's.
Renderer::MeshCount Renderer::drawWaterMesh(GLuint program, const float* cullViewProj, bool lod) {
    const GLint origin = gl_.GetUniformLocation(program, "uOrigin"), step = gl_.GetUniformLocation(program, "uStep"),
                row = gl_.GetUniformLocation(program, "uRow");
    gl_.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, waterIndexBuffer_);
    MeshCount n;
    if (!lod) {
        shownGridTriangles(meta_.nx, meta_.ny, shownWater_, waterGridIndices_);
        gl_.BufferData(GL_ELEMENT_ARRAY_BUFFER,
                       static_cast<GLsizeiptr>(waterGridIndices_.size() * sizeof(std::uint32_t)),
                       waterGridIndices_.data(), GL_STREAM_DRAW);
        gl_.Uniform2i(origin, 0, 0);
        gl_.Uniform1i(step, 1);
        gl_.Uniform1i(row, meta_.nx);
        gl_.DrawElements(GL_TRIANGLES, static_cast<GLsizei>(waterGridIndices_.size()), GL_UNSIGNED_INT, nullptr);
        n.triangles = static_cast<std::int64_t>(waterGridIndices_.size()) / 3;
        stats_.triangles += n.triangles;
        return n;
    }
    struct Piece {
        int x0, y0, step;
        std::size_t first;
        std::int64_t count;
    };
    std::vector<Piece> pieces;
    waterChunkIndices_.clear();
    for (const LodChunk& c : waterChunks_.chunks) {
        if (!c.wet || !boxInClipVolume(cullViewProj, c.boxMin, c.boxMax)) continue;
        const MeshPlacement p{c.x0, c.y0, 1 << c.level, kChunkQuads + 1, meta_.nx, meta_.ny};
        const std::size_t first = waterChunkIndices_.size();
        const std::int64_t count = appendShownTriangles(chunkIndices_.data() + chunkFirst_[c.stitched],
                                                        chunkCount_[c.stitched], p, shownWater_, waterChunkIndices_);
        if (count > 0) pieces.push_back({c.x0, c.y0, p.step, first, count});
    }
    gl_.BufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(waterChunkIndices_.size() * sizeof(std::uint16_t)),
                   waterChunkIndices_.data(), GL_STREAM_DRAW);
    gl_.Uniform1i(row, kChunkQuads + 1);
    for (const Piece& piece : pieces) {
        gl_.Uniform2i(origin, piece.x0, piece.y0);
        gl_.Uniform1i(step, piece.step);
        gl_.DrawElements(GL_TRIANGLES, static_cast<GLsizei>(piece.count), GL_UNSIGNED_SHORT,
                         reinterpret_cast<const void*>(piece.first * sizeof(std::uint16_t)));
        n.triangles += piece.count / 3;
        ++n.chunks;
    }
    stats_.triangles += n.triangles;
    return n;
}

void Renderer::releaseTarget(Target& t) {
    if (t.fbo) gl_.DeleteFramebuffers(1, &t.fbo);
    if (t.color) gl_.DeleteTextures(1, &t.color);
    if (t.depth) gl_.DeleteTextures(1, &t.depth);
    t = {};
}

// Where the camera and the key light's shadow map look from.
struct Renderer::FrameViews {
    glm::vec3 eye;
    glm::mat4 viewProj;
    glm::vec3 viewAxis;  // unit, from the eye towards the target
    glm::vec3 keyDir;
    glm::mat4 lightViewProj;  // orthographic, covering the terrain
};

// The lowest the eye may be at (x, y): above the highest surface of the
// finest chunks around it (render/terrain_lod.h) by twice the near plane's
// distance, so the camera never dips under the terrain nor cuts it open.
float Renderer::lowestEye(float x, float y, float nearPlane) const {
    float lowest = -std::numeric_limits<float>::infinity();
    for (const ChunkTree* tree : {&groundTree_, &waterTree_}) {
        if (tree->levels.empty()) continue;
        const ChunkTree::Level& fine = tree->levels[0];
        const float span = static_cast<float>(tree->quads) * tree->cellSize;
        const int cx = static_cast<int>(std::floor(x / span)), cy = static_cast<int>(std::floor(y / span));
        for (int j = std::max(cy - 1, 0); j <= std::min(cy + 1, fine.nodesY - 1); ++j)
            for (int i = std::max(cx - 1, 0); i <= std::min(cx + 1, fine.nodesX - 1); ++i)
                lowest = std::max(lowest, fine.zMax[static_cast<std::size_t>(j) * fine.nodesX + i] + 2.0f * nearPlane);
    }
    return lowest;
}

std::array<float, 3> Renderer::eyeOf(const OrbitCamera& cam) const {
    const engine::FrameData& f = meta_;
    const float exag = f.exaggeration;
    const float extent = static_cast<float>(std::max(f.nx, f.ny) - 1) * f.cellSize;
    const float cp = std::cos(cam.pitchDeg * kDeg), dist = extent * cam.distance;
    const float x = (cam.targetX * (f.nx - 1) + dist / f.cellSize * cp * std::cos(cam.yawDeg * kDeg)) * f.cellSize;
    const float y = (cam.targetY * (f.ny - 1) + dist / f.cellSize * cp * std::sin(cam.yawDeg * kDeg)) * f.cellSize;
    const float z = (f.zMin + cam.targetZ * (f.zMax - f.zMin)) * exag + dist * std::sin(cam.pitchDeg * kDeg);
    return {x, y, std::max(z, lowestEye(x, y, std::max(dist * 0.02f, 0.01f)))};
}

Renderer::FrameViews Renderer::frameViews(const OrbitCamera& cam, int width, int height) const {
    const engine::FrameData& f = meta_;
    const float exag = f.exaggeration;
    const float extent = static_cast<float>(std::max(f.nx, f.ny) - 1) * f.cellSize;
    const glm::vec3 centre(0.5f * (f.nx - 1) * f.cellSize, 0.5f * (f.ny - 1) * f.cellSize,
                           0.5f * (f.zMin + f.zMax) * exag);
    // ---- camera ------------------------------------------------------------------
    const glm::vec3 target(cam.targetX * (f.nx - 1) * f.cellSize, cam.targetY * (f.ny - 1) * f.cellSize,
                           (f.zMin + cam.targetZ * (f.zMax - f.zMin)) * exag);
    const std::array<float, 3> e = eyeOf(cam);
    const glm::vec3 eye(e[0], e[1], e[2]);
    const float dist = extent * cam.distance;
    const glm::mat4 view = glm::lookAt(eye, target, glm::vec3(0, 0, 1));
    const float nearPlane = std::max(dist * 0.02f, 0.01f), farPlane = dist * 4.0f + (f.zMax - f.zMin) * exag;
    const glm::mat4 proj =
        glm::perspective(cam.fovYDeg * kDeg, static_cast<float>(width) / height, nearPlane, farPlane);
    const glm::mat4 viewProj = proj * view;
    // ---- key light shadow map (orthographic, covering the terrain) ---------------
    const glm::vec3 keyDir = keyDirection(sunOf(f.lights));
    const float radius =
        0.5f * std::sqrt(2.0f * extent * extent + (f.zMax - f.zMin) * exag * (f.zMax - f.zMin) * exag) + 1.0f;
    const glm::vec3 up = std::abs(keyDir.z) > 0.99f ? glm::vec3(0, 1, 0) : glm::vec3(0, 0, 1);
    const glm::mat4 lightViewProj = glm::ortho(-radius, radius, -radius, radius, 0.0f, 4.0f * radius) *
                                    glm::lookAt(centre + keyDir * (2.0f * radius), centre, up);
    return {eye, viewProj, glm::normalize(target - eye), keyDir, lightViewProj};
}

namespace {

// The uniforms every mesh program reads: heights, grid, exaggeration, view.
void meshUniforms(const Gl& gl, const engine::FrameData& f, GLuint p, const glm::mat4& vp, int water) {
    Uniforms u{gl, p};
    u.i("uHeight", 0);
    u.i2("uGrid", f.nx, f.ny);
    u.f("uCell", f.cellSize);
    u.f("uExag", f.exaggeration);
    u.m4("uViewProj", vp);
    u.i("uWater", water);
}

}  // namespace

void Renderer::draw(const RenderSettings& s, int width, int height, GLuint framebuffer) {
    drawFrame(s, width, height);
    gl_.BindFramebuffer(GL_READ_FRAMEBUFFER, deferred_.displayFbo);
    gl_.BindFramebuffer(GL_DRAW_FRAMEBUFFER, framebuffer);
    gl_.BlitFramebuffer(0, 0, width, height, 0, 0, width, height, GL_COLOR_BUFFER_BIT, GL_NEAREST);
    gl_.BindFramebuffer(GL_FRAMEBUFFER, framebuffer);
    checkGlError(gl_, "draw");
}

void Renderer::drawFrame(const RenderSettings& s, int width, int height) {
    if (width < 1 || height < 1 || width > 16384 || height > 16384)
        throw InputError("image size must be 1..16384 pixels per side");
    if (!heightTex_) throw ContextError("renderer: draw before upload");
    if (!(s.lodPixelError >= 0.0f && s.lodPixelError <= kMaxLodPixelError))
        throw InputError("LOD pixel error must be in [0, " + std::to_string(kMaxLodPixelError) + "]");
    const FrameViews v = frameViews(s.camera, width, height);
    // The frame's chunks, for every mesh pass (render/terrain_lod.h).
    const bool lod = s.lodPixelError > 0.0f;
    stats_ = {};
    if (lod) {
        LodView view;
        std::copy_n(glm::value_ptr(v.eye), 3, view.eye);
        view.pixelsPerUnit = static_cast<float>(height) / (2.0f * std::tan(0.5f * s.camera.fovYDeg * kDeg));
        view.pixelError = s.lodPixelError;
        selectChunks(groundTree_, view, groundChunks_);
        if (meta_.hasWater) selectChunks(waterTree_, view, waterChunks_);
    }
    const bool debug = s.debug != DebugView::None;
    const bool water = s.water && meta_.hasWater && !debug;
    gl_.BindVertexArray(vao_);
    const bool wantShadowMap = s.shadow == ShadowMode::ShadowMap && !debug;
    // Targets first: creating one binds its textures to the active unit.
    const int shadowSide = std::clamp(s.shadowMapSize, 256, 8192);
    if (wantShadowMap) ensureTarget(shadow_, shadowSide, shadowSide, 0, true);
    deferred_.ensure(gl_, width, height);
    gl_.ActiveTexture(GL_TEXTURE0);
    gl_.BindTexture(GL_TEXTURE_2D, heightTex_);
    if (wantShadowMap) drawShadowMap(v, lod);
    gl_.Viewport(0, 0, width, height);
    drawSurfacePoints(v, lod, water);
    shadeSurfaces(s, v, wantShadowMap, water);
    drawDisplay(s, v, water);
    gl_.BindVertexArray(0);
    gl_.ActiveTexture(GL_TEXTURE0);
}

// ---- key light shadow map -----------------------------------------------------------
// The same chunks as the camera's (culled by the light's volume), so that the
// shadows fall from the surface the camera sees.
void Renderer::drawShadowMap(const FrameViews& v, bool lod) {
    const int side = shadow_.w;
    gl_.BindFramebuffer(GL_FRAMEBUFFER, shadow_.fbo);
    gl_.Viewport(0, 0, side, side);
    gl_.ClearDepth(1.0);
    gl_.Clear(GL_DEPTH_BUFFER_BIT);
    gl_.Enable(GL_DEPTH_TEST);
    gl_.DepthFunc(GL_LESS);
    gl_.Enable(GL_POLYGON_OFFSET_FILL);
    gl_.PolygonOffset(1.5f, 2.0f);
    gl_.UseProgram(shadowProgram_);
    meshUniforms(gl_, meta_, shadowProgram_, v.lightViewProj, 0);
    drawMesh(shadowProgram_, glm::value_ptr(v.lightViewProj), lod);
    gl_.Disable(GL_POLYGON_OFFSET_FILL);
}

// ---- the mesh passes: surface points ------------------------------------------------
// The terrain's points, then the water's where it is in front of the terrain,
// each marking the stencil with its surface (render/deferred_targets.h). The
// water writes no depth: the depth buffer keeps the terrain's, so that the
// water is tested against the terrain alone (where two water surfaces
// overlap on screen, the last drawn shows).
void Renderer::drawSurfacePoints(const FrameViews& v, bool lod, bool water) {
    gl_.BindFramebuffer(GL_FRAMEBUFFER, deferred_.pointsFbo);
    // The terrain's points need their clear (the water's march reads them
    // anywhere); the water's are read only where its stencil was set.
    // One draw buffer at a time: the points shader's one output goes to it.
    const GLenum terrainPoints = GL_COLOR_ATTACHMENT0, waterPoints = GL_COLOR_ATTACHMENT1;
    gl_.DrawBuffers(1, &terrainPoints);
    gl_.ClearColor(0, 0, 0, 0);
    gl_.ClearDepth(1.0);
    gl_.ClearStencil(0);
    gl_.Clear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT | GL_STENCIL_BUFFER_BIT);
    gl_.Enable(GL_DEPTH_TEST);
    gl_.DepthFunc(GL_LESS);
    gl_.Disable(GL_CULL_FACE);
    gl_.Enable(GL_STENCIL_TEST);
    gl_.StencilOp(GL_KEEP, GL_KEEP, GL_REPLACE);
    gl_.StencilFunc(GL_ALWAYS, kTerrainStencil, 0xff);
    gl_.UseProgram(pointsProgram_);
    meshUniforms(gl_, meta_, pointsProgram_, v.viewProj, 0);
    const MeshCount terrain = drawMesh(pointsProgram_, glm::value_ptr(v.viewProj), lod);
    stats_.terrainTriangles = terrain.triangles;
    stats_.terrainChunks = terrain.chunks;
    if (water) {
        gl_.DrawBuffers(1, &waterPoints);
        gl_.StencilFunc(GL_ALWAYS, kWaterStencil, 0xff);
        gl_.Uniform1i(gl_.GetUniformLocation(pointsProgram_, "uWater"), 1);
        gl_.DepthMask(GL_FALSE);
        drawWaterMesh(pointsProgram_, glm::value_ptr(v.viewProj), lod);
        gl_.DepthMask(GL_TRUE);
    }
    gl_.Disable(GL_DEPTH_TEST);
}

// ---- the shading passes: one full-screen triangle each --------------------------------
// The terrain's pass lights every pixel with a terrain point (under the water
// too: the water's march reflects it); the water's lights the water's pixels.
// Each writes its own HDR target, read only under its stencil (drawDisplay).
void Renderer::shadeSurfaces(const RenderSettings& s, const FrameViews& v, bool wantShadowMap, bool water) {
    const GLuint textures[] = {heightTex_,
                               shadeTex_,
                               keyTex_,
                               receiverTex_,
                               sky_.shTexture(),
                               shadow_.depth,
                               albedoTex_,
                               deferred_.terrainPoints,
                               deferred_.waterPoints,
                               deferred_.terrainColor,
                               hydrologyTex_};
    for (int i = 0; i < 11; ++i) {
        gl_.ActiveTexture(static_cast<GLenum>(GL_TEXTURE0 + i));
        gl_.BindTexture(GL_TEXTURE_2D, textures[i]);
    }
    gl_.StencilOp(GL_KEEP, GL_KEEP, GL_KEEP);
    gl_.BindFramebuffer(GL_FRAMEBUFFER, deferred_.terrainFbo);
    gl_.StencilFunc(GL_LEQUAL, kTerrainStencil, 0xff);  // terrain, or water over it
    const GLuint terrainProgram = shadingProgram(false, s, wantShadowMap);
    shadingUniforms(terrainProgram, v);
    Uniforms{gl_, terrainProgram}.i("uSurface", 7);
    gl_.DrawArrays(GL_TRIANGLES, 0, 3);
    if (water) {
        gl_.BindFramebuffer(GL_FRAMEBUFFER, deferred_.waterFbo);
        gl_.StencilFunc(GL_EQUAL, kWaterStencil, 0xff);
        const GLuint waterProgram = shadingProgram(true, s, wantShadowMap);
        shadingUniforms(waterProgram, v);
        Uniforms u{gl_, waterProgram};
        u.i("uSurface", 8);
        u.i("uTerrainPoints", 7);
        u.i("uSceneColor", 9);
        u.m4("uViewProj", v.viewProj);
        u.v3("uViewAxis", v.viewAxis);
        gl_.DrawArrays(GL_TRIANGLES, 0, 3);
    }
    gl_.Disable(GL_STENCIL_TEST);
}

GLuint Renderer::shadingProgram(bool water, const RenderSettings& s, bool wantShadowMap) {
    const engine::FrameData& f = meta_;
    const int lighting =
        f.lighting == engine::LightingMode::KeyOnly ? 0 : (f.lighting == engine::LightingMode::Direct ? 1 : 2);
    const int shadow = s.shadow == ShadowMode::SoftVisibility ? 0 : (wantShadowMap ? 1 : 2);
    const int specular = s.specular ? 1 : 0, debug = static_cast<int>(s.debug);
    const int key = (((water ? 1 : 0) * 3 + lighting) * 3 + shadow) * 2 * 16 + specular * 16 + debug;
    if (const auto found = shadingPrograms_.find(key); found != shadingPrograms_.end()) return found->second;
    const std::string constants = "#version 330 core\nconst int uLighting = " + std::to_string(lighting) +
                                  ";\nconst int uShadowMode = " + std::to_string(shadow) +
                                  ";\nconst int uSpecular = " + std::to_string(specular) +
                                  ";\nconst int uDebug = " + std::to_string(debug) + ";\n";
    const GLuint p =
        link(gl_, {shaders::kFullScreenVertex},
             {constants.c_str(), shaders::kCommon, water ? shaders::kWaterFragment : shaders::kTerrainFragment},
             water ? "water" : "terrain");
    shadingPrograms_.emplace(key, p);
    return p;
}

void Renderer::shadingUniforms(GLuint p, const FrameViews& v) {
    const engine::FrameData& f = meta_;
    gl_.UseProgram(p);
    Uniforms u{gl_, p};
    u.i("uHeight", 0);
    u.i("uShade", 1);
    u.i("uKey", 2);
    u.i("uReceiver", 3);
    u.i("uEnv", 4);
    u.i("uShadowMap", 5);
    u.i("uAlbedo", 6);
    u.i("uHydrology", 10);
    u.f2("uHydrologyMaxFlow", f.hydrologyMax[0], f.hydrologyMax[1]);
    u.f2("uHydrologyMaxGround", f.hydrologyMax[2], f.hydrologyMax[3]);
    u.i2("uGrid", f.nx, f.ny);
    u.f("uCell", f.cellSize);
    u.f("uExag", f.exaggeration);
    u.f("uHaze", f.lights.hazeExtinction);
    u.i2("uReceiverGrid", f.nxr, f.nyr);
    u.i("uSubsample", f.subsample);
    u.v3("uEye", v.eye);
    u.v3("uKeyDir", v.keyDir);
    const gi::KeyLight sun = sunOf(f.lights);
    u.v3("uKeyRgb", glm::vec3(sun.rgb[0], sun.rgb[1], sun.rgb[2]));
    u.f2("uZRange", f.zMin, f.zMax);
    u.m4("uLightViewProj", v.lightViewProj);
    u.f("uShadowTexel", shadow_.w > 0 ? 1.0f / static_cast<float>(shadow_.w) : 0.0f);
}

// ---- the display passes: tone mapping + sRGB, and the sky --------------------------------
// Each surface's HDR colour where its stencil is, then the sky where no
// surface was drawn (the debug views: black).
void Renderer::drawDisplay(const RenderSettings& s, const FrameViews& v, bool water) {
    const bool debug = s.debug != DebugView::None;
    gl_.BindFramebuffer(GL_FRAMEBUFFER, deferred_.displayFbo);
    if (debug) {
        gl_.ClearColor(0, 0, 0, 1);
        gl_.Clear(GL_COLOR_BUFFER_BIT);
    }
    gl_.Enable(GL_STENCIL_TEST);
    gl_.StencilOp(GL_KEEP, GL_KEEP, GL_KEEP);
    gl_.UseProgram(displayProgram_);
    Uniforms u{gl_, displayProgram_};
    u.i("uHdr", 0);
    u.f("uExposure", s.exposure);
    u.i("uTonemap", debug ? 0 : 1);
    gl_.ActiveTexture(GL_TEXTURE0);
    for (const auto& [stencil, color] :
         {std::pair{kTerrainStencil, deferred_.terrainColor}, std::pair{kWaterStencil, deferred_.waterColor}}) {
        if (stencil == kWaterStencil && !water) continue;
        gl_.BindTexture(GL_TEXTURE_2D, color);
        gl_.StencilFunc(GL_EQUAL, stencil, 0xff);
        gl_.DrawArrays(GL_TRIANGLES, 0, 3);
    }
    if (!debug) {
        gl_.UseProgram(skyProgram_);
        sky_.setBackground(skyProgram_, meta_.lights, 1, 2);
        Uniforms k{gl_, skyProgram_};
        k.f("uExposure", s.exposure);
        k.i("uTonemap", 1);
        k.m4("uInvViewProj", glm::inverse(v.viewProj));
        k.v3("uEye", v.eye);
        k.f2("uSize", static_cast<float>(deferred_.w), static_cast<float>(deferred_.h));
        gl_.StencilFunc(GL_EQUAL, 0, 0xff);
        gl_.DrawArrays(GL_TRIANGLES, 0, 3);
    }
    gl_.Disable(GL_STENCIL_TEST);
}

void Renderer::drawToImage(const RenderSettings& s, int width, int height, std::vector<std::uint8_t>& rgb) {
    if (width < 1 || height < 1 || width > 16384 || height > 16384)
        throw InputError("image size must be 1..16384 pixels per side");
    drawFrame(s, width, height);
    std::vector<std::uint8_t> rgba(static_cast<std::size_t>(width) * height * 4);
    gl_.BindFramebuffer(GL_FRAMEBUFFER, deferred_.displayFbo);
    gl_.ReadBuffer(GL_COLOR_ATTACHMENT0);
    gl_.PixelStorei(GL_PACK_ALIGNMENT, 1);
    gl_.ReadPixels(0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
    gl_.BindFramebuffer(GL_FRAMEBUFFER, 0);
    checkGlError(gl_, "read-back");
    rgb.resize(static_cast<std::size_t>(width) * height * 3);
    for (int y = 0; y < height; ++y) {
        const std::uint8_t* src =
            rgba.data() + static_cast<std::size_t>(height - 1 - y) * width * 4;  // GL: row 0 at the bottom
        std::uint8_t* dst = rgb.data() + static_cast<std::size_t>(y) * width * 3;
        for (int x = 0; x < width; ++x) {
            dst[3 * x] = src[4 * x];
            dst[3 * x + 1] = src[4 * x + 1];
            dst[3 * x + 2] = src[4 * x + 2];
        }
    }
}

}  // namespace terrain::render
