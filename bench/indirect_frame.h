#pragma once
// The frame the indirect-light suites measure (gi-indirect's accuracy, the
// paper's Table 1): sun-and-sky environment plus one key light
// (sunSkyAndBenchKey), a uniform albedo, Lambert, the engine's settings at a
// sub-sampling and a number of bounces; and its errors against the exact
// reference (bench/gi_reference_cache.h).
#include <array>
#include <string>
#include <vector>

#include "bench/bench_common.h"
#include "bench/gi_reference_cache.h"
#include "gi/frame.h"
#include "gi/lights.h"

namespace terrain::bench {

/// The albedo of the indirect-light frames, everywhere.
inline constexpr float kIndirectFrameAlbedo = 0.6f;

/// Variations of the engine's settings the gi-indirect suite explores.
struct IndirectVariant {
    int indirectAzimuths = 0;  // azimuths of the indirect scan (0: the settings' own)
    int radianceK = 0;         // radiance pyramid k_u (0: the default)
    int radianceO = -1;        // radiance pyramid o_u (-1: the default)
    bool shKernel = false;     // the paper's SH Lambert kernel and receiver planes
};

/// Whole frames (no incremental caching) of the engine's settings (or the
/// paper's) at sub-sampling s with `bounces` bounces.
gi::GiSettings indirectFrameSettings(int s, int bounces, bool paper, const IndirectVariant& v = {});

/// The engine settings as the results files print them.
std::string indirectSettingsSummary(const IndirectVariant& v = {});

/// The reference's lighting: the environment plus each key light as an SH cap.
gi::ShRgb foldKeys(const gi::GiLighting& l);

/// Relative RMSE and bias (interior) of a frame's total and indirect light.
struct IndirectErrors {
    double total = 0.0, totalBias = 0.0, indirect = 0.0, indirectBias = 0.0;
};
IndirectErrors indirectErrors(const gi::GiState& st, const GiReference& ref, int bounces);

}  // namespace terrain::bench
