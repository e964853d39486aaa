#pragma once
// Ground truth with indirect light (the first-hit gathering of Heidrich,
// Daubert, Kautz & Seidel 2000 with their Method of Dependent Tests: one fixed
// direction set shared by every texel).
//
// Bounce 0 is the direct exit radiance of the exact reference (gi/reference.h:
// exact visibility, exact elevation integrals, the same order-4 SH lighting).
// Bounce b >= 1: for every texel p and every direction w_k of the fixed set
// with N . w_k > 0, the ray is marched through the full-resolution bilinear
// height field to its first hit q_k; the irradiance is
//   E_b(p) = sum_k L_{b-1}(q_k) (N . w_k) 4 pi / K,
// with L_{b-1} the previous bounce's diffuse exit radiance, bilinear at q_k,
// and L_b = albedo(p) / pi * E_b. Rays that leave the domain or rise above the
// highest point escape (they see the sky, which bounce 0 already counted).
// Indirect = sum of L_b over b = 1..bounces; total = direct + indirect.
#include <array>
#include <vector>

#include "core/grid.h"
#include "gi/lights.h"
#include "gi/phong_lobe_quadrature.h"
#include "gi/reference.h"
#include "gi/shading.h"

namespace terrain::gi {

struct ReferenceGiSettings {
    int directions = 2048;   // K: fixed set over the sphere (Fibonacci), shared by every texel
    int bounces = 1;         // indirect bounces after the direct one
    int azimuths = 256;      // of the direct (bounce 0) reference
    float marchStep = 0.5f;  // march step along the ray, in cells
    bool progress = false;   // progress on stdout
    // Key lights as exact spherical caps (radiance RGB / sin^2(radius) inside
    // the cap, 0 outside): exact visibility per azimuth across the cap's
    // azimuthal extent and the exact elevation integral of the cap's chord
    // above max(horizon, tangent plane). Added to bounce 0. (Folding a small
    // cap into the SH lighting with keyLightSh instead spreads it over the
    // sphere and softens its shadows: not the light the fast path renders.)
    std::vector<KeyLight> keys;
    // Diagnostic: gather with the fast path's Lambert kernel, the clamped
    // cosine projected to SH bands 0-2 (k(c) = 1/4 + c/2 + 5/32 (3c^2 - 1),
    // still 0 below the tangent plane), instead of max(0, c): isolates the
    // order-4 SH truncation of indirect light (a floor for the fast path).
    bool shLambert = false;
    int keyAzimuths = 48;  // midpoint azimuths across each cap's extent
    // Glossy reference: quadrature of every Phong lobe it integrates exactly
    // (gi/phong_lobe_quadrature.h; n rings x 2n azimuths, n = 12), at the
    // receivers and at each of their rays' first hits.
    LobeLayout lobe = LobeLayout::uniform(12);
    // Glossy reference diagnostic: the first bounce's receivers shade their
    // incident radiance projected to order-4 SH with the lobe factors g_l
    // (as the fast path's receivers do) instead of integrating their lobe
    // exactly; the first hits stay exact. Separates the error of what the
    // fast path's casting-set members send from its receivers' order-4 lobe.
    bool receiverSh = false;
    // Glossy reference diagnostic: the first bounce's hits send the exit
    // radiance of their incident radiance projected to order-4 SH, Phong part
    // sum_lm g_l I_0,lm Y_lm (as the fast path's exit-radiance vectors E do),
    // instead of integrating their lobe exactly; the receivers stay exact
    // unless receiverSh is set too. The floor of what order-4 members send.
    bool membersSh = false;
    // Glossy reference diagnostic: the first bounce's hits send the lobe-
    // filtered light times the lobe's open fraction above their exact horizon
    // along R's azimuth, erfc((e_h - e_R) sqrt((S + 1) / 2)) / 2 (what the
    // lobe gather's windowed members send, gi/glossy_lobe_members.h, with
    // exact horizons), instead of integrating their lobe exactly.
    bool membersWindowed = false;
    // Glossy reference diagnostic: the first bounce's receivers see their
    // incident radiance only along m = receiverAzimuths evenly spaced
    // azimuths phi_j = 2 pi j / m (the fast path's scan azimuths), exactly
    // in elevation: each lobe ray takes the first hits of the rays at its
    // own elevation along the two azimuths on either side of it, linearly
    // weighted by its azimuth between them (a ray below the receiver's
    // tangent plane carries nothing). 0: every ray's own first hit. The
    // floor that the scan's azimuths set for a receiver that integrates its
    // own lobe.
    int receiverAzimuths = 0;
    // BRDF of every texel. Lambert (default): the scalar gathering above.
    // Phong / LambertPlusPhong: the glossy reference (renderReferenceGlossy).
    ShadingSettings shading;
};

struct ReferenceGiResult {
    std::array<Grid, 3> direct;    // bounce 0 exit radiance (Lambert, albedo applied)
    std::array<Grid, 3> indirect;  // sum of bounces 1..B
    std::array<Grid, 3> total;     // direct + indirect
    Grid ambient;                  // direct-only normal-weighted sky-view factor
};

/// Renders the reference with indirect light. `lighting`: the environment as
/// SH; settings.keys: key lights, integrated as exact caps. albedo may be null (1).
void renderReferenceGi(ConstGridView heights, float cellSize, const ShRgb& lighting, const AlbedoMap* albedo,
                       const ReferenceGiSettings& settings, ReferenceGiResult& out);

/// The glossy reference (ReferenceGiSettings::shading not Lambert): the same
/// BRDFs as the fast path (gi/shading.h, Section 7), with the Phong lobes of
/// the direct light and of the first bounce integrated against the exact
/// incident radiance (no SH projection, gi/reference_glossy_lobe.h). The exit
/// radiance of a texel p towards w is
///   L(p, w) = D(p) + w_s int I(p, w') f_p(w' . R_N(w)) dw',
/// R_N(w) = 2 (N . w) N - w, f_p the normalised Phong lobe of p's exponent
/// (the AlbedoMap's exponent map or ShadingSettings::phongExponent), w_s the
/// specular weight (1 for Phong, ShadingSettings::specularWeight for the
/// mixture), D the isotropic part; outputs are L towards the viewer.
/// Bounce 0: I = the SH sky through p's exact visibility (horizons of
/// gi/reference at settings.azimuths), D_0 = (0 for Phong, 1 for the mixture)
/// x the exact Lambert shade of gi/reference + exact-cap key lights (Lambert,
/// like the fast path's exact-cosine keys).
/// Bounce 1: I(p, w) = L_0(q, -w) at the first hit q of the ray from p in
/// direction w (D_0 and the normal bilinear at q, q's Phong part integrated
/// exactly against q's own sky); the Phong part samples p's lobe with
/// the lobe quadrature's rays, the Lambert part D_1 = w_d albedo(p) / pi
/// 4 pi / K sum_k L_0(q_k, -w_k) (N . w_k) the fixed direction set.
/// With receiverSh (a diagnostic) the first bounce's receivers shade as in
/// the bounces after it, from I_1 projected to SH; with membersSh (another)
/// its first hits send the Phong part of I_0 projected to SH.
/// Bounces b >= 2 (an approximation): the previous bounce's incident
/// radiance projected to order-4 SH at every texel,
///   I_b(p) = 4 pi / K sum_k L_(b-1)(q_k, -w_k) Y(w_k),
/// and the Phong part sum_lm g_l I_b,lm Y_lm(R_N(w)), g_l = e^{-l^2/(2S)}.
void renderReferenceGlossy(ConstGridView heights, float cellSize, const ShRgb& lighting, const AlbedoMap* surface,
                           const ReferenceGiSettings& settings, ReferenceGiResult& out);

/// I_0 of the glossy reference: per texel the exact incident radiance of the
/// SH `lighting` through the exact visibility, projected to order-4 SH
/// (out: 3 x 16 planes of nx * ny, plane c * 16 + i).
void referenceIncidentSh(ConstGridView heights, float cellSize, const ShRgb& lighting, int azimuths,
                         std::vector<float>& out);

/// First hit of the ray from grid point (x, y) (at its height) in direction d
/// through the bilinear height field; false when it escapes. Positions in
/// cells, heights in metres; hMax the field's maximum.
bool referenceFirstHit(const float* h, int nx, int ny, float hMax, float cellSize, int x, int y,
                       const std::array<float, 3>& d, float step, float& hx, float& hy);

/// Bounce 0 of both references: the exact direct reference (gi/reference.h)
/// of the SH `lighting` with settings.azimuths and settings.progress.
void renderDirectReference(ConstGridView heights, float cellSize, const ShRgb& lighting, const AlbedoMap* albedo,
                           const ReferenceGiSettings& settings, ReferenceResult& out);

/// One gathering bounce: next(p) = albedo(p) / pi * sum_k prev(q_k) (N . w_k) 4 pi / K
/// over the fixed direction set (the rays' first hits q_k). next is resized.
void gatherReferenceBounce(ConstGridView heights, float cellSize, const std::array<Grid, 3>& prev,
                           const AlbedoMap* albedo, const ReferenceGiSettings& settings, std::array<Grid, 3>& next);

/// Adds the direct light of an exact cap key light (Lambert, albedo applied)
/// to rgb (resized to the heights' size when empty).
void addReferenceKeyLight(ConstGridView heights, float cellSize, const KeyLight& key, const AlbedoMap* albedo,
                          int azimuths, std::array<Grid, 3>& rgb);

/// The fixed direction set: K unit vectors spread evenly over the sphere.
void referenceDirections(int count, std::vector<std::array<float, 3>>& out);

}  // namespace terrain::gi
