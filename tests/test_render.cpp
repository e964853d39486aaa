// Headless (OSMesa) renders of small scenes: the image is not empty, lit
// slopes are brighter than slopes facing away, sky light brightens shadowed
// valley floors, both key-light shadow modes darken them, and the same scene
// gives the same image bytes on repeated runs and for any thread count.
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include <doctest/doctest.h>

#include "core/parallel.h"
#include "engine/pipeline.h"
#include "render/context.h"
#include "render/gl.h"
#include "render/renderer.h"
#include "sim/scene.h"

using namespace terrain;
using namespace terrain::render;
using namespace terrain::engine;

namespace {

constexpr int kW = 160, kH = 90;

/// One OSMesa context and renderer for the whole test binary.
struct Gpu {
    std::unique_ptr<GlContext> context = createHeadlessContext();
    Gl gl;
    std::unique_ptr<Renderer> renderer;
    Gpu() {
        loadGl(gl, context->procAddress());
        renderer = std::make_unique<Renderer>(gl);
    }
};
Gpu& gpu() {
    static Gpu g;
    g.context->makeCurrent();
    return g;
}

RenderSettings topDown() {
    RenderSettings rs;
    rs.camera.pitchDeg = 89.0f;
    rs.camera.yawDeg = 270.0f;
    rs.camera.distance = 1.2f;
    return rs;
}

/// A 64^2 scene with no simulators whose ground is `height(x, y)` (m), lit by
/// a key light from azimuth 0 (+x), elevation `keyElevation`.
std::vector<std::uint8_t> renderShape(const std::function<float(float, float)>& height, LightingMode lighting,
                                      ShadowMode shadow, float keyElevation = 30.0f) {
    SceneSettings scene = builtinScene("erosion", 64, 1);
    scene.hydraulic = scene.thermal = false;
    scene.soilDepth = 0.0f;
    scene.cellSize = 10.0f;
    scene.materials = MaterialSet{};  // one grey: these tests measure the light, not the materials
    scene.materials.bedrock.albedo = {0.5f, 0.5f, 0.5f};
    PipelineSettings ps;
    ps.lighting = lighting;
    ps.verticalExaggeration = 1.0f;
    scene.lights.keys.at(0).azimuthDeg = 0.0f;
    scene.lights.keys.at(0).elevationDeg = keyElevation;
    FramePipeline pipeline(scene, ps);
    TerrainState& st = pipeline.simulation().state();
    for (int y = 0; y < st.ny; ++y)
        for (int x = 0; x < st.nx; ++x) {
            st.bedrock(x, y) = height(x * st.cellSize, y * st.cellSize);
            st.soil(x, y) = 0.0f;
        }
    pipeline.terrainReplaced();
    pipeline.advance();
    pipeline.light();
    RenderSettings rs = topDown();
    rs.shadow = shadow;
    rs.specular = false;
    std::vector<std::uint8_t> rgb;
    gpu().renderer->upload(pipeline.frame());
    gpu().renderer->drawToImage(rs, kW, kH, rgb);
    return rgb;
}

/// Mean luminance (0..255) of a centred box of the image.
double centreBrightness(const std::vector<std::uint8_t>& rgb, int halfW, int halfH) {
    double sum = 0.0;
    int n = 0;
    for (int y = kH / 2 - halfH; y < kH / 2 + halfH; ++y)
        for (int x = kW / 2 - halfW; x < kW / 2 + halfW; ++x) {
            const std::uint8_t* p = rgb.data() + (static_cast<std::size_t>(y) * kW + x) * 3;
            sum += 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
            ++n;
        }
    return sum / n;
}

std::uint64_t renderSceneHash(const char* name, int threads) {
    return withThreads(threads, [&] {
        PipelineSettings ps;
        ps.gi.subsample = 2;
        FramePipeline pipeline(resolveScene(name, 64, 3), ps);
        std::vector<std::uint8_t> rgb;
        for (int f = 0; f < 2; ++f) {
            pipeline.advance();
            pipeline.light();
            gpu().renderer->upload(pipeline.frame());
            gpu().renderer->drawToImage(RenderSettings{}, kW, kH, rgb);
        }
        return hashBytes(rgb);
    });
}

}  // namespace

TEST_CASE("render.headless: a small scene gives a non-empty image") {
    FramePipeline pipeline(resolveScene("erosion", 64, 1), PipelineSettings{});
    pipeline.advance();
    pipeline.light();
    std::vector<std::uint8_t> rgb;
    gpu().renderer->upload(pipeline.frame());
    gpu().renderer->drawToImage(RenderSettings{}, kW, kH, rgb);
    REQUIRE(rgb.size() == static_cast<std::size_t>(kW) * kH * 3);
    // The terrain covers the centre and differs from the sky in the corner.
    const std::uint8_t* corner = rgb.data();
    int differing = 0;
    std::uint8_t lo = 255, hi = 0;
    for (std::size_t i = 0; i < rgb.size(); i += 3) {
        if (rgb[i] != corner[0] || rgb[i + 1] != corner[1] || rgb[i + 2] != corner[2]) ++differing;
        lo = std::min(lo, rgb[i + 1]);
        hi = std::max(hi, rgb[i + 1]);
    }
    CHECK(differing > kW * kH / 4);
    CHECK(hi - lo > 40);
    const std::uint8_t* c = rgb.data() + (static_cast<std::size_t>(kH / 2) * kW + kW / 2) * 3;
    CHECK((c[0] != corner[0] || c[1] != corner[1] || c[2] != corner[2]));
}

TEST_CASE("render.materials: the renderer's base colour is the GI's albedo map") {
    SceneSettings scene = builtinScene("erosion", 64, 1);
    scene.hydraulic = scene.thermal = false;
    scene.materials = MaterialSet{};
    scene.materials.bedrock.albedo = {0.2f, 0.5f, 0.8f};
    scene.materials.soil.material = scene.materials.bedrock;
    FramePipeline pipeline(scene, PipelineSettings{});
    pipeline.advance();
    pipeline.light();
    RenderSettings rs = topDown();
    rs.debug = DebugView::Albedo;
    std::vector<std::uint8_t> rgb;
    gpu().renderer->upload(pipeline.frame());
    gpu().renderer->drawToImage(rs, kW, kH, rgb);
    // the albedo, sRGB-encoded, at the centre of the image
    const std::uint8_t* c = rgb.data() + (static_cast<std::size_t>(kH / 2) * kW + kW / 2) * 3;
    for (int k = 0; k < 3; ++k) {
        const double a = scene.materials.bedrock.albedo[static_cast<std::size_t>(k)];
        const double srgb = a <= 0.0031308 ? 12.92 * a : 1.055 * std::pow(a, 1.0 / 2.4) - 0.055;
        CHECK_MESSAGE(std::abs(c[k] - 255.0 * srgb) <= 1.5, "channel ", k, ": ", int(c[k]), " for ", 255.0 * srgb);
    }
}

TEST_CASE("render.headless: a slope facing the key light is brighter than one facing away") {
    // Planes at 30 degrees; the key light comes from +x at 30 degrees elevation.
    const float k = std::tan(30.0f * 0.017453292f);
    const auto facing =
        renderShape([&](float x, float) { return 400.0f - k * x; }, LightingMode::Direct, ShadowMode::SoftVisibility);
    const auto away =
        renderShape([&](float x, float) { return k * x; }, LightingMode::Direct, ShadowMode::SoftVisibility);
    const double bFacing = centreBrightness(facing, 20, 12), bAway = centreBrightness(away, 20, 12);
    MESSAGE("facing " << bFacing << ", away " << bAway);
    CHECK(bFacing > bAway + 30.0);
}

TEST_CASE("render.lighting: sky light brightens a shadowed valley floor (direct vs key light only)") {
    // A V valley across the light: 60 m deep, walls at ~50 degrees, floor 60 m
    // wide; the key light (from +x, 15 degrees up) cannot reach the floor.
    auto valley = [](float x, float) {
        const float d = std::abs(x - 315.0f);
        return d < 30.0f ? 0.0f : std::min(60.0f, (d - 30.0f) * 1.2f);
    };
    const auto keyOnly = renderShape(valley, LightingMode::KeyOnly, ShadowMode::SoftVisibility, 15.0f);
    const auto direct = renderShape(valley, LightingMode::Direct, ShadowMode::SoftVisibility, 15.0f);
    const double bKey = centreBrightness(keyOnly, 4, 4), bDirect = centreBrightness(direct, 4, 4);
    MESSAGE("valley floor: key only " << bKey << ", sky + key " << bDirect);
    CHECK(bDirect > bKey + 20.0);
}

TEST_CASE("render.lighting: with global illumination a valley floor is brighter than with direct light only") {
    // The same shadowed V valley: one indirect bounce off the lit walls adds
    // light on the floor (albedo 1 in gi/, the renderer's palette on top).
    auto valley = [](float x, float) {
        const float d = std::abs(x - 315.0f);
        return d < 30.0f ? 0.0f : std::min(60.0f, (d - 30.0f) * 1.2f);
    };
    const auto direct = renderShape(valley, LightingMode::Direct, ShadowMode::SoftVisibility, 15.0f);
    const auto global = renderShape(valley, LightingMode::Global, ShadowMode::SoftVisibility, 15.0f);
    const double bDirect = centreBrightness(direct, 4, 4), bGlobal = centreBrightness(global, 4, 4);
    MESSAGE("valley floor: direct only " << bDirect << ", direct + one bounce " << bGlobal);
    CHECK(bGlobal > bDirect + 5.0);
}

TEST_CASE("render.shadow: the shadow map and the engine's soft visibility both shadow a valley floor") {
    auto valley = [](float x, float) {
        const float d = std::abs(x - 315.0f);
        return d < 30.0f ? 0.0f : std::min(60.0f, (d - 30.0f) * 1.2f);
    };
    const double none = centreBrightness(renderShape(valley, LightingMode::KeyOnly, ShadowMode::None, 15.0f), 4, 4);
    const double soft =
        centreBrightness(renderShape(valley, LightingMode::KeyOnly, ShadowMode::SoftVisibility, 15.0f), 4, 4);
    const double map = centreBrightness(renderShape(valley, LightingMode::KeyOnly, ShadowMode::ShadowMap, 15.0f), 4, 4);
    MESSAGE("valley floor, key light only: no shadow " << none << ", soft visibility " << soft << ", shadow map "
                                                       << map);
    CHECK(none > soft + 30.0);
    CHECK(none > map + 30.0);
}

TEST_CASE("render.determinism: the same scene gives the same image bytes, for any thread count") {
    for (const char* scene : {"erosion", "waves"}) {
        const std::uint64_t a = renderSceneHash(scene, 1);
        const std::uint64_t b = renderSceneHash(scene, 1);
        const std::uint64_t c = renderSceneHash(scene, 2);
        CHECK(a == b);
        CHECK(a == c);
    }
}
