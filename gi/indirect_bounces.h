#pragma once
// The bounce loop of the indirect light (Sections 5.3 and 7) and what every
// strategy shares around it.
//
// Bounce b filters the previous bounce's exit radiance L_(b-1) into a pyramid
// (bounce 1: the direct light), scans the receivers' casting sets against it
// and shades the result into its own exit radiance L_b; the indirect light is
// L_1 + ... + L_B. A strategy (IndirectStrategy) supplies the three steps of a
// bounce; runBounces times them and keeps the sums.
#include <array>
#include <optional>

#include "core/grid.h"
#include "gi/indirect_inputs.h"
#include "gi/indirect_settings.h"
#include "gi/indirect_state.h"
#include "gi/shading.h"

namespace terrain::gi {

/// What a bounce reads: the previous bounce's exit radiance (full resolution)
/// and the shading it came from (incident SH vectors; null for bounce 1 when
/// IndirectInputs::directShade is).
struct BounceSource {
    const std::array<Grid, 3>* rgb;
    const ShadeMaps* shade;
    // Bounce 0 (IndirectInputs::direct) only: the texels that may differ
    // from the radiance the state's RGB pyramid was built from (every texel
    // unless that was the last call's bounce 0 too).
    std::optional<CellBox> directChanged;
};

/// One way of turning casting sets into light (gi/indirect_sh_kernel.h,
/// gi/indirect_blocker_radiance.h), over the inputs,
/// settings and state it was made with.
class IndirectStrategy {
public:
    virtual ~IndirectStrategy() = default;
    /// Sizes the strategy's buffers for this frame (throws InputError on
    /// inputs it cannot use).
    virtual void beginFrame() = 0;
    /// Bounce b's pyramid of the previous bounce's exit radiance (Section 5.3).
    virtual void buildPyramid(int b, const BounceSource& previous) = 0;
    /// Bounce b's step table and casting-set scan (with receiver tiles,
    /// IndirectInputs::only, the receivers of the dirty tiles only, where
    /// the strategy supports them).
    virtual void scan(int b) = 0;
    /// Bounce b's exit radiance L_b at full resolution (out.rgb; with U also
    /// its incident SH vectors).
    virtual void shade(int b, ShadeMaps& out) = 0;
};

/// Runs settings.bounces bounces of `strategy`: fills state.indirect, total,
/// bounceShade (one bounce: its exit radiance is state.indirect itself),
/// bounceMean and timings.
void runBounces(const IndirectInputs& in, const IndirectSettings& settings, IndirectStrategy& strategy,
                IndirectState& st);

/// Adds bounce b's exit radiance to st.indirect and records its mean
/// (st.bounceMean[b - 1], RGB average).
void accumulateBounce(const std::array<Grid, 3>& exit, int b, IndirectState& st);

/// st.total = direct + st.indirect; with `changed`, only there (the caller
/// knows st.total holds the sum everywhere else: IndirectState::totalValid).
void sumDirectAndIndirect(const std::array<Grid, 3>& direct, IndirectState& st, CellBox changed = {});

/// The shading lights of U: channel c lights channel c only (identity
/// product matrices over st.u).
void setUShadingLights(IndirectState& st);

}  // namespace terrain::gi
