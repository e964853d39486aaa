#pragma once
// Results and reusable buffers of the indirect light (gi/indirect.h): the
// bounces' sums, U, and each strategy's scratch. Sized on the first frame of
// a given size and settings; no allocation after it.
#include <array>
#include <cstdint>
#include <vector>

#include "core/grid.h"
#include "gi/blocker_radiance.h"
#include "gi/casting_set_scan.h"
#include "gi/glossy_exit_radiance.h"
#include "gi/glossy_lobe_gather.h"
#include "gi/radiance_pyramid.h"
#include "gi/receiver_tiles.h"
#include "gi/shading.h"
#include "gi/visibility.h"

namespace terrain::gi {

/// Sums of a field's blocks of rows, and the field's width.
struct RowBlockSums {
    std::vector<double> sums;
    int nx = 0;
};

struct IndirectTimings {
    double pyramid = 0.0, scan = 0.0, shading = 0.0, total = 0.0;
};

/// Buffers of the vector-pyramid bounce (GlossyIndirect::VectorPyramid and
/// LobeScan, gi/indirect_sh_kernel.h).
struct GlossyIndirectState {
    std::vector<float> exitSh;                 // 3 x 16 planes of nx * ny: E at full resolution (plane c * 16 + k)
    std::vector<std::uint16_t> exitTexels;     // LobeScan: E texel by texel, bfloat16 (glossyExitRadiance)
    LobeMembers members;                       // LobeScan, bounce 1: what the members send (windowed)
    PackedPyramids pyramid;                    // one field per plane of exitSh, bfloat16
    std::vector<ScanStep> steps;               // azimuths x steps: geometry and weights (field 0)
    std::vector<const std::uint16_t*> fields;  // azimuths x steps x 48: field + offA of each plane
    GlossyExitScratch exitScratch;             // E's rows and columns
    GlossyLobeState lobes;                     // GlossyIndirect::LobeScan: the receivers' gathered lobes
};

struct IndirectState {
    RadiancePyramid radiance;             // RGB pyramids: the previous bounce's RGB radiance pyramid
    bool radianceOfDirect = false;        // radiance is bounce 0's (IndirectInputs::direct) of the last call
    std::vector<ScanStep> heightSteps;    // azimuths x steps
    std::vector<ScanStep> radianceSteps;  // RGB pyramids: channels x azimuths x steps
    std::vector<int> stepsPerColumn, stepsPerRow;
    // what the RGB pyramids' tables above were built for (the height
    // pyramid's key, then each channel's); empty: not those tables
    std::vector<StepTableKey> radianceTableKey;
    std::vector<std::uint8_t> distanceGroups;  // per step (gi/pyramid.h, distanceGroup)
    DirtySpans spans;                          // the receiver columns to scan, per row
    std::vector<int> blocksWithWork;           // the row blocks with a span to scan
    std::vector<float> topOfRows;              // per block of raw-phase rows: its highest height (fieldTopHeight)
    std::uint64_t topOfBuild = 0;              // the height pyramid build topOfRows holds (0: none)
    std::vector<IndirectScratch> blocks;       // per worker slot (IndirectScan::scratch)
    std::array<VisibilityField, 3> u;      // U per channel (16 SH planes at the receivers; not with BlockerRadiance)
    int uZeroFrom = kShCount;              // U's planes from this one on are known to be 0
    std::array<ShadingLight, 3> lights;    // the shading lights of U
    std::array<ShadeMaps, 2> bounceShade;  // exit radiance of the current / previous bounce (several bounces)
    std::array<Grid, 3> indirect;          // sum of bounces 1..B, full resolution
    std::array<Grid, 3> total;             // direct + indirect
    bool totalValid = false;               // total is the sum of the last call's direct and indirect
    std::vector<double> bounceMean;        // mean exit radiance (RGB average) of each bounce
    RowBlockSums meanOfRows;               // one bounce: per block of texel rows, its sum of bounceMean[0]
    IndirectTimings timings;
    GlossyIndirectState glossy;    // GlossyIndirect::VectorPyramid
    BlockerRadianceState blocker;  // LambertIndirect::BlockerRadiance: horizons, occlusion, receivers' E
};

}  // namespace terrain::gi
