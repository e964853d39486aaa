#include "gi/indirect.h"

#include "gi/indirect_blocker_radiance.h"
#include "gi/indirect_bounces.h"
#include "gi/indirect_sh_kernel.h"

namespace terrain::gi {

void computeIndirect(const IndirectInputs& in, const IndirectSettings& settings, IndirectState& st) {
    validateIndirectSettings(settings);
    const bool lambertBrdf = in.shading.brdf == Brdf::Lambert;
    if (lambertBrdf && settings.lambert == LambertIndirect::BlockerRadiance) {
        BlockerRadianceIndirect strategy(in, settings, st);
        runBounces(in, settings, strategy, st);
    } else {
        ShKernelIndirect strategy(in, settings, st);
        runBounces(in, settings, strategy, st);
    }
}

bool readsIncidentSh(const IndirectSettings& settings, const ShadingSettings& shading) {
    return settings.glossy != GlossyIndirect::ScalarPyramid && shading.brdf != Brdf::Lambert && settings.bounces > 0;
}

bool gathersByTiles(const IndirectSettings& settings, const ShadingSettings& shading) {
    return settings.bounces == 1 && shading.brdf == Brdf::Lambert &&
           settings.lambert == LambertIndirect::BlockerRadiance;
}

}  // namespace terrain::gi
