#pragma once
// Azimuthal wedge operators (Section 6, Eqs. 18-21, Appendix A).
//
// Within the wedge between azimuth samples j and j+1 (re-oriented to start at
// phi = 0) the spherical function is the azimuthal interpolation of the NLP
// elevation functions of the neighbouring samples (Eq. 23):
//   W(theta, phi) = sum_k beta_k(phi / dphi) w_{j+k-offset} . NLP(cos theta).
// Its SH projection (Eq. 22) is linear in the NLP vectors: a 16 x 4K matrix
// (K = 2 taps for linear: 16 x 8; K = 4 for the cubic B-spline: 16 x 32).
// Because Y_i = shAssociated_i(z) * shAzimuthal_i(phi) separates, each entry
// is a product of a z integral and a phi integral, both done once here by
// Gauss-Legendre quadrature (64 nodes in theta: exact to double precision for
// these smooth integrands; 32 nodes in phi).
//
// Eq. 21 then z-rotates each wedge to its azimuth and sums. All rotations are
// fixed for a fixed azimuth set, so they are folded into the matrices: V is
// one 16 x 4m matrix times the stacked NLP vectors of the m azimuths.
// Only entries whose z integral is non-zero survive (NLP_l and the z part of
// Y_(l', m') couple only when l = l' - |m'| mod 2, and for m' = 0 only when
// l = l'): the folded operator is stored sparse, 28 of 64 entries per azimuth.
#include <cstdint>
#include <vector>

#include "gi/nlp.h"
#include "gi/sh.h"

namespace terrain::gi {

enum class AzimuthInterp { Linear, Bspline };

/// Taps per wedge: 2 (linear, samples j, j+1) or 4 (B-spline, j-1 .. j+2).
constexpr int wedgeTaps(AzimuthInterp i) { return i == AzimuthInterp::Linear ? 2 : 4; }

/// Weight of tap k at fraction a in [0, 1] of the wedge (Eq. 24 / cubic B-spline).
double wedgeTapWeight(AzimuthInterp interp, int k, double a);

/// M_lin (16 x 8) or M_bspl (16 x 32), row-major, column = tap * 4 + l,
/// for a wedge of angular extent deltaPhi (Appendix A).
std::vector<double> wedgeOperator(AzimuthInterp interp, double deltaPhi);

/// The wedge operator with the azimuth rotations folded in (Eq. 21):
/// V = sum_j G_j w_j, with G_j a 16 x 4 block per azimuth sample j.
struct FoldedWedgeOperator {
    int azimuths = 0;
    std::vector<double> phi;    // azimuth of each sample (radians, from +x towards +y)
    std::vector<double> dense;  // 16 x (4 * azimuths), row-major, column = j * 4 + l
    // Sparse form used by the kernels: the same (row, nlp) pattern for every j.
    std::vector<std::uint8_t> patternRow;  // SH row of each entry
    std::vector<std::uint8_t> patternNlp;  // NLP index of each entry
    std::vector<float> values;             // azimuths x pattern size
    int shRows = kShCount;                 // SH rows of V it gives: all, 1 (firstRowOnly) or 0 (horizonsOnly)
    int patternSize() const { return static_cast<int>(patternRow.size()); }
};

/// Complete azimuthal domain: m samples at phi_j = 2 pi j / m, m wedges
/// (the last one wraps around), linear or B-spline interpolation.
FoldedWedgeOperator foldFullCircle(int azimuths, AzimuthInterp interp);

/// Partial domain [phiStart, phiEnd] (key lights, Section 6): m samples
/// evenly spaced including both ends, m - 1 wedges, linear interpolation.
FoldedWedgeOperator foldPartialRange(double phiStart, double phiEnd, int azimuths);

/// The operator restricted to V's first SH row, V_00 (sqrt(4 pi) times the
/// visible fraction of the domain): all that an exact-cosine key light reads,
/// at a sixteenth of the output.
FoldedWedgeOperator firstRowOnly(FoldedWedgeOperator op);

/// The operator with no SH row: the scan gives its horizons (the maximum
/// blocking slope per azimuth) and no V, for a frame whose every reader of
/// the environment's visibility takes the horizons (the exact ambient and
/// sky, gi/ambient_horizon.h): the NLP vectors and V = sum_j G_j w_j
/// (Eq. 21) are then work nothing reads.
FoldedWedgeOperator horizonsOnly(FoldedWedgeOperator op);

/// Reference application of the dense operator: V = G [w_0; ...; w_{m-1}].
void applyFoldedDense(const FoldedWedgeOperator& op, const double* nlp, double out[kShCount]);

}  // namespace terrain::gi
