// Closed form of the elastic catenary (Irvine, "Cable Structures", MIT Press 1981, ch. 2),
// solved for the end forces by Newton's method. Used as the reference of the static tests.
//
// A cable of unstretched length L, weight w per unstretched length and axial stiffness EA
// hangs between A = (0, 0) and B = (span, rise) in a vertical plane. With H the (constant)
// horizontal and V0 the vertical component at A of n(s), the force that the part beyond the
// material point s exerts on the part before (so n_z(s) = V0 + w s), the position of s is
//   x(s) = H s / EA + (H / w) [asinh((V0 + w s)/H) - asinh(V0/H)]
//   z(s) = (V0 s + w s^2/2) / EA + (1 / w) [sqrt(H^2 + (V0 + w s)^2) - sqrt(H^2 + V0^2)]
// The support at A is pulled by n(0), the support at B by -n(L).
#ifndef MJTETHER_TESTS_CATENARY_REFERENCE_H_
#define MJTETHER_TESTS_CATENARY_REFERENCE_H_

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace mjtether::testing {

struct Catenary {
  double H = 0;   // [N] horizontal force component
  double V0 = 0;  // [N] vertical component of n(0) (negative when the cable leaves A downward)
  double w = 0;   // [N/m]
  double L = 0;   // [m]
  double tension_a() const { return std::hypot(H, V0); }
  double tension_b() const { return std::hypot(H, V0 + w * L); }
};

inline void CatenaryEnd(double H, double V0, double w, double L, double EA, double* x,
                        double* z) {
  const double V1 = V0 + w * L;
  *x = H * L / EA + H / w * (std::asinh(V1 / H) - std::asinh(V0 / H));
  *z = (V0 * L + w * L * L / 2) / EA + (std::hypot(H, V1) - std::hypot(H, V0)) / w;
}

// Solves for H and V0 so that end B lands at (span, rise) within 1e-13 L. Requires a sagging
// cable. Throws std::runtime_error if Newton's method does not converge.
inline Catenary SolveCatenary(double span, double rise, double L, double w, double EA) {
  double H = w * L / 4, V0 = -w * L / 2 + 0.5 * w * rise;
  bool converged = false;
  double miss = INFINITY;  // [m] distance of the solution's end B from B
  for (int it = 0; it < 100; ++it) {
    double x, z;
    CatenaryEnd(H, V0, w, L, EA, &x, &z);
    const double rx = x - span, rz = z - rise;
    miss = std::hypot(rx, rz);
    if (miss < 1e-13 * L) {
      converged = true;
      break;
    }
    const double dH = 1e-7 * H, dV = 1e-7 * (std::abs(V0) + w * L);
    double xh, zh, xv, zv;
    CatenaryEnd(H + dH, V0, w, L, EA, &xh, &zh);
    CatenaryEnd(H, V0 + dV, w, L, EA, &xv, &zv);
    const double a = (xh - x) / dH, b = (xv - x) / dV, c = (zh - z) / dH, d = (zv - z) / dV;
    const double det = a * d - b * c;
    double stepH = (d * rx - b * rz) / det, stepV = (-c * rx + a * rz) / det;
    // Keep H positive: halve the step when it would cross zero.
    while (H - stepH <= 0) {
      stepH /= 2;
      stepV /= 2;
    }
    H -= stepH;
    V0 -= stepV;
  }
  // A reference that did not converge is no reference: the test that asked for it fails
  // (GoogleTest reports the exception and its message).
  if (!converged || !std::isfinite(H) || !std::isfinite(V0)) {
    std::ostringstream s;
    s << "SolveCatenary(span " << span << ", rise " << rise << ", L " << L << ", w " << w
      << ", EA " << EA << "): Newton did not converge in 100 iterations (end B missed by "
      << miss << " m)";
    throw std::runtime_error(s.str());
  }
  return {H, V0, w, L};
}

}  // namespace mjtether::testing

#endif  // MJTETHER_TESTS_CATENARY_REFERENCE_H_
