#pragma once
// Shading in SH (Nowrouzezahrai & Snyder 2009, Section 7) with sub-sampling
// (Fig. 7).
//
// Direct light: the incident radiance of a light is the SH product of its
// radiance L and the visibility V it sees (a triple product; the 16 x 16
// matrix of "multiply by L" is built once per frame per light). It is formed
// at the receivers (the possibly sub-sampled grid) and interpolated
// bilinearly to full resolution as SH vectors, then dotted with the BRDF's
// zonal vector rotated to each texel's own full-resolution normal (Lambert)
// or reflection vector (Phong). Interpolating SH vectors, not shaded colours,
// keeps full-resolution normal detail (Fig. 7).
//
// Lambert needs bands 0..2 only (the clamped cosine's band-3 coefficient is
// 0), so Lambert-only shading interpolates 9 coefficients per channel.
// The ambient map is lam(N) . V_env / pi: the direct-only irradiance / pi
// under a uniform unit sky, i.e. the normal-weighted sky-view factor.
#include <array>
#include <cstdint>
#include <vector>

#include "core/grid.h"
#include "gi/sh.h"
#include "gi/texel_runs.h"
#include "gi/visibility.h"

namespace terrain::gi {

enum class Brdf { Lambert, Phong, LambertPlusPhong };

// Non-negative glossy light. The order-4 SH lobe rings below zero wherever
// the incident radiance varies sharply (a horizon, the sun): Off keeps the
// paper's linear evaluation; Clamp (default) clamps the exit radiance a glossy
// casting-set member sends (max(0, E . Y(-d)), gi/casting_set_scan) and every
// Phong / mixture shade (max(0, .)). Against the exact glossy reference
// (bench/results/gi_glossy.md) the clamp was the most accurate of the
// variants measured, and it is the only one that guarantees no negative
// radiance (the incident SH vectors themselves ring, so no lobe window can).
enum class GlossyPositivity { Off, Clamp };

struct ShadingSettings {
    Brdf brdf = Brdf::Lambert;
    float phongExponent = 32.0f;                            // S in Section 7
    float specularWeight = 0.25f;                           // weight of the Phong lobe in LambertPlusPhong
    float viewDir[3] = {0.0f, 0.0f, 1.0f};                  // unit vector towards the viewer (distant viewer)
    GlossyPositivity positivity = GlossyPositivity::Clamp;  // paper: Off
    bool operator==(const ShadingSettings&) const = default;
};

/// Per-texel surface parameters; empty grids mean the uniform values.
struct AlbedoMap {
    std::array<Grid, 3> channel;  // RGB albedo (empty: 1)
    // Per-texel Phong exponent S (empty: ShadingSettings::phongExponent) and
    // the lobe factors the shading reads, phongLobe[l - 1] = e^{-l^2 / (2 S)}
    // (l = 1..3, rounded to float exactly as phongLobeFactors does). Filled
    // together by setPhongExponentMap: the factors are computed once per map
    // in double, so shading costs 3 loads per texel, has no table error, and
    // a map of constant S shades bit for bit like the scalar exponent S.
    Grid phongExponent;
    std::array<Grid, 3> phongLobe;
};

/// The Phong lobe's per-band factors as shading applies them:
/// ph[l] = float(sqrt(4 pi / (2l+1)) zh_l) with zh = phongZonal(exponent),
/// i.e. e^{-l^2 / (2 S)} (Section 7; Ramamoorthi & Hanrahan 2002).
void phongLobeFactors(double exponent, float ph[kShOrder]);

/// Sets the per-texel Phong exponent map (and its lobe factors). Throws
/// InputError when an exponent is not finite or outside [kMinPhongExponent,
/// kMaxPhongExponent].
void setPhongExponentMap(AlbedoMap& map, const Grid& exponent);
inline constexpr float kMinPhongExponent = 0.01f, kMaxPhongExponent = 10000.0f;

/// Lobe factors of texel i (index into the full-resolution grid): from the
/// map when it has one, else `uniform` (phongLobeFactors of the settings).
inline void texelPhongLobe(const AlbedoMap* map, std::size_t i, const float uniform[kShOrder], float ph[kShOrder]) {
    ph[0] = uniform[0];
    const bool m = map && !map->phongLobe[0].empty();
    for (int l = 1; l < kShOrder; ++l) ph[l] = m ? map->phongLobe[static_cast<std::size_t>(l - 1)].v[i] : uniform[l];
}

/// Weight of the Phong lobe in a BRDF (1 Phong, specularWeight mixture, 0 Lambert).
inline float specularWeightOf(const ShadingSettings& s) {
    return s.brdf == Brdf::Phong ? 1.0f : (s.brdf == Brdf::LambertPlusPhong ? s.specularWeight : 0.0f);
}

/// Where full-resolution texel x reads the receiver grid (receiver X at s X,
/// n receivers; Fig. 7): between receivers i0 and i1 = min(i0 + 1, n - 1) at
/// fraction f, clamped past the last receiver.
/// The Lambert (clamped-cosine) zonal factors with the real SH constants of
/// bands 0..2 folded in: lam(N)_i = c(i) Y_i-polynomial(N), c = c0; c1 x 3;
/// c4, c4, c6, c4, c8 (see lambertAtNormal).
struct LambertFactors {
    float c0, c1, c4, c6, c8;
};
LambertFactors lambertFactors();

/// lam(N): the clamped-cosine zonal vector (divided by pi) turned to the unit
/// normal (X, Y, Z), bands 0..2, for T = float or a float vector; the shade
/// of an SH radiance vector U at that normal is lam . U.
template <class T>
inline void lambertAtNormal(const LambertFactors& f, T X, T Y, T Z, T* lam) {
    lam[0] = T{} + f.c0;
    lam[1] = f.c1 * Y;
    lam[2] = f.c1 * Z;
    lam[3] = f.c1 * X;
    lam[4] = f.c4 * X * Y;
    lam[5] = f.c4 * Y * Z;
    lam[6] = f.c6 * (3.0f * Z * Z - 1.0f);
    lam[7] = f.c4 * X * Z;
    lam[8] = f.c8 * (X * X - Y * Y);
}

struct ReceiverLerp {
    int i0 = 0, i1 = 0;
    float f = 0.0f;
};
inline ReceiverLerp receiverLerp(int x, int s, int n) {
    ReceiverLerp r;
    r.i0 = x / s < n - 2 ? x / s : (n - 2 > 0 ? n - 2 : 0);
    r.i1 = r.i0 + 1 < n - 1 ? r.i0 + 1 : n - 1;
    r.f = n > 1 ? static_cast<float>(x - s * r.i0) / static_cast<float>(s) : 0.0f;
    if (r.f > 1.0f) r.f = 1.0f;
    return r;
}
/// receiverLerp of every texel 0..count-1 (a row's columns or a grid's rows),
/// into `out` (resized: no allocation once it is large enough).
inline void receiverLerps(int count, int s, int n, std::vector<ReceiverLerp>& out) {
    out.resize(static_cast<std::size_t>(count > 0 ? count : 0));
    for (int x = 0; x < count; ++x) out[static_cast<std::size_t>(x)] = receiverLerp(x, s, n);
}

/// A row of receiver values v (nxr of them) interpolated to the texel
/// columns [x0, x1) (Fig. 7): out[x] = v[i0] + f (v[i1] - v[i0]), `columns`
/// the row's receiverLerps. At s = 2 and 4 the whole receiver intervals
/// inside [x0, x1) are unrolled with the fractions k / s (the same
/// operations: there i0 = x / s and f = k / s) so that the compiler
/// vectorises them; the other columns, and every column at other s, come
/// from the table.
template <int S>
inline ColumnSpan lerpReceiverIntervals(const float* v, int nxr, int x0, int x1, float* out) {
    float frac[S];
    for (int k = 0; k < S; ++k) frac[k] = static_cast<float>(k) / static_cast<float>(S);
    const int intervals = nxr > 1 ? nxr - 1 : 0;
    const int first = (x0 + S - 1) / S, last = x1 / S < intervals ? x1 / S : intervals;
    for (int X = first; X < last; ++X) {
        const float v0 = v[X], d = v[X + 1] - v[X];
        for (int k = 0; k < S; ++k) out[S * X + k] = v0 + frac[k] * d;
    }
    return last > first ? ColumnSpan{S * first, S * last} : ColumnSpan{x0, x0};
}
inline void lerpReceiverSpan(const float* v, int nxr, int s, const ReceiverLerp* columns, int x0, int x1, float* out) {
    ColumnSpan unrolled{x0, x0};
    if (s == 2) unrolled = lerpReceiverIntervals<2>(v, nxr, x0, x1, out);
    if (s == 4) unrolled = lerpReceiverIntervals<4>(v, nxr, x0, x1, out);
    const auto fromTable = [&](int a, int b) {
        for (int x = a; x < b; ++x) {
            const ReceiverLerp& r = columns[x];
            out[x] = v[r.i0] + r.f * (v[r.i1] - v[r.i0]);
        }
    };
    fromTable(x0, unrolled.x0);
    fromTable(unrolled.x1, x1);
}
inline void lerpReceiverRow(const float* v, int nxr, int s, const ReceiverLerp* columns, int nx, float* out) {
    lerpReceiverSpan(v, nxr, s, columns, 0, nx, out);
}

/// An albedo map of one value everywhere (every channel).
AlbedoMap uniformAlbedo(int nx, int ny, float albedo);

/// One light as the shading stage sees it.
struct ShadingLight {
    const VisibilityField* visibility = nullptr;
    std::array<ShMatrix, 3> product{};  // shProductMatrix of the light's RGB radiance
};

struct ShadeMaps {
    int nx = 0, ny = 0;
    std::array<Grid, 3> rgb;  // outgoing radiance towards the viewer, full resolution
    Grid ambient;             // normal-weighted sky-view factor, full resolution
    // The ambient's parts that light the analytic sky exactly
    // (gi/ambient_horizon.h, AmbientOutputs), when skyParts says they hold
    // this geometry's values.
    Grid skyBelow, skyRising;
    bool skyParts = false;
    // Set by the owner when a later pass reads the receivers' incident SH
    // (the glossy vector bounces): shading then keeps the whole field in
    // `incident`. Otherwise each block of texel rows computes the receiver
    // rows it reads into its worker's window (a few rows, not the field).
    bool keepIncident = false;
    // receiver-resolution buffers
    std::vector<float> incident;             // with keepIncident: 3 x coefficients planes, sum over lights of T_L V
    std::vector<float> incidentWindow;       // without: per worker slot, those planes at one block's receiver rows
    std::vector<int> colIndex;               // per full-res column: left receiver
    std::vector<float> colFrac;              // and the fraction towards the right one
    std::vector<ShadingLight> activeLights;  // the call's lights that add something (lightContributes)
    std::vector<float> lightMatrices;        // lights x 3 x 16 x 16, float copies of the product matrices
    // The output coefficients of I_c = sum_L T_{L,c} V_L in blocks of
    // kIncidentBlock (the last padded with zero rows): per block, each
    // input (light, k) some output of the block reads, in the order (light,
    // k), with the block's matrix entries for it.
    static constexpr int kIncidentBlock = 4;
    struct BlockTerm {
        float value[kIncidentBlock];  // the entries of the block's outputs (0 where an output has none)
        int index;                    // light * 16 + k
    };
    std::vector<BlockTerm> incidentTerms;    // per block of output coefficients
    std::vector<int> incidentTermStart;      // blocks + 1
    std::vector<float> rowScratch;           // per worker slot: interpolated SH planes of one row
    std::vector<int> busyBlocks;             // the row blocks with texels to shade
    std::vector<std::uint8_t> receiverRows;  // per receiver row: its incident radiance is updated (restricted rows)
};

/// Whether a light adds anything to a shade: some entry of its product
/// matrices is not 0 in float. A light that does reads all 16 SH planes of
/// its visibility.
bool lightContributes(const ShadingLight& light);

/// Shades every texel. envVisibility supplies the ambient map (with ambient
/// false none is made and out.ambient is left as it is: the indirect bounces,
/// the exact ambient of gi/ambient_horizon.h);
/// lights the incident radiance. gradX/gradY are the full resolution height
/// derivatives. `runs` (gi/texel_runs.h; null: every texel): only those
/// texels are shaded, the others keep what `out` holds, which must be a
/// result of the same size and settings (which texels may keep theirs is the
/// caller's: gi/shading_tiles.h). Each texel's values do not depend on the runs.
/// Lights that add nothing are left out (their visibility is not read); when
/// none is left and neither the ambient nor the incident SH is asked for, the
/// texels of the runs are 0 without the SH work. InputError when the ambient or a
/// light that adds something lacks the SH planes it reads.
void shadeTexels(ConstGridView gradX, ConstGridView gradY, int subsample, const VisibilityField& envVisibility,
                 const ShadingLight* lights, int lightCount, const AlbedoMap* albedo, const ShadingSettings& settings,
                 ShadeMaps& out, bool ambient = true, const TexelRuns* runs = nullptr);

}  // namespace terrain::gi
