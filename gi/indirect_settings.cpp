#include "gi/indirect_settings.h"

#include "gi/settings_ranges.h"

namespace terrain::gi {

void validateIndirectSettings(const IndirectSettings& s) {
    checkRange(ranges::kBounces, s.bounces);
    checkRange(ranges::kRadianceLevelsPerOctave, s.radiance.levelsPerOctave);
    checkRange(ranges::kRadianceLevelOffset, s.radiance.levelOffset);
    checkRange(ranges::kIndirectAzimuths, s.azimuths);
    checkRange(ranges::kLobeAzimuths, s.lobeAzimuths);
    checkRange(ranges::kLobeRings, s.lobeRings);
    checkRange(ranges::kLobeInnerDirections, s.lobeInnerDirections);
    checkRange(ranges::kLobeNearStepsPerOctave, s.lobeNearStepsPerOctave);
    checkRange(ranges::kLobeNearOctaves, s.lobeNearOctaves);
}

}  // namespace terrain::gi
