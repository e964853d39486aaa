#pragma once
// Lambert indirect light between sub-sampled receivers
// (LambertIndirect::BlockerRadiance, gi/indirect_blocker_radiance.h).
//
// A receiver's casting sets give its exact clamped-cosine irradiance E
// (gi/casting_set_scan.h, CastingMoments::Irradiance) and, from the same walk,
// its horizon along every indirect azimuth (the highest blocking slope over
// the scan's steps, which start one receiver spacing away). Indirect
// irradiance is the blockers' radiance times the cosine-weighted solid angle
// they cover, E = Lbar O. Of the two factors the blockers' mean radiance
// Lbar = E / O is smooth (it is the filtered exit radiance of the terrain
// around), while the occlusion O changes from texel to texel (a channel's
// floor is enclosed by its walls, the rim beside it is not). So between
// receivers the engine interpolates Lbar, as the ratio of the bilinearly
// interpolated E and O, and multiplies it by each texel's own O:
//   E(x) = O(x) sum_k w_k E_k / sum_k w_k O_k,
// where O(x) is the clamped-cosine integral (the exact F = f2 - g f1 of the
// indirect scan, per azimuth, box weights) below the texel's horizon
// max(near(x), far(x)): near(x) from the full-resolution heights at 0.5,
// 1, ..., s - 0.5 cells (closer than the scan's first step), far(x) the
// receivers' horizons interpolated bilinearly. O_k is taken below the
// receiver's scan horizons alone, the blockers its E_k saw (the scan starts
// s cells away), so that E_k / O_k is their mean radiance; a receiver's own
// texel then gets E_k O(x) / O_k: its near field at that radiance. (With the
// near field in O_k too, i.e. the same estimate as the texels', the blockers'
// radiance came out low.) A texel with no blocker above its plane gets
// exactly 0 (a flat plane stays dark).
//
// Why: with sub-sampling most of the indirect error was between the
// receivers, and most of that in the most concave and most convex tenths of
// the texels (a channel's floor below its interpolated neighbours got too
// little light, a crest too much); interpolating an SH radiance vector U and
// shading it at each texel's normal cannot see a height difference. Accuracy
// and cost are measured in bench/results/gi_indirect_accuracy.md (1x is
// unchanged: every texel is a receiver).
//
// Deterministic: fixed blocks of rows, per texel a pure function of its
// inputs; the 4- and 8-wide kernels use the same lane-wise IEEE operations.
#include <array>
#include <cstdint>
#include <vector>

#include "core/grid.h"
#include "gi/pyramid.h"
#include "gi/receiver_tiles.h"
#include "gi/shading.h"
#include "gi/texel_runs.h"

namespace terrain::gi {

/// One near-field sample of an azimuth: the bilinear taps at a constant offset.
struct NearTap {
    int dx, dy;  // offset of the lower-left tap, cells
    float w00, w10, w01, w11;
    float invDist;  // 1 / (t cellSize)
};

struct BlockerRadianceState {
    int nx = 0, ny = 0, nxr = 0, nyr = 0, subsample = 1, azimuths = 0;
    std::vector<float> farSlope;  // azimuths planes of nxr * nyr: the receivers' horizons (tan), from the scan
    std::vector<float> heights;   // full-resolution heights with a border of s cells (outside: no blocker)
    std::array<std::ptrdiff_t, 4> heightsLayout{};  // its nx, ny, border and row stride (0: not laid out yet)
    std::uint64_t heightsOfBuild = 0;               // the pyramid build (HeightPyramid::buildId) they copy
    Grid occlusion;                                 // O / pi at every texel
    bool occlusionValid = false;                    // occlusion and receiverOcclusion hold a result of this grid
    std::vector<float> receiverOcclusion;           // O / pi at the receivers
    // per azimuth j (planes of nxr * nyr): the receivers' occlusion sum over
    // the azimuths 0..j, unnormalised (azimuth j's share of O_k is
    // (running_j - running_(j-1)) / running_(m-1); gi/indirect_cache.h)
    std::vector<float> receiverOcclusionRunning;
    // per distance group g (kDistanceGroups planes of nxr * nyr, gi/pyramid.h):
    // the part of the receivers' occlusion that group's members cover,
    // unnormalised as the running sums, from the scan (summed |Delta F| over
    // the azimuths; the groups add up to the last running sum, up to rounding)
    std::vector<float> receiverGroupOcclusion;
    std::array<std::vector<float>, 3> receiverShade;  // E / pi at the receivers, per channel
    std::vector<float> scratch;                       // per block of rows: padded row buffers
    std::vector<int> busyBlocks;                      // the blocks of rows with runs (scratch)
    std::vector<NearTap> taps;                        // azimuths x near samples
    std::vector<float> cosPhi, sinPhi;
    std::vector<ReceiverLerp> cols;  // per full-resolution column: the receivers it reads
    // The texel passes' extent: the receivers to redo and the texels
    // (gi/texel_runs.h).
    DirtySpans receiverRuns;
    TexelRuns texelRuns;
};

/// Sizes the buffers for a frame (farSlope is then filled by the scan).
void prepareBlockerRadiance(const HeightPyramid& pyr, int azimuths, BlockerRadianceState& st);

/// O / pi at every texel from the receivers' horizons (farSlope, filled) and
/// the full-resolution heights; phi: the indirect azimuths (radians). With
/// receiver tiles (null: every texel) and a valid occlusion of this grid in
/// the state, only the receivers of the dirty tiles and the texels of
/// `runs` (null: those whose lower receiver, receiverLerp's i0 along both
/// axes, is one of them); the others keep their values (gi/texel_runs.h).
/// Each value is the same whichever are computed.
void computeTexelOcclusion(const HeightPyramid& pyr, ConstGridView gradX, ConstGridView gradY,
                           const std::vector<double>& phi, const ReceiverTiles* tiles, const TexelRuns* runs,
                           BlockerRadianceState& st);

/// The bounce's exit radiance albedo E(x) / pi at every texel from the
/// receivers' E / pi (receiverShade). With s = 1 every texel is a receiver.
/// With receiver tiles (null: every texel), only the texels of `runs` (null:
/// those whose lower receiver lies in a dirty tile; with s = 1 the dirty
/// tiles' receivers); rgb keeps the others (it must hold a result of this
/// grid).
void shadeBlockerRadiance(BlockerRadianceState& st, const AlbedoMap* albedo, const ReceiverTiles* tiles,
                          const TexelRuns* runs, std::array<Grid, 3>& rgb);

}  // namespace terrain::gi
