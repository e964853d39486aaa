// gi/shading: the receivers' incident SH computed per block of texel rows in
// a worker's window shades every texel bit for bit like the whole field
// (ShadeMaps::keepIncident), for each sub-sampling, BRDF, thread count and
// with restricted texels (runs of columns in some rows).
#include <array>
#include <vector>

#include <doctest/doctest.h>

#include "core/parallel.h"
#include "gi/frame.h"
#include "gi/shading.h"
#include "tests/gi_test_terrain.h"

using namespace terrain;
using namespace terrain::gi;

namespace {

bool sameShade(const ShadeMaps& a, const ShadeMaps& b, bool ambient) {
    bool ok = !ambient || gi_test::sameBits(a.ambient.v, b.ambient.v);
    for (int c = 0; c < 3; ++c)
        ok = ok && gi_test::sameBits(a.rgb[static_cast<std::size_t>(c)].v, b.rgb[static_cast<std::size_t>(c)].v);
    return ok;
}

// The frame's shading lights with every lighting matrix scaled: other light, same visibility.
std::vector<ShadingLight> dimmed(const std::vector<ShadingLight>& lights, double factor) {
    std::vector<ShadingLight> out = lights;
    for (ShadingLight& l : out)
        for (ShMatrix& m : l.product)
            for (double& v : m) v *= factor;
    return out;
}

// Runs per row of an ny-row field: row y's runs are runsOf(y).
template <class RunsOf>
TexelRuns texelRuns(int ny, RunsOf runsOf) {
    TexelRuns r;
    r.ny = ny;
    r.first.push_back(0);
    for (int y = 0; y < ny; ++y) {
        for (ColumnSpan run : runsOf(y)) r.runs.push_back(run);
        r.first.push_back(static_cast<int>(r.runs.size()));
    }
    return r;
}

}  // namespace

TEST_CASE("gi.shading: incident SH in per-block windows shades like the whole field, bit for bit") {
    const Grid h = gi_test::hills(75, 40.0f);  // 75: the receiver grid's last rows and columns are cut
    const GiLighting light = gi_test::sunSkyAndKey();
    for (int s : {1, 2, 4})
        for (Brdf brdf : {Brdf::Lambert, Brdf::LambertPlusPhong}) {
            CAPTURE(s);
            CAPTURE(static_cast<int>(brdf));
            GiSettings settings = gi_test::withBounces(GiSettings{}, s, 0);
            settings.keyLightExactCosine = false;  // the key light goes through the incident SH too
            settings.shading.brdf = brdf;
            GiState st;
            runGiFrame(h.cview(), 10.0f, light, settings, st);
            const std::vector<ShadingLight> lights = dimmed(st.shadingLights, 0.5);
            const int n = static_cast<int>(lights.size());
            // rows 7..18 in two runs (one not starting on a lane group), rows 60 and 74 whole
            const TexelRuns runs = texelRuns(h.ny, [&](int y) {
                if (y >= 7 && y < 19) return std::vector<ColumnSpan>{{0, 21}, {37, h.nx}};
                if (y == 60 || y == 74) return std::vector<ColumnSpan>{{0, h.nx}};
                return std::vector<ColumnSpan>{};
            });
            for (int threads : {1, 3}) {
                CAPTURE(threads);
                std::array<ShadeMaps, 2> whole, windowed;  // [0]: every texel; [1]: the runs over the old light
                for (ShadeMaps* m : {&whole[0], &whole[1]}) m->keepIncident = true;
                withThreads(threads, [&] {
                    const auto shade = [&](const std::vector<ShadingLight>& l, ShadeMaps& out, const TexelRuns* only) {
                        shadeTexels(st.gradX.cview(), st.gradY.cview(), s, st.envVisibility, l.data(), n, nullptr,
                                    settings.shading, out, true, only);
                    };
                    for (std::array<ShadeMaps, 2>* maps : {&whole, &windowed}) {
                        shade(lights, (*maps)[0], nullptr);
                        shade(st.shadingLights, (*maps)[1], nullptr);
                        shade(lights, (*maps)[1], &runs);
                    }
                });
                CHECK(windowed[0].incident.empty());
                CHECK(whole[0].incidentWindow.empty());
                CHECK(sameShade(whole[0], windowed[0], true));
                CHECK(sameShade(whole[1], windowed[1], true));
                // the runs shade the new light, the other texels keep the old one
                CHECK(windowed[1].rgb[0](3, 10) == windowed[0].rgb[0](3, 10));
                CHECK(windowed[1].rgb[0](40, 10) == windowed[0].rgb[0](40, 10));
                CHECK(windowed[1].rgb[0](30, 10) != windowed[0].rgb[0](30, 10));
                CHECK(windowed[1].rgb[0](3, 74) == windowed[0].rgb[0](3, 74));
                CHECK(windowed[1].rgb[0](3, 30) != windowed[0].rgb[0](3, 30));
            }
        }
}
