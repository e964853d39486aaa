#pragma once
// Order-4 real spherical harmonics (16 coefficients, bands l = 0..3).
//
// Conventions (used by every gi/ file):
//   index i = l*l + l + m, m in [-l, l];
//   direction d = (x, y, z), z up; theta from +z, phi from +x towards +y;
//   Y_lm = sqrt(2) K_lm cos(m phi) P_l^m(z)      (m > 0)
//        = K_l0 P_l(z)                            (m = 0)
//        = sqrt(2) K_l|m| sin(|m| phi) P_l^|m|(z)  (m < 0)
//   without the Condon-Shortley phase (Y_11 = +0.4886 x).
// Every Y_i separates as Y_i(theta, phi) = shAssociated_i(z) * shAzimuthal_i(phi),
// which the wedge operators (gi/wedge.h) rely on.
#include <array>

namespace terrain::gi {

inline constexpr int kShOrder = 4;
inline constexpr int kShCount = 16;
inline constexpr double kPi = 3.14159265358979323846;
/// Y_0^0 = 1 / (2 sqrt(pi)): a constant radiance L has band-0 coefficient L / Y_0^0.
inline constexpr double kShY00 = 0.28209479177387814;

using ShVector = std::array<double, kShCount>;
/// Row-major 16 x 16 matrix.
using ShMatrix = std::array<double, kShCount * kShCount>;

constexpr int shIndex(int l, int m) { return l * l + l + m; }
constexpr int shBand(int i) { return i < 1 ? 0 : (i < 4 ? 1 : (i < 9 ? 2 : 3)); }
constexpr int shOrderM(int i) { return i - shBand(i) * shBand(i) - shBand(i); }

/// Y_i(d) for a unit direction d (cartesian polynomial form).
void shEvaluate(double x, double y, double z, double out[kShCount]);
void shEvaluate(float x, float y, float z, float out[kShCount]);

/// The z part of Y_i: Y_i(theta, phi) = shAssociated(i, cos theta) * shAzimuthal(i, phi).
double shAssociated(int i, double z);
/// The phi part of Y_i: cos(m phi) (m > 0), 1 (m = 0), sin(|m| phi) (m < 0).
double shAzimuthal(int i, double phi);

/// Matrix R with (R c) the coefficients of f(theta, phi - angle), i.e. f
/// turned by +angle about z (Eq. 21's Rot_z).
ShMatrix shRotationZ(double angle);
/// In place: c <- R(angle) c, using the band structure (pairs +-m).
void shRotateZ(double angle, ShVector& c);

/// Zonal harmonic coefficients zh[l] (l = 0..3, of a function symmetric about
/// +z) turned so their axis is the unit vector `axis`:
/// out_lm = sqrt(4 pi / (2l+1)) zh_l Y_lm(axis)  [Sloan et al. 2005].
void shRotateZonal(const double zh[kShOrder], double ax, double ay, double az, double out[kShCount]);

/// Zonal (ZH) vector of the clamped cosine max(cos theta, 0) (Section 7):
/// {0.886227, 1.02333, 0.495416, 0}. Dotted (after rotation to N) with an
/// incident radiance vector it gives irradiance.
const double* lambertZonal();
/// ZH vector whose rotation to the reflection vector R gives
/// e^{-l^2 / (2 S)} Y_lm(R) (Section 7, [RH02]): dotted with incident
/// radiance it gives the normalised Phong lobe's reflected radiance.
void phongZonal(double exponent, double zh[kShOrder]);

/// C_ijk = integral over the sphere of Y_i Y_j Y_k (exact by quadrature,
/// computed once). Index (i * 16 + j) * 16 + k.
const double* shTripleProductTensor();
/// The 16 x 16 matrix of "multiply by L" in SH: (T v)_i = sum_jk C_ijk L_j v_k.
/// Built once per frame per light (Section 7, direct light = SH product L * V).
ShMatrix shProductMatrix(const ShVector& light);

/// Gauss-Legendre nodes/weights on [-1, 1] (n <= 128), double precision.
void gaussLegendre(int n, double* nodes, double* weights);

/// The order-4 real SH basis (the conventions above) at a unit direction in
/// float arithmetic, for T = float or a float vector (one direction per lane);
/// only the first `count` (9 or 16) values are written.
template <class T>
inline void shBasisLanes(T x, T y, T z, T* o, int count = kShCount) {
    o[0] = T{} + 0.28209479177387814f;
    o[1] = 0.48860251190291992f * y;
    o[2] = 0.48860251190291992f * z;
    o[3] = 0.48860251190291992f * x;
    o[4] = 1.0925484305920792f * x * y;
    o[5] = 1.0925484305920792f * y * z;
    o[6] = 0.31539156525252005f * (3.0f * z * z - 1.0f);
    o[7] = 1.0925484305920792f * x * z;
    o[8] = 0.54627421529603959f * (x * x - y * y);
    if (count <= 9) return;
    o[9] = 0.59004358992664352f * y * (3.0f * x * x - y * y);
    o[10] = 2.8906114426405538f * x * y * z;
    o[11] = 0.45704579946446572f * y * (5.0f * z * z - 1.0f);
    o[12] = 0.37317633259011546f * (5.0f * z * z * z - 3.0f * z);
    o[13] = 0.45704579946446572f * x * (5.0f * z * z - 1.0f);
    o[14] = 1.4453057213202769f * z * (x * x - y * y);
    o[15] = 0.59004358992664352f * x * (x * x - 3.0f * y * y);
}

}  // namespace terrain::gi
