// The 8-wide AVX2 kernels (chosen at run time where the processor has AVX2)
// against the 4-wide SSE2 baseline (the lobe gather's walks: 4 double lanes
// against 2): every GI output must be bit-identical,
// so results do not depend on which path a machine takes.
#include <vector>

#include <doctest/doctest.h>

#include "core/parallel.h"
#include "core/simd.h"
#include "gi/frame.h"
#include "tests/gi_test_terrain.h"

using namespace terrain;
using namespace terrain::gi;

namespace {

std::vector<float> frameOutputs(bool wide, const GiSettings& s, const Grid& h, const AlbedoMap& a) {
    const bool was = simd::wideEnabled();
    simd::setWideEnabled(wide);
    GiState st;
    withThreads(2, [&] { runGiFrame(h.view(), 1.5f, GiLighting{}, s, st, &a); });
    simd::setWideEnabled(was);
    std::vector<float> all;
    for (int c = 0; c < 3; ++c) {
        const auto& d = st.shade.rgb[static_cast<std::size_t>(c)].v;
        all.insert(all.end(), d.begin(), d.end());
        if (s.indirect.bounces > 0) {
            const auto& ind = st.indirect.indirect[static_cast<std::size_t>(c)].v;
            all.insert(all.end(), ind.begin(), ind.end());
        }
    }
    return all;
}

}  // namespace

TEST_CASE("simd: the AVX2 and SSE2 kernels give bit-identical GI frames") {
    if (!simd::setWideEnabled(true)) {
        MESSAGE("no AVX2 on this processor: only the SSE2 path exists");
        return;
    }
    const Grid h = gi_test::hills(77, 12.0f);
    AlbedoMap a = uniformAlbedo(77, 77, 0.6f);
    for (int y = 0; y < 77; ++y)
        for (int x = 0; x < 77; ++x)
            a.channel[0](x, y) = 0.3f + 0.5f * static_cast<float>((x * 5 + y * 3) % 13) / 13.0f;
    for (int sub : {1, 2, 4})
        for (LambertIndirect lam : {LambertIndirect::BlockerRadiance, LambertIndirect::ShKernel}) {
            GiSettings s = GiSettings{};
            s.subsample = sub;
            s.indirect.bounces = 2;
            s.indirect.lambert = lam;
            CAPTURE(sub);
            CAPTURE(static_cast<int>(lam));
            const std::vector<float> narrow = frameOutputs(false, s, h, a);
            const std::vector<float> wide = frameOutputs(true, s, h, a);
            REQUIRE(narrow.size() == wide.size());
            CHECK(narrow == wide);
        }
    // the glossy lobe gather: its walks test 2 (SSE2) or 4 (AVX2) texels per
    // block of lanes; at 4x a receiver's 16 texels fill several blocks
    for (int sub : {1, 2, 4}) {
        GiSettings s = GiSettings{};
        s.subsample = sub;
        s.indirect.bounces = 1;
        s.shading.brdf = Brdf::Phong;
        s.shading.phongExponent = 24.0f;
        s.indirect.glossy = GlossyIndirect::LobeScan;
        CAPTURE(sub);
        const std::vector<float> narrow = frameOutputs(false, s, h, a);
        const std::vector<float> wide = frameOutputs(true, s, h, a);
        REQUIRE(narrow.size() == wide.size());
        CHECK(narrow == wide);
    }
}
