#pragma once
// What a surface point sends back along a ray of the lobe gather's first
// bounce (GlossyIndirect::LobeScan, gi/glossy_lobe_gather.h): its Phong exit
// radiance as the lobe-filtered light times the part of the lobe its
// horizon leaves open, instead of its order-4 SH exit-radiance vector E.
//
// Why. E (gi/glossy_exit_radiance.h) carries the member's incident radiance
// T_L V projected to order-4 SH, so the horizon's edge, which a sharp lobe
// resolves, is blurred to band 3. Measured with the glossy reference's
// diagnostics (README, "The lobe gather"), members sending order-4 SH are
// 3.4 / 6.4 / 10.0 / 13.4 % from the truth at S = 8 / 16 / 32 / 64, the
// floor under the gather at sharp lobes; the product below is 5.6 / 3.5 /
// 2.2 / 1.5 %.
//
// What is sent. Member q (normal N, exponent S) towards w, R = R_N(w) =
// 2 (N . w) N - w: its first-bounce incident radiance is the lights' SH
// radiance L(w') where w' clears q's horizon, 0 below, and its Phong part
// int L V f_R dw' (f_R the normalised lobe about R) is taken as the product
// of the two integrals
//   L_q(w) = D_q + w_s [sum_lm g_l L_lm Y_lm(R)] Vbar_q(R),
// the lobe-filtered light (Section 7's factors g_l, as the direct shading
// filters it) times the lobe's open fraction Vbar. The product is exact
// where the light is constant across the lobe, so it suits sharp lobes; a
// wide lobe (S = 8) that holds the sun on one side of a horizon is where it
// errs most. D_q is the diffuse part of the member's shade
// (glossyExitRadiance's `diffuse`).
//
// The open fraction. About R the lobe's directions spread as a 2D normal of
// variance 1 / (S + 1) per axis (the quadrature's measure: the chance of an
// angle beyond x from R is cos^(S+1) x ~ e^{-(S+1) x^2 / 2}), so their
// elevations spread about R's elevation e_R with that variance, and the part
// above the horizon's elevation e_h at R's azimuth is
//   Vbar = erfc((e_h - e_R) sqrt((S + 1) / 2)) / 2,
// with sin(e_h - e_R) for the angle (no inverse trigonometry per hit; the
// two agree where the lobe's edge lies, and beyond a quarter turn, where the
// sine turns back, Vbar is 0 or 1 by the angle's sign). The horizon is the
// environment scan's (VisibilityField::maxSlope at its m azimuths 2 pi j / m,
// Section 6): linear between azimuths, bilinear between receivers (Fig. 7).
// Against the reference with exact horizons (lobe fraction by quadrature)
// the closed form costs nothing measurable (README).
//
// Cost. A hit reads one record of 8 floats for each of the four texels
// about it (gradients, D, exponent) and one line of horizons for each of the
// four receivers about it, asked for when the hit is found (the hits fall
// anywhere); erfc comes from a table (x in [-4, 4], steps of 1 / 64, linear:
// within 1e-4 of it).
//
// Positions are full-resolution cells; the gradients, D and the exponent
// are read bilinear there, as E was.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <vector>

#include "core/grid.h"
#include "gi/azimuth.h"
#include "gi/lights.h"
#include "gi/shading.h"
#include "gi/visibility.h"

namespace terrain::gi {

/// The first bounce's members of one frame (reused: no allocation after the
/// first frame of a size).
struct LobeMembers {
    static constexpr int kRecord = 8;   // floats per texel: gx, gy, D (RGB), S, two unused
    static constexpr int kDiffuse = 2;  // where D starts in a record
    static constexpr int kErfcSteps = 64, kErfcRange = 4;
    int nx = 0, ny = 0, nxr = 0, nyr = 0, azimuths = 0, subsample = 1;
    std::vector<float> texels;    // kRecord per texel
    std::vector<float> horizons;  // per receiver its horizon slope at each azimuth 2 pi j / azimuths
    bool exponentMap = false;     // S varies by texel (else the lobe factors are the settings')
    // w_s L_lm of the lights (RGB x 16), and w_s g_l L_lm with the settings' lobe
    std::array<std::array<float, kShCount>, 3> light{}, filtered{};
    // erfc(x) / 2 at x = -range + k / steps
    std::array<float, 2 * kErfcRange * kErfcSteps + 2> halfErfc{};
};

/// Fills `m` for a frame but for the D of each record, which the exit
/// radiance kernel writes (glossyExitRadiance's `diffuse`, stride kRecord at
/// texels + kDiffuse): the gradients, the exponents (the AlbedoMap's map or
/// the settings'), the environment scan's horizons per receiver, and the
/// lights `light` (SH radiance, unoccluded) weighted by w_s.
void prepareLobeMembers(ConstGridView gradX, ConstGridView gradY, const VisibilityField& env, int subsample,
                        const ShRgb& light, const AlbedoMap* surface, const ShadingSettings& shading, LobeMembers& m);

namespace lobe_members_detail {

// Bilinear taps of an n x ny grid at (p, q) in its own cells.
struct Tap {
    std::size_t i00, dx, dy;
    float w00, w10, w01, w11;
    [[gnu::always_inline]] float at(const float* v, std::size_t stride) const {
        return w00 * v[i00 * stride] + w10 * v[(i00 + dx) * stride] + w01 * v[(i00 + dy) * stride] +
               w11 * v[(i00 + dx + dy) * stride];
    }
};

[[gnu::always_inline]] inline Tap tapAt(int n, int ny, double p, double q) {
    const int ix = std::clamp(static_cast<int>(std::floor(p)), 0, std::max(n - 2, 0));
    const int iy = std::clamp(static_cast<int>(std::floor(q)), 0, std::max(ny - 2, 0));
    const float fx = std::clamp(static_cast<float>(p - ix), 0.0f, 1.0f);
    const float fy = std::clamp(static_cast<float>(q - iy), 0.0f, 1.0f);
    return {static_cast<std::size_t>(iy) * static_cast<std::size_t>(n) + static_cast<std::size_t>(ix),
            n > 1 ? std::size_t{1} : std::size_t{0},
            ny > 1 ? static_cast<std::size_t>(n) : std::size_t{0},
            (1.0f - fx) * (1.0f - fy),
            fx * (1.0f - fy),
            (1.0f - fx) * fy,
            fx * fy};
}

// Vbar: the part of a lobe of exponent S about r (unit) above horizon slope
// h along r's azimuth (see above).
[[gnu::always_inline]] inline float openFraction(const LobeMembers& m, const float r[3], float h, float S) {
    const float horizontal = std::sqrt(r[0] * r[0] + r[1] * r[1]);
    const float inv = 1.0f / std::sqrt(1.0f + h * h);
    const float sinD = (h * horizontal - r[2]) * inv;  // sin(e_h - e_R)
    const float cosD = (horizontal + h * r[2]) * inv;
    if (cosD <= 0.0f) return sinD > 0.0f ? 0.0f : 1.0f;
    const float u = (std::clamp(sinD * std::sqrt(0.5f * (S + 1.0f)), -1.0f * LobeMembers::kErfcRange,
                                1.0f * LobeMembers::kErfcRange) +
                     LobeMembers::kErfcRange) *
                    LobeMembers::kErfcSteps;
    const int k = std::min(static_cast<int>(u), 2 * LobeMembers::kErfcRange * LobeMembers::kErfcSteps);
    const float f = u - static_cast<float>(k);
    const auto kk = static_cast<std::size_t>(k);
    return m.halfErfc[kk] + f * (m.halfErfc[kk + 1] - m.halfErfc[kk]);
}

}  // namespace lobe_members_detail

/// Asks for the cache lines the member at (px, py) will be read from.
[[gnu::always_inline]] inline void prefetchLobeMember(const LobeMembers& m, double px, double py) {
    using lobe_members_detail::tapAt;
    const auto t = tapAt(m.nx, m.ny, px, py);
    const float* a = m.texels.data() + t.i00 * LobeMembers::kRecord;
    __builtin_prefetch(a);
    __builtin_prefetch(a + LobeMembers::kRecord);
    __builtin_prefetch(a + t.dy * LobeMembers::kRecord);
    __builtin_prefetch(a + (t.dy + 1) * LobeMembers::kRecord);
    const double s = m.subsample;
    const auto r = tapAt(m.nxr, m.nyr, px / s, py / s);
    const std::size_t line = static_cast<std::size_t>(m.azimuths);
    const float* h = m.horizons.data() + r.i00 * line;
    for (std::size_t k : {std::size_t{0}, r.dx, r.dy, r.dx + r.dy}) __builtin_prefetch(h + k * line);
}

/// The radiance (RGB) the member at full-resolution position (px, py) sends
/// towards `back` (unit): D + w_s filtered light x Vbar (see above).
[[gnu::always_inline]] inline void lobeMemberSends(const LobeMembers& m, double px, double py, const float back[3],
                                                   float out[3]) {
    using namespace lobe_members_detail;
    constexpr std::size_t R = LobeMembers::kRecord;
    const Tap t = tapAt(m.nx, m.ny, px, py);
    const float* rec = m.texels.data();
    // the member's normal and the reflection of `back` about it
    const float gx = t.at(rec, R), gy = t.at(rec + 1, R);
    const float inv = 1.0f / std::sqrt(1.0f + gx * gx + gy * gy);
    const float n[3] = {-gx * inv, -gy * inv, inv};
    const float nb = 2.0f * (n[0] * back[0] + n[1] * back[1] + n[2] * back[2]);
    const float r[3] = {nb * n[0] - back[0], nb * n[1] - back[1], nb * n[2] - back[2]};
    float y[kShCount];
    shBasisLanes<float>(r[0], r[1], r[2], y);
    const float S = t.at(rec + 5, R);
    float spec[3];
    if (m.exponentMap) {
        // g_l = q^(l^2), q = e^{-1 / (2 S)}
        const float q = std::exp(-0.5f / S), q4 = (q * q) * (q * q);
        const float ph[kShOrder] = {1.0f, q, q4, q4 * q4 * q};
        for (std::size_t c = 0; c < 3; ++c) {
            spec[c] = 0.0f;
            for (int i = 0; i < kShCount; ++i)
                spec[c] += ph[shBand(i)] * m.light[c][static_cast<std::size_t>(i)] * y[i];
        }
    } else {
        for (std::size_t c = 0; c < 3; ++c) {
            spec[c] = 0.0f;
            for (int i = 0; i < kShCount; ++i) spec[c] += m.filtered[c][static_cast<std::size_t>(i)] * y[i];
        }
    }
    // the horizon along R's azimuth: linear between the scan's azimuths,
    // bilinear between the receivers
    const double s = m.subsample;
    const Tap rt = tapAt(m.nxr, m.nyr, px / s, py / s);
    const double u = azimuthOf(r[0], r[1]) / (2.0 * kPi) * m.azimuths;
    const int a0 = std::min(static_cast<int>(u), m.azimuths - 1), a1 = (a0 + 1) % m.azimuths;
    const float fa = static_cast<float>(u - a0);
    const std::size_t line = static_cast<std::size_t>(m.azimuths);
    const float h0 = rt.at(m.horizons.data() + a0, line), h1 = rt.at(m.horizons.data() + a1, line);
    const float open = openFraction(m, r, h0 + fa * (h1 - h0), S);
    for (std::size_t c = 0; c < 3; ++c) out[c] = t.at(rec + LobeMembers::kDiffuse + c, R) + open * spec[c];
}

}  // namespace terrain::gi
