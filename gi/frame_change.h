#pragma once
// What a GI frame's cached results were computed from, and what changed
// since: the frame's stages rerun only where their inputs changed.
//
// Every stage is a pure function of its inputs, so a stage whose inputs are
// bit for bit those of the cached result reproduces it bit for bit; skipping
// it changes nothing. The dependencies:
//   heights, cell size, settings -> gradient, height pyramid, environment V
//   + a key light's direction and size -> that key light's V
//   + lighting (radiances), albedo -> direct shading, indirect bounces
// Static geometry and static lights: a frame does no GI work. A moving sun on
// static geometry: its key light's visibility and the shading. A changed
// environment: the shading (V is cached).
#include <array>
#include <vector>

#include "core/grid.h"
#include "gi/lights.h"
#include "gi/settings.h"
#include "gi/shading.h"

namespace terrain::gi {

/// The inputs of the last frame (copies: the caller may reuse its buffers).
struct FrameInputs {
    bool valid = false;
    Grid heights;
    float cellSize = 0.0f;
    GiSettings settings;
    ShRgb environment;
    std::optional<SkyGradient> gradient;
    std::vector<KeyLight> keys;
    bool hasAlbedo = false;
    AlbedoMap albedo;
};

/// Which inputs differ from the recorded ones.
struct FrameChange {
    bool geometry = true;  // heights, cell size or any setting: gradient, pyramid and every V
    // Only the heights changed (same size, cell size and settings): the
    // visibility may be recomputed tile by tile (gi/visibility_cache.h).
    bool heightsOnly = false;
    // With heightsOnly: the box holding every height that differs from the
    // record bit for bit (the first to the last differing row, and in those
    // rows the first to the last differing column); otherwise every cell.
    CellBox heightBox;
    // The box holding every height that differs from the recorded heights
    // bit for bit, whatever else changed (every cell without a record of
    // this size): the others are the record's, checked when recorded.
    CellBox newHeights;
    std::vector<bool> keyRegion;  // per key light: its region of the sky is new (direction, size, count)
    bool radiance = true;         // environment, key radiances or albedo: shading and indirect light
    bool any() const;
    /// Key light k's visibility must be recomputed (the geometry or its region changed).
    bool keyVisibility(std::size_t k) const { return geometry || keyRegion[k]; }
};

/// Everything changed (no record, or incremental frames switched off).
FrameChange everythingChanged(std::size_t keys);

/// Compares this frame's inputs with the record.
FrameChange compareFrameInputs(const FrameInputs& last, ConstGridView heights, float cellSize,
                               const GiLighting& lighting, const GiSettings& settings, const AlbedoMap* albedo);

/// Records this frame's inputs; the heights (their changed rows) and the
/// albedo maps are copied only when `change` says they may differ from the
/// record (buffers reused).
void recordFrameInputs(ConstGridView heights, float cellSize, const GiLighting& lighting, const GiSettings& settings,
                       const AlbedoMap* albedo, const FrameChange& change, FrameInputs& out);

}  // namespace terrain::gi
