#pragma once
// Glossy indirect light through a pyramid of SH exit-radiance vectors
// (GlossyIndirect::VectorPyramid with a non-Lambert BRDF; Section 5.3,
// "non-diffuse surfaces", Fig. 5 middle; Section 7's Phong lobe).
//
// Each bounce turns the previous bounce's incident SH vectors and shade into
// exit-radiance SH vectors E at full resolution and filters their 48 planes
// into a pyramid (gi/glossy_exit_radiance.h). The scan (Eq. 12 with a
// direction-dependent u): casting sets as in gi/casting_set_scan.h (Eq. 17,
// segments clamped to [omega_min, pi/2], moments of s = sin omega); member
// t_i at elevation omega_i in azimuth phi sends
//   u(t_i) = Ebar(t_i) . Y(-d_i),  d_i = (cos phi cos omega_i, sin phi cos omega_i, sin omega_i),
// Ebar the pyramid sample at the member's step (16 bilinear reads per
// channel instead of 1), -d_i the direction from the member back to the
// receiver (s(t) in the paper). U then goes through the same folded wedge
// operator (Eqs. 19-21) and shading as the SH kernel (gi/indirect_sh_kernel.h).
// Accuracy and cost against the scalar pyramid and the glossy reference
// (gi/reference_gi.h) are measured in bench/results/gi_glossy.md.
//
// Schedule: fixed row blocks, each receiver written by one block, no
// reductions across blocks: bit-identical for any thread count; no
// allocation after the first frame of a given size and settings. Receiver
// tiles (IndirectInputs::only) are ignored: every receiver is scanned.
#include "gi/indirect_bounces.h"
#include "gi/sh.h"

namespace terrain::gi {

class VectorPyramidIndirect final : public IndirectStrategy {
public:
    VectorPyramidIndirect(const IndirectInputs& in, const IndirectSettings& settings, IndirectState& st);
    /// Throws InputError without IndirectInputs::directShade or when it is not
    /// a Phong shading of this field.
    void beginFrame() override;
    void buildPyramid(const BounceSource& previous) override;
    void scan(int b) override;
    void shade(int b, ShadeMaps& out) override;

private:
    void scanBlock(int block);
    void scanRow(int Y, float* scratch, int* list);
    void castAzimuth(int j, int Y, float* scratch, int* list);
    void accumulateU(int j, float* (*uRows)[kShCount], const float* nlp) const;

    const IndirectInputs& in_;
    const IndirectSettings& settings_;
    IndirectState& st_;
    int pad_, nSteps_, nBlocks_;
};

}  // namespace terrain::gi
