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
//
// A second path, where the caller takes it: the drift S_t from the last
// planned frame's inputs (sinceInputs) plus this frame's bound L_t from
// those inputs to its own. A change that stays (a pit dropped and left)
// counts twice from the anchor in the tiles it recomputed (A_t = E_t, and
// E_t again), so without it each new change elsewhere would move the
// anchor, and every move adds each far change's small bound to every kept
// tile (the plain sum); with it such a tile keeps its result while the
// changes since the last frame stay small near it, the drift being the
// smaller of A_t + E_t and S_t + L_t, and a tile that path could have kept
// (L_t taken) does not move the anchor. The anchor then moves when a tile
// without it (S_t past the tolerance: the changes since it was recomputed
// added up) is recomputed while moving away. A terrain that moves
// everywhere (waves) then moves its anchor less often and leans on the sum
// of the per-frame bounds (README, "A change that stays").
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

/// How far tile t's result can be from this frame's: A_t + excursion[t],
/// or with `sinceLast` (empty: not known) the smaller of that and S_t +
/// sinceLast[t] (below).
float driftNow(const AnchoredDrift& drift, std::span<const float> excursion, std::span<const float> sinceLast,
               std::size_t t);

/// Marks dirty[t] (1: recompute) where forced[t] (empty: none) or where the
/// drift times `scale` exceeds `tolerance`, and adds the tiles' votes. The
/// drift is A_t + excursion[t], or with `sinceLast` (empty: not known) the smaller of
/// that and S_t + sinceLast[t]: the drift from the last planned frame's
/// inputs (sinceInputs) plus this frame's bound from those inputs to its own
/// (infinite where not taken). Both bound how far the tile's result is
/// from this frame's; the second keeps a tile recomputed since the anchor
/// for a change that stays (a pit dropped and left) while other changes
/// come, where measured from the anchor the change it was recomputed for
/// counts twice (A_t and E_t) and the anchor would move every frame.
void markAnchoredDrift(std::span<const float> excursion, std::span<const float> sinceLast,
                       std::span<const std::uint8_t> forced, float scale, float tolerance, const AnchoredDrift& drift,
                       std::span<std::uint8_t> dirty, AnchorVotes& votes);

/// After the marks: a recomputed tile's result is this frame's (A_t = E_t,
/// or 0 when the anchor moves here); a kept tile's drift from this frame's
/// inputs is the smaller of A_t + E_t and S_t + sinceLast[t] (the first
/// alone without sinceLast), and from a new anchor the same.
void advanceAnchoredDrift(std::span<const float> excursion, std::span<const float> sinceLast,
                          std::span<const std::uint8_t> dirty, bool reanchor, AnchoredDrift& drift);

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
