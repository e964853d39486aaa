#pragma once
// Indirect light through U and the SH kernel (LambertIndirect::ShKernel, the
// paper: Sections 5-7; Eqs. 12, 19-21), with what the casting-set members
// send read from one of two pyramids.
//
// Per receiver and azimuth the casting-set scan gives the 4 NLP coefficients
// of Eq. 12 per channel (gi/casting_set_scan.h); U per receiver and channel
// comes from them through the same folded wedge operator as the environment
// visibility (Eqs. 19-21). The incident radiance is U itself; it is shaded
// like direct light (gi/shading.h: SH vectors interpolated from the receiver
// grid, dotted with the BRDF rotated to each full-resolution normal), giving
// the bounce's exit radiance L_b. A Lambert BRDF reads U's bands 0..2 only
// (the others stay 0).
//
// What the members send:
// - the RGB radiance pyramid of L_(b-1) (CastingMoments::Nlp): a Lambert
//   BRDF, and the glossy single-pyramid approximation
//   (GlossyIndirect::ScalarPyramid, Fig. 5 right), whose shade (diffuse +
//   glossy towards the viewer) is forwarded as if it left every texel in
//   every direction;
// - the pyramid of exit-radiance SH vectors (GlossyIndirect::VectorPyramid
//   with a glossy BRDF; Section 5.3, "non-diffuse surfaces", Fig. 5 middle;
//   CastingMoments::GlossyNlp): each bounce turns the previous bounce's
//   incident SH vectors and shade into E at full resolution
//   (gi/glossy_exit_radiance.h) and filters its 48 planes into a pyramid;
//   member t_i sends Ebar(t_i) . Y(-d_i) back to its receiver. Accuracy and
//   cost against the scalar pyramid and the glossy reference
//   (gi/reference_gi.h): bench/results/gi_glossy.md.
// GlossyIndirect::LobeScan: the Phong part of each bounce's shade is each
// receiver's own lobe gathered along the directions it covers, reading E at
// full resolution (gi/glossy_lobe_gather.h), not the order-4 lobe applied to
// U; U (and the pyramid it reads) is scanned only where something still
// reads it: the diffuse part of a mixture and the next bounce's incident SH.
#include "gi/indirect_bounces.h"
#include "gi/indirect_scan.h"

namespace terrain::gi {

class ShKernelIndirect final : public IndirectStrategy {
public:
    ShKernelIndirect(const IndirectInputs& in, const IndirectSettings& settings, IndirectState& st);
    /// With the exit-radiance vectors, throws InputError without
    /// IndirectInputs::directShade or when it is not a Phong shading of this field.
    void beginFrame() override;
    void buildPyramid(int b, const BounceSource& previous) override;
    void scan(int b) override;
    void shade(int b, ShadeMaps& out) override;

private:
    void checkExitVectorInputs();
    void scanBlock(int block);

    const IndirectInputs& in_;
    const IndirectSettings& settings_;
    IndirectState& st_;
    /// LobeScan: bounce b reads U (its diffuse part, or a bounce after it).
    bool needsU(int b) const;
    bool windowedMembers(int b) const;

    bool exitVectors_;  // the members send E . Y(-d) (GlossyIndirect::VectorPyramid, LobeScan)
    bool lobes_;        // the receivers gather their own lobes (GlossyIndirect::LobeScan)
    IndirectScan scan_;
    int nRows_;  // SH rows of U that shading reads
};

}  // namespace terrain::gi
