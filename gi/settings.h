#pragma once
// The settings of a GI frame. GiSettings{} is the engine's choice, measured
// on real DEMs against the exact references (bench/results/gi_accuracy.md,
// gi_indirect_accuracy.md, gi_convergence.md); paperGiSettings() gives the
// settings of Nowrouzezahrai & Snyder 2009 for comparison. Every numeric
// range is declared once in gi/settings_ranges.h and checked by
// validateGiSettings, which the frame, the pipeline and the command line call.
#include "gi/ambient_horizon.h"
#include "gi/indirect.h"
#include "gi/pyramid.h"
#include "gi/settings_ranges.h"
#include "gi/shading.h"
#include "gi/visibility.h"

namespace terrain::gi {

struct GiSettings {
    int subsample = 1;  // 1, 2 or 4: visibility on the (N/s)^2 receiver grid (Fig. 7)
    PyramidSettings pyramid;
    VisibilitySettings visibility;
    int keyLightAzimuths = 3;  // azimuth samples per key light (Nowrouzezahrai & Snyder 2009, Section 9)
    // Key lights shaded with the exact cosine: albedo RGB f max(0, N . l), f the
    // visible fraction of the light's region (V_key's band-0 coefficient times
    // sqrt(4 pi) over the region's solid angle), instead of V_key dotted with
    // the order-4 SH clamped cosine (whose band-2 truncation is off for a
    // small light: measured in bench/results/gi_indirect_accuracy.md).
    bool keyLightExactCosine = true;  // paper: false
    // The ambient map integrated exactly above each azimuth's horizon
    // (gi/ambient_horizon.h) instead of lam(N) . V_env / pi, whose order-4
    // SH truncation is a floor on its error (bench/results/gi_accuracy.md).
    AmbientMethod ambient = AmbientMethod::Horizons;  // paper: ShProduct
    // At least this many SH rows of the environment's V are computed: 0, 1
    // (V_00, the visible fraction of the sky at each receiver: the renderer's
    // water dims its mirrored sky by it) or 16 (diagnostics that shade with
    // V). The frame computes all 16 when a light or the SH ambient reads V;
    // a uniform or analytic sky with the exact ambient reads the horizons
    // alone.
    int minEnvironmentShRows = 0;
    ShadingSettings shading;
    IndirectSettings indirect;  // bounces, radiance pyramid, amortisation
    // Incremental frames (gi/frame_change.h): a stage reruns only when its
    // inputs changed since the cached result; off: every frame recomputes
    // everything (for comparison).
    bool incremental = true;
    // With incremental frames: the largest change, in shade units, a cached
    // result may be behind by, by conservative bounds: of the ambient map
    // (unit sky, irradiance / pi) for a receiver's visibility
    // (gi/visibility_cache.h), of the gathered radiance for its indirect
    // light (gi/indirect_cache.h); 0: recompute whatever may have changed at
    // all (bit-identical to full frames). The default is the largest that
    // kept every frame of 300-frame erosion and waves runs, and every case
    // of the incremental benchmark (a moving sun, a crater, pits), within
    // 0.2 % relative RMS and 1 % of the mean at any texel of full frames
    // (bench/results/gi_incremental.md, README).
    float tolerance = 0.05f;
    // With incremental frames: every refreshEvery-th frame recomputes
    // everything, bit-identical to a full frame, whatever the bounds say
    // (0: never).
    int refreshEvery = 0;
    bool operator==(const GiSettings&) const = default;
};

/// The paper's settings: m = 32 azimuths, k_v = 4, o_v = 2, a mean height
/// pyramid, the B-spline maximum of Eq. 16, the receiver's own tangent plane,
/// key lights through the SH clamped cosine, k_u = 4, o_u = 2 and the order-4
/// SH kernel for indirect light (Eq. 12 and the wedge operators).
GiSettings paperGiSettings();

/// Throws InputError naming the first setting outside its range.
void validateGiSettings(const GiSettings& s);

/// The indirect scan's azimuths: its own (IndirectSettings::azimuths) or,
/// for 0, the environment's.
int indirectScanAzimuths(const GiSettings& s);

}  // namespace terrain::gi
