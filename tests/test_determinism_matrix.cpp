// The determinism matrix: every built-in scene and every scene file in
// scenes/, under GI modes that together use every setting that changes the
// code path (1x / 2x / 4x sub-sampling, 0-3 bounces, both Lambert kernels,
// glossy scalar and vector pyramids, amortised and incremental frames, the
// key light alone), run through the frame pipeline (simulation ticks, GI,
// material maps, the arrays the renderer uploads) for 1, 2, 3 and 8
// threads: every byte of every frame must be the same.
//
// Scenes run at 64² cells over their own extent, four ticks a frame, without
// spin-up, so the matrix stays a few seconds; the DEM scenes run when their
// elevation file is present (TERRAIN_DATA).
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <doctest/doctest.h>

#include "core/parallel.h"
#include "engine/pipeline.h"
#include "sim/frame_layers.h"
#include "sim/scene.h"

using namespace terrain;
using namespace terrain::engine;

namespace {

constexpr int kSide = 64;
constexpr int kFrames = 3;

struct GiMode {
    const char* name;
    LightingMode lighting;
    int subsample;
    int bounces;
    gi::LambertIndirect lambert;
    gi::Brdf brdf;
    gi::GlossyIndirect glossy;
    bool amortise;
    bool incremental;
};

constexpr auto kBlocker = gi::LambertIndirect::BlockerRadiance;
constexpr auto kShKernel = gi::LambertIndirect::ShKernel;
constexpr auto kScalar = gi::GlossyIndirect::ScalarPyramid;
constexpr auto kVector = gi::GlossyIndirect::VectorPyramid;
constexpr auto kLambert = gi::Brdf::Lambert;
constexpr auto kGlossy = gi::Brdf::LambertPlusPhong;

// A covering set, not the full product: each value of each setting appears
// at least once, the costly ones (3 bounces, glossy) at 2x.
const GiMode kModes[] = {
    {"key light only", LightingMode::KeyOnly, 1, 0, kBlocker, kLambert, kScalar, false, false},
    {"direct 1x", LightingMode::Direct, 1, 0, kBlocker, kLambert, kScalar, false, false},
    {"blocker radiance 2x, 1 bounce", LightingMode::Global, 2, 1, kBlocker, kLambert, kScalar, false, false},
    {"SH kernel 4x, 2 bounces", LightingMode::Global, 4, 2, kShKernel, kLambert, kScalar, false, false},
    {"blocker radiance 2x, 3 bounces", LightingMode::Global, 2, 3, kBlocker, kLambert, kScalar, false, false},
    {"SH kernel 1x, 1 bounce", LightingMode::Global, 1, 1, kShKernel, kLambert, kScalar, false, false},
    {"glossy scalar 2x, 1 bounce", LightingMode::Global, 2, 1, kBlocker, kGlossy, kScalar, false, false},
    {"glossy vector 2x, 2 bounces", LightingMode::Global, 2, 2, kBlocker, kGlossy, kVector, false, false},
    {"amortised 2x, 1 bounce", LightingMode::Global, 2, 1, kBlocker, kLambert, kScalar, true, false},
    {"incremental 2x, 1 bounce", LightingMode::Global, 2, 1, kBlocker, kLambert, kScalar, false, true},
};

PipelineSettings settingsFor(const GiMode& m) {
    PipelineSettings ps;
    ps.lighting = m.lighting;
    ps.ticksPerFrame = 4;
    ps.gi.subsample = m.subsample;
    ps.gi.indirect.bounces = m.bounces;
    ps.gi.indirect.lambert = m.lambert;
    ps.gi.indirect.glossy = m.glossy;
    ps.gi.indirect.amortise = m.amortise;
    ps.gi.shading.brdf = m.brdf;
    ps.gi.incremental = m.incremental;
    return ps;
}

// A scene at kSide² over the extent it declares, started at once.
SceneSettings shrunk(SceneSettings s) {
    const float extent = s.cellSize * static_cast<float>(std::max(s.nx, s.ny));
    s.nx = s.ny = kSide;
    s.cellSize = extent / kSide;
    s.spinUp = 0.0f;
    return s;
}

void appendBytes(std::vector<std::uint8_t>& out, const void* data, std::size_t bytes) {
    const auto* p = static_cast<const std::uint8_t*>(data);
    out.insert(out.end(), p, p + bytes);
}

template <class T>
void appendVector(std::vector<std::uint8_t>& out, const std::vector<T>& v) {
    const std::uint64_t n = v.size();
    appendBytes(out, &n, sizeof n);
    appendBytes(out, v.data(), v.size() * sizeof(T));
}

// Every byte a frame hands on: the simulation state (as its hash over all
// layers), the frame's layers a frame file carries (hydrology maps included)
// and each array the renderer uploads.
void appendFrame(std::vector<std::uint8_t>& out, const FramePipeline& p) {
    const std::uint64_t state = hashState(p.simulation().state());
    appendBytes(out, &state, sizeof state);
    for (const FrameLayer& layer : frameLayers(p.simulation()).layers)
        appendBytes(out, layer.grid.data(), layer.grid.size() * sizeof(float));
    const FrameData& f = p.frame();
    appendVector(out, f.heights);
    appendVector(out, f.albedo);
    appendVector(out, f.shade);
    appendVector(out, f.key);
    appendVector(out, f.receiver);
}

std::vector<std::uint8_t> runFrames(const SceneSettings& scene, const PipelineSettings& ps) {
    std::vector<std::uint8_t> bytes;
    FramePipeline pipeline(scene, ps);
    for (int i = 0; i < kFrames; ++i) {
        pipeline.advance();
        pipeline.light();
        appendFrame(bytes, pipeline);
    }
    return bytes;
}

bool demPresent(const SceneSettings& s) {
    return s.terrain.kind != TerrainSource::Kind::Dem || std::ifstream(s.terrain.demFile).good();
}

std::vector<std::pair<std::string, SceneSettings>> everyScene() {
    std::vector<std::pair<std::string, SceneSettings>> scenes;
    for (const std::string& name : builtinSceneNames()) scenes.emplace_back(name, builtinScene(name, kSide, 7));
    std::vector<std::filesystem::path> files;
    for (const auto& e : std::filesystem::directory_iterator(std::string(TERRAIN_SOURCE_DIR) + "/scenes"))
        if (e.path().extension() == ".toml") files.push_back(e.path());
    std::sort(files.begin(), files.end());
    for (const auto& f : files) scenes.emplace_back(f.filename().string(), loadSceneFile(f.string()));
    return scenes;
}

}  // namespace

TEST_CASE("determinism: every scene x GI mode gives the same bytes for 1, 2, 3 and 8 threads") {
    int runs = 0;
    for (const auto& named : everyScene()) {
        // plain locals: Clang 14 lambdas (doctest's INFO) cannot capture structured bindings
        const std::string& name = named.first;
        const SceneSettings& declared = named.second;
        if (!demPresent(declared)) {
            MESSAGE("skipped " << name << ": its elevation file is not here (" << declared.terrain.demFile << ")");
            continue;
        }
        const SceneSettings scene = shrunk(declared);
        for (const GiMode& mode : kModes) {
            INFO(name << ", " << mode.name);
            const PipelineSettings ps = settingsFor(mode);
            const std::vector<std::uint8_t> one = withThreads(1, [&] { return runFrames(scene, ps); });
            for (int threads : {2, 3, 8}) {
                CAPTURE(threads);
                CHECK(withThreads(threads, [&] { return runFrames(scene, ps); }) == one);
            }
            ++runs;
        }
    }
    CHECK(runs >= 3 * static_cast<int>(std::size(kModes)));
}
