#pragma once
// What the indirect scan (gi/indirect_scan.h) reads besides the pyramids:
// the per-bounce step tables and each receiver row's inputs.
//
// The scans walk the height pyramid's exponential steps (Eq. 14) and read the
// radiance pyramid (gi/radiance_pyramid.h) at the same step positions. Like
// gi/visibility, a bounce first builds a table of steps per azimuth (integer
// offsets, two linear weights, 1 / tau) and each receiver's valid prefix, the
// steps whose samples lie inside the domain in every field read.
//
// Heights equal up to float rounding must not count as blockers (a flat
// plane gets exactly no indirect light): a sample counts in the casting set
// only when it rises above the receiver's height by more than 2^-20 |h0|
// (a few ulp, kHeightMarginRel), which is subtracted from every height
// difference.
#include <cstddef>
#include <functional>
#include <vector>

#include "core/grid.h"
#include "gi/pyramid.h"
#include "gi/radiance_pyramid.h"
#include "gi/visibility.h"

namespace terrain::gi {

/// Receiver rows of the indirect scans are padded to a multiple of the widest
/// lane group (8: AVX2, or 2 x 4 SSE2 lanes).
inline constexpr int kIndirectLaneGroup = 8;
inline int indirectRowPad(int n) { return (n + kIndirectLaneGroup - 1) / kIndirectLaneGroup * kIndirectLaneGroup; }

/// The scan inputs of receiver row Y (Lambert and glossy scans), pad floats
/// each (0 past the row): the height gradients, the receiver height h0, and
/// the margin 2^-20 |h0| below which a height difference is rounding (a
/// flat plane stays exactly dark).
void loadReceiverRow(const HeightPyramid& pyr, ConstGridView gradX, ConstGridView gradY, int Y, int pad, float* gx,
                     float* gy, float* h0, float* margin);

/// The step tables of an indirect scan, per azimuth phi[j] (in parallel):
/// heightSteps[j * steps + i] and each receiver's valid prefix (steps inside
/// the domain: stepsPerColumn, azimuths x pad; stepsPerRow, azimuths x nyr);
/// radiance(i, cos, sin, j * steps + i, prefix) records the radiance steps of
/// step i (Lambert: 3 channels; glossy: the SH planes) and narrows the prefix.
using RadianceStepFn = std::function<void(int, double, double, std::size_t, ValidPrefix&)>;
void buildIndirectStepTable(const HeightPyramid& pyr, const std::vector<double>& phi, int pad,
                            std::vector<ScanStep>& heightSteps, std::vector<int>& stepsPerColumn,
                            std::vector<int>& stepsPerRow, const RadianceStepFn& radiance);

/// buildIndirectStepTable over the pyramids of the exit-radiance planes (the
/// glossy members, gi/glossy_exit_radiance.h): per step the planes' shared
/// geometry (planeSteps[j * steps + i]) and each plane's origin, field + offA
/// (planeOrigins[(j * steps + i) * planes.count + f]).
void buildGlossyStepTable(const HeightPyramid& pyr, const PackedPyramids& planes, const std::vector<double>& phi,
                          int pad, std::vector<ScanStep>& heightSteps, std::vector<int>& stepsPerColumn,
                          std::vector<int>& stepsPerRow, std::vector<ScanStep>& planeSteps,
                          std::vector<const std::uint16_t*>& planeOrigins);

}  // namespace terrain::gi
