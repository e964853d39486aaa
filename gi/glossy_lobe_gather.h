#pragma once
// The glossy receivers' own lobe, gathered along the scan directions it
// covers (GlossyIndirect::LobeScan): the engine's answer to the order-4 floor
// of the vector pyramid (gi/indirect_sh_kernel.h, README "Glossy indirect
// light").
//
// Why. The vector pyramid shades each receiver's SH-projected incident
// radiance U with the order-4 Phong lobe factors (Section 7). Measured
// against the exact glossy reference that projection is the vector mode's
// floor, and the sharper the lobe the higher it lies; the scan's few azimuths
// are another (a sharp lobe lies between two of them). What the members
// send, E . Y of their exit radiance, costs less (README, "Glossy indirect
// light", gives the measured floors).
//
// What is gathered. The Phong part of a receiver's first-bounce exit
// radiance towards the viewer, int I(w) f(w) dw with f the normalised Phong
// lobe about the viewer's reflection R (gi/phong_lobe_quadrature.h), by the
// lobe quadrature's directions (gi/phong_lobe_quadrature.h; its growing rule,
// IndirectSettings::lobeRings and lobeInnerDirections, gatherLobeLayout).
// Each direction w is seen along the scan's global azimuths phi_j = 2 pi j /
// M (IndirectSettings::lobeAzimuths): at w's own elevation along the two
// azimuths on either side of w's, weighted linearly (the reference's
// receiverAzimuths diagnostic, gi/reference_gi.h). Along azimuth j the
// receiver walks the height pyramid's exponential steps (Eq. 14, the
// casting-set scan's tables at M azimuths); a ray of slope tan(elevation) te
// is met by the first step whose blocking slope t reaches te (Eq. 17's
// casting set: that step is the member whose segment holds te, Eq. 8). It
// meets the surface between that step and the one before, where the ray's
// height above the two samples, linearly interpolated, crosses zero, and
// brings back what the surface sends towards the receiver from there along
// the ray (not the member's own elevation), max(0, .) with
// GlossyPositivity::Clamp: in the first bounce its windowed lobe
// (gi/glossy_lobe_members.h, GlossyLobeMembers::Windowed), else E . Y(-w_j)
// with E the full-resolution exit radiance, bilinear. Reading what the
// surface sends there rather than at the member's pyramid sample, which
// stands for the whole step and a footprint as wide, made the gather
// markedly more accurate (README).
// A ray below the tangent plane along phi_j carries nothing; one that meets
// no step sees the sky (direct light, bounce 0).
//
// Where. Every texel gathers its own lobe (its normal, exponent from
// AlbedoMap::phongExponent, and reflection) along the walks of the receiver
// that owns it, the nearest one (with sub-sampling s up to s / 2 cells
// away; the receivers' step tables serve all), but sees their samples from
// where it stands: over its own height, at its own distance along the
// azimuth (the samples lie on the receiver's ray, at most s / 2 cells beside
// its own), its rays leaving from it. Seen from the receiver instead, 2x lost
// 6-9 points of accuracy against 1x (README). A receiver's texels share its
// walks: one per azimuth some ray of theirs reads, each step's sample read
// once for all of them; a texel's part of a walk stops once its lowest unmet
// ray rises above the highest sample the walk has left (taken per distance
// band for 64 receivers of a row at once, GlossyLobeScratch::bandTops): narrow
// lobes walk 2-4 azimuths, and rays above the horizon stop after a few steps.
// A ray that passes above every band's highest sample, each seen from the
// band's nearest step, is never appended, and a texel whose whole lobe does
// makes no rays at all.
// Interpolating receivers' gathered radiance instead (Fig. 7) would lose
// what makes a glossy texel glossy: its lobe follows its own normal. The
// diffuse part of a mixture and the bounces after the first keep the SH
// kernel (U); their incident SH comes from U as in the vector mode.
//
// Deterministic: per receiver a pure function of its inputs (the rays a step
// meets taken by slope, then in the order appended), receiver rows in
// parallel.
#include <array>
#include <cstdint>
#include <vector>

#include "core/grid.h"
#include "gi/glossy_lobe_members.h"
#include "gi/phong_lobe_quadrature.h"
#include "gi/pyramid.h"
#include "gi/shading.h"
#include "gi/visibility.h"

namespace terrain::gi {

/// GCC vectors of N doubles and their comparison masks (GCC does not size a
/// vector by a template argument).
template <int N>
struct TexelLaneTypes;
template <>
struct TexelLaneTypes<2> {
    using Lanes = double __attribute__((vector_size(16)));
    using Mask = std::int64_t __attribute__((vector_size(16)));
};
template <>
struct TexelLaneTypes<4> {
    using Lanes = double __attribute__((vector_size(32)));
    using Mask = std::int64_t __attribute__((vector_size(32)));
};
/// N texels of a walk side by side (2 with SSE2, 4 with AVX2; in double, as
/// one texel alone would compute): each one's offset from the receiver along
/// the azimuth (cells), height and float margin (metres), the slope of its
/// lowest ray left, and the last step below every ray left: its sample's
/// rise over the texel and its distance from it (metres; 0: none yet).
template <int N>
struct alignas(8 * N) TexelLanes {
    using Lanes = typename TexelLaneTypes<N>::Lanes;
    using Mask = typename TexelLaneTypes<N>::Mask;
    Lanes along, h, margin, slope, riseBefore, runBefore;
};

/// Per worker slot: one receiver row's inputs and the rays of one receiver's texels.
struct GlossyLobeScratch {
    struct Ray {
        int azimuth;    // global azimuth j of the walk that reads the ray
        int texel;      // which of the receiver's texels it serves
        float slope;    // tan of the ray's elevation (+inf once the walk met it)
        float weight;   // quadrature weight x the linear azimuth weight
        float back[3];  // unit direction from the member back to the receiver
    };
    std::vector<Ray> rays, byAzimuth;  // as appended, and by azimuth (then texel)
    std::vector<int> bucketStart;      // the counting sort's buckets (one per azimuth)
    std::vector<double> acc;           // 3 per texel of the receiver
    // Per texel of the receiver: its height and float margin (metres), and
    // its offset from the receiver (cells).
    struct TexelFrame {
        float h, margin;
        double ox, oy;
    };
    std::vector<TexelFrame> texelFrames;
    // A chunk of the receiver row's highest samples (GlossyLobeState::
    // stepBand): of azimuth j, band k and the chunk's receiver x at
    // (j bands + k) 64 + x, the highest height sample of band k of its walk
    // (-inf: none); and of one walk, per band the highest of that band and
    // the bands after it.
    std::vector<float> bandTops, topsAhead;
    // Per global azimuth, the slope above which the current texel's rays
    // meet nothing along it (escapeSlope), valid where its stamp is the
    // texel's serial.
    std::vector<double> escape;
    std::vector<std::uint64_t> escapeStamp;
    std::uint64_t texelSerial = 0;
    // One texel's part of a walk: its rays along the azimuth (as appended) and
    // where it stands; the rest of its state is in its lane.
    struct TexelWalk {
        Ray *first, *end;  // a met ray's slope becomes +inf
        const TexelFrame* frame;
    };
    std::vector<Ray*> met;  // one texel's rays met at one step
    std::vector<TexelWalk> walks;
    // walk k in lane k % N of block k / N (the SSE2 and the AVX2 variant)
    std::vector<TexelLanes<2>> narrowLanes;
    std::vector<TexelLanes<4>> wideLanes;
    // Where a ray meets the surface (full-resolution cells); the receiver's
    // hits in the walks' order.
    struct Hit {
        double px, py;
        const Ray* ray;
    };
    std::vector<Hit> hits;
    LobeMemberHits memberHits;  // with windowed members: the hits' taps and ways back, as hits
    LobeQuadrature quadrature;  // the lobe directions of the last exponent
    // One texel's lobe directions, stage by stage: the unit direction, its
    // horizontal length, its azimuth in units of the global azimuths and its
    // slope.
    struct Directions {
        std::vector<double> x, y, z, horizontal, u, slope;
        void resize(int n) {
            for (std::vector<double>* v : {&x, &y, &z, &horizontal, &u, &slope}) v->resize(static_cast<std::size_t>(n));
        }
    } directions;
};

/// The gather's step tables and its result (reused: no allocation after the
/// first frame of a size and settings).
struct GlossyLobeState {
    std::vector<double> phi;            // the M global azimuths 2 pi j / M
    std::vector<float> cosPhi, sinPhi;  // their directions
    // The walks' steps (GlossyLobeInputs::nearStepsPerOctave): azimuth j's
    // from j * stepStride; each step's sample distance from its receiver, in
    // cells; per receiver column and row the steps inside the domain.
    int stepStride = 0;
    std::vector<ScanStep> heightSteps;
    std::vector<double> stepCells;
    std::vector<int> stepsPerColumn, stepsPerRow;
    // Per step (as heightSteps) its distance band (0 out to 1 cell, k from
    // 2^(k-1) to 2^k cells) and the receivers whose walks reach it (a box:
    // the valid prefixes narrow step by step); per azimuth its steps; the
    // bands of the longest walk.
    std::vector<std::uint8_t> stepBand;
    std::vector<double> bandStart;  // azimuth j's band k: its nearest step at j * bands + k (cells; +inf: none)
    std::vector<ValidPrefix::Receivers> stepReceivers;
    std::vector<int> stepCounts;
    int bands = 0;
    std::vector<float> gathered;  // 3 planes of nx * ny: int I f dw per texel (RGB)
    std::vector<GlossyLobeScratch> scratch;
};

/// What the gather reads of a frame.
struct GlossyLobeInputs {
    const HeightPyramid& heights;  // the frame's height pyramid (receivers, steps)
    ConstGridView gradX, gradY;    // full-resolution height gradients
    // E at full resolution texel by texel (value f of texel k at k * 48 + f),
    // bfloat16 (glossyExitRadiance's texels): a ray's E is four runs of 96 bytes
    const std::uint16_t* exit;
    // Bounce 1's members (gi/glossy_lobe_members.h): when given, what they
    // send instead of E (exit may then be null).
    const LobeMembers* members;
    const AlbedoMap* surface;  // per-texel exponent (null or empty: the settings')
    const ShadingSettings& shading;
    int azimuths;  // M, the global azimuths
    // The lobe quadrature: gatherLobeLayout(S, rings, innerDirections).
    int rings, innerDirections;
    // The walks' raw steps: out to 2^nearOctaves cells, nearStepsPerOctave per
    // octave (then the pyramid's steps).
    int nearStepsPerOctave;
    int nearOctaves;
};

/// Lobes of exponents below this are wide enough to take a third ring.
inline constexpr double kWideLobeExponent = 16.0;

/// The quadrature the gather samples a lobe of exponent S with:
/// LobeLayout::growing(rings, innerDirections), where rings 0 chooses by
/// the lobe's width: 3 rings below kWideLobeExponent, 2 from it up. A wide
/// lobe spans more of the terrain's variation: with 2 rings its error at
/// S = 8 passed the 15 % target on two of three DEM crops, with 3 it stays
/// well below on all three (README, "Fewer rays").
LobeLayout gatherLobeLayout(double S, int rings, int innerDirections);

/// GlossyLobeState::gathered at every texel (see above).
void gatherGlossyLobes(const GlossyLobeInputs& in, GlossyLobeState& st);

/// out[c] = base[c] + w_s gathered (base: out's own values, or 0 when
/// `addToOut` is false); a value that is not finite becomes 0, and below 0
/// becomes 0 with GlossyPositivity::Clamp.
void shadeGlossyLobes(const GlossyLobeState& st, const HeightPyramid& heights, const ShadingSettings& shading,
                      bool addToOut, std::array<Grid, 3>& out);

}  // namespace terrain::gi
