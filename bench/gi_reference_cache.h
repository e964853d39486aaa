#pragma once
// The exact references the GI suites measure the fast path against
// (gi/reference_gi.h): direct light, the running sums of the indirect bounces
// and the ambient map of one terrain under one lighting. They take minutes,
// so cachedReference keeps them on disk under a name that hashes every input
// they depend on: a changed height, cell size, lighting, albedo or reference
// setting never reads a stale file.
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "bench/bench_common.h"
#include "core/grid.h"
#include "gi/lights.h"
#include "gi/shading.h"

namespace terrain::bench {

/// Direct light, the indirect light of bounces 1..b for each b, and the
/// ambient map (normal-weighted sky-view factor, 256 azimuths).
struct GiReference {
    std::array<Grid, 3> direct;
    std::vector<std::array<Grid, 3>> indirectUpTo;  // [b - 1]: bounces 1..b
    Grid ambient;
    double seconds = 0.0;  // time it took to compute (as recorded beside the cache file when read from it)
    bool fromCache = false;
};

/// The environment as SH and the key lights as exact caps, `directions`
/// gathering directions per texel, bounces 1..maxBounces; progress on stderr.
GiReference computeReference(const Dem& d, const gi::GiLighting& light, const gi::AlbedoMap& albedo, int maxBounces,
                             int directions);

/// Where the suites keep references across runs unless told otherwise: a
/// folder in the system's temporary directory.
std::string defaultReferenceCacheDir();

/// The reference of computeReference, read from cacheDir when a file of the
/// same inputs is there, else computed and written there (cacheDir created).
GiReference cachedReference(const std::string& cacheDir, const Dem& d, const gi::GiLighting& light,
                            const gi::AlbedoMap& albedo, int maxBounces, int directions);

/// FNV-1a 64 of a byte sequence, fed piecewise.
class Fnv1a64 {
public:
    void add(const void* data, std::size_t bytes);
    template <class T>
    void addValue(const T& v) {
        add(&v, sizeof v);
    }
    std::uint64_t value() const { return h_; }

private:
    std::uint64_t h_ = 0xcbf29ce484222325ull;
};

/// The cache file's name for these inputs: gi_reference_<dem>_<hash>.bin.
std::string referenceCacheName(const Dem& d, const gi::GiLighting& light, const gi::AlbedoMap& albedo, int maxBounces,
                               int directions);

}  // namespace terrain::bench
