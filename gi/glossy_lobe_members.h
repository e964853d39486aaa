#pragma once
// What a surface point sends back along a ray of the lobe gather's first
// bounce (GlossyIndirect::LobeScan, gi/glossy_lobe_gather.h): its Phong exit
// radiance as the lobe-filtered light times the part of the lobe its
// horizon leaves open, instead of its order-4 SH exit-radiance vector E.
//
// Why. E (gi/glossy_exit_radiance.h) carries the member's incident radiance
// T_L V projected to order-4 SH, so the horizon's edge, which a sharp lobe
// resolves, is blurred to band 3: measured with the glossy reference's
// diagnostics (membersSh, membersWindowed; README, "The lobe gather"), that
// was the floor under the gather at sharp lobes, and the product below lies
// far lower there.
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
// The README compares the closed form with the lobe's open fraction taken
// by quadrature over the reference's exact horizons.
//
// Cost. A hit reads one record of 8 floats for each of the four texels
// about it (gradients, D, exponent) and one line of horizons for each of the
// four receivers about it, asked for when the hit is found (the hits fall
// anywhere); erfc / 2 comes from a table (x in [-4, 4], steps of 1 / 64,
// linear: within 2e-5, the step squared / 8 times its largest curvature).
//
// Positions are full-resolution cells; the gradients, D and the exponent
// are read bilinear there, as E was.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <vector>

#include "core/grid.h"
#include "core/simd.h"
#include "gi/azimuth.h"
#include "gi/bilinear_tap.h"
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
    int nx = 0, ny = 0, nxr = 0, nyr = 0, azimuths = 0;
    double perReceiver = 1.0;        // 1 / the sub-sampling: receiver cells per texel cell
    double azimuthsPerRadian = 0.0;  // azimuths / (2 pi)
    // (64-byte aligned: a receiver's 16 horizons are one cache line, two
    // texels' records share one)
    FloatVector texels;        // kRecord per texel
    FloatVector horizons;      // per receiver its horizon slope at each azimuth 2 pi j / azimuths
    bool exponentMap = false;  // S varies by texel (else the lobe factors are the settings')
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

/// Where rays met the surface, one per hit: the taps of the texels' records
/// and of the receivers' horizons about where it met it, and the unit
/// direction back to the receiver (one array per component, read as lanes).
struct LobeMemberHits {
    struct Taps {
        BilinearTap record, horizon;
    };
    std::vector<Taps> taps;
    std::vector<float> bx, by, bz;
    std::vector<float> sent[3];  // what lobeMembersSend writes: RGB per hit
    void clear() {
        taps.clear();
        for (auto* v : {&bx, &by, &bz}) v->clear();
    }
    /// A hit at (px, py) (full-resolution cells) whose way back is `back`;
    /// asks for the cache lines its member will be read from (the rays meet
    /// the surface anywhere, and the hits are read after the walks).
    [[gnu::always_inline]] void push(const LobeMembers& m, double px, double py, const float back[3]) {
        const Taps t{bilinearTap(m.nx, m.ny, px, py),
                     bilinearTap(m.nxr, m.nyr, px * m.perReceiver, py * m.perReceiver)};
        const float* a = m.texels.data() + t.record.i00 * LobeMembers::kRecord;
        __builtin_prefetch(a);
        __builtin_prefetch(a + LobeMembers::kRecord);
        __builtin_prefetch(a + t.record.dy * LobeMembers::kRecord);
        __builtin_prefetch(a + (t.record.dy + 1) * LobeMembers::kRecord);
        const std::size_t line = static_cast<std::size_t>(m.azimuths);
        const float* h = m.horizons.data() + t.horizon.i00 * line;
        for (std::size_t k : {std::size_t{0}, t.horizon.dx, t.horizon.dy, t.horizon.dx + t.horizon.dy})
            __builtin_prefetch(h + k * line);
        taps.push_back(t);
        bx.push_back(back[0]);
        by.push_back(back[1]);
        bz.push_back(back[2]);
    }
    /// A copy of the last hit (to fill up a group of lanes).
    void pushLast() {
        taps.push_back(taps.back());
        bx.push_back(bx.back());
        by.push_back(by.back());
        bz.push_back(bz.back());
    }
    std::size_t size() const { return taps.size(); }
};

namespace lobe_members_detail {

// The azimuth of (x, y) in [0, 2 pi) per lane: atan of the smaller over the
// larger component (simd::atanv), then the octant.
template <class V>
[[gnu::always_inline]] inline V azimuthLanes(V x, V y) {
    const V zero = simd::splat<V>(0.0f);
    const V ax = x < zero ? -x : x, ay = y < zero ? -y : y;
    const V lo = simd::vmin(ax, ay), hi = simd::vmax(ax, ay);
    V a = simd::atanv(hi > zero ? lo / hi : zero);
    const V halfPi = simd::splat<V>(static_cast<float>(0.5 * kPi)), pi = simd::splat<V>(static_cast<float>(kPi));
    a = ay > ax ? halfPi - a : a;
    a = x < zero ? pi - a : a;
    a = y < zero ? 2.0f * pi - a : a;
    return a >= 2.0f * pi ? zero : a;
}

// What the members of hits [k, k + lanes of V) send (see the header's
// formula): each lane the arithmetic of one hit alone, so both lane widths
// give the same values.
template <class V>
[[gnu::always_inline]] inline void sendLanes(const LobeMembers& m, LobeMemberHits& hits, std::size_t k) {
    using simd::load;
    using simd::splat;
    constexpr int L = simd::kLaneCount<V>;
    constexpr std::size_t R = LobeMembers::kRecord;
    // the texels' records about each hit, bilinear: a whole record per lane
    // (two runs of 4 floats), then the lanes field by field: gx, gy, D (RGB), S
    alignas(32) float bilinear[L][R];
    for (int l = 0; l < L; ++l) {
        const BilinearTap& t = hits.taps[k + l].record;
        const float* rec = m.texels.data() + t.i00 * R;
        const std::size_t dx = t.dx * R, dy = t.dy * R;
        const simd::F4 w00 = splat<simd::F4>(t.w00), w10 = splat<simd::F4>(t.w10), w01 = splat<simd::F4>(t.w01),
                       w11 = splat<simd::F4>(t.w11);
        for (std::size_t h = 0; h < R; h += 4)
            simd::store(bilinear[l] + h, w00 * load<simd::F4>(rec + h) + w10 * load<simd::F4>(rec + dx + h) +
                                             w01 * load<simd::F4>(rec + dy + h) +
                                             w11 * load<simd::F4>(rec + dx + dy + h));
    }
    V f6[6];
    for (int f = 0; f < 6; ++f) {
        alignas(32) float lanes[L];
        for (int l = 0; l < L; ++l) lanes[l] = bilinear[l][f];
        f6[f] = load<V>(lanes);
    }
    const V one = splat<V>(1.0f), zero = splat<V>(0.0f);
    // the member's normal and the reflection of the way back about it
    const V gx = f6[0], gy = f6[1], S = f6[5];
    const V inv = one / simd::sqrtv(one + gx * gx + gy * gy);
    const V nx = -gx * inv, ny = -gy * inv, nz = inv;
    const V bx = load<V>(hits.bx.data() + k), by = load<V>(hits.by.data() + k), bz = load<V>(hits.bz.data() + k);
    const V nb = 2.0f * (nx * bx + ny * by + nz * bz);
    const V rx = nb * nx - bx, ry = nb * ny - by, rz = nb * nz - bz;
    // the horizon along R's azimuth: linear between the scan's azimuths,
    // bilinear between the receivers
    alignas(32) float u[L], hz[L];
    simd::store(u, azimuthLanes(rx, ry) * static_cast<float>(m.azimuthsPerRadian));
    const std::size_t line = static_cast<std::size_t>(m.azimuths);
    for (int l = 0; l < L; ++l) {
        const BilinearTap& rt = hits.taps[k + l].horizon;
        const int a0 = std::min(static_cast<int>(u[l]), m.azimuths - 1), a1 = a0 + 1 < m.azimuths ? a0 + 1 : 0;
        const float fa = u[l] - static_cast<float>(a0);
        const float h0 = rt.at(m.horizons.data() + a0, line), h1 = rt.at(m.horizons.data() + a1, line);
        hz[l] = h0 + fa * (h1 - h0);
    }
    // Vbar: sin and cos of e_h - e_R, then erfc from the table
    const V h = load<V>(hz);
    const V horizontal = simd::sqrtv(rx * rx + ry * ry), invH = one / simd::sqrtv(one + h * h);
    const V sinD = (h * horizontal - rz) * invH, cosD = (horizontal + h * rz) * invH;
    const V range = splat<V>(static_cast<float>(LobeMembers::kErfcRange));
    const V x = simd::vmin(simd::vmax(sinD * simd::sqrtv(0.5f * (S + one)), -range), range);
    alignas(32) float tableAt[L], open[L];
    simd::store(tableAt, (x + range) * static_cast<float>(LobeMembers::kErfcSteps));
    for (int l = 0; l < L; ++l) {
        const int i = std::min(static_cast<int>(tableAt[l]), 2 * LobeMembers::kErfcRange * LobeMembers::kErfcSteps);
        const auto ii = static_cast<std::size_t>(i);
        open[l] = m.halfErfc[ii] + (tableAt[l] - static_cast<float>(i)) * (m.halfErfc[ii + 1] - m.halfErfc[ii]);
    }
    // beyond a quarter turn the sine turns back: 0 or 1 by the angle's sign
    const V Vbar = cosD <= zero ? (sinD > zero ? zero : one) : load<V>(open);
    // the lobe-filtered light at R
    V y[kShCount];
    shBasisLanes<V>(rx, ry, rz, y);
    V ph[kShOrder] = {one, one, one, one};
    if (m.exponentMap) {
        // g_l = q^(l^2), q = e^{-1 / (2 S)}
        alignas(32) float Ss[L], q[L];
        simd::store(Ss, S);
        for (int l = 0; l < L; ++l) q[l] = std::exp(-0.5f / Ss[l]);
        const V qv = load<V>(q), q4 = (qv * qv) * (qv * qv);
        ph[1] = qv;
        ph[2] = q4;
        ph[3] = q4 * q4 * qv;
    }
    for (std::size_t c = 0; c < 3; ++c) {
        V spec = zero;
        if (m.exponentMap)
            for (int i = 0; i < kShCount; ++i) spec += ph[shBand(i)] * m.light[c][static_cast<std::size_t>(i)] * y[i];
        else
            for (int i = 0; i < kShCount; ++i) spec += m.filtered[c][static_cast<std::size_t>(i)] * y[i];
        simd::store(hits.sent[c].data() + k, f6[2 + c] + Vbar * spec);
    }
}

}  // namespace lobe_members_detail

/// hits.sent: what the member of every hit sends back along its ray (RGB,
/// see above), lanes of V at a time (the last group filled up with copies of
/// the last hit, whose results are dropped).
template <class V>
[[gnu::always_inline]] inline void lobeMembersSend(const LobeMembers& m, LobeMemberHits& hits) {
    constexpr std::size_t L = simd::kLaneCount<V>;
    const std::size_t n = hits.size();
    if (n == 0) return;
    while (hits.size() % L != 0) hits.pushLast();
    for (auto& s : hits.sent) s.resize(hits.size());
    for (std::size_t k = 0; k < hits.size(); k += L) lobe_members_detail::sendLanes<V>(m, hits, k);
}

}  // namespace terrain::gi
