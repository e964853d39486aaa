#pragma once
// Height pyramid with B-spline filtering (Nowrouzezahrai & Snyder 2009,
// Section 5.2, Eqs. 14-16).
//
// Steps along every ray grow exponentially (Eq. 14): tau_i = 2^(i / k_v)
// cells, i = i_0..n_v-1, n_v chosen so the last step reaches the domain
// diagonal ("number of levels from the resolution and the domain size").
// With sub-sampling s the first step is one receiver spacing, 2^(i_0 / k_v) = s
// (the synthesised stack lives at the receiver grid, Section 9).
// Step i reads pyramid level l = i - k_v * o_v (the level offset o_v biases
// towards finer levels, Section 5.2); l < 0 reads the unfiltered full
// resolution heights (bilinear), which makes the method converge to
// brute-force marching as o_v grows.
//
// Level l is filtered at a scale of 2^(l / k_v) cells: octave images B_o are
// repeated 2x2 box ("bilinear") decimations of the heights; each octave o >= 1
// is synthesised at the receiver grid by cubic B-spline reconstruction (as the
// paper's GPU version does, after Sigg & Hadwiger 2005), S_o; S_0 is the
// height field itself at the receivers (level 0 is unfiltered, f_0 = f); a
// level between octaves blends the two neighbouring ones:
// f_l = (1 - q) S_o + q S_(o+1), o + q = l / k_v. Level o k_v is S_o itself
// (q = 0), synthesised in place: no copy of it is kept.
// Like the paper we keep the stack "blown out" to the receiver resolution,
// so for a fixed azimuth and step every receiver reads its level at the same
// fractional offset: the scan streams rows with constant bilinear weights.
//
// Optional peak keeping (PyramidSettings::peakBlend): the octave images can
// also be max-decimated; levels then blend mean and max syntheses, which
// counters the filtered pyramid's lowering of distant peaks.
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "core/grid.h"

namespace terrain::gi {

// Defaults: the engine's (gi/settings.h), measured on real DEMs against the
// exact reference (bench/results/gi_ambient_dems.md, gi_explore.csv,
// gi_indirect_accuracy.md). The mean filter lowers distant peaks, which ends
// casting sets early and lifts the ambient light (the paper settings'
// positive bias): a level offset of 3 and max-decimated octaves keep the
// peaks at the same cost. Nearly all max: the ambient integrated exactly
// above the horizons (gi/ambient_horizon.h) has no SH truncation left to
// offset a lowered horizon, and the indirect light's casting sets need the
// peaks; but the maximum over a level's footprint also lifts a horizon above
// what the ray itself meets, most on rough fine-celled DEMs (the ambient
// turns dark), so a tenth of the mean is kept: the blend with the smallest
// ambient bias across the DEMs measured.
struct PyramidSettings {
    int levelsPerOctave = 4;  // k_v (paper: 4)
    int levelOffset = 3;      // o_v in octaves (paper: 2)
    float peakBlend = 0.9f;   // 0 = mean pyramid (paper); 1 = max-decimated octaves
    bool operator==(const PyramidSettings&) const = default;
};

/// Floats of slack before and after a scanned field: the scan's 16-receiver
/// vector reads at a step where some receivers' samples have left the domain
/// stay inside the allocation (those lanes are discarded).
inline constexpr std::ptrdiff_t kFieldGuard = 32;

/// One sampled field: a row-major grid padded with one replicated column and
/// row so bilinear reads at the last sample stay in bounds.
struct PaddedField {
    int nx = 0, ny = 0;         // logical size
    std::ptrdiff_t stride = 0;  // nx + 1
    std::vector<float> v;       // guard + (nx + 1) * (ny + 1) + guard
    void resize(int w, int h);
    float* data() { return v.data() + kFieldGuard; }
    const float* data() const { return v.data() + kFieldGuard; }
    float* row(int y) { return data() + y * stride; }
    const float* row(int y) const { return data() + y * stride; }
    // Copies the last column / row into the padding, after the cells of
    // `changed` were written (every cell by default): only what they reach.
    void padEdges(CellBox changed = {});
};

struct PyramidStep {
    double tauCells = 1.0;     // distance in full-resolution cells (Eq. 14)
    float invTauWorld = 1.0f;  // 1 / (tau * cellSize)
    int level = -1;            // -1: raw heights, else index into levels
};

struct HeightPyramid {
    // Geometry of this build.
    int nx = 0, ny = 0;     // full resolution
    int subsample = 1;      // receiver spacing in cells (1, 2, 4)
    int nxr = 0, nyr = 0;   // receiver grid: receiver (X, Y) sits at cell (s X, s Y)
    float cellSize = 1.0f;  // metres
    PyramidSettings settings;
    std::vector<PyramidStep> steps;  // n_v steps

    // Full-resolution heights split by column phase (sub-sampling s): plane q
    // holds columns q, q + s, q + 2 s, ..., so receivers s cells apart read
    // consecutive floats at any column offset (the scan's raw steps stream
    // rows with SIMD). Plane width rawPhaseWidth = nx / s + 1 (columns past
    // the last one replicate it), ny + 1 rows (the last row replicated), so
    // the bilinear neighbours of any sample inside the domain are in bounds.
    // Plane 0 row s Y holds the receiver heights of receiver row Y.
    int rawPhaseWidth = 0;
    std::ptrdiff_t rawPhasePlane = 0;  // floats per plane: rawPhaseWidth * (ny + 1)
    std::vector<float> rawPhase;       // guard + s planes + guard
    const float* rawPhaseData() const { return rawPhase.data() + kFieldGuard; }
    const float* rawPhaseRow(int q, int y) const {
        return rawPhaseData() + q * rawPhasePlane + static_cast<std::ptrdiff_t>(y) * rawPhaseWidth;
    }
    // Each build's id (unique in the process) and that of the build whose
    // pyramid it redid in part (0: built whole), with the raw phases' rows
    // it redid: a copy of build `basedOn`'s raw heights needs only those.
    std::uint64_t buildId = 0, basedOn = 0;
    RowSpan rawRowsRedone;
    std::vector<Grid> meanOctaves;           // B_1, B_2, ... (B_0 is the input)
    std::vector<Grid> maxOctaves;            // same, max-decimated (only when peakBlend > 0)
    int octaves = 0;                         // octaves synthesised, S_0 .. S_(octaves - 1)
    std::vector<PaddedField> levels;         // f_l at the receiver grid, spacing s; level o k_v is S_o
    std::vector<PaddedField> synth;          // S_o of the octaves above the last level (octaveSynthesis)
    std::vector<std::vector<float>> rowTmp;  // per octave: scratch of the separable synthesis
    // Each octave's synthesis taps (4 indices into B_o and 4 weights per
    // receiver column, then per receiver row), a function of the grids
    // alone: kept while they are the same.
    struct OctaveTaps {
        std::array<int, 5> grid{};  // nxr, nyr, subsample, B_o's nx and ny
        std::vector<int> index;
        std::vector<float> weight;
    };
    std::vector<OctaveTaps> taps;  // per octave (o >= 1)
};

/// The steps grouped by distance, in doubling bands of tau (cells): [0, 4),
/// [4, 8), ..., [256, inf). A group's members cover a part of a receiver's
/// occlusion, and the indirect cache weighs a change of the group's samples
/// by that part (gi/indirect_cache.h): a far change (a pit, a crater) then
/// counts by the share of the sky the far members cover.
inline constexpr int kDistanceGroups = 8;
int distanceGroup(double tauCells);

/// Receiver grid size along one axis for n cells and sub-sampling s.
inline int receiverCount(int n, int s) { return n <= 0 ? 0 : (n - 1) / s + 1; }

/// Number of exponential steps n_v for a grid (Eq. 14 and the domain size),
/// before dropping the i_0 steps shorter than the receiver spacing.
int pyramidStepCount(int nx, int ny, int levelsPerOctave);

/// S_o at the receiver grid, o < pyramid.octaves: level o k_v, or for the
/// octaves above the last level (which the top levels blend towards) a
/// field of its own.
const PaddedField& octaveSynthesis(const HeightPyramid& pyramid, int o);

/// The octaves a level blends (gi/pyramid.cpp, blendLevels): f_l = (1 - q)
/// S_o + q S_(o+1), q = 0 where it is S_o alone (levels past the last octave
/// repeat it).
struct LevelOctaves {
    int octave = 0;
    float q = 0.0f;
};
LevelOctaves levelOctaves(const HeightPyramid& pyramid, int level);

/// 2^o, the cells across a texel of octave o: exact, as std::ldexp(1, o),
/// without its library call (the change bounds ask it per box they read).
inline double octaveScale(int o) {
    return o >= 0 && o < 63 ? static_cast<double>(std::uint64_t{1} << o) : std::ldexp(1.0, o);
}

/// The texels [y0, y1) of octave o's image B_o (o >= 1; `size` texels along
/// the axis) that the B-spline synthesis at the receivers [r0, r1] of that
/// axis reads: each receiver's four taps, clamped to the image.
RowSpan synthesisTexels(const HeightPyramid& pyramid, int octave, int size, int r0, int r1);

/// Builds (or rebuilds, reusing every buffer) the pyramid of `heights`.
/// With `changed`, when `out` holds the pyramid of heights that differ only
/// inside that box of cells on the same grid and settings: the passes that
/// copy rows (the raw phases, the receivers' heights) redo the box's rows,
/// the octave images, their syntheses and the levels the cells that read a
/// cell of the box (each with the arithmetic of the whole pass, so the
/// pyramid is the full build's bit for bit).
void buildHeightPyramid(ConstGridView heights, float cellSize, int subsample, const PyramidSettings& settings,
                        HeightPyramid& out, CellBox changed = {});

}  // namespace terrain::gi
