#include "bench/indirect_frame.h"

#include <cstdio>

#include "core/simd.h"

namespace terrain::bench {

using namespace terrain::gi;

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

IndirectErrors indirectErrors(const GiState& st, const GiReference& ref, int bounces) {
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
