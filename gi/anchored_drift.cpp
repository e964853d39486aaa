#include "gi/anchored_drift.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace terrain::gi {

void AnchoredDrift::reset(std::size_t tiles) {
    fromAnchor.assign(tiles, 0.0f);
    lastExcursion.assign(tiles, 0.0f);
    sinceInputs.assign(tiles, 0.0f);
}

namespace {

void requireLayout(const AnchoredDrift& drift, std::size_t n, std::size_t dirty, std::span<const float> sinceLast) {
    if (!drift.fits(n) || dirty != n || (!sinceLast.empty() && sinceLast.size() != n))
        throw InputError("anchored drift: tiles of another layout");
}

}  // namespace

float driftNow(const AnchoredDrift& drift, std::span<const float> excursion, std::span<const float> sinceLast,
               std::size_t t) {
    const float fromAnchor = drift.fromAnchor[t] + excursion[t];
    return sinceLast.empty() ? fromAnchor : std::min(fromAnchor, drift.sinceInputs[t] + sinceLast[t]);
}

void markAnchoredDrift(std::span<const float> excursion, std::span<const float> sinceLast,
                       std::span<const std::uint8_t> forced, float scale, float tolerance, const AnchoredDrift& drift,
                       std::span<std::uint8_t> dirty, AnchorVotes& votes) {
    const std::size_t n = excursion.size();
    requireLayout(drift, n, dirty.size(), sinceLast);
    if (!forced.empty() && forced.size() != n) throw InputError("anchored drift: tiles of another layout");
    for (std::size_t t = 0; t < n; ++t) {
        const float e = excursion[t], a = drift.fromAnchor[t];
        const bool isForced = !forced.empty() && forced[t] != 0;
        const bool byDrift = driftNow(drift, excursion, sinceLast, t) * scale > tolerance;
        // a tile the second path could have kept moves the anchor no more:
        // recomputed since, it will be kept by that path until the change
        // since then, not the anchor's, passes the tolerance
        const bool secondPath = !sinceLast.empty() && std::isfinite(sinceLast[t]);
        if (byDrift && !isForced && !secondPath && a > 0.0f && e >= drift.lastExcursion[t]) votes.movingAway = true;
        dirty[t] = byDrift || isForced ? 1 : 0;
        (dirty[t] ? votes.recomputedMoved : votes.keptMoved) |= e > 0.0f;
    }
}

void advanceAnchoredDrift(std::span<const float> excursion, std::span<const float> sinceLast,
                          std::span<const std::uint8_t> dirty, bool reanchor, AnchoredDrift& drift) {
    const std::size_t n = excursion.size();
    requireLayout(drift, n, dirty.size(), sinceLast);
    for (std::size_t t = 0; t < n; ++t) {
        const float e = excursion[t];
        drift.sinceInputs[t] = dirty[t] ? 0.0f : driftNow(drift, excursion, sinceLast, t);
        if (reanchor) {
            drift.fromAnchor[t] = drift.sinceInputs[t];  // this frame's inputs are the anchor
            drift.lastExcursion[t] = 0.0f;
        } else {
            if (dirty[t]) drift.fromAnchor[t] = e;
            drift.lastExcursion[t] = e;
        }
    }
}

bool planAnchoredDrift(std::span<const float> excursion, std::span<const std::uint8_t> forced, float tolerance,
                       AnchoredDrift& drift, std::span<std::uint8_t> dirty) {
    AnchorVotes votes;
    markAnchoredDrift(excursion, {}, forced, 1.0f, tolerance, drift, dirty, votes);
    advanceAnchoredDrift(excursion, {}, dirty, votes.reanchor(), drift);
    return votes.reanchor();
}

bool markDriftAgain(float scale, float tolerance, AnchoredDrift& drift, std::span<std::uint8_t> dirty) {
    if (!drift.fits(dirty.size())) return false;
    bool any = false;
    for (std::size_t t = 0; t < dirty.size(); ++t) {
        const bool recompute = drift.sinceInputs[t] * scale > tolerance;
        if (recompute) {
            drift.fromAnchor[t] = drift.lastExcursion[t];
            drift.sinceInputs[t] = 0.0f;
        }
        dirty[t] = recompute ? 1 : 0;
        any = any || recompute;
    }
    return any;
}

}  // namespace terrain::gi
