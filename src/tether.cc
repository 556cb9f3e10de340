#include "tether.h"

#include <algorithm>
#include <cmath>
#include <complex>

#include "block_band.h"

namespace mjtether {
namespace {

constexpr double kPi = 3.14159265358979323846;
// A segment shorter than this fraction of its rest length has no direction: it carries no
// tension, no bending shear and no tangent (coincident nodes must not produce NaN).
constexpr double kMinLengthRatio = 1e-9;
// Fraction of the explicit stability limit actually used (the estimate ignores drag and the
// geometric stiffness T/l, both small against EA/L0 in practice).
constexpr double kExplicitSafety = 0.8;
// An implicit step whose linearisation missed more tension than this fraction of the largest
// (from segments turning within the step) iterates again (see ImplicitStep).
constexpr double kLinearisationTolerance = 0.01;
// Where the implicit step's law changed within it, its Newton iteration goes on until every
// node's velocity error |G_i|/m_i is below this fraction of the step's largest velocity change
// (see ImplicitStep), with at most kMaxNewton linear solves, and a line search that may shorten
// a Newton step down to kMinLineSearchStep.
constexpr double kNewtonTolerance = 1e-2;
constexpr int kMaxNewton = 12;
constexpr double kMinLineSearchStep = 1.0 / 64;
// Kinetic energy above this multiple of EnergyBound() is a blow-up (the bound is already
// generous; the factor keeps a violent but physical transient, e.g. a whipping free end,
// clear of it).
constexpr double kEnergyBlowUp = 10;

// Largest stable step of classical RK4 [s] for the modes of a chain whose highest frequency is
// w [rad/s] with damping ratio zeta. Internal damping is stiffness-proportional, so a mode of
// frequency s w has ratio s zeta and eigenvalues s w (-s zeta +- i sqrt(1 - s^2 zeta^2)) (real
// when overdamped). Each must lie in the region |R(z)| <= 1, R(z) = 1 + z + z^2/2 + z^3/6 +
// z^4/24 (radius 2.83 along the imaginary axis, 2.79 along the negative real one); the step is
// the smallest over the modes of the radius along the mode's ray divided by |lambda|.
double Rk4StableStep(double w, double zeta) {
  auto stable = [](std::complex<double> z) {
    return std::abs(1.0 + z * (1.0 + z * (0.5 + z * (1.0 / 6 + z / 24.0)))) <= 1 + 1e-12;
  };
  // Radius of the stability region along the unit direction u (left half plane): the region
  // is an interval [0, r] along each such ray, found by a coarse scan and bisection.
  auto radius = [&](std::complex<double> u) {
    double lo = 0, hi = 0;
    while (hi < 4 && stable(hi * u)) lo = hi, hi += 0.05;
    for (int k = 0; k < 40; ++k) {
      const double mid = 0.5 * (lo + hi);
      (stable(mid * u) ? lo : hi) = mid;
    }
    return lo;
  };
  double h = INFINITY;
  for (int k = 20; k >= 1; --k) {
    const double s = k / 20.0, z = s * zeta, ws = s * w;
    std::complex<double> lambda;
    if (z < 1) {
      lambda = ws * std::complex<double>(-z, std::sqrt(1 - z * z));
    } else {
      lambda = -ws * (z + std::sqrt(z * z - 1));  // the faster of the two real roots
    }
    h = std::min(h, radius(lambda / std::abs(lambda)) / std::abs(lambda));
  }
  return h;
}

// Scratch memory of one evaluation, carved from the caller's workspace.
struct Work {
  double* f;     // 3 x n   node forces
  double* t;     // 3 x N   unit segment tangents
  double* l;     // N       segment lengths
  double* T;     // N       segment tensions
  double* M;     // 3 x n   nodal bending moments
  double* q;     // 3 x n   unit node tangents
  double* x2;    // 3 x n   state copy for Reactions
  double* v2;    // 3 x n
  double* rhs;   // 3 x n   implicit right-hand side / velocity change
  double* band;  // 27 x n  implicit block-band matrix (3x3 blocks, block_band.h)
  double* xs;    // 3 x n   state saved before an implicit step, to retry it in halves
  double* vs;    // 3 x n
  double* x0;    // 3 x n   state at the start of a two-stage step (implicit2)
  double* v0;    // 3 x n
  double* dv;    // 3 x n   implicit Newton correction (line search)
  double* vb;    // 3 x n   implicit iterate the line search starts from
  static int Size(int N) {
    const int n = N + 1;
    return 3 * n + 3 * N + N + N + 3 * n + 3 * n + 3 * n + 3 * n + 3 * n +
           BlockBand::Size(n) + 18 * n;
  }
  Work(double* w, int N) {
    const int n = N + 1;
    f = w;
    t = f + 3 * n;
    l = t + 3 * N;
    T = l + N;
    M = T + N;
    q = M + 3 * n;
    x2 = q + 3 * n;
    v2 = x2 + 3 * n;
    rhs = v2 + 3 * n;
    band = rhs + 3 * n;
    xs = band + BlockBand::Size(n);
    vs = xs + 3 * n;
    x0 = vs + 3 * n;
    v0 = x0 + 3 * n;
    dv = v0 + 3 * n;
    vb = dv + 3 * n;
  }
};

// Cubic Hermite interpolation of an end between two instants dt apart, at fraction s.
EndState Interpolate(const EndState& e0, const EndState& e1, double dt, double s) {
  const double s2 = s * s, s3 = s2 * s;
  const double h00 = 2 * s3 - 3 * s2 + 1, h10 = s3 - 2 * s2 + s;
  const double h01 = -2 * s3 + 3 * s2, h11 = s3 - s2;
  const double d00 = 6 * s2 - 6 * s, d10 = 3 * s2 - 4 * s + 1;
  const double d01 = -6 * s2 + 6 * s, d11 = 3 * s2 - 2 * s;
  EndState e;
  e.pos = h00 * e0.pos + h10 * dt * e0.vel + h01 * e1.pos + h11 * dt * e1.vel;
  e.vel = dt > 0 ? ((d00 * e0.pos + d01 * e1.pos) / dt + d10 * e0.vel + d11 * e1.vel)
                 : e1.vel;
  Vec3 axis = (1 - s) * e0.axis + s * e1.axis;
  e.axis = axis.norm() > 0 ? Vec3(axis.normalized()) : e1.axis;
  return e;
}

Ends Interpolate(const Ends& from, const Ends& to, double dt, double s) {
  return {Interpolate(from.a, to.a, dt, s), Interpolate(from.b, to.b, dt, s),
          from.time + s * (to.time - from.time), to.contacts};
}

}  // namespace

std::optional<Tether> Tether::Create(const TetherParams& params, const Environment& env,
                                     std::string* error) {
  auto fail = [&](const std::string& message) -> std::optional<Tether> {
    if (error) *error = message;
    return std::nullopt;
  };
  if (!(params.segments >= 1)) return fail("segments must be >= 1");
  if (!(params.length > 0) || !(params.EA > 0) || !(params.mass_per_length > 0) ||
      !(params.diameter > 0)) {
    return fail("length, EA, mass_per_length and diameter must be > 0");
  }
  if ((params.effects & kCompression) && !(params.EAc > 0)) {
    return fail("the compression effect needs EAc > 0");
  }
  Tether tether;
  Tether& c = tether;
  c.p_ = params;
  c.env_ = env;
  // Water::seabed_friction_axial < 0 means "same as across" (params.h). Resolve it here, not
  // only in the parser: a negative coefficient would push the line along its slip.
  if (c.env_.water.seabed_friction_axial < 0) {
    c.env_.water.seabed_friction_axial = c.env_.water.seabed_friction;
  }
  c.N_ = params.segments;
  c.L0_ = params.length / c.N_;
  c.area_ = kPi * params.diameter * params.diameter / 4;
  const int n = c.N_ + 1;
  const double rho = env.wet ? env.water.density : 0;

  // Lumped masses: half of each adjacent segment.
  c.share_ = Eigen::VectorXd::Constant(n, c.L0_);
  c.share_(0) = c.share_(c.N_) = c.L0_ / 2;
  c.mass_ = params.mass_per_length * c.share_;
  c.added_ = c.Has(kAddedMass) ? Eigen::VectorXd(params.Can * rho * c.area_ * c.share_)
                               : Eigen::VectorXd::Zero(n);
  c.inv_mass_ = c.mass_.cwiseInverse();
  c.damping_per_L0_ = params.damping / c.L0_;
  c.inv_mass_normal_ = (c.mass_ + c.added_).cwiseInverse();
  // Net weight: dry weight minus buoyancy of the displaced volume.
  c.weight_ = Eigen::Matrix3Xd::Zero(3, n);
  for (int i = 0; i < n; ++i) {
    double m = 0;
    if (c.Has(kWeight)) m += c.mass_(i);
    if (c.Has(kBuoyancy)) m -= rho * c.area_ * c.share_(i);
    c.weight_.col(i) = m * env.gravity;
  }
  // Morison drag per unit length: 1/2 rho Cdn d |vn| vn and 1/2 rho Cdt pi d |vt| vt.
  c.kn_ = 0.5 * rho * params.Cdn * params.diameter;
  c.kt_ = 0.5 * rho * params.Cdt * kPi * params.diameter;
  // Seabed per unit length; default damping critical for the line's own mass.
  if (c.Has(kSeabed)) {
    c.seabed_k_ = env.water.seabed_stiffness;
    c.seabed_c_ = env.water.seabed_damping >= 0
                      ? env.water.seabed_damping
                      : 2 * std::sqrt(c.seabed_k_ * params.mass_per_length);
  }
  // Contact per unit length, the same way (a segment's contact point carries its length L0).
  if (c.Has(kContact)) {
    c.contact_k_ = params.contact_stiffness;
    c.contact_c_ = params.contact_damping >= 0
                       ? params.contact_damping
                       : 2 * std::sqrt(c.contact_k_ * params.mass_per_length);
  }

  // Explicit stability limit. Highest frequencies of the discrete operators on the lightest
  // dynamic node: axial chain 4 (EA/L0)/m (EA the larger of EA and EAc when compressed
  // segments push back), fourth difference 16 EI/(L0^3 m) (doubled when an
  // end is clamped, whose curvature weight is L0/2), seabed k l / m. Damping (internal,
  // seabed, friction) shortens the limit of symplectic Euler to 2/w (sqrt(1+z^2) - z).
  double m_min = INFINITY, mn_min = INFINITY;
  for (int i = 0; i < n; ++i) {
    if (!c.Dynamic(i)) continue;
    m_min = std::min(m_min, c.mass_(i));
    mn_min = std::min(mn_min, c.mass_(i) + c.added_(i));
  }
  if (!std::isfinite(m_min)) {
    c.explicit_dt_ = INFINITY;  // no dynamic node (one segment between two sites)
  } else {
    const double ea = c.Has(kCompression) ? std::max(params.EA, params.EAc) : params.EA;
    double w2 = 4 * (ea / c.L0_) / m_min;
    if (c.Has(kBending)) {
      w2 += (c.Has(kClamp) ? 32 : 16) * params.EI / (c.L0_ * c.L0_ * c.L0_ * mn_min);
    }
    if (c.Has(kSeabed)) w2 += c.seabed_k_ * c.L0_ / m_min;
    // A contact point at a node puts its whole stiffness k L0 on that node.
    if (c.Has(kContact)) w2 += c.contact_k_ * c.L0_ / m_min;
    double rate = 0;  // [1/s] damping / mass
    if (c.Has(kDamping)) rate += 4 * (params.damping / c.L0_) / m_min;
    if (c.Has(kSeabed)) {
      rate += c.seabed_c_ * c.L0_ / m_min;
      const double mu = std::max(env.water.seabed_friction, env.water.seabed_friction_axial);
      const double wet = c.weight_.col(1 % n).norm() / std::max(c.share_(1 % n), 1e-300);
      rate += mu * wet * c.L0_ / (env.water.seabed_friction_speed * m_min);
    }
    if (c.Has(kContact)) rate += c.contact_c_ * c.L0_ / m_min;
    const double w = std::sqrt(w2);
    const double zeta = rate / (2 * w);
    c.explicit_dt_ = kExplicitSafety * (params.integrator == Integrator::kRK4
                                            ? Rk4StableStep(w, zeta)
                                            : 2 / w * (std::sqrt(1 + zeta * zeta) - zeta));
  }
  // The 3-node window for the end reactions: rest length L0 per segment, so its end nodes
  // carry the same lumped length, mass, weight and curvature weights as the tether's.
  if (c.N_ >= 3) {
    TetherParams wp = params;
    wp.segments = 2;
    wp.length = 2 * c.L0_;
    std::optional<Tether> window = Create(wp, env, error);
    if (!window) return std::nullopt;
    c.window_ = std::make_shared<const Tether>(std::move(*window));
  }
  return tether;
}

// The window's inputs (x, v 3 x 3 each), outputs (f 3 x 3, T 2) and its own scratch follow
// the tether's scratch.
constexpr int kWindowIo = 9 + 9 + 9 + 2;

int Tether::WorkspaceSize() const {
  return Work::Size(N_) + (window_ ? kWindowIo + window_->WorkspaceSize() : 0);
}

int Tether::SubstepsFor(double dt) const {
  if (!(dt > 0)) return 0;
  if (p_.substeps > 0) return p_.substeps;
  if (!IsExplicit(p_.integrator) && !(p_.max_step > 0)) return 1;
  // At most 1e9, so that the count fits an int whatever the step (a max_step of 1e-54 is
  // in its range; the plugin refuses counts above 1e5 at load time).
  const double n = std::ceil(dt / (p_.max_step > 0 ? p_.max_step : explicit_dt_) - 1e-9);
  return static_cast<int>(std::min(std::max(n, 1.0), 1e9));
}

// ---------------------------------------------------------------------------------------------
// Initial shape

void Tether::InitialShape(const Ends& ends, double* xp, double* vp) const {
  Nodes x(xp, 3, N_ + 1), v(vp, 3, N_ + 1);
  v.setZero();
  const Vec3 A = ends.a.pos;
  const double L = p_.length;
  // "Down" is the way the net weight pulls; without weight, gravity's way; without gravity, -z.
  Vec3 down = weight_.col(0).norm() > 0 ? Vec3(weight_.col(0).normalized())
              : env_.gravity.norm() > 0 ? Vec3(env_.gravity.normalized())
                                        : Vec3(0, 0, -1);
  if (p_.free_end) {
    Vec3 dir = env_.gravity.norm() > 0 ? down : ends.a.axis.normalized();
    for (int k = 0; k <= N_; ++k) x.col(k) = A + dir * (L * k / N_);
    if (Has(kSeabed)) RestOnSeabed(ends, x);
    v.col(0) = ends.a.vel;
    return;
  }
  const Vec3 B = ends.b.pos;
  const Vec3 chord = B - A;
  if (chord.norm() >= L) {
    // Taut: evenly spaced on the chord (stretched).
    for (int k = 0; k <= N_; ++k) x.col(k) = A + chord * (double(k) / N_);
  } else {
    // Inextensible catenary y = a cosh((s - s0)/a) in the plane of `up` and the horizontal
    // direction of the chord, through both ends, arc length L:
    //   sqrt(L^2 - v^2) = 2 a sinh(h / 2a)   (h, v: horizontal and vertical span).
    const Vec3 up = -down;
    double vspan = chord.dot(up);
    Vec3 horiz = chord - vspan * up;
    double h = horiz.norm();
    if (h < 1e-6 * L) {
      // Ends on one vertical: hang a narrow U in any horizontal direction.
      Vec3 any = std::abs(up.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
      horiz = (any - any.dot(up) * up).normalized() * (1e-6 * L);
      h = horiz.norm();
    }
    const Vec3 eh = horiz / h;
    // The catenary of arc length Ls through both ends: its parameter a, the abscissa x0 of its
    // lowest point and the arc coordinate sA of end A (arc coordinates from the lowest point).
    struct Curve {
      double a, x0, sA;
    };
    auto solve = [&](double Ls) {
      // Solve sinh(xi)/xi = r for xi = h/(2a) by bisection (monotone in xi).
      const double r = std::sqrt(Ls * Ls - vspan * vspan) / h;
      double lo = 0, hi = 1;
      while (std::sinh(hi) / hi < r && hi < 700) hi *= 2;
      for (int it = 0; it < 200; ++it) {
        double mid = 0.5 * (lo + hi);
        (std::sinh(mid) / mid < r ? lo : hi) = mid;
      }
      const double xi = 0.5 * (lo + hi);
      Curve c;
      c.a = h / (2 * xi);
      c.x0 = h / 2 - c.a * std::atanh(vspan / Ls);  // abscissa of the lowest point
      c.sA = c.a * std::sinh(-c.x0 / c.a);            // arc coordinate of end A
      return c;
    };
    auto point = [&](const Curve& c, double s) -> Vec3 {
      const double xc = c.x0 + c.a * std::asinh(s / c.a);
      const double yc = c.a * (std::cosh((xc - c.x0) / c.a) - std::cosh(c.x0 / c.a));
      return A + xc * eh + yc * up;
    };
    const Curve c = solve(L);
    for (int k = 0; k <= N_; ++k) x.col(k) = point(c, c.sA + L * k / N_);
    // With compression, nodes at arc spacing L0 would start compressed (a chord is shorter than
    // its arc by ~L0^3 kappa^2 / 24) and spring apart at the first step. Instead walk chords of
    // exactly L0 along a catenary a little longer than L, its length found by the secant method
    // so that the N-th chord ends on B. Kept as above if the walk fails (a hairpin U).
    if (Has(kCompression)) {
      // Arc coordinate reached beyond end B after N chords of L0 on the catenary of length Ls.
      auto walk = [&](double Ls, bool store) -> double {
        const Curve cs = solve(Ls);
        double sk = cs.sA;
        Vec3 P = A;
        for (int k = 1; k <= N_; ++k) {
          // Newton on |P(s) - P|^2 = L0^2, from one arc length L0 on (the chord is shorter).
          double s = sk + L0_;
          for (int it = 0; it < 50; ++it) {
            const Vec3 d = point(cs, s) - P;
            const double q = s / cs.a;
            const Vec3 tangent = (eh + q * up) / std::sqrt(1 + q * q);  // dP/ds
            const double slope = 2 * d.dot(tangent);
            if (!(slope > 0)) return NAN;
            const double ds = (d.squaredNorm() - L0_ * L0_) / slope;
            s -= ds;
            if (std::abs(ds) <= 1e-14 * (std::abs(s) + L0_)) break;
          }
          sk = s;
          P = point(cs, sk);
          if (store) x.col(k) = P;
        }
        return sk - (cs.sA + Ls);
      };
      double L1 = L, f1 = walk(L1, false);
      double L2 = L + f1, f2 = walk(L2, false);
      for (int it = 0; it < 50 && std::isfinite(f2) && std::abs(f2) > 1e-13 * L && f2 != f1;
           ++it) {
        const double L3 = L2 - f2 * (L2 - L1) / (f2 - f1);
        L1 = L2;
        f1 = f2;
        L2 = L3;
        f2 = walk(L2, false);
      }
      if (std::isfinite(f2) && std::abs(f2) <= 1e-9 * L) walk(L2, true);
    }
    x.col(N_) = B;  // remove round-off at the far end
  }
  if (Has(kSeabed)) RestOnSeabed(ends, x);
  v.col(0) = ends.a.vel;
  v.col(N_) = ends.b.vel;
}

// A shape that dips below the seabed is replaced by one that lies on it: the line hangs from
// each end as a catenary whose lowest point touches the seabed with a horizontal tangent, and
// the length in between lies flat on the seabed along the ends' horizontal direction (the
// grounded part carries the horizontal tension a w unchanged, without friction). For an end at height h above the seabed, a
// catenary of parameter a (horizontal tension / weight per length) reaches the seabed after
// arc length s = sqrt(h^2 + 2 a h) and horizontal distance x = a acosh(1 + h/a) (Irvine,
// "Cable Structures", 1981, ch. 1); one a for both ends (the horizontal tension is continuous
// through a frictionless grounded part) solves
//   s_A(a) + s_B(a) + (H - x_A(a) - x_B(a)) = L,
// whose left side falls monotonically from h_A + h_B + H (a -> 0) to H (a -> inf), by bisection
// on log a. When even vertical drops leave length over (L > h_A + h_B + H), the ends hang
// straight down and the rest lies on the seabed in a sideways U of the extra length. This
// needs the net weight along -z (a horizontal seabed under ordinary gravity); otherwise (or
// for an end below the seabed, which the MuJoCo glue refuses at load) the nodes are only
// lifted onto the seabed. A free end hangs down to the seabed and lies along its site's axis.
void Tether::RestOnSeabed(const Ends& ends, Nodes x) const {
  const double zb = env_.water.seabed;
  const double L = p_.length;
  bool below = false;
  for (int k = 0; k <= N_ && !below; ++k) below = x(2, k) < zb;
  if (!below) return;
  const Vec3 g = weight_.col(0).norm() > 0 ? Vec3(weight_.col(0)) : env_.gravity;
  const bool vertical = g.norm() > 0 && -g.z() >= (1 - 1e-9) * g.norm();
  const Vec3& A = ends.a.pos;
  const Vec3 ez = Vec3::UnitZ();
  const double hA = A.z() - zb;
  // Horizontal direction of the grounded part: towards B, else along site A's axis, else x.
  auto horizontal = [](const Vec3& d) {
    const Vec3 hd(d.x(), d.y(), 0);
    return hd.norm() > 1e-9 * std::max(1.0, d.norm()) ? Vec3(hd.normalized()) : Vec3::UnitX();
  };
  if (!vertical || hA < 0 || (!p_.free_end && ends.b.pos.z() < zb)) {
    for (int k = 0; k <= N_; ++k) x(2, k) = std::max(x(2, k), zb);
    return;
  }
  const Vec3 A0(A.x(), A.y(), zb);  // end A projected on the seabed
  if (p_.free_end) {
    const Vec3 eh = horizontal(ends.a.axis);
    for (int k = 0; k <= N_; ++k) {
      const double s = L * k / N_;
      x.col(k) = s <= hA ? Vec3(A - s * ez) : Vec3(A0 + (s - hA) * eh);
    }
    return;
  }
  const Vec3& B = ends.b.pos;
  const double hB = B.z() - zb;
  const Vec3 B0(B.x(), B.y(), zb);
  const double H = (B0 - A0).norm();
  const Vec3 eh = H > 1e-9 * L ? Vec3((B0 - A0) / H) : horizontal(ends.a.axis);
  const Vec3 en(-eh.y(), eh.x(), 0);  // horizontal normal: the side of the U
  // Arc length s and horizontal reach x of one hanging part (h >= 0, a >= 0).
  auto hang = [](double a, double h, double* s, double* xh) {
    *s = std::sqrt(h * h + 2 * a * h);
    *xh = a > 0 ? a * std::acosh(1 + h / a) : 0;
  };
  double a = 0, sA = hA, sB = hB, xA = 0, xB = 0, detour = 0;
  if (L >= hA + hB + H) {
    detour = 0.5 * (L - hA - hB - H);
  } else {
    double lo = std::log(1e-12 * L), hi = std::log(1e12 * L);
    for (int it = 0; it < 200; ++it) {
      const double mid = 0.5 * (lo + hi);
      hang(std::exp(mid), hA, &sA, &xA);
      hang(std::exp(mid), hB, &sB, &xB);
      (sA + sB + H - xA - xB > L ? lo : hi) = mid;
    }
    a = std::exp(0.5 * (lo + hi));
    hang(a, hA, &sA, &xA);
    hang(a, hB, &sB, &xB);
  }
  const double run = std::max(0.0, H - xA - xB);  // grounded length along eh
  const Vec3 TA = A0 + xA * eh, TB = B0 - xB * eh;  // touchdown points
  // A point of a hanging part at arc length sigma from its touchdown point T, going along dir.
  auto hanging = [&](const Vec3& T, const Vec3& dir, double sigma) -> Vec3 {
    const double u = a > 0 ? a * std::asinh(sigma / a) : 0;
    return T + u * dir + (std::sqrt(a * a + sigma * sigma) - a) * ez;
  };
  for (int k = 1; k < N_; ++k) {
    const double s = L * k / N_;
    if (s <= sA) {
      x.col(k) = hanging(TA, -eh, sA - s);
    } else if (s >= L - sB) {
      x.col(k) = hanging(TB, eh, s - (L - sB));
    } else {
      const double r = s - sA;  // along the grounded part: out by `detour`, along, back
      x.col(k) = r < detour         ? Vec3(TA + r * en)
                 : r < detour + run ? Vec3(TA + detour * en + (r - detour) * eh)
                                    : Vec3(TA + (2 * detour + run - r) * en + run * eh);
    }
    x(2, k) = std::max(x(2, k), zb);  // round-off
  }
  x.col(0) = A;
  x.col(N_) = B;
}

// ---------------------------------------------------------------------------------------------
// Force terms. Convention: n_j = T_j t_j + V_j is the force that the part of the tether beyond
// segment j exerts across it on the part before; node i receives n_i - n_{i-1}.

void Tether::SegmentGeometry(ConstNodes x, Nodes t, double* l) const {
  for (int j = 0; j < N_; ++j) {
    Vec3 dx = x.col(j + 1) - x.col(j);
    l[j] = dx.norm();
    if (l[j] > kMinLengthRatio * L0_) {
      t.col(j) = dx * (1 / l[j]);
    } else {
      t.col(j).setZero();
      l[j] = 0;
    }
  }
}

// Axial: T_j = EA eps_j + damping deps_j/dt, eps_j = l_j/L0 - 1, zero when slack (eps <= 0)
// and never negative (Buckham et al. 2003, eq. for the viscoelastic segment).
//
// With the compression effect (EAc declared) a shortened segment pushes back instead, the way
// OrcaFlex lets a line "allow compression": for eps < 0, T_j = min(0, EAc eps_j + damping
// deps_j/dt) (the mirror of the taut law: damping never makes a shortened segment pull). This
// is what keeps the segments of a bending tether at their length at zero tension, where the
// bending shear would otherwise fold them (the Galerkin curvature below, Buckham & Nahon,
// weighs with the rest length L0, so it presumes segments near it). T[j] reports the tension
// only (>= 0); a compression is reported as 0, like slack.
// The law of one segment, from its strain eps, unit tangent t and the velocity difference dv of
// its ends: EA eps + (damping/L0) t.dv, never negative, when stretched; EAc eps + the same
// damping, never positive, when shortened with the compression effect; else 0.
//
// Engagement within an implicit step (engage_h > 0, the step's length [s], for a segment that
// was on the other side of L0 at the start of the step): the damping acts on the strain rate of
// the engaged law, d(eps+)/dt (eps+ = max(eps, 0), or min(eps, 0) for compression), whose
// backward-Euler impulse over the step is damping (eps+ - 0), i.e. the rate is limited to
// eps/engage_h in magnitude. The instantaneous law would jump from 0 to damping deps/dt as l
// crosses L0, and the step's equations would then have no root (see ImplicitStep); this one
// is continuous in l and converges to the same law as the step shrinks.
inline double Tether::AxialForce(double eps, const Vec3& t, const Vec3& dv,
                                 double engage_h) const {
  const bool taut = eps > 0;
  if (!taut && !(eps < 0 && Has(kCompression))) return 0;
  double T = (taut ? p_.EA : p_.EAc) * eps;
  if (Has(kDamping)) {
    double rate = t.dot(dv);  // [m/s] L0 deps/dt
    if (engage_h > 0) {
      const double engaged = eps * L0_ / engage_h;  // [m/s] L0 eps/h
      rate = taut ? std::min(rate, engaged) : std::max(rate, engaged);
    }
    T += damping_per_L0_ * rate;
  }
  return taut ? std::max(T, 0.0) : std::min(T, 0.0);
}

void Tether::AddAxial(ConstNodes x, ConstNodes v, ConstNodes t, const double* l, double* T,
                      Nodes f, const Start* start) const {
  (void)x;
  const double inv_L0 = 1 / L0_;  // [1/m]
  const double L0sq = L0_ * L0_;
  const bool engaging = start && Has(kDamping);
  for (int j = 0; j < N_; ++j) {
    double engage_h = 0;
    Vec3 dv = v.col(j + 1) - v.col(j);
    if (engaging) {
      // On the other side of L0 at the start of the step than now?
      const double ls2 = (start->x.col(j + 1) - start->x.col(j)).squaredNorm();
      if (l[j] > L0_ ? ls2 <= L0sq : l[j] < L0_ && ls2 >= L0sq) engage_h = start->h;
      if (start->discrete) {
        // In the Newton iterations past the first: the backward difference of the engaged
        // strain over the step, (eps+ - max(eps_start, 0))/h (see ImplicitStep).
        const double ls = std::sqrt(ls2);
        const double from = l[j] > L0_ ? std::max(ls, L0_) : std::min(ls, L0_);
        dv = t.col(j) * ((l[j] - from) / start->h);
        engage_h = 0;
      }
    }
    const double Tj = AxialForce(l[j] * inv_L0 - 1, t.col(j), dv, engage_h);
    T[j] = std::max(Tj, 0.0);
    f.col(j) += Tj * t.col(j);
    f.col(j + 1) -= Tj * t.col(j);
  }
}

// Bending moment at each node, M_i = EI kappa_i, with the Galerkin (lumped weight) curvature
//   kappa_i = (t_{i-1} x t_i) / w_i,  w_i = integral of the hat function N_i = (L0_{i-1}+L0_i)/2
// (Buckham & Nahon 1999: curvature from the jump of the piecewise-constant tangent, weighted
// residual with linear shape functions). A clamped end uses its site axis as the tangent
// before node 0 (or after node N) with w = L0/2; a pinned or free end has M = 0.
//
// With bending=der the curvature is that of the discrete elastic rod (Bergou et al., "Discrete
// elastic rods", SIGGRAPH 2008), |kappa| = 2 tan(theta/2)/w, and M is the derivative of its
// energy 2 EI/w tan^2(theta/2) with respect to theta: M = 4 EI/w (ta x tb)/(1 + ta.tb)^2.
// Both equal EI theta/w to first order. (1 + ta.tb) is kept above 1e-2 (a node folded back
// by more than ~170 degrees) so that the moment stays finite.
void Tether::BendingMoments(ConstNodes t, const Ends& ends, Nodes M) const {
  const bool der = p_.bending == Bending::kDER;
  auto moment = [&](const Vec3& ta, const Vec3& tb, double w) -> Vec3 {
    if (!der) return p_.EI / w * ta.cross(tb);
    const double c = std::max(1 + ta.dot(tb), 1e-2);
    return 4 * p_.EI / (w * c * c) * ta.cross(tb);
  };
  M.setZero();
  for (int i = 1; i < N_; ++i) {
    M.col(i) = moment(t.col(i - 1), t.col(i), L0_);
  }
  if (Has(kClamp) && p_.clamp_a) {
    M.col(0) = moment(ends.a.axis, t.col(0), 0.5 * L0_);
  }
  if (Has(kClamp) && p_.clamp_b) {
    M.col(N_) = moment(t.col(N_ - 1), ends.b.axis, 0.5 * L0_);
  }
}

// Shear from the moment gradient with no rotational inertia (dM/ds + t x n = 0):
//   V_j = t_j x (M_{j+1} - M_j) / l_j,
// added as +V_j on node j and -V_j on node j+1.
void Tether::AddBending(ConstNodes t, const double* l, ConstNodes M, Nodes f) const {
  for (int j = 0; j < N_; ++j) {
    if (l[j] == 0) continue;
    Vec3 V = Vec3(t.col(j)).cross(Vec3(M.col(j + 1) - M.col(j))) / l[j];
    f.col(j) += V;
    f.col(j + 1) -= V;
  }
}

// Node tangent: the normalised sum of the adjacent segment tangents (the segment's own at an
// end). Used for drag, added mass and seabed friction.
void Tether::NodeTangents(ConstNodes x, ConstNodes t, Nodes q) const {
  (void)x;
  for (int i = 0; i <= N_; ++i) {
    Vec3 s = Vec3::Zero();
    if (i > 0) s += t.col(i - 1);
    if (i < N_) s += t.col(i);
    double norm = s.norm();
    q.col(i) = norm > 1e-12 ? Vec3(s * (1 / norm)) : Vec3(t.col(std::min(i, N_ - 1)));
  }
}

// Morison drag on the velocity relative to the current u, per unit length (length share
// l_i = (l_{i-1} + l_i)/2, stretched):
//   f_n = 1/2 rho Cdn d |vn| vn,   f_t = 1/2 rho Cdt pi d |vt| vt,   v_r = u - v_i.
void Tether::AddDrag(ConstNodes v, ConstNodes q, const double* l, Nodes f) const {
  const Vec3 u = Has(kCurrent) ? env_.water.current : Vec3::Zero();
  for (int i = 0; i <= N_; ++i) {
    const double li = 0.5 * ((i > 0 ? l[i - 1] : 0) + (i < N_ ? l[i] : 0));
    const Vec3 vr = u - v.col(i);
    const Vec3 qi = q.col(i);
    const double vq = vr.dot(qi);  // |vt| = |vq|: q is a unit vector
    const Vec3 vn = vr - vq * qi;
    f.col(i) += li * (kn_ * vn.norm() * vn + (kt_ * std::abs(vq) * vq) * qi);
  }
}

// Flat seabed at z = zb: a penalty per unit length (rest share l_i) on penetration
//   N_i = max(0, k l_i (zb - z_i) - c l_i vz_i),
// and Coulomb friction smoothed by tanh over the slip speed, separately along the tether's
// horizontal tangent (mu_axial) and across it (mu).
//
// Within an implicit step (start given), a node that was above the seabed at the start of the
// step and is in contact at its end has its damping act on d(pen+)/dt, as AxialForce does for
// a segment crossing L0: the sink rate is limited to pen/h, so that the normal force does not
// jump from 0 to c |vz| at first contact.
void Tether::AddSeabed(ConstNodes x, ConstNodes v, ConstNodes q, Nodes f,
                       const Start* start) const {
  const Water& w = env_.water;
  for (int i = 0; i <= N_; ++i) {
    const double pen = w.seabed - x(2, i);
    if (pen <= 0) continue;
    double sink = -v(2, i);  // [m/s]
    if (start && start->x(2, i) >= w.seabed) sink = std::min(sink, pen / start->h);
    const double N = std::max(0.0, share_(i) * (seabed_k_ * pen + seabed_c_ * sink));
    f(2, i) += N;
    if (w.seabed_friction == 0 && w.seabed_friction_axial == 0) continue;
    Vec3 qh(q(0, i), q(1, i), 0);
    qh = qh.norm() > 1e-12 ? Vec3(qh.normalized()) : Vec3::Zero();
    const Vec3 vh(v(0, i), v(1, i), 0);
    const Vec3 va = vh.dot(qh) * qh, vc = vh - va;
    const double eps = w.seabed_friction_speed;
    if (va.norm() > 0) f.col(i) -= w.seabed_friction_axial * N * std::tanh(va.norm() / eps) *
                                    va.normalized();
    if (vc.norm() > 0) f.col(i) -= w.seabed_friction * N * std::tanh(vc.norm() / eps) *
                                   vc.normalized();
  }
}

// Contact with another body's surface (contact.h): on the point x_s of segment j at fraction s,
// a penalty per unit length (the segment's rest length L0) on the penetration of the tether's
// surface, with damping on the normal approach speed, never pulling:
//   N = max(0, L0 (k (-g) - c vn)),  g = n.(x_s - p(t)) - d/2,  vn = n.(v_s - v_b),
// and Coulomb friction on the slip velocity vt = (v_s - v_b) - vn n, smoothed like the
// seabed's: -mu N tanh(|vt|/eps) vt/|vt|. The force acts at x_s, shared (1 - s), s by the
// segment's two nodes (the linear shape functions). dt_ref = t - time_ref.
Vec3 Tether::ContactForce(const ContactPoint& c, const double* xp, const double* vp, double dt_ref,
                          double* normal_force) const {
  ConstNodes x(xp, 3, N_ + 1), v(vp, 3, N_ + 1);
  const int j = c.segment;
  const double s = c.s;
  const Vec3 xs = (1 - s) * x.col(j) + s * x.col(j + 1);
  const Vec3 p = c.point + dt_ref * c.velocity;
  const double gap = c.normal.dot(xs - p) - 0.5 * p_.diameter;
  *normal_force = 0;
  if (!(gap < 0)) return Vec3::Zero();
  const Vec3 vrel = (1 - s) * v.col(j) + s * v.col(j + 1) - c.velocity;
  const double vn = c.normal.dot(vrel);
  const double N = std::max(0.0, L0_ * (contact_k_ * -gap - contact_c_ * vn));
  *normal_force = N;
  Vec3 F = N * c.normal;
  if (p_.contact_friction > 0 && N > 0) {
    const Vec3 vt = vrel - vn * c.normal;
    const double slip = vt.norm();
    if (slip > 0) {
      F -= (p_.contact_friction * N * std::tanh(slip / p_.contact_friction_speed) / slip) * vt;
    }
  }
  return F;
}

void Tether::AddContact(ConstNodes x, ConstNodes v, const Ends& ends, Nodes f) const {
  const ContactSet& set = *ends.contacts;
  const double dt_ref = ends.time - set.time_ref;
  for (int k = 0; k < set.count; ++k) {
    const ContactPoint& c = set.points[k];
    double N;
    const Vec3 F = ContactForce(c, x.data(), v.data(), dt_ref, &N);
    if (N == 0) continue;
    f.col(c.segment) += (1 - c.s) * F;
    f.col(c.segment + 1) += c.s * F;
  }
}

// Adds weight x the contact force of the state (x, v) at `ends` to each candidate's impulse
// (or to its `stage` scratch): each integrator calls it with the weights by which its update
// combines the forces of its stages, so that the impulses are the ones the tether received.
void Tether::AccumulateContactImpulse(const double* x, const double* v, const Ends& ends,
                                      double weight, bool to_stage) const {
  if (!Has(kContact) || !ends.contacts) return;
  const ContactSet& set = *ends.contacts;
  const double dt_ref = ends.time - set.time_ref;
  for (int k = 0; k < set.count; ++k) {
    ContactPoint& c = set.points[k];
    double N;
    const Vec3 F = ContactForce(c, x, v, dt_ref, &N);
    (to_stage ? c.stage : c.impulse) += weight * F;
  }
}

void Tether::ComputeForces(const double* xp, const double* vp, const Ends& ends, double* fp,
                           double* Tp, double* work) const {
  Forces(xp, vp, ends, fp, Tp, work, nullptr);
}

void Tether::Forces(const double* xp, const double* vp, const Ends& ends, double* fp, double* Tp,
                    double* work, const Start* start) const {
  Work w(work, N_);
  const int n = N_ + 1;
  ConstNodes x(xp, 3, n), v(vp, 3, n);
  Nodes f(fp, 3, n), t(w.t, 3, N_), M(w.M, 3, n), q(w.q, 3, n);
  ConstNodes tc(w.t, 3, N_), Mc(w.M, 3, n), qc(w.q, 3, n);
  double* T = Tp ? Tp : w.T;
  f.setZero();
  SegmentGeometry(x, t, w.l);
  std::fill(T, T + N_, 0.0);
  if (Has(kAxial)) AddAxial(x, v, tc, w.l, T, f, start);
  if (Has(kBending)) {
    BendingMoments(tc, ends, M);
    AddBending(tc, w.l, Mc, f);
  }
  if (Has(kWeight) || Has(kBuoyancy)) f += weight_;
  if (Has(kDrag) || Has(kAddedMass) || Has(kSeabed)) NodeTangents(x, tc, q);
  if (Has(kDrag)) AddDrag(v, qc, w.l, f);
  if (Has(kSeabed)) AddSeabed(x, v, qc, f, start);
  if (Has(kContact) && ends.contacts) AddContact(x, v, ends, f);
}

EndReactions Tether::Reactions(const double* xp, const double* vp, const Ends& ends,
                               double* work) const {
  Work w(work, N_);
  const int n = N_ + 1;
  if (window_) {
    // Each end from its 3-node window: the force on an end node involves only its segment,
    // the curvature at its neighbour (the segment after) and its own drag, weight and seabed.
    const Tether& wt = *window_;
    double* io = work + Work::Size(N_);
    double *wx = io, *wv = io + 9, *wf = io + 18, *wT = io + 27;
    double* scratch = io + kWindowIo;
    ConstNodes x(xp, 3, n), v(vp, 3, n);
    Nodes X(wx, 3, 3), V(wv, 3, 3);
    // The window knows nothing of the candidates (they index the whole tether): the contact
    // share of each end node is added below.
    Ends we = ends;
    we.contacts = nullptr;
    auto contact_on_node = [&](int i) {
      Vec3 F = Vec3::Zero();
      if (!Has(kContact) || !ends.contacts) return F;
      const ContactSet& set = *ends.contacts;
      for (int k = 0; k < set.count; ++k) {
        const ContactPoint& c = set.points[k];
        if (c.segment != i && c.segment != i - 1) continue;
        double N;
        const Vec3 Fc = ContactForce(c, x.data(), v.data(), ends.time - set.time_ref, &N);
        F += (c.segment == i ? 1 - c.s : c.s) * Fc;
      }
      return F;
    };
    ConstNodes F(wf, 3, 3), M(Work(scratch, 2).M, 3, 3);
    EndReactions r;
    X.col(0) = ends.a.pos;
    V.col(0) = ends.a.vel;
    X.rightCols(2) = x.middleCols(1, 2);
    V.rightCols(2) = v.middleCols(1, 2);
    wt.ComputeForces(wx, wv, we, wf, wT, scratch);
    r.force_a = F.col(0) + contact_on_node(0);
    r.tension_a = r.force_a.norm();
    if (Has(kClamp) && p_.clamp_a) r.torque_a = M.col(0);
    X.leftCols(2) = x.middleCols(N_ - 2, 2);
    V.leftCols(2) = v.middleCols(N_ - 2, 2);
    X.col(2) = p_.free_end ? Vec3(x.col(N_)) : ends.b.pos;
    V.col(2) = p_.free_end ? Vec3(v.col(N_)) : ends.b.vel;
    wt.ComputeForces(wx, wv, we, wf, wT, scratch);
    if (p_.free_end) {
      r.tension_b = wT[1];
    } else {
      r.force_b = F.col(2) + contact_on_node(N_);
      r.tension_b = r.force_b.norm();
      if (Has(kClamp) && p_.clamp_b) r.torque_b = -M.col(2);
    }
    return r;
  }
  Nodes x(w.x2, 3, n), v(w.v2, 3, n);
  x = ConstNodes(xp, 3, n);
  v = ConstNodes(vp, 3, n);
  x.col(0) = ends.a.pos;
  v.col(0) = ends.a.vel;
  if (!p_.free_end) {
    x.col(N_) = ends.b.pos;
    v.col(N_) = ends.b.vel;
  }
  ComputeForces(w.x2, w.v2, ends, w.f, w.T, work);
  ConstNodes f(w.f, 3, n), M(w.M, 3, n);
  EndReactions r;
  r.force_a = f.col(0);
  r.tension_a = r.force_a.norm();
  if (Has(kClamp) && p_.clamp_a) r.torque_a = M.col(0);
  if (p_.free_end) {
    r.tension_b = w.T[N_ - 1];
  } else {
    r.force_b = f.col(N_);
    r.tension_b = r.force_b.norm();
    if (Has(kClamp) && p_.clamp_b) r.torque_b = -M.col(N_);
  }
  return r;
}

// Tension only: a compressed segment (compression effect) reads 0, like a slack one.
void Tether::Tensions(const double* xp, const double* vp, double* T) const {
  ConstNodes x(xp, 3, N_ + 1), v(vp, 3, N_ + 1);
  const double inv_L0 = 1 / L0_;  // [1/m]
  for (int j = 0; j < N_; ++j) {
    const Vec3 dx = x.col(j + 1) - x.col(j);
    const double l = dx.norm();
    T[j] = 0;
    if (Has(kAxial) && l > L0_) {
      T[j] = AxialForce(l * inv_L0 - 1, dx * (1 / l), v.col(j + 1) - v.col(j), 0);
    }
  }
}

double Tether::KineticEnergy(const double* xp, const double* vp) const {
  ConstNodes x(xp, 3, N_ + 1), v(vp, 3, N_ + 1);
  double E = 0;
  for (int i = 0; i <= N_; ++i) {
    E += 0.5 * mass_(i) * v.col(i).squaredNorm();
    if (added_(i) > 0) {
      Vec3 s = x.col(std::min(i + 1, N_)) - x.col(std::max(i - 1, 0));
      Vec3 q = s.norm() > 0 ? Vec3(s.normalized()) : Vec3::Zero();
      Vec3 vn = v.col(i) - v.col(i).dot(q) * q;
      E += 0.5 * added_(i) * vn.squaredNorm();
    }
  }
  return E;
}

double Tether::PotentialEnergy(const double* xp, const Ends& ends) const {
  ConstNodes x(xp, 3, N_ + 1);
  double E = 0;
  Vec3 t_prev = Vec3::Zero();
  for (int j = 0; j < N_; ++j) {
    Vec3 dx = x.col(j + 1) - x.col(j);
    const double l = dx.norm();
    if (Has(kAxial) && l > L0_) E += 0.5 * p_.EA / L0_ * (l - L0_) * (l - L0_);
    if (Has(kCompression) && l < L0_) E += 0.5 * p_.EAc / L0_ * (l - L0_) * (l - L0_);
    Vec3 t = l > 0 ? Vec3(dx / l) : Vec3::Zero();
    // Bending: the potential of the forces of AddBending is EI/w (1 - cos theta) per node
    // (theta the turning angle, w the curvature weight), since M = EI sin(theta)/w.
    // With bending=der: 2 EI/w tan^2(theta/2) = 2 EI/w (1 - cos)/(1 + cos).
    if (Has(kBending)) {
      auto energy = [&](const Vec3& ta, const Vec3& tb, double w) {
        const double c = ta.dot(tb);
        if (p_.bending != Bending::kDER) return p_.EI / w * (1 - c);
        return 2 * p_.EI / w * (1 - c) / std::max(1 + c, 1e-2);
      };
      if (j > 0) E += energy(t_prev, t, L0_);
      if (j == 0 && Has(kClamp) && p_.clamp_a) E += energy(ends.a.axis, t, 0.5 * L0_);
      if (j == N_ - 1 && Has(kClamp) && p_.clamp_b) E += energy(t, ends.b.axis, 0.5 * L0_);
    }
    t_prev = t;
  }
  for (int i = 0; i <= N_; ++i) E -= weight_.col(i).dot(x.col(i));
  return E;
}

// ---------------------------------------------------------------------------------------------
// Integrators

// The attached end nodes at the ends' positions and velocities `e` (end B only if attached).
void Tether::PlaceEnds(const Ends& e, Nodes x, Nodes v) const {
  x.col(0) = e.a.pos;
  v.col(0) = e.a.vel;
  if (!p_.free_end) {
    x.col(N_) = e.b.pos;
    v.col(N_) = e.b.vel;
  }
}

// Acceleration of dynamic node i under force fi [N], node tangent qi: with normal added mass
// the node mass matrix is m I + ma (I - q q^T), whose inverse is q q^T/m + (I - q q^T)/(m + ma).
inline Vec3 Tether::Acceleration(int i, const Vec3& fi, const Vec3& qi) const {
  if (!Has(kAddedMass)) return inv_mass_(i) * fi;
  const Vec3 ft = fi.dot(qi) * qi;
  return inv_mass_(i) * ft + inv_mass_normal_(i) * (fi - ft);
}

// Symplectic (semi-implicit) Euler: v += h M^-1 f(x, v); x += h v.
void Tether::ExplicitStep(Nodes x, Nodes v, const Ends& now, const Ends& next, double h,
                          double* work) const {
  Work w(work, N_);
  ComputeForces(x.data(), v.data(), now, w.f, nullptr, work);
  AccumulateContactImpulse(x.data(), v.data(), now, h, false);  // v+ = v + h M^-1 f(x, v)
  ConstNodes f(w.f, 3, N_ + 1), q(w.q, 3, N_ + 1);
  for (int i = 1; i <= N_; ++i) {
    if (!Dynamic(i)) continue;
    v.col(i) += h * Acceleration(i, f.col(i), q.col(i));
    x.col(i) += h * v.col(i);
  }
  PlaceEnds(next, x, v);
}

// Classical fourth-order Runge-Kutta (Kutta 1901; Hairer, Norsett & Wanner, Solving ODEs I,
// table II.1.2) on y = (x, v), y' = (v, M^-1 f(x, v)), with the attached ends at t, t + h/2 and
// t + h from their Hermite curve. MoorDyn offers the same scheme for its lines. Four force
// evaluations per step, but fourth order, and a stability region that reaches 2.8/w along
// both the imaginary and the negative real axis (symplectic Euler: 2/w, less with damping),
// so at its own limit it costs 1.1-1.5x symplectic Euler per simulated second on a damped
// line (about 3x where undamped bending sets the step) and is far more accurate.
void Tether::Rk4Step(Nodes x, Nodes v, const Ends& now, const Ends& next, double h,
                     double* work) const {
  Work w(work, N_);
  const int n = N_ + 1;
  Nodes xk(w.x2, 3, n), vk(w.v2, 3, n), dx(w.xs, 3, n), dv(w.vs, 3, n);
  ConstNodes f(w.f, 3, n), q(w.q, 3, n);
  const Ends mid = Interpolate(now, next, h, 0.5);
  // Stage k at (xk, vk), ends `e`: k_k = (vk, a_k) is added to the sum (dx, dv) with weight
  // b = 1, 2, 2, 1, and the next stage state is y + c h k_k with c = 1/2, 1/2, 1; the last
  // stage completes y + h/6 (k1 + 2 k2 + 2 k3 + k4). One pass over the nodes per stage.
  xk = x;
  vk = v;
  const Ends* ends[4] = {&now, &mid, &mid, &next};
  const double b[4] = {1, 2, 2, 1}, c[3] = {0.5 * h, 0.5 * h, h};
  for (int k = 0; k < 4; ++k) {
    const Ends& e = *ends[k];
    PlaceEnds(e, xk, vk);
    ComputeForces(w.x2, w.v2, e, w.f, nullptr, work);
    AccumulateContactImpulse(xk.data(), vk.data(), e, b[k] * h / 6, false);
    for (int i = 0; i < n; ++i) {
      if (!Dynamic(i)) continue;
      const Vec3 ai = Acceleration(i, f.col(i), q.col(i)), vi = vk.col(i);
      if (k == 0) {
        dx.col(i) = vi;
        dv.col(i) = ai;
      } else {
        dx.col(i) += b[k] * vi;
        dv.col(i) += b[k] * ai;
      }
      if (k < 3) {
        xk.col(i) = x.col(i) + c[k] * vi;
        vk.col(i) = v.col(i) + c[k] * ai;
      } else {
        x.col(i) += (h / 6) * dx.col(i);
        v.col(i) += (h / 6) * dv.col(i);
      }
    }
  }
  PlaceEnds(next, x, v);
}

// Backward Euler, solved by Newton's method on the velocities at the end of the step:
//   G(v+) = M (v+ - v) - h f(x + h v+, v+) = 0,
//   (M - h D - h^2 K) dv = -G,   K = df/dx, D = df/dv at the current iterate,
// starting from v+ = v with the attached ends already at their positions and velocities at
// the end of the step. The linear system is the one of Baraff & Witkin (SIGGRAPH 1998).
//
// With smooth forces one iteration suffices (linearly implicit Euler) and the step takes it
// when no segment changed between slack (or compressed) and taut within it and the tension
// that segments turning within the step made the linearisation miss stays below
// kLinearisationTolerance of the largest. Otherwise the law that applies changed at l = L0
// (from nothing or EAc to EA): G is only piecewise smooth there, with kinks where a segment
// goes slack, a damped tension is clipped at zero or a node touches the seabed. (It has no
// jumps: a segment or a seabed contact that engages within the step takes the engaged damping
// law of AxialForce and AddSeabed, without which G jumps by h damping deps/dt as l crosses L0
// and has no root at all.) In these iterations the axial damping acts on the backward
// difference of the engaged strain over the step, (eps+ - max(eps, 0))/h, instead of
// t+ . (v+_{j+1} - v+_j)/L0: the two differ by l theta^2/(2 h L0) for a segment turning by
// theta in the step (first order in h, as backward Euler itself), but the difference depends
// on the lengths only, so its Jacobian is the symmetric (EA + damping/h)/L0 t t^T the matrix
// holds, where the rate along the turning tangent adds a non-symmetric term (damping h/(L0 l))
// t (P dv)^T that the matrix cannot hold and without which heavily damped slack tethers made
// the line search fail. The iteration then goes on as a semismooth Newton method (Qi & Sun,
// Math. Programming 58, 1993: the Jacobian of the piece the iterate is on is an element of
// the generalised Jacobian) with a backtracking line search on the merit function
// phi = 1/2 sum_i |G_i|^2/m_i (Armijo; Nocedal & Wright, Numerical Optimization, 2006, ch. 3
// and 11), which stops the slack/taut cycling of the plain iteration: each accepted iterate
// lowers phi. It stops when every node's velocity error |G_i|/m_i is below
// kNewtonTolerance of the largest velocity change of the step (plus a round-off floor).
// Returns false if it stalled (kMaxNewton iterations, or a line search that found no descent);
// the caller then retries the step in two halves and counts it.
//
// K holds the axial stiffness EA/L0 t t^T + T/l (I - t t^T) of taut segments, the small-angle
// bending stiffness EI/w g g^T (g the second-difference stencil of the curvature), and the
// seabed stiffness; D the axial damping, the drag and seabed damping, and the secant of the
// friction. Every block is symmetric and K <= 0, D <= 0, so the matrix is SPD and banded
// (3x3 blocks, two off-diagonals with bending, one without): a block Cholesky with fixed-size
// 3x3 blocks (block_band.h) solves it, assembled directly block by block.
bool Tether::ImplicitStep(Nodes x, Nodes v, const Ends& now, const Ends& next, double h,
                          double* work, StepStatus* stats) const {
  (void)now;
  Work w(work, N_);
  const int n = N_ + 1;
  const int nu = N_ - 1 + (p_.free_end ? 1 : 0);  // dynamic nodes 1..nu, unknown u = i - 1
  Nodes xk(w.x2, 3, n), vk(w.v2, 3, n);
  // Initial iterate: velocities unchanged, ends at the end of the step.
  vk = v;
  vk.col(0) = next.a.vel;
  if (!p_.free_end) vk.col(N_) = next.b.vel;
  auto place = [&]() {
    xk = x + h * vk;
    xk.col(0) = next.a.pos;
    if (!p_.free_end) xk.col(N_) = next.b.pos;
  };
  place();
  if (nu == 0) {
    x = xk;
    v = vk;
    return true;
  }
  ConstNodes f(w.f, 3, n), t(w.t, 3, N_), q(w.q, 3, n);
  BlockBand A(w.band, nu, Has(kBending) ? 2 : 1);
  Nodes rhs(w.rhs, 3, nu), dv(w.dv, 3, nu), vb(w.vb, 3, nu);
  const Mat3 I = Mat3::Identity();
  const double h2 = h * h;
  const bool added = Has(kAddedMass);
  Start start{ConstNodes(x.data(), 3, n), h, false};

  // Forces at the iterate, and the residual -G = h f - M (v+ - v) (node mass with normal added
  // mass) into rhs. Returns phi*2 and, in *err, the largest |G_i|/m_i [m/s].
  auto residual = [&](double* err) {
    place();
    Forces(w.x2, w.v2, next, w.f, w.T, work, &start);
    double phi = 0, worst = 0;
    for (int i = 1; i <= nu; ++i) {
      const Vec3 dvi = vk.col(i) - v.col(i);
      Vec3 r = h * f.col(i) - mass_(i) * dvi;
      if (added) {
        const Vec3 qi = q.col(i);
        r -= added_(i) * (dvi - qi.dot(dvi) * qi);
      }
      rhs.col(i - 1) = r;
      const double r2 = r.squaredNorm();
      phi += r2 * inv_mass_(i);
      worst = std::max(worst, r2 * inv_mass_(i) * inv_mass_(i));
    }
    *err = std::sqrt(worst);
    return phi;
  };

  // The matrix M - h D - h^2 K at the iterate of the last residual, factored; the Newton
  // correction replaces the residual in rhs. False if the factorisation failed.
  bool newton = false;  // past the first iteration
  auto solve = [&]() {
    A.SetZero();
    for (int i = 1; i <= nu; ++i) {
      BlockBand::Block d = A.D(i - 1);
      if (added) {
        const Vec3 qi = q.col(i);
        d = mass_(i) * I + added_(i) * (I - qi * qi.transpose());
      } else {
        d.diagonal().setConstant(mass_(i));
      }
    }
    // Axial stiffness and damping of taut segments: B = h D + h^2 K with
    // K = EA/L0 t t^T + T/l (I - t t^T), D = damping/L0 t t^T; +B on both diagonal blocks,
    // -B on the coupling block.
    // A compressed segment (compression effect, 0 < l < L0) adds h^2 EAc/L0 t t^T and its
    // damping while it pushes, without the geometric term -|T|/l (I - t t^T): that negative
    // stiffness (buckling) would make the matrix indefinite, and bending carries it instead.
    if (Has(kAxial)) {
      const double ka = p_.EA / L0_;
      const double kc = p_.EAc / L0_;
      const double ca = Has(kDamping) ? p_.damping / L0_ : 0;
      const bool compression = Has(kCompression);
      for (int j = 0; j < N_; ++j) {
        const bool taut = w.l[j] > L0_;
        if (!taut && !(compression && w.l[j] > 0 && w.l[j] < L0_)) continue;
        const Vec3 tj = t.col(j);
        Mat3 B;
        if (taut) {
          // In the Newton iterations after the first, a taut segment whose damped tension is
          // clipped at zero (it shortens faster than EA eps/damping) is on the piece where
          // the law is 0: its Jacobian there is 0 (the first keeps the linearly implicit step's
          // matrix of before).
          if (newton && !(w.T[j] > 0)) continue;
          const double geo = h2 * w.T[j] / w.l[j];
          const double along = h2 * ka + (w.T[j] > 0 ? h * ca : 0) - geo;
          B = along * tj * tj.transpose() + geo * I;
        } else {
          const double rate = tj.dot(vk.col(j + 1) - vk.col(j)) / L0_;  // [1/s] deps/dt
          const bool pushes = p_.EAc * (w.l[j] / L0_ - 1) + ca * L0_ * rate < 0;
          B = (h2 * kc + (pushes ? h * ca : 0)) * tj * tj.transpose();
        }
        const bool d0 = Dynamic(j), d1 = Dynamic(j + 1);
        if (d0) A.D(j - 1) += B;
        if (d1) A.D(j) += B;
        if (d0 && d1) A.L1(j) -= B;
      }
    }
    // Bending: K = -EI/w g g^T I on the stencil of each curvature; B = h^2 EI/(w L0^2) g g^T I.
    // Every block is a multiple of I: the stencils add scalars per block row (on the diagonal,
    // first and second band), gathered in the free moment buffer, then one pass adds them.
    if (Has(kBending)) {
      double* band0 = w.M;  // 3 x n scratch (the moments are no longer needed): D, L1, L2
      std::fill(band0, band0 + 3 * n, 0.0);
      auto stencil = [&](int first, const double* g, int count, double weight) {
        const double k = h2 * p_.EI / (weight * L0_ * L0_);
        for (int a = 0; a < count; ++a) {
          const int ia = first + a;
          if (!Dynamic(ia)) continue;
          for (int b = 0; b <= a; ++b) {
            if (!Dynamic(first + b)) continue;
            band0[3 * (ia - 1) + (a - b)] += k * g[a] * g[b];
          }
        }
      };
      const double g3[3] = {1, -2, 1}, g2[2] = {-1, 1};
      for (int i = 1; i < N_; ++i) stencil(i - 1, g3, 3, L0_);
      if (Has(kClamp) && p_.clamp_a) stencil(0, g2, 2, 0.5 * L0_);
      if (Has(kClamp) && p_.clamp_b) stencil(N_ - 1, g2, 2, 0.5 * L0_);
      for (int u = 0; u < nu; ++u) {
        A.D(u).diagonal().array() += band0[3 * u];
        if (u >= 1) A.L1(u).diagonal().array() += band0[3 * u + 1];
        if (u >= 2) A.L2(u).diagonal().array() += band0[3 * u + 2];
      }
    }
    // Drag: d(|vn| vn)/dv_r = |vn| P + vn vn^T/|vn|, d(|vt| vt)/dv_r = 2 |vt| q q^T; B = -h D.
    if (Has(kDrag)) {
      const Vec3 u = Has(kCurrent) ? env_.water.current : Vec3::Zero();
      for (int i = 1; i <= nu; ++i) {
        const double li = 0.5 * (w.l[i - 1] + (i < N_ ? w.l[i] : 0));
        const Vec3 qi = q.col(i);
        const Vec3 vr = u - vk.col(i);
        const double vq = vr.dot(qi);
        const Vec3 vn = vr - vq * qi;
        const double vnn = vn.norm();
        const double ht = h * li;
        Mat3 J = (ht * (kt_ * 2 * std::abs(vq) - kn_ * vnn)) * qi * qi.transpose();
        J.diagonal().array() += ht * kn_ * vnn;
        if (vnn > 0) J += (ht * kn_ / vnn) * vn * vn.transpose();
        A.D(i - 1) += J;
      }
    }
    // Seabed: normal stiffness and damping, friction secant.
    if (Has(kSeabed)) {
      const Water& wt = env_.water;
      for (int i = 1; i <= nu; ++i) {
        const double pen = wt.seabed - xk(2, i);
        if (pen <= 0) continue;
        BlockBand::Block d = A.D(i - 1);
        d(2, 2) += h2 * seabed_k_ * share_(i) + h * seabed_c_ * share_(i);
        const double N = std::max(0.0, share_(i) * (seabed_k_ * pen - seabed_c_ * vk(2, i)));
        const double mu = std::max(wt.seabed_friction, wt.seabed_friction_axial);
        const double vh = std::hypot(vk(0, i), vk(1, i));
        const double eps = wt.seabed_friction_speed;
        const double secant = vh > 1e-9 * eps ? mu * N * std::tanh(vh / eps) / vh : mu * N / eps;
        d(0, 0) += h * secant;
        d(1, 1) += h * secant;
      }
    }
    // Contact: normal stiffness and damping L0 (h^2 k + h c) n n^T and the friction's
    // derivative in the tangent plane at the contact point, shared by the segment's
    // nodes with the weights (1 - s), s of the force (so w_a w_b on each block).
    if (Has(kContact) && next.contacts) {
      const ContactSet& set = *next.contacts;
      const double dt_ref = next.time - set.time_ref;
      for (int k = 0; k < set.count; ++k) {
        const ContactPoint& c = set.points[k];
        double N;
        ContactForce(c, xk.data(), vk.data(), dt_ref, &N);
        const Vec3 xs = (1 - c.s) * xk.col(c.segment) + c.s * xk.col(c.segment + 1);
        if (!(c.normal.dot(xs - c.point - dt_ref * c.velocity) < 0.5 * p_.diameter)) continue;
        const Mat3 nn = c.normal * c.normal.transpose();
        Mat3 B = (L0_ * (h2 * contact_k_ + h * contact_c_)) * nn;
        if (p_.contact_friction > 0 && N > 0) {
          const Vec3 vrel = (1 - c.s) * vk.col(c.segment) + c.s * vk.col(c.segment + 1) -
                            c.velocity;
          const Vec3 vt = vrel - c.normal.dot(vrel) * c.normal;
          const double slip = vt.norm();
          const double eps = p_.contact_friction_speed;
          const double muN = p_.contact_friction * N;
          // Tangent of mu N tanh(|vt|/eps) vt/|vt|: sech^2/eps along the slip, the secant
          // tanh(|vt|/eps)/|vt| across it (both mu N/eps at rest). The secant along the slip
          // too would hold a sliding tether back at the creep speed step after step.
          if (slip > 1e-9 * eps) {
            const Vec3 e = vt / slip;
            const double th = std::tanh(slip / eps);
            const Mat3 ee = e * e.transpose();
            B += h * muN * ((1 - th * th) / eps * ee + th / slip * (I - nn - ee));
          } else {
            B += h * muN / eps * (I - nn);
          }
        }
        const int j = c.segment;
        const double wa = 1 - c.s, wb = c.s;
        const bool d0 = Dynamic(j), d1 = Dynamic(j + 1);
        if (d0) A.D(j - 1) += (wa * wa) * B;
        if (d1) A.D(j) += (wb * wb) * B;
        if (d0 && d1) A.L1(j) += (wa * wb) * B;
      }
    }
    if (A.Factor() >= 0) return false;
    A.Solve(w.rhs);
    ++stats->newton_iterations;
    return true;
  };
  // A failed factorisation leaves NaN behind for the divergence check to report.
  auto fail = [&]() {
    vk.col(1).setConstant(NAN);
    x = xk;
    v = vk;
    return true;  // nothing to retry
  };

  // The iterate xk, vk just moved by a full Newton step from the iterate the matrix was
  // assembled at (whose segment lengths, tangents and tensions are still in w.l, t, w.T): was
  // the linearisation right? Not if a segment changed between slack (or compressed) and taut:
  // the law changes at l = L0 (from nothing or EAc to EA). Nor if segments turned so far that
  // the linearisation missed tension: it took each taut segment's new length as
  // l + t . d(dx), along its tangent at the start; a segment that turns by theta in the step
  // is longer than that by about l theta^2/2. Where that would exceed kLinearisationTolerance
  // of the largest tension (or a microstrain), the step was too long for the linearisation.
  // (Without this, the fixed line at 160 segments and 50 ms steps went wrong by 3.6 kN RMS,
  // not 60 N.)
  const double L0sq = L0_ * L0_;
  auto linearisation_held = [&]() {
    for (int j = 0; j < N_; ++j) {
      if (((xk.col(j + 1) - xk.col(j)).squaredNorm() > L0sq) != (w.l[j] > L0_)) return false;
    }
    // Friction saturates over the slip speed eps: where the slip of a contact changed the
    // friction's tanh by more than 0.1 in the full Newton step just taken (rhs still holds it),
    // the linearisation was not good for it (a tether starting to slide).
    if (Has(kContact) && next.contacts && p_.contact_friction > 0) {
      const ContactSet& set = *next.contacts;
      const double eps = p_.contact_friction_speed;
      for (int k = 0; k < set.count; ++k) {
        const ContactPoint& c = set.points[k];
        auto node_v = [&](int i, bool after) -> Vec3 {
          if (after || !Dynamic(i)) return vk.col(i);
          return vk.col(i) - rhs.col(i - 1);
        };
        auto slip = [&](bool after) {
          const Vec3 vr = (1 - c.s) * node_v(c.segment, after) +
                          c.s * node_v(c.segment + 1, after) - c.velocity;
          return (vr - c.normal.dot(vr) * c.normal).norm();
        };
        if (std::abs(std::tanh(slip(true) / eps) - std::tanh(slip(false) / eps)) > 0.1) {
          return false;
        }
      }
    }
    if (!Has(kAxial)) return true;
    double T_max = 0, missed = 0;
    for (int j = 0; j < N_; ++j) {
      T_max = std::max(T_max, w.T[j]);
      if (!(w.l[j] > L0_)) continue;
      const Vec3 d = xk.col(j + 1) - xk.col(j);
      missed = std::max(missed, p_.EA / L0_ * (d.norm() - t.col(j).dot(d)));
    }
    return missed <= std::max(kLinearisationTolerance * T_max, 1e-6 * p_.EA);
  };

  // First iteration: the linearly implicit step.
  double err = 0;
  double phi = residual(&err);
  if (!solve()) return fail();
  for (int i = 1; i <= nu; ++i) vk.col(i) += rhs.col(i - 1);
  place();
  if (linearisation_held()) {
    x = xk;
    v = vk;
    return true;
  }

  // Semismooth Newton with a line search on phi, until a full Newton step holds its
  // linearisation as above, or the velocity error is below kNewtonTolerance of the step's
  // largest velocity change. The round-off floor: the net force at a node is a sum of terms up
  // to the largest tension or weight, each exact to ~1e-16 of itself.
  double dv_max = 0, W_max = 0, m_min = INFINITY, T_max = 0;
  for (int i = 1; i <= nu; ++i) {
    dv_max = std::max(dv_max, (vk.col(i) - v.col(i)).squaredNorm());
    W_max = std::max(W_max, weight_.col(i).norm());
    m_min = std::min(m_min, mass_(i));
  }
  for (int j = 0; j < N_; ++j) T_max = std::max(T_max, w.T[j]);
  const double tolerance =
      kNewtonTolerance * std::sqrt(dv_max) + 1e-12 * h * (2 * T_max + W_max) / m_min;
  start.discrete = true;
  phi = residual(&err);
  newton = true;
  for (int iter = 1; err > tolerance; ++iter) {
    if (iter == kMaxNewton) return false;
    if (!solve()) return fail();
    dv = rhs;
    for (int i = 1; i <= nu; ++i) vb.col(i - 1) = vk.col(i);
    for (int i = 1; i <= nu; ++i) vk.col(i) += dv.col(i - 1);
    place();
    if (linearisation_held()) break;
    // Backtracking (Armijo, sigma = 1e-4): phi(alpha) <= (1 - 2 sigma alpha) phi(0), the
    // directional derivative of phi along an exact Newton step being -2 phi(0).
    double alpha = 1, trial = 0;
    for (;;) {
      trial = residual(&err);
      if (trial <= (1 - 2e-4 * alpha) * phi) break;
      alpha *= 0.5;
      if (alpha < kMinLineSearchStep) return false;
      for (int i = 1; i <= nu; ++i) vk.col(i) = vb.col(i - 1) + alpha * dv.col(i - 1);
    }
    phi = trial;
  }
  x = xk;
  v = vk;
  return true;
}

// An implicit step whose Newton iteration did not settle is redone as two half steps (the
// ends at the midpoint from the same Hermite curve), down to 1/2^kMaxHalvings of the step;
// at that depth the last iterate is accepted.
void Tether::ImplicitStepAdaptive(Nodes x, Nodes v, const Ends& now, const Ends& next, double h,
                                  int depth, double* work, StepStatus* stats,
                                  double impulse_weight) const {
  constexpr int kMaxHalvings = 8;
  Work w(work, N_);
  const int n = N_ + 1;
  Nodes xs(w.xs, 3, n), vs(w.vs, 3, n);
  xs = x;
  vs = v;
  const bool converged = ImplicitStep(x, v, now, next, h, work, stats);
  if (converged || depth == kMaxHalvings) {
    if (!converged) ++stats->stalled_steps;
    // Backward Euler: M (v+ - v) = h f(x+, v+), so the impulse is h times the final force.
    AccumulateContactImpulse(x.data(), v.data(), next, impulse_weight * h, false);
    return;
  }
  ++stats->halvings;
  x = xs;
  v = vs;
  const Ends mid = Interpolate(now, next, h, 0.5);
  ImplicitStepAdaptive(x, v, now, mid, h / 2, depth + 1, work, stats, impulse_weight);
  ImplicitStepAdaptive(x, v, mid, next, h / 2, depth + 1, work, stats, impulse_weight);
}

// Two-stage, stiffly accurate, L-stable SDIRK of order 2 (Alexander, SIAM J. Numer. Anal. 14,
// 1977), gamma = 1 - 1/sqrt(2), on y = (x, v), y' = F(y) = (v, a(x, v)):
//   Y1 = y + gamma h F(Y1),   y+ = Y2 = y + (1 - gamma) h F(Y1) + gamma h F(Y2).
// Both stages are backward-Euler steps of size gamma h: the first from y (ends at t + gamma h),
// the second from y~ = y + (1 - gamma)/gamma (Y1 - y), i.e. x~ = x + (1 - gamma) h V1,
// v~ = v + (1 - gamma)/gamma (V1 - v) (ends at t + h). Backward Euler damps a mode of frequency
// w by about w h/2 per radian, which at the vehicle's step is as much as the tether's own
// damping of its first axial modes; this scheme's error is O(h^2) and its damping O((w h)^3),
// and it still removes the unresolved axial modes (L-stable).
void Tether::Sdirk2Step(Nodes x, Nodes v, const Ends& now, const Ends& next, double h,
                        double* work, StepStatus* stats) const {
  constexpr double kGamma = 0.29289321881345247560;  // 1 - 1/sqrt(2)
  Work w(work, N_);
  const int n = N_ + 1;
  Nodes x0(w.x0, 3, n), v0(w.v0, 3, n);
  x0 = x;
  v0 = v;
  const Ends mid = Interpolate(now, next, h, kGamma);
  // A stage whose Newton iteration does not settle (a segment switching between slack and
  // taut) makes the extrapolation to y~ below unreliable (it amplifies Y1 - y by 2.4): such a
  // step is taken by backward Euler instead, retried in halves as the implicit scheme does.
  auto fall_back = [&]() {
    x = x0;
    v = v0;
    ImplicitStepAdaptive(x, v, now, next, h, 0, work, stats);
  };
  if (!ImplicitStep(x, v, now, mid, kGamma * h, work, stats)) return fall_back();
  // Contact impulse: y+ = y + (1 - gamma) h F(Y1) + gamma h F(Y2); the first part is kept
  // aside until the second stage settles (a fallback replaces both).
  if (Has(kContact) && mid.contacts) {
    for (int k = 0; k < mid.contacts->count; ++k) mid.contacts->points[k].stage.setZero();
    AccumulateContactImpulse(x.data(), v.data(), mid, (1 - kGamma) * h, true);
  }
  // x, v hold Y1; form y~ on the dynamic nodes (the ends are set by the next stage).
  const double a = (1 - kGamma) / kGamma;
  for (int i = 0; i < n; ++i) {
    if (!Dynamic(i)) continue;
    x.col(i) = x0.col(i) + (1 - kGamma) * h * v.col(i);
    v.col(i) = v0.col(i) + a * (v.col(i) - v0.col(i));
  }
  if (!ImplicitStep(x, v, mid, next, kGamma * h, work, stats)) return fall_back();
  if (Has(kContact) && next.contacts) {
    for (int k = 0; k < next.contacts->count; ++k) {
      ContactPoint& c = next.contacts->points[k];
      c.impulse += c.stage;
    }
    AccumulateContactImpulse(x.data(), v.data(), next, kGamma * h, false);
  }
}

StepStatus Tether::Advance(double* xp, double* vp, const Ends& from, const Ends& to, double dt,
                           double* work) const {
  const int n = N_ + 1;
  Nodes x(xp, 3, n), v(vp, 3, n);
  StepStatus status;
  const int steps = SubstepsFor(dt);
  if (steps == 0) return status;
  const double h = dt / steps;
  Ends now = from;
  PlaceEnds(from, x, v);
  for (int k = 0; k < steps; ++k) {
    const Ends next = k + 1 == steps ? to : Interpolate(from, to, dt, double(k + 1) / steps);
    if (p_.integrator == Integrator::kExplicit) {
      ExplicitStep(x, v, now, next, h, work);
    } else if (p_.integrator == Integrator::kRK4) {
      Rk4Step(x, v, now, next, h, work);
    } else if (p_.integrator == Integrator::kImplicit2) {
      Sdirk2Step(x, v, now, next, h, work, &status);
    } else {
      ImplicitStepAdaptive(x, v, now, next, h, 0, work, &status);
    }
    now = next;
  }
  // Divergence: a non-finite value, or a strain no tether survives.
  for (int i = 0; i < n; ++i) {
    if (!x.col(i).allFinite() || !v.col(i).allFinite()) {
      status.ok = false;
      status.node = i;
      status.reason = "non-finite position or velocity";
      return status;
    }
  }
  for (int j = 0; j < N_; ++j) {
    const double strain = (x.col(j + 1) - x.col(j)).norm() / L0_ - 1;
    if (strain > p_.max_strain) {
      status.ok = false;
      status.node = j + 1;
      status.reason = "strain " + std::to_string(strain) + " of segment " + std::to_string(j) +
                      " exceeds max_strain " + std::to_string(p_.max_strain);
      return status;
    }
  }
  // Energy blow-up: more kinetic energy than the tether could hold physically (an unstable
  // mode grows geometrically and crosses this long before it overflows to NaN).
  double kinetic = 0, node_max = -1;
  int fastest = -1;
  for (int i = 0; i < n; ++i) {
    if (!Dynamic(i)) continue;
    const double e = 0.5 * (mass_(i) + added_(i)) * v.col(i).squaredNorm();
    kinetic += e;
    if (e > node_max) node_max = e, fastest = i;
  }
  const double bound = kEnergyBlowUp * EnergyBound(from, to);
  if (kinetic > bound) {
    status.ok = false;
    status.node = fastest;
    status.reason = "kinetic energy " + std::to_string(kinetic) + " J exceeds " +
                    std::to_string(bound) + " J, " + std::to_string(kEnergyBlowUp) +
                    " times the most the tether can physically hold";
  }
  return status;
}

// The most energy the tether can hold without diverging [J]: elastic energy at max_strain
// along its whole length, ½ EA max_strain² L; with compression, every segment shortened to
// nothing, ½ EAc L; bending energy of a fold at every node,
// ½ EI (2/L0)² L; the kinetic energy of the whole tether (with added mass) moving with its
// fastest end plus the current; and the work of its net weight falling its own length.
double Tether::EnergyBound(const Ends& from, const Ends& to) const {
  const double L = p_.length;
  double v = std::max(from.a.vel.norm(), to.a.vel.norm());
  if (!p_.free_end) v = std::max({v, from.b.vel.norm(), to.b.vel.norm()});
  if (Has(kCurrent)) v += env_.water.current.norm();
  const double M = mass_.sum() + added_.sum();
  double E = 0.5 * p_.EA * p_.max_strain * p_.max_strain * L + 0.5 * M * v * v;
  if (Has(kBending)) E += 0.5 * p_.EI * (4 / (L0_ * L0_)) * L;
  if (Has(kCompression)) E += 0.5 * p_.EAc * L;
  double W = 0;  // [N] net weight, without sign
  for (int i = 0; i <= N_; ++i) W += weight_.col(i).norm();
  return E + W * L;
}

}  // namespace mjtether
