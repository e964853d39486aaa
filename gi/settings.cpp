#include "gi/settings.h"

#include <string>

#include "core/error.h"

namespace terrain::gi {

GiSettings paperGiSettings() {
    GiSettings s;
    s.pyramid.levelsPerOctave = 4;
    s.pyramid.levelOffset = 2;
    s.pyramid.peakBlend = 0.0f;
    s.visibility.azimuths = 32;
    s.visibility.interp = AzimuthInterp::Linear;
    s.visibility.blockingMax = BlockingMax::BsplineKnotsAndMidpoints;
    s.visibility.footprintTangent = false;
    s.keyLightAzimuths = 3;
    s.keyLightExactCosine = false;
    s.ambient = AmbientMethod::ShProduct;
    s.shading.positivity = GlossyPositivity::Off;
    s.indirect.radiance.levelsPerOctave = 4;
    s.indirect.radiance.levelOffset = 2;
    s.indirect.lambert = LambertIndirect::ShKernel;
    s.indirect.glossy = GlossyIndirect::ScalarPyramid;
    s.indirect.azimuths = 0;
    return s;
}

void validateGiSettings(const GiSettings& s) {
    checkRange(ranges::kSubsample, s.subsample);
    if (s.subsample == 3) throw InputError("subsample must be 1, 2 or 4 (got 3)");
    if (s.minEnvironmentShRows != 0 && s.minEnvironmentShRows != 1 && s.minEnvironmentShRows != kShCount)
        throw InputError("minEnvironmentShRows must be 0, 1 or 16 (got " + std::to_string(s.minEnvironmentShRows) +
                         ")");
    checkRange(ranges::kAzimuths, s.visibility.azimuths);
    checkRange(ranges::kLevelsPerOctave, s.pyramid.levelsPerOctave);
    checkRange(ranges::kLevelOffset, s.pyramid.levelOffset);
    checkRange(ranges::kPeakBlend, s.pyramid.peakBlend);
    checkRange(ranges::kKeyLightAzimuths, s.keyLightAzimuths);
    checkRange(ranges::kPhongExponent, s.shading.phongExponent);
    checkRange(ranges::kSpecularWeight, s.shading.specularWeight);
    checkRange(ranges::kTolerance, s.tolerance);
    checkRange(ranges::kRefreshEvery, s.refreshEvery);
    validateIndirectSettings(s.indirect);
}

int indirectScanAzimuths(const GiSettings& s) {
    return s.indirect.azimuths == 0 ? s.visibility.azimuths : s.indirect.azimuths;
}

}  // namespace terrain::gi
