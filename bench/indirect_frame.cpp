#include "bench/indirect_frame.h"

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <span>

#include "core/parallel.h"
#include "core/simd.h"
#include "gi/reference_gi.h"

namespace terrain::bench {

using namespace terrain::gi;

KeyLight benchKey() {
    KeyLight k;
    k.azimuthDeg = 135.0f;
    k.elevationDeg = 35.0f;
    k.radiusDeg = 5.0f;
    k.rgb[0] = 1.2f;
    k.rgb[1] = 1.1f;
    k.rgb[2] = 1.0f;
    return k;
}

GiLighting indirectFrameLighting() {
    GiLighting l;
    l.environment = sunSkyLight();
    l.keys.push_back(benchKey());
    return l;
}

GiSettings indirectFrameSettings(int s, int bounces, bool paper, const IndirectVariant& v) {
    GiSettings g = wholeFrames(paper ? paperGiSettings() : GiSettings{});
    g.subsample = s;
    g.indirect.bounces = bounces;
    if (v.indirectAzimuths > 0) g.indirect.azimuths = v.indirectAzimuths;
    if (!paper && v.radianceK > 0) g.indirect.radiance.levelsPerOctave = v.radianceK;
    if (!paper && v.radianceO >= 0) g.indirect.radiance.levelOffset = v.radianceO;
    if (!paper && v.shKernel) {
        g.indirect.lambert = LambertIndirect::ShKernel;
        g.visibility.footprintTangent = false;
    }
    return g;
}

std::string indirectSettingsSummary(const IndirectVariant& v) {
    const GiSettings g = indirectFrameSettings(2, 1, false, v);
    char b[512];
    std::snprintf(b, sizeof b,
                  "m %d, k_v %d, o_v %d, peak blend %.2f, k_u %d, o_u %d, %d indirect azimuths, %s, footprint "
                  "tangent planes %s; %s kernels",
                  g.visibility.azimuths, g.pyramid.levelsPerOctave, g.pyramid.levelOffset, g.pyramid.peakBlend,
                  g.indirect.radiance.levelsPerOctave, g.indirect.radiance.levelOffset,
                  g.indirect.azimuths > 0 ? g.indirect.azimuths : g.visibility.azimuths,
                  g.indirect.lambert == LambertIndirect::BlockerRadiance
                      ? "exact cosine at the receivers, blocker radiance x occlusion between them"
                      : "SH kernel",
                  g.visibility.footprintTangent ? "on" : "off", simd::wideEnabled() ? "8-wide AVX2" : "4-wide SSE2");
    return b;
}

ShRgb foldKeys(const GiLighting& l) {
    ShRgb total = l.environment;
    for (const KeyLight& k : l.keys) {
        const ShRgb cap = keyLightSh(k);
        for (std::size_t c = 0; c < 3; ++c)
            for (std::size_t i = 0; i < static_cast<std::size_t>(kShCount); ++i) total.c[c][i] += cap.c[c][i];
    }
    return total;
}

IndirectReference computeIndirectReference(const Dem& d, const GiLighting& light, const AlbedoMap& a, int maxBounces,
                                           int directions) {
    const auto t0 = std::chrono::steady_clock::now();
    IndirectReference r;
    ReferenceGiSettings s;
    s.directions = directions;
    s.bounces = 0;
    s.keys = light.keys;  // exact caps (not folded into the SH lighting)
    ReferenceGiResult res;
    withThreads(0, [&] {
        renderReferenceGi(d.heights.cview(), d.cell, light.environment, &a, s, res);
        r.direct = res.direct;
        std::array<Grid, 3> prev = res.direct, next, sum;
        for (Grid& g : sum) g.resize(d.heights.nx, d.heights.ny, 0.0f);
        for (int b = 1; b <= maxBounces; ++b) {
            gatherReferenceBounce(d.heights.cview(), d.cell, prev, &a, s, next);
            for (std::size_t c = 0; c < 3; ++c)
                for (std::size_t i = 0; i < sum[c].v.size(); ++i) sum[c].v[i] += next[c].v[i];
            r.indirectUpTo.push_back(sum);
            std::swap(prev, next);
        }
    });
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return r;
}

namespace {

// FNV-1a, 64 bits: names a cached reference by everything it depends on.
struct Fnv1a {
    std::uint64_t h = 14695981039346656037ull;
    void add(const void* p, std::size_t n) {
        const auto* b = static_cast<const unsigned char*>(p);
        for (std::size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 1099511628211ull;
    }
    template <class T>
    void add(const T& v) {
        add(&v, sizeof v);
    }
};

std::uint64_t referenceKey(const Dem& d, const GiLighting& light, const AlbedoMap& a, int maxBounces, int directions) {
    Fnv1a f;
    f.add(d.heights.nx);
    f.add(d.heights.ny);
    f.add(d.cell);
    f.add(d.heights.v.data(), d.heights.v.size() * sizeof(float));
    for (const auto& c : light.environment.c) f.add(c.data(), c.size() * sizeof(float));
    for (const KeyLight& k : light.keys) f.add(k);
    for (const Grid& g : a.channel) f.add(g.v.data(), g.v.size() * sizeof(float));
    f.add(maxBounces);
    f.add(directions);
    return f.h;
}

}  // namespace

IndirectReference cachedIndirectReference(const std::string& cacheDir, const Dem& d, const GiLighting& light,
                                          const AlbedoMap& a, int maxBounces, int directions) {
    if (cacheDir.empty()) return computeIndirectReference(d, light, a, maxBounces, directions);
    char name[96];
    std::snprintf(name, sizeof name, "indirect-ref-%016llx.f32",
                  static_cast<unsigned long long>(referenceKey(d, light, a, maxBounces, directions)));
    const std::string file = (std::filesystem::path(cacheDir) / name).string();
    const std::size_t count = 3 * (1 + static_cast<std::size_t>(maxBounces));
    std::vector<Grid> grids(count);
    IndirectReference r;
    if (!readCachedGrids(file, d.heights.nx, d.heights.ny, grids)) {
        std::fprintf(stderr, "reference %s %dx%d, %d directions ...\n", d.name.c_str(), d.heights.nx, d.heights.ny,
                     directions);
        r = computeIndirectReference(d, light, a, maxBounces, directions);
        std::fprintf(stderr, "  %.0f s\n", r.seconds);
        for (std::size_t c = 0; c < 3; ++c) grids[c] = r.direct[c];
        for (std::size_t b = 0; b < r.indirectUpTo.size(); ++b)
            for (std::size_t c = 0; c < 3; ++c) grids[3 * (b + 1) + c] = r.indirectUpTo[b][c];
        std::filesystem::create_directories(cacheDir);
        writeCachedGrids(file, grids);
        return r;
    }
    for (std::size_t c = 0; c < 3; ++c) r.direct[c] = grids[c];
    r.indirectUpTo.resize(static_cast<std::size_t>(maxBounces));
    for (std::size_t b = 0; b < r.indirectUpTo.size(); ++b)
        for (std::size_t c = 0; c < 3; ++c) r.indirectUpTo[b][c] = grids[3 * (b + 1) + c];
    return r;
}

IndirectErrors indirectErrors(const GiState& st, const IndirectReference& ref, int bounces) {
    const std::array<Grid, 3>& ind = ref.indirectUpTo[static_cast<std::size_t>(bounces - 1)];
    std::array<Grid, 3> total = ref.direct;
    for (std::size_t c = 0; c < 3; ++c)
        for (std::size_t i = 0; i < total[c].v.size(); ++i) total[c].v[i] += ind[c].v[i];
    IndirectErrors e;
    e.total = relRmse(st.indirect.total, total, e.totalBias);
    e.indirect = relRmse(st.indirect.indirect, ind, e.indirectBias);
    return e;
}

}  // namespace terrain::bench
