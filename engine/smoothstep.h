#pragma once
// The Hermite ramp the scene rules fade with (GLSL's smoothstep): 0 at or
// below e0, 1 at or above e1 (e0 < e1), 3t^2 - 2t^3 between.
#include <algorithm>

namespace terrain::engine {

inline float smoothstep(float e0, float e1, float x) {
    const float t = std::clamp((x - e0) / (e1 - e0), 0.0f, 1.0f);
    return t * t * (3.0f - 2.0f * t);
}

}  // namespace terrain::engine
