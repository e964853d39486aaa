#include "bench/gi_reference_cache.h"

#include <chrono>
#include <cinttypes>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <utility>

#include "core/parallel.h"
#include "gi/reference_gi.h"

namespace terrain::bench {
namespace {
using namespace terrain::gi;
using Clock = std::chrono::steady_clock;

// Bumped when the cache file's layout or the reference's meaning changes.
constexpr char kCacheFormat[] = "gi-reference-cache 1";

ReferenceGiSettings referenceSettings(const GiLighting& light, int directions) {
    ReferenceGiSettings s;
    s.directions = directions;
    s.bounces = 0;
    s.keys = light.keys;  // exact caps (not folded into the SH lighting)
    return s;
}

void addGrid(Fnv1a64& h, const Grid& g) {
    h.addValue(g.nx);
    h.addValue(g.ny);
    h.add(g.data(), g.size() * sizeof(float));
}

double secondsSince(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// The cache file's grids in order: ambient, direct RGB, then each running indirect sum's RGB.
std::vector<Grid> flatten(const GiReference& r) {
    std::vector<Grid> out{r.ambient};
    out.insert(out.end(), r.direct.begin(), r.direct.end());
    for (const std::array<Grid, 3>& sum : r.indirectUpTo) out.insert(out.end(), sum.begin(), sum.end());
    return out;
}

GiReference unflatten(std::vector<Grid>&& grids) {
    GiReference r;
    r.ambient = std::move(grids[0]);
    for (std::size_t c = 0; c < 3; ++c) r.direct[c] = std::move(grids[1 + c]);
    for (std::size_t first = 4; first + 3 <= grids.size(); first += 3) {
        std::array<Grid, 3>& sum = r.indirectUpTo.emplace_back();
        for (std::size_t c = 0; c < 3; ++c) sum[c] = std::move(grids[first + c]);
    }
    return r;
}

}  // namespace

void Fnv1a64::add(const void* data, std::size_t bytes) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < bytes; ++i) {
        h_ ^= p[i];
        h_ *= 0x100000001b3ull;
    }
}

std::string referenceCacheName(const Dem& d, const GiLighting& light, const AlbedoMap& albedo, int maxBounces,
                               int directions) {
    Fnv1a64 h;
    h.add(kCacheFormat, sizeof kCacheFormat);
    addGrid(h, d.heights);
    h.addValue(d.cell);
    for (const ShVector& c : light.environment.c) h.add(c.data(), c.size() * sizeof(double));
    for (const Grid& g : albedo.channel) addGrid(h, g);
    const ReferenceGiSettings s = referenceSettings(light, directions);
    for (const KeyLight& k : s.keys) {
        h.addValue(k.azimuthDeg);
        h.addValue(k.elevationDeg);
        h.addValue(k.radiusDeg);
        h.add(k.rgb, sizeof k.rgb);
    }
    h.addValue(s.directions);
    h.addValue(s.azimuths);
    h.addValue(s.marchStep);
    h.addValue(s.keyAzimuths);
    h.addValue(maxBounces);
    char hex[17];
    std::snprintf(hex, sizeof hex, "%016" PRIx64, h.value());
    return "gi_reference_" + d.name + "_" + hex + ".bin";
}

GiReference computeReference(const Dem& d, const GiLighting& light, const AlbedoMap& albedo, int maxBounces,
                             int directions) {
    const auto t0 = Clock::now();
    const ReferenceGiSettings s = referenceSettings(light, directions);
    GiReference r;
    ReferenceGiResult res;
    renderReferenceGi(d.heights.cview(), d.cell, light.environment, &albedo, s, res);
    r.direct = res.direct;
    r.ambient = std::move(res.ambient);
    std::fprintf(stderr, "  %s: direct light and ambient %.0f s\n", d.name.c_str(), secondsSince(t0));
    std::array<Grid, 3> prev = res.direct, next, sum;
    for (Grid& g : sum) g.resize(d.heights.nx, d.heights.ny, 0.0f);
    for (int b = 1; b <= maxBounces; ++b) {
        gatherReferenceBounce(d.heights.cview(), d.cell, prev, &albedo, s, next);
        for (std::size_t c = 0; c < 3; ++c)
            for (std::size_t i = 0; i < sum[c].v.size(); ++i) sum[c].v[i] += next[c].v[i];
        r.indirectUpTo.push_back(sum);
        std::swap(prev, next);
        std::fprintf(stderr, "  %s: bounce %d of %d done, %.0f s\n", d.name.c_str(), b, maxBounces, secondsSince(t0));
    }
    r.seconds = secondsSince(t0);
    return r;
}

std::string defaultReferenceCacheDir() {
    return (std::filesystem::temp_directory_path() / "terrain_bench_references").string();
}

GiReference cachedReference(const std::string& cacheDir, const Dem& d, const GiLighting& light, const AlbedoMap& albedo,
                            int maxBounces, int directions) {
    const std::filesystem::path file =
        std::filesystem::path(cacheDir) / referenceCacheName(d, light, albedo, maxBounces, directions);
    std::vector<Grid> grids(4 + 3 * static_cast<std::size_t>(maxBounces));
    if (readCachedGrids(file.string(), d.heights.nx, d.heights.ny, grids)) {
        std::fprintf(stderr, "reference %s: read %s\n", d.name.c_str(), file.c_str());
        GiReference r = unflatten(std::move(grids));
        r.fromCache = true;
        std::ifstream(file.string() + ".seconds") >> r.seconds;  // 0 when the note is missing
        return r;
    }
    std::fprintf(stderr, "reference %s %dx%d, %d directions, %d bounces (minutes; cached as %s) ...\n", d.name.c_str(),
                 d.heights.nx, d.heights.ny, directions, maxBounces, file.c_str());
    GiReference r = withThreads(0, [&] { return computeReference(d, light, albedo, maxBounces, directions); });
    // written under another name and renamed: an interrupted run leaves no partial file under the real one
    std::filesystem::create_directories(cacheDir);
    const std::filesystem::path partial = file.string() + ".partial";
    writeCachedGrids(partial.string(), flatten(r));
    std::filesystem::rename(partial, file);
    std::ofstream(file.string() + ".seconds") << r.seconds << "\n";
    return r;
}

}  // namespace terrain::bench
