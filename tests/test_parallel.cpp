#include <algorithm>
#include <cstdint>
#include <vector>

#include <doctest/doctest.h>

#include "core/error.h"
#include "core/parallel.h"
#include "sim/terrain.h"

using namespace terrain;

TEST_CASE("sim.parallel: deterministic reduction is bit-identical for any thread count") {
    std::vector<float> v(100003);
    for (std::size_t i = 0; i < v.size(); ++i)
        v[i] = 1.0f / static_cast<float>(i + 1) + 1e-3f * static_cast<float>(i % 7);
    auto sum = [&] {
        return deterministicReduce(
            0, static_cast<int>(v.size()), 4096, 0.0f,
            [&](int b, int e) {
                float s = 0.0f;
                for (int i = b; i < e; ++i) s += v[static_cast<std::size_t>(i)];
                return s;
            },
            [](float a, float b) { return a + b; });
    };
    const float s1 = withThreads(1, sum);
    for (int t : {2, 3, 8}) CHECK(withThreads(t, sum) == s1);
    // and against a serial loop with the same chunking
    float serial = 0.0f;
    for (std::size_t b = 0; b < v.size(); b += 4096) {
        float s = 0.0f;
        for (std::size_t i = b; i < std::min(v.size(), b + 4096); ++i) s += v[i];
        serial += s;
    }
    CHECK(serial == s1);
}

TEST_CASE("sim.terrain: state hash sees every layer and ignores nothing") {
    TerrainState s;
    s.allocate(13, 7, 2.0f, LayerSet{.water = true, .sediment = true, .pipes = true, .faceVelocity = true});
    const auto h0 = hashState(s);
    CHECK(hashState(s) == h0);
    s.faceV(12, 7) = 1e-30f;  // last element of the last layer
    const auto h1 = hashState(s);
    CHECK(h1 != h0);
    s.faceV(12, 7) = 0.0f;
    s.bedrock(0, 0) = -0.0f;  // sign bit differs: a different byte pattern
    CHECK(hashState(s) != h0);
    CHECK(hashHex(0x0123456789abcdefull) == "0123456789abcdef");
}

TEST_CASE("sim.terrain: absurd sizes are rejected with a clear error") {
    TerrainState s;
    CHECK_THROWS_WITH_AS(s.allocate(0, 10, 1.0f, {}), doctest::Contains("grid width must be in [1, 16384] (got 0)"),
                         InputError);
    CHECK_THROWS_AS(s.allocate(100000, 10, 1.0f, {}), InputError);
    CHECK_THROWS_AS(s.allocate(10, 10, -1.0f, {}), InputError);
    s.allocate(1, 1, 1.0f, {});
    CHECK(s.bedrock.size() == 1);
}
