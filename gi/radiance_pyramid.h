#pragma once
// Radiance pyramids for indirect light (Section 5.3).
//
// Diffuse surfaces: the exit radiance of bounce b-1 is one RGB value per
// texel. Each channel gets the same multi-resolution treatment as the heights
// (gi/pyramid.h): 2x2 box octaves, cubic B-spline synthesis at the receiver
// grid, k_u levels per octave, level offset o_u (paper defaults k_u = 4,
// o_u = 2); level 0 is the field itself, steps whose level would be negative
// read the full-resolution radiance (bilinear, phase-split like the heights).
//
// The scan samples heights and radiance at the same steps: step i of the
// height pyramid (distance tau_i) reads radiance level
//   l_u(i) = round(k_u log2(tau_i)) - k_u o_u,
// so k_u may differ from the heights' k_v (with k_u = k_v the level index is
// the step index minus k_u o_u, as in the paper).
//
// Glossy surfaces (vector pyramid): the same pyramid over each coefficient of
// an SH radiance vector field (RGB x SH planes),
// kept as bfloat16 in one block (buildPackedPyramids): the 48 planes'
// pyramids are far larger than any cache, and bfloat16 halves their memory.
#include <array>
#include <cstdint>
#include <vector>

#include "core/grid.h"
#include "gi/pyramid.h"

namespace terrain::gi {

// Defaults: the engine's (gi/settings.h). Offset 3 like the heights'; 2
// levels per octave: a casting-set member reads the nearest level and the
// filtered radiance is smooth enough that finer spacing does not show, with
// half the levels to build and keep in cache (bench/results/gi_indirect_accuracy.md).
struct RadiancePyramidSettings {
    int levelsPerOctave = 2;  // k_u (paper: 4)
    int levelOffset = 3;      // o_u in octaves (paper: 2)
    bool operator==(const RadiancePyramidSettings&) const = default;
};

/// One pyramid per scalar field (3 for RGB radiance, 3 x n for SH vectors),
/// each with the height pyramid's steps (same tau) and its own level map.
struct RadiancePyramid {
    std::vector<HeightPyramid> fields;
};

/// Builds the RGB radiance pyramid of `radiance` (full resolution, the height
/// pyramid's size) at the height pyramid's receiver grid and steps. With
/// `changed`, when `out` holds the pyramid of a radiance that differs only
/// inside that box of texels (same grid and settings), each channel redoes
/// the cells that read the box (buildHeightPyramid), bit for bit a full build.
void buildRadiancePyramid(const std::array<Grid, 3>& radiance, const HeightPyramid& heights,
                          const RadiancePyramidSettings& settings, RadiancePyramid& out, CellBox changed = {});

/// The pyramids of many scalar fields stored as bfloat16 (core/bfloat16.h:
/// 2^-9 relative precision, float's range): every field's pyramid has the
/// layout of `geometry`, the float pyramid of field 0, whose steps and
/// offsets (scanStepInfo) therefore address every field's copy too.
struct PackedPyramids {
    HeightPyramid geometry;
    int count = 0;
    // Every field's levels and full-resolution phases in one block, field
    // after field: region (f, l) at regionAt[f * (levels + 1) + l] holds
    // PaddedField::v of level l, region (f, levels) HeightPyramid::rawPhase.
    std::vector<std::uint16_t> block;
    std::vector<std::size_t> regionAt;
    std::vector<HeightPyramid> scratch;  // per worker slot: a field's float pyramid
    /// Field f's copy of p, an address inside the geometry's level (-1: its
    /// full-resolution phases).
    const std::uint16_t* address(int f, int level, const float* p) const;
};

/// Builds the pyramids of `count` scalar fields (row-major nx x ny each,
/// consecutive in `fields`), each as one channel of buildRadiancePyramid, and
/// keeps them rounded to bfloat16; field 0's float pyramid stays as the geometry.
void buildPackedPyramids(const float* fields, int count, const HeightPyramid& heights,
                         const RadiancePyramidSettings& settings, PackedPyramids& out);

}  // namespace terrain::gi
