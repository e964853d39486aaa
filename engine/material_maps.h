#pragma once
// Per-texel albedo and Phong exponent from a scene's materials and the
// terrain state (the rules in sim/materials.h). The same maps feed the GI
// bounces (gi::AlbedoMap) and the renderer's base colour, so what the light
// bounces off is what the eye sees.
#include "core/grid.h"
#include "gi/shading.h"
#include "sim/materials.h"
#include "sim/terrain.h"

namespace terrain::engine {

struct MaterialMaps {
    gi::AlbedoMap albedo;  // linear RGB albedo (channel[0..2]); the exponent is kept apart
    Grid exponent;         // Phong exponent S per texel
};

/// Derives the maps for every texel of `state` (rows in parallel; after the
/// first call of a size nothing is allocated). Deterministic: each texel is
/// a pure function of its own and its four neighbours' layers.
void deriveMaterialMaps(const TerrainState& state, const MaterialSet& materials, MaterialMaps& out);

/// The material of one texel from its ground altitude (m), slope (degrees),
/// soil thickness, water depth (m) and the magnitude of the depth's gradient
/// (m per m): the rules of sim/materials.h.
Material materialAt(const MaterialSet& m, float altitude, float slopeDeg, float soil, float water,
                    float depthGradient = 0.0f);

}  // namespace terrain::engine
