#include "gi/indirect_settings.h"

#include "core/error.h"

namespace terrain::gi {

void validateIndirectSettings(const IndirectSettings& s) {
    if (s.bounces < 0 || s.bounces > 16) throw InputError("bounces must be in [0, 16]");
    if (s.radiance.levelsPerOctave < 1 || s.radiance.levelsPerOctave > 64)
        throw InputError("radiance levels per octave must be in [1, 64]");
    if (s.radiance.levelOffset < 0 || s.radiance.levelOffset > 32)
        throw InputError("radiance level offset must be in [0, 32]");
    if (s.azimuths != 0 && (s.azimuths < 3 || s.azimuths > 4096))
        throw InputError("indirect azimuths must be 0 or in [3, 4096]");
}

}  // namespace terrain::gi
