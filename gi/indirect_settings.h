#pragma once
// Settings of the indirect light (gi/indirect.h): the number of bounces, the
// radiance pyramid, and which strategy turns the casting sets into light.
#include "gi/radiance_pyramid.h"

namespace terrain::gi {

// Glossy BRDFs (Phong, Lambert + Phong).
enum class GlossyIndirect {
    // One RGB pyramid of the scalar shade (diffuse + glossy towards the
    // viewer), Fig. 5 right: the SH kernel's scan, shaded with the BRDF
    // (gi/indirect_sh_kernel.h).
    ScalarPyramid,
    // A pyramid of SH exit-radiance vectors, evaluated towards each receiver
    // (Fig. 5 middle; gi/indirect_sh_kernel.h).
    VectorPyramid,
    // The vector pyramid's members, gathered by each receiver's own Phong
    // lobe along the global azimuths it covers instead of shading the
    // order-4 SH projection of U (gi/glossy_lobe_gather.h).
    LobeScan,
};

// What the lobe gather's first-bounce members send (GlossyIndirect::LobeScan).
enum class GlossyLobeMembers {
    // The lobe-filtered light times the part of the lobe above the member's
    // horizon (gi/glossy_lobe_members.h): no order-4 projection of the
    // horizon's edge.
    Windowed,
    // The vector pyramid's exit-radiance SH vectors E, order 4
    // (gi/glossy_exit_radiance.h).
    Sh,
};

// How Lambert receivers turn their casting sets into irradiance.
enum class LambertIndirect {
    // Eq. 12 + the folded wedge operator + the order-4 SH clamped cosine (the
    // paper; gi/indirect_sh_kernel.h). The SH kernel over-weights light near
    // the horizon (k(0) = 0.094): the indirect light comes out biased high
    // (bench/results/gi_indirect_diagnosis.md).
    ShKernel,
    // The exact clamped-cosine irradiance E at the receivers; between them
    // the blockers' mean radiance E / O interpolated and multiplied by each
    // texel's own occlusion O (gi/indirect_blocker_radiance.h). No U: the
    // scan keeps the exact moment and the horizon only. Lambert BRDF; with
    // another BRDF the SH kernel runs.
    BlockerRadiance,
};

// Defaults: the engine's (gi/settings.h): blocker radiance (no SH-kernel
// bias near the horizon) and 8 azimuths for the indirect scan, whose light is
// smooth in azimuth, at about half the scan time of 16
// (bench/results/gi_indirect_accuracy.md).
struct IndirectSettings {
    int bounces = 0;  // 0: direct light only
    RadiancePyramidSettings radiance;
    bool amortise = false;  // Section 7: alternate direct / indirect on static geometry
    GlossyIndirect glossy = GlossyIndirect::ScalarPyramid;
    LambertIndirect lambert = LambertIndirect::BlockerRadiance;  // paper: ShKernel
    // Azimuths of the indirect scan (0: the visibility's m; paper: 0).
    int azimuths = 8;
    // GlossyIndirect::LobeScan: the global azimuths the lobes are gathered
    // along, the lobe quadrature (gatherLobeLayout: the i-th ring from the
    // lobe's axis holds i lobeInnerDirections directions, gi/
    // phong_lobe_quadrature.h; lobeRings 0 takes 3 rings for lobes of
    // exponent below 16 and 2 from 16 up), and the walks' raw steps, out to
    // 2^lobeNearOctaves cells at lobeNearStepsPerOctave per octave
    // (gi/glossy_lobe_gather.h). 28 azimuths and 12 steps per octave rather
    // than 32 and 16: with the quadrature's staggered rings about the
    // accuracy the denser walks had with aligned ones, for less work. 2
    // rings of 5 and 10 directions for the narrower lobes rather than the 18
    // of 3 rings of 6: fewer rays, and fewer of them low enough to walk far
    // (bench/results/gi_glossy.md, the lobe quadrature table).
    int lobeAzimuths = 28;
    int lobeRings = 0;
    int lobeInnerDirections = 5;
    int lobeNearStepsPerOctave = 12;
    int lobeNearOctaves = 7;
    // What the first bounce's members send to the lobe gather; the bounces
    // after it send E.
    GlossyLobeMembers lobeMembers = GlossyLobeMembers::Windowed;
    bool operator==(const IndirectSettings&) const = default;
};

/// Throws InputError when a setting is out of range.
void validateIndirectSettings(const IndirectSettings& s);

}  // namespace terrain::gi
