#pragma once
// Indirect light through U and the SH kernel (LambertIndirect::ShKernel, the
// paper: Sections 5-7; Eqs. 12, 19-21), and the glossy single-pyramid
// approximation (GlossyIndirect::ScalarPyramid, Fig. 5 right).
//
// Per receiver and azimuth the casting-set scan gives the 4 NLP coefficients
// of Eq. 12 per channel (gi/casting_set_scan.h, CastingMoments::Nlp); U per
// receiver and channel comes from them through the same folded wedge
// operator as the environment visibility (Eqs. 19-21). The incident radiance
// is U itself; it is shaded like direct light (gi/shading.h: SH vectors
// interpolated from the receiver grid, dotted with the BRDF rotated to each
// full-resolution normal), giving the bounce's exit radiance L_b, whose RGB
// radiance pyramid the next bounce reads. A Lambert BRDF reads U's bands 0..2
// only (the others stay 0). With a glossy BRDF the shade is the scalar one
// (diffuse + glossy towards the viewer): the next bounce's RGB pyramid
// forwards it as if it left every texel in every direction.
#include "gi/indirect_bounces.h"
#include "gi/lambert_scan.h"

namespace terrain::gi {

class ShKernelIndirect final : public IndirectStrategy {
public:
    ShKernelIndirect(const IndirectInputs& in, const IndirectSettings& settings, IndirectState& st);
    void beginFrame() override;
    void buildPyramid(const BounceSource& previous) override;
    void scan(int b) override;
    void shade(int b, ShadeMaps& out) override;

private:
    void scanBlock(int block);

    const IndirectInputs& in_;
    const IndirectSettings& settings_;
    IndirectState& st_;
    LambertScan scan_;
    int nRows_;  // SH rows of U that shading reads
};

}  // namespace terrain::gi
