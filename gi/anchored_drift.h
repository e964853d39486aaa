#pragma once
// How far each tile's cached result can have drifted, measured from an
// anchor: the inputs of some earlier frame, kept until it stops paying.
//
// A frame's conservative bound (gi/change_bound.h) compares two sets of
// inputs. Summed frame by frame, the bounds bound a tile's drift (triangle
// inequality), but a change that comes and goes (an edit undone, a pit
// dropped and filled, a wave passing) adds to the sum every frame although
// the terrain keeps coming back. Comparing every frame with one anchor
// instead, the drift of a tile is at most
//   A_t + E_t,
// A_t a bound on how far its cached result is from the result at the
// anchor's inputs (0 when it was computed from them), E_t this frame's bound
// from the anchor's inputs to this frame's: a change that comes back costs
// nothing once it is gone. A tile whose drift exceeds the tolerance is
// recomputed, and its A_t becomes E_t (its new result is this frame's).
//
// The anchor moves to this frame's inputs (re-anchoring) when a tile was
// recomputed because of where its result stood from the anchor (A_t > 0)
// while its excursion E_t did not shrink: the terrain is moving away from
// the anchor there, and without a new anchor such a tile would be
// recomputed frame after frame; and when it costs nothing: every tile kept
// is where it was (E_t = 0) and a recomputed one moved (a frame that
// recomputes everything). Re-anchoring sets A_t to the tile's drift,
// A_t + E_t (0 where recomputed); re-anchoring every frame is the plain sum
// of per-frame bounds. A tile recomputed for another reason (forced: the
// geometry moved) does not move the anchor. The choice depends on the
// bounds alone, so it is deterministic; tolerance 0 recomputes every tile
// whose drift is not 0, so the results are those of full recomputes.
#include <cstdint>
#include <span>
#include <vector>

namespace terrain::gi {

struct AnchoredDrift {
    std::vector<float> fromAnchor;     // A_t per tile
    std::vector<float> lastExcursion;  // E_t of the last planned frame (0 after re-anchoring)
    std::vector<float> sinceInputs;    // the drift from the last planned frame's inputs (0: recomputed then)

    /// Every tile's result is at the anchor (just computed from its inputs).
    void reset(std::size_t tiles);
    /// Every tile's result was just computed from the last planned frame's inputs.
    void recomputedAll() {
        fromAnchor = lastExcursion;
        sinceInputs.assign(sinceInputs.size(), 0.0f);
    }
    bool fits(std::size_t tiles) const {
        return fromAnchor.size() == tiles && lastExcursion.size() == tiles && sinceInputs.size() == tiles;
    }
};

/// What the tiles of one frame say about moving the anchor (above); several
/// drifts that share an anchor (one change of the heights) vote together.
struct AnchorVotes {
    bool movingAway = false;       // a tile not at the anchor recomputed, its excursion not shrinking
    bool keptMoved = false;        // a kept tile moved from the anchor (E_t > 0)
    bool recomputedMoved = false;  // a recomputed tile did
    bool reanchor() const { return movingAway || (recomputedMoved && !keptMoved); }
};

/// Marks dirty[t] (1: recompute) where forced[t] (empty: none) or where the
/// drift (A_t + excursion[t]) x scale exceeds `tolerance`, and adds the
/// tiles' votes.
void markAnchoredDrift(std::span<const float> excursion, std::span<const std::uint8_t> forced, float scale,
                       float tolerance, const AnchoredDrift& drift, std::span<std::uint8_t> dirty, AnchorVotes& votes);

/// After the marks: a recomputed tile's result is this frame's (A_t = E_t,
/// or 0 when the anchor moves here); a kept tile's drift from a new anchor
/// is A_t + E_t.
void advanceAnchoredDrift(std::span<const float> excursion, std::span<const std::uint8_t> dirty, bool reanchor,
                          AnchoredDrift& drift);

/// Both for a drift with an anchor of its own (scale 1). Returns whether the
/// anchor moves to this frame's inputs: the caller then records them.
bool planAnchoredDrift(std::span<const float> excursion, std::span<const std::uint8_t> forced, float tolerance,
                       AnchoredDrift& drift, std::span<std::uint8_t> dirty);

/// A frame on the same inputs as the last planned one (only the lights'
/// brightness changed): marks the tiles whose drift from those inputs times
/// `scale` exceeds `tolerance`; their results are about to be recomputed
/// from them (A_t = the last excursion). True when any is.
bool markDriftAgain(float scale, float tolerance, AnchoredDrift& drift, std::span<std::uint8_t> dirty);

}  // namespace terrain::gi
