#include "gi/glossy_lobe_members.h"

#include <cmath>

#include "core/error.h"
#include "core/parallel.h"

namespace terrain::gi {

void prepareLobeMembers(ConstGridView gradX, ConstGridView gradY, const VisibilityField& env, int subsample,
                        const ShRgb& light, const AlbedoMap* surface, const ShadingSettings& shading, LobeMembers& m) {
    const int nx = gradX.nx, ny = gradX.ny;
    const std::size_t receivers = static_cast<std::size_t>(env.nxr) * env.nyr;
    if (gradY.nx != nx || gradY.ny != ny || receivers == 0 || env.maxSlope.size() % receivers != 0)
        throw InputError("glossy lobe members: the gradients and the environment scan do not match");
    m.nx = nx;
    m.ny = ny;
    m.nxr = env.nxr;
    m.nyr = env.nyr;
    m.azimuths = static_cast<int>(env.maxSlope.size() / receivers);
    m.perReceiver = 1.0 / subsample;
    m.azimuthsPerRadian = m.azimuths / (2.0 * kPi);
    m.exponentMap = surface && !surface->phongExponent.empty();
    constexpr std::size_t R = LobeMembers::kRecord;
    m.texels.resize(static_cast<std::size_t>(nx) * ny * R);
    parallelFor(0, ny, 16, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) {
            const float *gx = gradX.row(y), *gy = gradY.row(y);
            float* rec = m.texels.data() + static_cast<std::size_t>(y) * nx * R;
            for (int x = 0; x < nx; ++x, rec += R) {
                rec[0] = gx[x];
                rec[1] = gy[x];
                rec[5] = m.exponentMap ? surface->phongExponent(x, y) : shading.phongExponent;
                rec[6] = rec[7] = 0.0f;
            }
        }
    });
    // the horizons receiver by receiver: a hit reads all of a receiver's
    // azimuths it needs from one line
    const std::size_t M = static_cast<std::size_t>(m.azimuths);
    m.horizons.resize(receivers * M);
    parallelFor(0, env.nyr, 16, [&](int Y0, int Y1) {
        for (std::size_t i = static_cast<std::size_t>(Y0) * env.nxr; i < static_cast<std::size_t>(Y1) * env.nxr; ++i)
            for (std::size_t a = 0; a < M; ++a) m.horizons[i * M + a] = env.maxSlope[a * receivers + i];
    });
    float ph[kShOrder];
    phongLobeFactors(shading.phongExponent, ph);
    const float ws = specularWeightOf(shading);
    for (std::size_t c = 0; c < 3; ++c)
        for (int i = 0; i < kShCount; ++i) {
            const auto k = static_cast<std::size_t>(i);
            m.light[c][k] = ws * static_cast<float>(light.c[c][k]);
            m.filtered[c][k] = ph[shBand(i)] * m.light[c][k];
        }
    for (std::size_t k = 0; k < m.halfErfc.size(); ++k) {
        const double x = -LobeMembers::kErfcRange + static_cast<double>(k) / LobeMembers::kErfcSteps;
        m.halfErfc[k] = static_cast<float>(0.5 * std::erfc(x));
    }
}

}  // namespace terrain::gi
