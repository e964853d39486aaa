#pragma once
// Lambert indirect light by blocker radiance (LambertIndirect::BlockerRadiance,
// the engine's default).
//
// At the receivers: the exact clamped-cosine irradiance E of the casting sets
// (gi/casting_set_scan.h, CastingMoments::Irradiance), summed over the
// azimuths with box weights, E / pi = (2 / m) / |n| sum_j (...), and, on the
// first bounce with sub-sampling, each receiver's horizon along every
// azimuth (the walk's running maximum). Between the receivers: the blockers'
// mean radiance E / O interpolated and multiplied by each texel's own
// occlusion O (gi/blocker_radiance.h). No U is formed and nothing is shaded
// from SH. With s = 1 every texel is a receiver: E alone.
#include "gi/indirect_bounces.h"
#include "gi/indirect_scan.h"

namespace terrain::gi {

class BlockerRadianceIndirect final : public IndirectStrategy {
public:
    BlockerRadianceIndirect(const IndirectInputs& in, const IndirectSettings& settings, IndirectState& st);
    void beginFrame() override;
    void buildPyramid(int b, const BounceSource& previous) override;
    void scan(int b) override;
    void shade(int b, ShadeMaps& out) override;

private:
    void scanBlock(int block, bool horizons);
    void receiverIrradiance(const RowBlock& rb, const IndirectScratch& sc);
    void storeGroupOcclusion(const RowBlock& rb, IndirectScratch& sc);

    const IndirectInputs& in_;
    const IndirectSettings& settings_;
    IndirectState& st_;
    IndirectScan scan_;
};

}  // namespace terrain::gi
