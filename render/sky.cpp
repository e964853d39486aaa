#include "render/sky.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace terrain::render {
namespace {

constexpr int kShWidth = 64, kShHeight = 32;
constexpr float kDeg = 0.017453292519943295f;

void defineSkyTexture(const Gl& gl, GLuint tex, int w, int h, const float* rgb) {
    gl.BindTexture(GL_TEXTURE_2D, tex);
    gl.TexImage2D(GL_TEXTURE_2D, 0, GL_RGB32F, w, h, 0, GL_RGB, GL_FLOAT, rgb);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_REPEAT);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
}

// The SH radiance at the centres of an equirectangular grid (gi/lights.h's
// convention: column u at azimuth 2 pi (u + 0.5) / W, row 0 at the zenith).
void bakeSh(const gi::ShRgb& sh, std::vector<float>& out) {
    out.resize(static_cast<std::size_t>(kShWidth) * kShHeight * 3);
    for (int v = 0; v < kShHeight; ++v)
        for (int u = 0; u < kShWidth; ++u) {
            const double phi = 2.0 * gi::kPi * (u + 0.5) / kShWidth;
            const double el = gi::kPi * (0.5 - (v + 0.5) / kShHeight);
            double rgb[3];
            gi::evaluateShRgb(sh, std::cos(el) * std::cos(phi), std::cos(el) * std::sin(phi), std::sin(el), rgb);
            for (int c = 0; c < 3; ++c)
                out[(static_cast<std::size_t>(v) * kShWidth + u) * 3 + static_cast<std::size_t>(c)] =
                    static_cast<float>(std::max(0.0, rgb[c]));
        }
}

}  // namespace

Sky::Sky(const Gl& gl) : gl_(gl) {
    gl_.GenTextures(1, &shTex_);
    gl_.GenTextures(1, &imageTex_);
    const float black[3] = {0.0f, 0.0f, 0.0f};
    defineSkyTexture(gl_, imageTex_, 1, 1, black);
}

Sky::~Sky() {
    const GLuint textures[] = {shTex_, imageTex_};
    gl_.DeleteTextures(2, textures);
}

void Sky::upload(const engine::SceneLights& l) {
    gl_.PixelStorei(GL_UNPACK_ALIGNMENT, 4);
    if (!baked_ || bakedSh_.c != l.sky.c) {
        bakeSh(l.sky, pixels_);
        defineSkyTexture(gl_, shTex_, kShWidth, kShHeight, pixels_.data());
        bakedSh_ = l.sky;
        baked_ = true;
    }
    const engine::EnvironmentImage* image = l.skyKind == engine::SkyKind::Image ? l.image.get() : nullptr;
    if (image && image != uploadedImage_)
        defineSkyTexture(gl_, imageTex_, image->width, image->height, image->rgb.data());
    if (image) uploadedImage_ = image;
    checkGlError(gl_, "sky upload");
}

void Sky::setBackground(GLuint program, const engine::SceneLights& l, int shUnit, int imageUnit) const {
    gl_.ActiveTexture(static_cast<GLenum>(GL_TEXTURE0 + shUnit));
    gl_.BindTexture(GL_TEXTURE_2D, shTex_);
    gl_.ActiveTexture(static_cast<GLenum>(GL_TEXTURE0 + imageUnit));
    gl_.BindTexture(GL_TEXTURE_2D, imageTex_);
    auto at = [&](const char* name) { return gl_.GetUniformLocation(program, name); };
    gl_.Uniform1i(at("uEnv"), shUnit);
    gl_.Uniform1i(at("uSkyImage"), imageUnit);
    gl_.Uniform1i(at("uSkyKind"), static_cast<int>(l.skyKind));
    gl_.Uniform3f(at("uZenith"), l.zenith[0], l.zenith[1], l.zenith[2]);
    gl_.Uniform3f(at("uHorizon"), l.horizon[0], l.horizon[1], l.horizon[2]);
    gl_.Uniform1f(at("uImageScale"), l.imageScale);
    // key lights as discs of their cap radiance, rgb / sin^2(radius) (gi/lights.h)
    const int n = std::min(static_cast<int>(l.keys.size()), kSkyDiscs);
    gl_.Uniform1i(at("uDiscs"), n);
    for (int k = 0; k < n; ++k) {
        const gi::KeyLight& key = l.keys[static_cast<std::size_t>(k)];
        const float ce = std::cos(key.elevationDeg * kDeg), r = key.radiusDeg * kDeg;
        char name[32];
        std::snprintf(name, sizeof name, "uDiscDir[%d]", k);
        gl_.Uniform3f(at(name), ce * std::cos(key.azimuthDeg * kDeg), ce * std::sin(key.azimuthDeg * kDeg),
                      std::sin(key.elevationDeg * kDeg));
        std::snprintf(name, sizeof name, "uDiscCos[%d]", k);
        gl_.Uniform1f(at(name), std::cos(r));
        const float s2 = std::sin(r) * std::sin(r);
        std::snprintf(name, sizeof name, "uDiscRadiance[%d]", k);
        gl_.Uniform3f(at(name), key.rgb[0] / s2, key.rgb[1] / s2, key.rgb[2] / s2);
    }
}

}  // namespace terrain::render
