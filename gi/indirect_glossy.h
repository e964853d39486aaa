#pragma once
// Glossy indirect light through a pyramid of SH radiance vectors (Section 5.3,
// "non-diffuse surfaces", Fig. 5 middle; Section 7's Phong lobe).
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
// 48 planes (buildScalarPyramids, the same B-spline filtering as the scalar
// radiance pyramid) is the filtered exit-radiance function itself: a coarse
// level's E . Y(w) is the area average of L_q(w). (Filtering I, N and S
// separately, the paper's "augment with the BRDF parameters", would mix
// normals and lobes of different texels.) Error: only what the order-4 SH
// already costs (the lobe is band-limited to l <= 3 like the direct shading;
// S > ~10 is blurred to that) and the pyramid's spatial filtering.
//
// The scan (Eq. 12 with a direction-dependent u): casting sets as in
// gi/indirect (Eq. 17, segments clamped to [omega_min, pi/2], moments of
// s = sin omega); member t_i at elevation omega_i in azimuth phi sends
//   u(t_i) = Ebar(t_i) . Y(-d_i),  d_i = (cos phi cos omega_i, sin phi cos omega_i, sin omega_i),
// Ebar the pyramid sample at the member's step (16 bilinear reads per
// channel instead of 1), -d_i the direction from the member back to the
// receiver (s(t) in the paper). U then goes through the same folded wedge
// operator (Eqs. 19-21) and shading as the Lambert path.
//
// Measured (bench/results/gi_glossy.md, 96^2 Mont Blanc crop, sun and sky,
// 1 bounce, indirect rel. RMSE vs gi/reference_glossy): Phong S = 8 / 64:
// 17.5 / 20.2 % at 1x (scalar pyramid 41.3 / 46.2 %), 26.5 / 28.8 % at 2x
// (39.8 / 44.7 %); biased low (-8 % at 1x, -13 % at 2x). Cost: 48 planes per
// member instead of 3: at 512^2 2x one bounce ~1.36 s vs ~0.15 s (2 threads).
//
// Schedule as gi/indirect: fixed row blocks, each receiver written by one
// block, no reductions across blocks: bit-identical for any thread count; no
// allocation after the first frame of a given size and settings.
#include <array>
#include <vector>

#include "gi/pyramid.h"
#include "gi/radiance_pyramid.h"
#include "gi/shading.h"
#include "gi/visibility.h"
#include "gi/wedge.h"
#include "core/grid.h"

namespace terrain::gi {

struct IndirectSettings;
struct IndirectState;

inline constexpr int kGlossyFields = 3 * kShCount;  // RGB x 16 SH planes of E

/// Buffers of the vector-pyramid bounce (inside IndirectState).
struct GlossyIndirectState {
    std::vector<float> exitSh;  // kGlossyFields planes of nx * ny: E at full resolution (plane c * 16 + k)
    RadiancePyramid pyramid;    // kGlossyFields fields
    std::vector<ScanStep> steps;        // azimuths x steps: geometry and weights (field 0)
    std::vector<const float*> fields;   // azimuths x steps x kGlossyFields: field + offA of each plane
    std::vector<float> blockScratch;    // per row block: scan scratch (moments, basis, NLP)
    std::vector<int> blockList;         // per row block: steps with a new member
    std::vector<float> rowScratch;      // per row block: interpolated incident SH of one row
};

/// Exit-radiance SH vectors E (kGlossyFields planes of nx * ny, see above)
/// from the previous bounce's incident radiance at the receivers
/// (`incident`: 3 x 16 planes of nxr * nyr, as ShadeMaps::incident with a
/// Phong BRDF) and its shade towards the viewer (full resolution).
void glossyExitRadiance(ConstGridView gradX, ConstGridView gradY, int subsample, int nxr, int nyr, const float* incident,
                        const std::array<Grid, 3>& shade, const AlbedoMap* surface, const ShadingSettings& shading,
                        GlossyIndirectState& st, float* out);

/// Exit-radiance SH vector of one texel (the scalar twin for tests and the
/// reference): E = Rot_N(pi)(w_s g (.) I) + sqrt(4 pi) D e_00 for unit normal
/// n, lobe factors ph (phongLobeFactors), specular weight ws, diffuse D.
void glossyExitVector(const float incident[kShCount], float nx, float ny, float nz, const float ph[kShOrder], float ws,
                      float diffuse, float out[kShCount]);

/// Bounces 1..B with the vector pyramid (IndirectSettings::glossy ==
/// VectorPyramid and a non-Lambert BRDF): fills state.u, bounceShade,
/// indirect, total, bounceMean and timings like computeIndirect.
/// directShade: the direct shading of this frame (incident + rgb).
void computeGlossyIndirect(const HeightPyramid& heights, ConstGridView gradX, ConstGridView gradY,
                           const FoldedWedgeOperator& op, const VisibilityField& envVisibility,
                           const ShadeMaps& directShade, const AlbedoMap* surface, const ShadingSettings& shading,
                           const IndirectSettings& settings, IndirectState& state);

}  // namespace terrain::gi
