#pragma once
// Exit radiance of glossy surfaces as SH vectors (Section 5.3, "non-diffuse
// surfaces", Fig. 5 middle; Section 7's Phong lobe): what the vector pyramid
// of GlossyIndirect::VectorPyramid filters (gi/indirect_sh_kernel.h).
//
// What each texel stores (the choice of this engine). Bounce b - 1 leaves at
// every texel q an incident-radiance SH vector I_q (RGB x order-4 SH: T_L V
// of the lights for bounce 0, U of the previous scan later; interpolated from
// the receivers to full resolution as in Fig. 7) and its exit radiance
// towards the viewer (the shade). With the texel's normal N, reflection about
// N, R_N(w) = 2 (N . w) N - w, and the Phong lobe factors g_l = e^{-l^2/(2S)}
// of its exponent S (Section 7), the exit radiance towards any direction w is
//   L_q(w) = D_q + w_s sum_lm g_l I_q,lm Y_lm(R_N(w)),
// D_q the isotropic (diffuse) part, w_s the specular weight. R_N is the
// rotation by pi about N, so h(w) = sum_lm c_lm Y_lm(R_N w) stays in band l:
// the texel stores the exit-radiance SH vector E_q with L_q(w) = E_q . Y(w),
//   E_q = Rot_N(pi)(w_s g (.) I_q) + sqrt(4 pi) D_q e_00,
// i.e. the incident radiance convolved with its own Phong lobe, turned to
// the reflection frame, with the diffuse scalar riding in band 0 (the
// paper's "two pyramids" for mixture surfaces become one: band 0 is the
// diffuse pyramid). D_q = shade_q - w_s (Phong towards the viewer): what
// the direct shading added beside the lobe (albedo x Lambert, exact-cosine
// key lights). The rotation is exact per band: h is evaluated at 2l+1 fixed
// directions d_j and solved with the precomputed inverse of [Y_lm(d_j)].
//
// Filtering. E is linear in the exit-radiance field, so the pyramid over its
// 48 planes (buildPackedPyramids, the same B-spline filtering as the scalar
// radiance pyramid) is the filtered exit-radiance function itself: a coarse
// level's E . Y(w) is the area average of L_q(w). (Filtering I, N and S
// separately, the paper's "augment with the BRDF parameters", would mix
// normals and lobes of different texels.) Error: only what the order-4 SH
// already costs (the lobe is band-limited to l <= 3 like the direct shading;
// S > ~10 is blurred to that) and the pyramid's spatial filtering.
//
// Deterministic: fixed blocks of rows, per texel a pure function of its inputs.
#include <array>
#include <cstdint>
#include <vector>

#include "core/grid.h"
#include "gi/sh.h"
#include "gi/shading.h"

namespace terrain::gi {

inline constexpr int kGlossyFields = 3 * kShCount;  // RGB x 16 SH planes of E

/// Exit-radiance SH vectors E (see above) from the previous bounce's
/// incident radiance at the receivers (`incident`: 3 x 16 planes of
/// nxr * nyr, as ShadeMaps::incident with a Phong BRDF) and its shade towards
/// the viewer (full resolution), into `planes` (kGlossyFields planes of
/// nx * ny, plane c * 16 + k; what the vector pyramid filters) and into
/// `texels` (texel by texel, value f of texel k at k * kGlossyFields + f,
/// rounded to bfloat16: what the lobe gather reads where its rays meet the
/// surface) and the diffuse parts D_q alone into `diffuse` (what the lobe
/// gather's first-bounce members add to their lobe); any may be null. scratch: reused (no allocation after the
/// first call of a size).
struct GlossyExitScratch {
    std::vector<float> rows;            // per worker slot: the incident SH of one row, at receivers and texels
    std::vector<ReceiverLerp> columns;  // per texel column: the receivers it lies between
};
/// What glossyExitRadiance writes; any may be null.
struct GlossyExitOutputs {
    float* planes = nullptr;          // E's kGlossyFields planes of nx * ny
    std::uint16_t* texels = nullptr;  // E texel by texel, bfloat16
    float* diffuse = nullptr;         // D_q RGB texel by texel (texel k at diffuseStride k; gi/glossy_lobe_members.h)
    int diffuseStride = 3;
};
void glossyExitRadiance(ConstGridView gradX, ConstGridView gradY, int subsample, int nxr, int nyr,
                        const float* incident, const std::array<Grid, 3>& shade, const AlbedoMap* surface,
                        const ShadingSettings& shading, GlossyExitScratch& scratch, const GlossyExitOutputs& out);

/// Exit-radiance SH vector of one texel (the scalar twin for tests and the
/// reference): E = Rot_N(pi)(w_s g (.) I) + sqrt(4 pi) D e_00 for unit normal
/// n, lobe factors ph (phongLobeFactors), specular weight ws, diffuse D.
void glossyExitVector(const float incident[kShCount], float nx, float ny, float nz, const float ph[kShOrder], float ws,
                      float diffuse, float out[kShCount]);

}  // namespace terrain::gi
