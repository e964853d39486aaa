#pragma once
// One GI frame: gradient -> height pyramid -> visibility (environment, then
// each key light) -> shading. GiState holds every buffer and is reused across
// frames: after the first frame of a given size and settings, a frame
// allocates nothing.
#include <cstdint>
#include <vector>

#include "core/grid.h"
#include "gi/ambient_horizon.h"
#include "gi/frame_change.h"
#include "gi/indirect.h"
#include "gi/indirect_cache.h"
#include "gi/lights.h"
#include "gi/pyramid.h"
#include "gi/settings.h"
#include "gi/shading.h"
#include "gi/shading_tiles.h"
#include "gi/visibility.h"
#include "gi/visibility_cache.h"
#include "gi/wedge.h"

namespace terrain::gi {

/// Milliseconds per stage of the last frame.
struct GiTimings {
    double gradient = 0.0, pyramid = 0.0, visibility = 0.0, keyVisibility = 0.0, shading = 0.0, total = 0.0;
    double indirect = 0.0;  // all bounces (pyramids, scans, shading); 0 when not updated this frame
};

struct GiState {
    Grid gradX, gradY;  // full resolution dh/dx, dh/dy (metres per metre)
    HeightPyramid pyramid;
    FoldedWedgeOperator envOperator;  // cached for (azimuths, interp)
    int envOperatorAzimuths = -1;
    AzimuthInterp envOperatorInterp = AzimuthInterp::Linear;
    FoldedWedgeOperator indirectOperator;  // cached when the indirect scan has its own azimuths
    int indirectOperatorAzimuths = -1;
    AzimuthInterp indirectOperatorInterp = AzimuthInterp::Linear;
    VisibilityState visibilityState;
    FootprintBox footprint;  // this frame's receiver footprint boxes (sub-sampling)
    // The environment's scan: its horizons always; its SH planes V all 16 when
    // a light or the SH ambient reads them, else GiSettings::minEnvironmentShRows.
    VisibilityField envVisibility;
    std::vector<FoldedWedgeOperator> keyOperators;
    std::vector<KeyLight> keyOperatorLights;  // the lights the key operators were built for
    std::vector<VisibilityField> keyVisibility;
    std::vector<ShadingLight> shadingLights;
    // The lights' SH radiance those shading lights filter, unoccluded (the
    // environment's SH part and the SH key lights as caps): what the lobe
    // gather's first-bounce members reflect (IndirectInputs::memberLight).
    ShRgb shadedLight;
    ShadeMaps shade;
    std::vector<float> envCosSin;  // cos, sin of each envOperator azimuth (the exact ambient's), built with it
    AmbientScratch ambientScratch;
    GiTimings timings;
    // Indirect light (gi/indirect.h): indirect.indirect and indirect.total
    // (= shade.rgb + indirect) are valid when settings.indirect.bounces > 0.
    IndirectState indirect;
    // Incremental frames (GiSettings::incremental, gi/frame_change.h): the
    // inputs of the cached results, and whether an amortised frame left the
    // direct or the indirect light behind its inputs.
    FrameInputs lastInputs;
    bool geometryOfRecord = false;    // the gradients, footprint boxes and height pyramid are lastInputs.heights'
    VisibilityCache visibilityCache;  // per tile, how far the cached V may have drifted
    IndirectCache indirectCache;      // per tile, how far the cached indirect light may have drifted
    bool directStale = false, indirectStale = false;
    TexelRuns shadingRuns;  // this frame's texels whose direct light was redone (gi/shading_tiles.h)
    CellBox directChanged;  // texels of shade.rgb that may differ from what the indirect light last read (all)
    std::array<std::vector<float>, 3> shadeBefore;  // scratch: the redone texels' light before the shading (copyRuns)
    TexelRuns ambientRuns;                          // of those, the texels whose exact ambient was redone
    KeyVisibilityBefore keyBefore;                  // scratch: the key tiles' visibility before this frame's scan
    std::vector<ReceiverRun> keyReceiversChanged;   // the key receivers whose visibility this frame's scan changed
    std::vector<TexelRect> texelRects;              // their scratch
    double receiversRecomputed = 0.0;   // fraction of the receivers whose environment V the last frame recomputed
    int keyVisibilitiesRecomputed = 0;  // key lights whose V the last frame recomputed
    int framesSinceRefresh = 0;         // incremental frames since the last full one (GiSettings::refreshEvery)
    double indirectRecomputed = 0.0;    // fraction of the receivers whose indirect light the last frame re-gathered
    // Shading amortisation (Section 7): with settings.indirect.amortise, frames
    // on unchanged geometry update the direct and the indirect light
    // alternately. Incremental frames set geometryChanged themselves; without
    // them the caller says whether the heights changed since the last frame
    // (e.g. from the simulator's change report).
    bool geometryChanged = true;
    int amortisePhase = 0;             // next static frame: 0 direct, 1 indirect
    bool amortiseReady = false;        // a full frame with the current key ran before
    std::array<int, 7> amortiseKey{};  // nx, ny, subsample, bounces, azimuths, brdf, indirect azimuths of that frame
    bool directUpdated = false, indirectUpdated = false;  // what the last frame recomputed
    std::uint64_t geometryVersion = 0;                    // counts the frames that recomputed the gradient and pyramid
};

/// Runs one frame. Throws InputError when heights contain NaN/Inf, the cell
/// size is not positive and finite, or a setting is out of range.
void runGiFrame(ConstGridView heights, float cellSize, const GiLighting& lighting, const GiSettings& settings,
                GiState& state, const AlbedoMap* albedo = nullptr);

/// Central-difference height derivatives (one-sided at the borders, 0 on a
/// 1-wide axis), in metres per metre. With `changed` (gradients of the same
/// size already there, of heights that differ only in those rows), only the
/// rows whose derivatives read a changed row.
void computeGradient(ConstGridView heights, float cellSize, Grid& gradX, Grid& gradY, RowSpan changed = {});

/// Throws InputError naming the first NaN/Inf height of the cells `box`
/// (every cell by default).
void checkHeightsFinite(ConstGridView heights, CellBox box = {});

/// Redoes the direct light of every texel (and the ambient map) from the
/// visibility `st` holds, as the last frame's shading stage would with every
/// row: what a frame's shading gives, apart from the rows it kept.
/// InputError when `lighting` has a part that goes through the SH product
/// and the last frame, whose lighting had none, computed no SH visibility.
void shadeDirect(const GiLighting& lighting, const GiSettings& settings, const AlbedoMap* albedo, GiState& st);

/// The shade key light k alone gives every texel (white albedo) in the last
/// frame run on `st`, the way that frame computed it (exact cosine times the
/// visible fraction, or SH shading of its visibility). scratch is reused.
void shadeKeyLight(const GiState& st, const GiSettings& settings, const GiLighting& lighting, int k, ShadeMaps& scratch,
                   std::array<Grid, 3>& out);

}  // namespace terrain::gi
