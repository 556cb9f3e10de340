#include "tether.h"

#include <algorithm>
#include <cmath>
#include <vector>
#include <complex>

#include "detail/work.h"

namespace mjtether {
using namespace detail;
namespace {

// Moves the interior nodes of y (3 x (N+1), the ends fixed) so that every chord is L0:
// nonlinear Gauss-Seidel on |y_k+1 - y_k| = L0 (as SHAKE/RATTLE do for rigid bonds), each sweep
// moving both nodes of a segment along it by half its length error (the node next to an end
// by all of it), then `floor` (a node lifted onto the seabed, or nothing). True if every chord
// ends within 1e-9 L0 of L0; y is then the shape (else it is left as it came out).
template <class Floor>
bool ProjectOntoChords(Eigen::Matrix3Xd& y, double L0, Floor&& floor) {
  const int N = static_cast<int>(y.cols()) - 1;
  if (N < 2) return false;
  double worst = INFINITY;
  for (int sweep = 0; sweep < 20000 && !(worst <= 1e-10 * L0); ++sweep) {
    worst = 0;
    for (int k = 0; k < N; ++k) {
      const Vec3 d = y.col(k + 1) - y.col(k);
      const double l = d.norm();
      if (!(l > 1e-12 * L0)) return false;  // coincident nodes: no direction to push along
      worst = std::max(worst, std::abs(l - L0));
      const Vec3 c = (l - L0) / l * d;  // [m] shortens d by l - L0
      if (k == 0) {
        y.col(k + 1) -= c;
      } else if (k + 1 == N) {
        y.col(k) += c;
      } else {
        y.col(k) += 0.5 * c;
        y.col(k + 1) -= 0.5 * c;
      }
    }
    for (int k = 1; k < N; ++k) {
      Vec3 p = y.col(k);
      floor(p);
      y.col(k) = p;
    }
  }
  for (int k = 0; k < N; ++k) {
    if (!(std::abs((y.col(k + 1) - y.col(k)).norm() - L0) <= 1e-9 * L0)) return false;
  }
  return true;
}

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
  auto arrays = std::make_shared<NodeArrays>();
  NodeArrays& a = *arrays;
  a.share = Eigen::VectorXd::Constant(n, c.L0_);
  a.share(0) = a.share(c.N_) = c.L0_ / 2;
  a.mass = params.mass_per_length * a.share;
  a.added = c.Has(kAddedMass) ? Eigen::VectorXd(params.Can * rho * c.area_ * a.share)
                              : Eigen::VectorXd::Zero(n);
  a.inv_mass = a.mass.cwiseInverse();
  c.damping_per_L0_ = params.damping / c.L0_;
  // The segment axial mode (SegmentModeFrequency): read at every step by the plugin's snap watch.
  c.segment_mode_w_ = 2 / c.L0_ * std::sqrt(params.EA / params.mass_per_length);
  c.segment_mode_ratio_ =
      c.Has(kDamping) ? params.damping / (c.L0_ * std::sqrt(params.EA * params.mass_per_length))
                      : 0.0;
  a.inv_mass_normal = (a.mass + a.added).cwiseInverse();
  // Net weight: dry weight minus buoyancy of the displaced volume.
  a.weight = Eigen::Matrix3Xd::Zero(3, n);
  for (int i = 0; i < n; ++i) {
    double m = 0;
    if (c.Has(kWeight)) m += a.mass(i);
    if (c.Has(kBuoyancy)) m -= rho * c.area_ * a.share(i);
    a.weight.col(i) = m * env.gravity;
  }
  c.mass_ = a.mass.data();
  c.added_ = a.added.data();
  c.inv_mass_ = a.inv_mass.data();
  c.inv_mass_normal_ = a.inv_mass_normal.data();
  c.share_ = a.share.data();
  c.weight_ = a.weight.data();
  c.total_mass_ = a.mass.sum() + a.added.sum();
  c.total_weight_ = a.weight.colwise().norm().sum();
  c.arrays_ = std::move(arrays);
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

  // Explicit stability limit, node by node. By Gershgorin's theorem every eigenvalue w^2 of
  // M^-1 K lies within some row's disc, so w^2 <= max_i (sum_j |K_ij|)/m_i: the axial chain
  // gives 2 sum (EA/L0) over the node's segments (4 EA/(L0 m) inside, and at a free end half
  // the stiffness on half the mass: the same), with EA the larger of EA and EAc when
  // compressed segments push back; the Galerkin fourth difference 16 EI/L0^3 inside (doubled
  // next to a clamped end, whose curvature weight is L0/2) and 4 EI/L0^3 at a free end; the
  // seabed k l_i and a contact point k L0. Damping (internal, seabed, friction, contact) per
  // node likewise; with damping ratio z, symplectic Euler is stable up to 2/w (sqrt(1+z^2) - z)
  // (the trace and determinant conditions of its 2x2 step matrix), RK4 up to Rk4StableStep.
  // On the reference scenes the measured limit is 0.98-1.06 times this (tests/stable_step_test.cc;
  // a step beyond it does not always blow up: the slack clamp T >= 0 bounds the unstable
  // highest mode, and the run goes on with tensions tens of percent wrong).
  // With a winch the shortest segment is the winch segment at its shortest, L0/2: the limit
  // is that of a tether of segments L0/2 throughout (node masses and lengths halved with them).
  const double L0_save = c.L0_;
  const double winch_scale = params.winch ? 0.5 : 1.0;
  c.L0_ *= winch_scale;
  c.explicit_limit_ = INFINITY;  // no dynamic node (one segment between two sites)
  a.stab_w = a.stab_rate = a.stab_h = Eigen::VectorXd::Zero(n);
  {
    const double ea = c.Has(kCompression) ? std::max(params.EA, params.EAc) : params.EA;
    for (int i = 0; i < n; ++i) {
      if (!c.Dynamic(i)) continue;
      const int segments_at_node = (i > 0) + (i < c.N_);
      const double m = winch_scale * c.mass_[i];                     // [kg]
      const double mn = winch_scale * (c.mass_[i] + c.added_[i]);    // [kg]
      double w2 = 2 * segments_at_node * (ea / c.L0_) / m;           // [1/s^2]
      double rate = 0;                                               // [1/s] damping / mass
      c.terms_.w_axial = std::max(c.terms_.w_axial, std::sqrt(w2));
      if (c.Has(kBending)) {
        const double row = segments_at_node == 1 ? 4 : (c.Has(kClamp) ? 32 : 16);
        const double wb2 = row * params.EI / (c.L0_ * c.L0_ * c.L0_ * mn);
        w2 += wb2;
        c.terms_.w_bending = std::max(c.terms_.w_bending, std::sqrt(wb2));
      }
      if (c.Has(kSeabed)) {
        w2 += c.seabed_k_ * winch_scale * c.share_[i] / m;
        c.terms_.w_seabed = std::max(c.terms_.w_seabed, std::sqrt(c.seabed_k_ * winch_scale * c.share_[i] / m));
        rate += c.seabed_c_ * winch_scale * c.share_[i] / m;
        const double mu = std::max(env.water.seabed_friction, env.water.seabed_friction_axial);
        rate += mu * winch_scale * c.Weight(i).norm() / (env.water.seabed_friction_speed * m);
      }
      // A contact point at a node puts its whole stiffness k L0 on that node.
      if (c.Has(kContact)) {
        w2 += c.contact_k_ * c.L0_ / m;
        rate += c.contact_c_ * c.L0_ / m;
      }
      if (c.Has(kDamping)) rate += 2 * segments_at_node * (params.damping / c.L0_) / m;
      c.terms_.rate = std::max(c.terms_.rate, rate);
      const double w = std::sqrt(w2);
      const double zeta = rate / (2 * w);
      const double h = params.integrator == Integrator::kRK4
                           ? Rk4StableStep(w, zeta)
                           : 2 / w * (std::sqrt(1 + zeta * zeta) - zeta);
      c.explicit_limit_ = std::min(c.explicit_limit_, h);
      a.stab_w(i) = w;
      a.stab_rate(i) = rate;
      a.stab_h(i) = h;
      if (c.Has(kDrag) && c.mass_[i] > 0) {
        c.drag_rate_per_speed_ =
            std::max(c.drag_rate_per_speed_, 2 * std::max(c.kn_ / (c.mass_[i] + c.added_[i]),
                                                          c.kt_ / c.mass_[i]) *
                                                 c.share_[i] * (1 + params.max_strain));
      }
    }
  }
  c.L0_ = L0_save;
  c.explicit_dt_ =
      (params.integrator == Integrator::kRK4 ? kRk4Safety : kExplicitSafety) * c.explicit_limit_;
  // The 3-node window for the end reactions: rest length L0 per segment, so its end nodes
  // carry the same lumped length, mass, weight and curvature weights as the tether's.
  if (c.N_ >= 3) {
    TetherParams wp = params;
    wp.segments = 2;
    wp.length = 2 * c.L0_;
    wp.winch = false;
    std::optional<Tether> window = Create(wp, env, error);
    if (!window) return std::nullopt;
    c.window_ = std::make_shared<const Tether>(std::move(*window));
  }
  return tether;
}

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

// Drag in the explicit stable step (docs/numerics.md). Quadratic drag, 1/2 rho C d l |v| v,
// damps a node at the rate 2 (1/2 rho C d) l |v| / m along v (d(|v| v)/dv = 2 |v|; normal
// drag on the mass with added mass, tangential on the dry mass), which the load-time limit
// (stiffness, internal, seabed and contact damping) cannot know: it grows with the speed. The
// safety factor under the load-time limit (0.5, rk4 0.8) covers a moderate drag; on scene
// fuzzer seed 4880 (explicit, 2 segments of 49 m, d 6.4 mm, towed to 250 m/s by a thrust
// ramp) it reached 16,000 1/s on the middle node, 7x beyond symplectic Euler's limit at the
// load-time step of 0.43 ms: the run diverged at 0.148 s, and at a 10x smaller MuJoCo step at
// 0.196 s, since the substep did not change.
// Each node's limit from Create, h0_i = 2/(sqrt(w^2 + r0^2/4) + r0/2) for symplectic Euler
// (the damped oscillator's limit, r0 the load-time rate; RK4's from Rk4StableStep), is scaled
// by that expression's ratio with the drag's rate added to r0, which is exact for symplectic
// Euler and keeps RK4's shape (its region reaches 2.79 along the negative real axis against
// Euler's 2). Where the substep dt/steps exceeds 0.9 of the smallest scaled limit, the count
// is raised to put the substep at the safety factor of it again; otherwise it is left as it
// is, so that ordinary scenes keep their substeps. The speed is the largest of any node's or
// either end's (at both times) relative to the current: a towing end drags its neighbours up
// to its own speed within the step. Lengths: the stretched ones, as AddDrag. Not with a
// declared `substeps` or `max_step` (the step is then the user's), nor with a winch (its nodes
// are regridded; the Deployed views' arrays are offset).
int Tether::DragSubsteps(const double* xp, const double* vp, const Ends& from, const Ends& to,
                         double dt, int steps) const {
  if (!Has(kDrag) || !IsExplicit(p_.integrator) || p_.substeps > 0 || p_.max_step > 0 ||
      head_ || p_.winch || !(dt > 0) || steps <= 0) {
    return steps;
  }
  ConstNodes x(xp, 3, N_ + 1), v(vp, 3, N_ + 1);
  auto relative = [&](const Vec3& p, const Vec3& vel) {
    return ((Has(kCurrent) ? env_.water.CurrentAt(p.z()) : Vec3::Zero()) - vel).norm();
  };
  double s = std::max(relative(from.a.pos, from.a.vel), relative(to.a.pos, to.a.vel));
  if (!DynamicB()) {
    s = std::max({s, relative(from.b.pos, from.b.vel), relative(to.b.pos, to.b.vel)});
  }
  for (int i = 0; i <= N_; ++i) s = std::max(s, relative(x.col(i), v.col(i)));
  const double safety = p_.integrator == Integrator::kRK4 ? kRk4Safety : kExplicitSafety;
  const double substep = dt / steps;  // [s]
  // Quick test: with every node's drag rate at most q 2/limit, every node's limit stays above
  // limit/(1 + q) (h_i >= 2/(2/h0_i + drag_i)), and the substep, at most safety x limit
  // (SubstepsFor without max_step), is then within 0.9 of it while q <= 0.9/safety - 1 (0.8
  // for explicit, 0.125 for rk4). Ordinary scenes stop here, after one pass over the speeds.
  const double q = s * drag_rate_per_speed_ * explicit_limit_ / 2;
  if (!(q > 0.9 / safety - 1)) return steps;
  const NodeArrays& a = *arrays_;
  double h = INFINITY;  // [s] the smallest scaled limit
  for (int i = 1; i <= N_; ++i) {
    // (End node B carrying a body, the consistent coupling: its inertia is the body's.)
    if (!Dynamic(i) || (dynamic_b_ && i == N_) || !(a.stab_w(i) > 0) || !(Mass(i) > 0)) continue;
    const double l = 0.5 * ((x.col(i) - x.col(i - 1)).norm() +
                            (i < N_ ? (x.col(i + 1) - x.col(i)).norm() : 0.0));  // [m]
    const double drag =
        2 * s * l * std::max(kn_ / (Mass(i) + Added(i)), kt_ / Mass(i));  // [1/s]
    const double w = a.stab_w(i), r0 = a.stab_rate(i), r = r0 + drag;
    const double ratio =
        (std::sqrt(w * w + 0.25 * r0 * r0) + 0.5 * r0) / (std::sqrt(w * w + 0.25 * r * r) + 0.5 * r);
    h = std::min(h, a.stab_h(i) * ratio);
  }
  if (!(substep > 0.9 * h)) return steps;
  return static_cast<int>(std::min(std::max(std::ceil(dt / (safety * h) - 1e-9), double(steps)), 1e9));
}

// ---------------------------------------------------------------------------------------------
// Initial shape

// The static shape of the discrete chain itself (the funicular polygon): its interior nodes
// carry their net weights W_k (along `down`) and its segments are straight, of the length
// their tension gives them, l_i = L0 (1 + T_i/EA). With H the horizontal tension (the same in
// every segment, no horizontal load) and V_i the vertical force of segment i on its node i,
// equilibrium at node k gives V_k = V_{k-1} + W_k, so
//   V_i = V_0 + sum_{k=1..i} W_k,   T_i = sqrt(H^2 + V_i^2),
//   sum_i l_i H / T_i = h,   sum_i l_i V_i / T_i = v   (h, v: horizontal and vertical span).
// The vertical sum rises monotonically with V_0 (bisection for each H), and the horizontal one
// with H (bisection on log H). This is the catenary's discrete counterpart (Irvine, "Cable
// Structures", 1981, sec. 1.2 for the polygon of a cable under point loads): the continuous
// catenary sampled at arc spacing L0 puts every chord short of L0 by ~L0^3 kappa^2/24, so
// every segment starts slack, the nodes fall and the line snaps taut at the first steps. On
// the polygon every segment starts at the tension that holds its nodes. A line without net
// weight (neutral, or no gravity) has no such shape: every slack shape is at rest, and the
// catenary stays. Returns false (x untouched) then, and where no bracket is found.
bool Tether::HangChain(const Vec3& A, const Vec3& eh, const Vec3& up, double h, double vspan,
                       bool elastic, Nodes x) const {
  const int n = N_;
  std::vector<double> W(n, 0.0);  // [N] W[i] = sum of the weights of nodes 1..i
  const Vec3 down = -up;
  bool weighted = true;
  for (int k = 1; k < n; ++k) {
    if (!(Weight(k).dot(down) > 0)) weighted = false;
  }
  if (!weighted || n < 2) return false;
  for (int i = 1; i < n; ++i) W[i] = W[i - 1] + Weight(i).dot(down);
  const double Wt = W[n - 1];  // [N] the load the polygon carries
  // The axial law at rest, T = EA strain (inextensible where `elastic` is false).
  const double flex = elastic && p_.EA > 0 ? 1.0 / p_.EA : 0.0;  // [1/N]
  auto span = [&](double H, double V0, double* dx, double* dz) {
    double sx = 0, sz = 0;
    for (int i = 0; i < n; ++i) {
      const double V = V0 + W[i], T = std::hypot(H, V), l = L0_ * (1 + T * flex);
      sx += l * H / T;
      sz += l * V / T;
    }
    *dx = sx;
    *dz = sz;
  };
  // V_0 that closes the vertical span for this H.
  auto vertical = [&](double H) {
    double lo = -Wt - H, hi = H, dx, dz;
    for (int it = 0; it < 200; ++it) {
      span(H, lo, &dx, &dz);
      if (dz < vspan) break;
      lo = 2 * lo - hi;
    }
    for (int it = 0; it < 200; ++it) {
      span(H, hi, &dx, &dz);
      if (dz > vspan) break;
      hi = 2 * hi - lo;
    }
    for (int it = 0; it < 200 && hi - lo > 1e-15 * (std::abs(lo) + std::abs(hi)); ++it) {
      const double mid = 0.5 * (lo + hi);
      span(H, mid, &dx, &dz);
      (dz < vspan ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
  };
  double llo = std::log(1e-12 * Wt), lhi = std::log(1e12 * Wt);
  auto horizontal = [&](double logH) {
    const double H = std::exp(logH), V0 = vertical(H);
    double dx, dz;
    span(H, V0, &dx, &dz);
    return dx - h;
  };
  if (!(horizontal(llo) < 0) || !(horizontal(lhi) > 0)) return false;
  for (int it = 0; it < 200 && lhi - llo > 1e-14; ++it) {
    const double mid = 0.5 * (llo + lhi);
    (horizontal(mid) < 0 ? llo : lhi) = mid;
  }
  const double H = std::exp(0.5 * (llo + lhi)), V0 = vertical(H);
  // A line too soft to hold its own weight within a quarter of max_strain (the fuzzer's seeds
  // 1575, 5320: w L / EA = 2.1 and 0.98) would start near the divergence check's limit and
  // cross it at the first step: it hangs as the inextensible polygon instead and stretches
  // from there, as it does from the catenary.
  if (flex > 0) {
    double strain = 0;
    for (int i = 0; i < n; ++i) strain = std::max(strain, std::hypot(H, V0 + W[i]) * flex);
    if (strain > 0.25 * p_.max_strain) return HangChain(A, eh, up, h, vspan, false, x);
  }
  Eigen::Matrix3Xd y(3, n);
  y.col(0) = A;
  for (int i = 0; i + 1 < n; ++i) {
    const double V = V0 + W[i], T = std::hypot(H, V), l = L0_ * (1 + T * flex);
    y.col(i + 1) = y.col(i) + l * (H * eh + V * up) / T;
  }
  if (!y.allFinite()) return false;
  x.leftCols(n) = y;
  return true;
}

void Tether::InitialShape(const Ends& ends, double* xp, double* vp) const {
  Nodes x(xp, 3, N_ + 1), v(vp, 3, N_ + 1);
  v.setZero();
  const Vec3 A = ends.a.pos;
  const double L = p_.length;
  // "Down" is the way the net weight pulls; without weight, gravity's way; without gravity, -z.
  Vec3 down = Weight(0).norm() > 0 ? Vec3(Weight(0).normalized())
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
    // A weighted line: the chain at rest (HangChain). Not where it dips below the seabed: the
    // path lying on the seabed (RestOnSeabed) is built for the inextensible length, and where
    // only the stretched chain reaches the seabed it has no grounded part (the fuzzer's seed
    // 4658: a node 4 m from the next); the catenary, clear of the seabed, is kept there.
    Eigen::Matrix3Xd chain = x;
    if (HangChain(A, eh, up, h, vspan, true, Nodes(chain.data(), 3, N_ + 1))) {
      chain.col(N_) = B;
      bool grounded = false;
      for (int k = 1; k < N_ && Has(kSeabed) && !grounded; ++k) {
        grounded = chain(2, k) < env_.water.SeabedHeight(chain(0, k), chain(1, k));
      }
      if (!grounded) {
        x = chain;
        v.col(0) = ends.a.vel;
        v.col(N_) = ends.b.vel;
        return;
      }
    }
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
      if (std::isfinite(f2) && std::abs(f2) <= 1e-9 * L) {
        walk(L2, true);
      } else {
        // The walk fails on a deep U (a chord's Newton step passes the bottom, slope <= 0) or
        // its secant leaves the bracket: every one of the 319 session-9 fuzz scenes of 2-244
        // segments with EAc that started compressed (chords 0.18-0.999 L0; 2 segments on a
        // span of a third of the length: 0.18 L0, EAc x 0.82 pushing the vehicle away at the
        // first step). Instead project the arc-spaced nodes onto chords of L0 (nonlinear
        // Gauss-Seidel, ProjectOntoChords above). The shape stays near the catenary (for 2
        // segments the middle node goes to the point a chord L0 from both ends below the
        // chord). Kept only if every chord ends within 1e-9 L0 of L0; otherwise the arc
        // spacing stays and the plugin refuses the compressed start at load
        // (plugin/plugin.cc, CompressedStart).
        Eigen::Matrix3Xd y = x;
        y.col(N_) = B;
        if (ProjectOntoChords(y, L0_, [](Vec3&) {})) {
          for (int k = 1; k < N_; ++k) x.col(k) = y.col(k);
        }
      }
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
// grounded part carries the horizontal tension a w unchanged, without friction). For an end at
// height h above the seabed, a catenary of parameter a (horizontal tension / weight per length)
// reaches the seabed after arc length s = sqrt(h^2 + 2 a h) and horizontal distance
// x = a acosh(1 + h/a) (Irvine, "Cable Structures", 1981, ch. 1); one a for both ends (the
// horizontal tension is continuous through a frictionless grounded part) solves
//   s_A(a) + s_B(a) + (H - x_A(a) - x_B(a)) = L,
// whose left side falls monotonically from h_A + h_B + H (a -> 0) to H (a -> inf), by bisection
// on log a. When even vertical drops leave length over (L > h_A + h_B + H), the ends hang
// straight down and the rest lies on the seabed in a sideways U of the extra length. This
// needs the net weight along -z (a horizontal seabed under ordinary gravity); otherwise (or
// for an end below the seabed, which the MuJoCo glue refuses at load) the nodes are only
// lifted onto the seabed. A free end hangs down to the seabed and lies along its site's axis.
//
// A geom seabed (seabed.h) is met approximately: the shape above for a flat seabed at the
// lower of the surface heights under the ends, with every point of it still below the surface
// lifted vertically onto it (which stretches the segments over rough ground a little, unless
// the nodes are placed by chords, below).
//
// Nodes go at arc spacing L0 along that path. The path has corners (where a catenary with a
// small a, or a vertical drop, meets the seabed; the U's turns; the ground's bumps), and a
// node next to a corner cuts it: its chord is shorter than L0 (an anchor 5 cm above the
// seabed with 0.2 m segments: 0.79 L0). A slack segment exerts no force, but with EAc it
// pushes (10.5 kN at EAc 5e4 there). So with EAc the nodes go a chord of exactly L0 apart
// along the path (on its straight parts the same as arc spacing), which needs a longer path:
// the path's length Ls is solved (bisection) so that node N lands on end B.
void Tether::RestOnSeabed(const Ends& ends, Nodes x) const {
  const Water& w = env_.water;
  double zb = w.SeabedHeight(ends.a.pos.x(), ends.a.pos.y());
  if (w.surface.declared() && !p_.free_end)
    zb = std::min(zb, w.SeabedHeight(ends.b.pos.x(), ends.b.pos.y()));
  if (RestOnLevel(ends, zb, x) || !w.surface.declared()) return;
  // Not replaced: lift the nodes of the shape as it is onto the surface's bumps.
  for (int k = 1; k <= N_; ++k) {
    if (k == N_ && !p_.free_end) break;
    x(2, k) = std::max(x(2, k), w.SeabedHeight(x(0, k), x(1, k)));
  }
}

bool Tether::RestOnLevel(const Ends& ends, double zb, Nodes x) const {
  const Water& w = env_.water;
  const double L = p_.length;
  bool below = false;
  for (int k = 0; k <= N_ && !below; ++k) below = x(2, k) < zb;
  if (!below) return false;
  const Vec3 g = Weight(0).norm() > 0 ? Weight(0) : env_.gravity;
  const bool vertical = g.norm() > 0 && -g.z() >= (1 - 1e-9) * g.norm();
  const Vec3& A = ends.a.pos;
  const Vec3 ez = Vec3::UnitZ();
  const double hA = A.z() - zb;
  // A point of the path on the seabed level zb, lifted onto the geom seabed's surface.
  auto ground = [&](Vec3 p) -> Vec3 {
    p.z() = std::max(p.z(), zb);
    if (w.surface.declared()) p.z() = std::max(p.z(), w.SeabedHeight(p.x(), p.y()));
    return p;
  };
  // Horizontal direction of the grounded part: towards B, else along site A's axis, else x.
  auto horizontal = [](const Vec3& d) {
    const Vec3 hd(d.x(), d.y(), 0);
    return hd.norm() > 1e-9 * std::max(1.0, d.norm()) ? Vec3(hd.normalized()) : Vec3::UnitX();
  };
  if (!vertical || hA < 0 || (!p_.free_end && ends.b.pos.z() < zb)) {
    for (int k = 0; k <= N_; ++k) x(2, k) = std::max(x(2, k), zb);
    if (w.surface.declared()) {
      for (int k = 1; k <= N_; ++k) {
        if (k == N_ && !p_.free_end) break;
        x(2, k) = std::max(x(2, k), w.SeabedHeight(x(0, k), x(1, k)));
      }
    }
    return true;
  }
  const bool chords = Has(kCompression);
  const bool flat = !w.surface.declared();
  // Places node k (k = first..last) a chord L0 from node k-1 at the first point of the path
  // beyond node k-1's arc position (path(s): a point of the path at arc position s of the flat
  // path, s <= end). Returns the number of nodes placed (fewer when the path ran out).
  auto walk = [&](auto&& path, double end, int first, int last) -> int {
    double s = 0;
    for (int k = first; k <= last; ++k) {
      const Vec3 c = x.col(k - 1);
      const double ds = 0.25 * L0_;
      // March to a point at least L0 away, then solve back for the first crossing. A chord is
      // at most its arc, so on a flat path the march starts one L0 of arc on; a path lifted
      // onto a geom seabed is longer than its flat arc, so there it starts at node k-1.
      double lo = flat ? std::min(s + L0_, end) : s, hi = lo;
      while ((path(hi) - c).norm() < L0_) {
        if (hi >= end) return k - first;
        lo = hi;
        hi = std::min(hi + ds, end);
      }
      // Regula falsi (Illinois) on |path(s) - c| - L0, bisecting outside the bracket.
      double glo = (path(lo) - c).norm() - L0_, ghi = (path(hi) - c).norm() - L0_;
      int side = 0;
      for (int it = 0; it < 200 && hi - lo > 1e-15 * (hi + L0_); ++it) {
        double mid = (lo * ghi - hi * glo) / (ghi - glo);
        if (!(mid > lo && mid < hi)) mid = 0.5 * (lo + hi);
        const double gm = (path(mid) - c).norm() - L0_;
        if (std::abs(gm) <= 1e-14 * L0_) {
          hi = mid;
          break;
        }
        if (gm < 0) {
          lo = mid;
          glo = gm;
          if (side == -1) ghi *= 0.5;
          side = -1;
        } else {
          hi = mid;
          ghi = gm;
          if (side == 1) glo *= 0.5;
          side = 1;
        }
      }
      s = hi;
      x.col(k) = path(s);
    }
    return last - first + 1;
  };
  const Vec3 A0(A.x(), A.y(), zb);  // end A projected on the seabed
  if (p_.free_end) {
    const Vec3 eh = horizontal(ends.a.axis);
    auto path = [&](double s) {
      return ground(s <= hA ? Vec3(A - s * ez) : Vec3(A0 + (s - hA) * eh));
    };
    for (int k = 0; k <= N_; ++k) x.col(k) = path(L * k / N_);
    x.col(0) = A;
    // The path goes on along eh without end: the walk always places every node.
    if (chords) walk(path, 1e3 * L + 1e3, 1, N_);
    return true;
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
  // The flat path of length Ls: catenary parameter a, hanging lengths, U detour, grounded run.
  struct Path {
    double Ls, a = 0, sA, sB, xA = 0, xB = 0, detour = 0, run;
  };
  auto make = [&](double Ls) {
    Path p;
    p.Ls = Ls;
    p.sA = hA;
    p.sB = hB;
    if (Ls >= hA + hB + H) {
      p.detour = 0.5 * (Ls - hA - hB - H);
    } else {
      double lo = std::log(1e-12 * L), hi = std::log(1e12 * L);
      for (int it = 0; it < 200; ++it) {
        const double mid = 0.5 * (lo + hi);
        hang(std::exp(mid), hA, &p.sA, &p.xA);
        hang(std::exp(mid), hB, &p.sB, &p.xB);
        (p.sA + p.sB + H - p.xA - p.xB > Ls ? lo : hi) = mid;
      }
      p.a = std::exp(0.5 * (lo + hi));
      hang(p.a, hA, &p.sA, &p.xA);
      hang(p.a, hB, &p.sB, &p.xB);
    }
    p.run = std::max(0.0, H - p.xA - p.xB);  // grounded length along eh
    return p;
  };
  // The point at arc position s (0 <= s <= Ls) of path p, lifted onto the ground.
  auto point = [&](const Path& p, double s) -> Vec3 {
    const Vec3 TA = A0 + p.xA * eh, TB = B0 - p.xB * eh;  // touchdown points
    // A point of a hanging part at arc length sigma from its touchdown point T, along dir.
    auto hanging = [&](const Vec3& T, const Vec3& dir, double sigma) -> Vec3 {
      const double u = p.a > 0 ? p.a * std::asinh(sigma / p.a) : 0;
      return T + u * dir + (std::sqrt(p.a * p.a + sigma * sigma) - p.a) * ez;
    };
    if (s <= p.sA) return ground(hanging(TA, -eh, p.sA - s));
    if (s >= p.Ls - p.sB) return ground(hanging(TB, eh, std::min(s, p.Ls) - (p.Ls - p.sB)));
    const double r = s - p.sA;  // along the grounded part: out by `detour`, along, back
    const double d = p.detour, run = p.run;
    return ground(r < d         ? Vec3(TA + r * en)
                  : r < d + run ? Vec3(TA + d * en + (r - d) * eh)
                                : Vec3(TA + (2 * d + run - r) * en + run * eh));
  };
  const Path p = make(L);
  for (int k = 1; k < N_; ++k) x.col(k) = point(p, L * k / N_);
  x.col(0) = A;
  x.col(N_) = B;
  if (!chords) return true;
  // Chords of L0: F(Ls) = |B - node N-1| - L0 after walking nodes 1..N-1 along the path of
  // length Ls (-L0 per node the path ran short of), which grows with Ls; F(L) <= 0 on a flat
  // path (each chord takes at least L0 of arc). Bracket, then regula falsi; keep the arc
  // spacing if that fails.
  auto F = [&](double Ls) {
    const Path q = make(Ls);
    const int placed = walk([&](double s) { return point(q, s); }, Ls, 1, N_ - 1);
    if (placed < N_ - 1) return -L0_ * (N_ - placed);
    return (B - x.col(N_ - 1)).norm() - L0_;
  };
  double lo = L, hi = L, flo = F(L), fhi = flo;
  for (double step = L0_; fhi < 0 && step < 1e3 * L; step *= 2) fhi = F(hi = lo + step);
  for (double step = L0_; flo > 0 && step < L; step *= 2) flo = F(lo = hi - step);
  bool ok = flo <= 0 && fhi >= 0;
  // Regula falsi with the Illinois modification (F is close to linear in Ls: a few steps),
  // bisecting when the interpolated point falls outside the bracket.
  double glo = flo, ghi = fhi;  // the values interpolated (halved on a stuck side)
  int side = 0;
  for (int it = 0; ok && it < 200 && std::min(-flo, fhi) > 1e-12 * L0_ && hi - lo > 1e-15 * L;
       ++it) {
    double mid = (lo * ghi - hi * glo) / (ghi - glo);
    if (!(mid > lo && mid < hi)) mid = 0.5 * (lo + hi);
    const double fm = F(mid);
    if (fm < 0) {
      lo = mid;
      flo = glo = fm;
      if (side == -1) ghi *= 0.5;
      side = -1;
    } else {
      hi = mid;
      fhi = ghi = fm;
      if (side == 1) glo *= 0.5;
      side = 1;
    }
  }
  ok = ok && std::min(-flo, fhi) <= 1e-9 * L0_;
  if (ok) {
    F(-flo < fhi ? lo : hi);
  } else {
    // No bracket (e.g. 2 segments whose one interior node cannot be a chord L0 from both ends
    // on this path): the arc spacing, projected onto chords of L0 above the seabed
    // (ProjectOntoChords; 15 session-9 fuzz scenes of 2-7 segments that started on the seabed
    // at chords of 0.54-0.83 L0 before); kept as it is if that does not converge (the plugin
    // then refuses it if compressed).
    for (int k = 1; k < N_; ++k) x.col(k) = point(p, L * k / N_);
    // A node pressed onto the seabed below the ends' vertical plane can lengthen its chords
    // only sideways, where the projection's corrections cancel: it stalls (fuzz seed 7095, 2
    // segments: stuck at chords 0.79 L0 with the seabed at full precision, converged with it
    // rounded to 10 digits). Then again from the nodes nudged sideways by L0/100 (along en,
    // the side of the U).
    for (const double nudge : {0.0, 0.01 * L0_}) {
      Eigen::Matrix3Xd y = x;
      y.col(0) = A;
      y.col(N_) = B;
      for (int k = 1; k < N_; ++k) y.col(k) += nudge * en;
      if (ProjectOntoChords(y, L0_, [&](Vec3& q) { q = ground(q); })) {
        for (int k = 1; k < N_; ++k) x.col(k) = y.col(k);
        break;
      }
    }
  }
  x.col(0) = A;
  x.col(N_) = B;
  return true;
}

}  // namespace mjtether

namespace mjtether {
using namespace detail;

// ---------------------------------------------------------------------------------------------
// Static start

// Pseudo-transient continuation (Kelley & Keyes, SIAM J. Numer. Anal. 35, 1998) on the nodal
// equilibrium f(x, 0) = 0 (f: every force on a node of the still tether: weight, buoyancy,
// EA/EAc/EI, the current's drag on v = 0, the seabed). Each iteration is one backward-Euler
// step of the implicit integrator (ImplicitStepAdaptive, with its Newton iteration, line
// search and halvings) from rest,
//   M (v+ - 0) = h f(x + h v+, v+),   x+ = x + h v+,
// after which v is reset to zero: (M/h^2 + K + C/h) dx = f(x) to first order (K the stiffness,
// C the damping and drag derivatives), a Newton step on f = 0 regularised by the mass. Small h:
// a damped descent (each step moves a node by h^2 f/m); large h: Newton's method. The pseudo
// step h grows by 2 after every step that succeeded without halving or stall and whose largest
// displacement did not grow, and falls by 4 otherwise (a step that failed is undone), between
// h_min = 1e-4 s and h_max = 1e4 s. Converged when, at a pseudo step of at least
// h_conv = 10 sqrt(L/g) (ten times the pendulum time of the whole line, so that the mass term
// M/h^2 is at most 1% of the geometric stiffness of a hanging line), the largest displacement of
// a step is below tolerance x L: with h that large, the step is the Newton correction, so the
// displacement is the distance to equilibrium. A fixed point x+ = x has v+ = 0 and so
// f(x, 0) = 0 exactly: the relaxation changes nothing but the start.
StaticResult Tether::RelaxToStatic(const Ends& ends, double* xp, double* vp, double* work,
                                   const StaticOptions& options) const {
  const int n = N_ + 1;
  Nodes x(xp, 3, n), v(vp, 3, n);
  StaticResult result;
  Tether t = *this;
  t.p_.integrator = Integrator::kImplicit;
  t.p_.substeps = 0;
  t.p_.max_step = 0;
  t.dynamic_b_ = false;
  Ends held = ends;
  held.a.vel.setZero();
  held.b.vel.setZero();
  held.time = 0;
  held.contacts = nullptr;
  held.body_b = nullptr;
  const double g = env_.gravity.norm();
  const double L = p_.length;
  const double h_min = 1e-4, h_max = 1e4;  // [s]
  const double h_conv = g > 0 ? std::min(h_max, 10 * std::sqrt(L / g)) : 10.0;  // [s]
  double h = g > 0 ? std::min(1.0, 0.1 * std::sqrt(L / g)) : 0.1;  // [s]
  Eigen::Matrix3Xd saved(3, n);
  Work w(work, N_);
  // [N] the load the line carries: its net weight and the current's drag on all of it at
  // rest, sum_i (|w_i| + kn |U|^2 l_i) (the residual's scale).
  double load = 0;
  for (int i = 0; i < n; ++i) {
    const double U = Has(kCurrent) ? env_.water.MaxCurrentSpeed() : 0;
    load += Weight(i).norm() + kn_ * U * U * Share(i);
  }
  result.load = load;
  // The largest net force on a dynamic node of x at rest [N], and that node.
  auto residual = [&](int* node) {
    v.setZero();
    t.PlaceEnds(held, x, v);
    t.ComputeForces(xp, vp, held, w.f, nullptr, work);
    const ConstNodes f(w.f, 3, n);
    double r = 0;
    for (int i = 0; i < n; ++i) {
      if (!t.Dynamic(i)) continue;
      const double fi = f.col(i).norm();
      if (!(fi <= r)) r = fi, *node = i;
    }
    return r;
  };
  residual(&result.node);  // the node to name if the first step fails
  for (int it = 0; it < options.max_iterations; ++it) {
    result.iterations = it + 1;
    saved = x;
    v.setZero();
    const StepStatus s = t.Advance(xp, vp, held, held, h, work);
    const double d = (x - saved).colwise().norm().maxCoeff();  // [m]
    result.final_step = h;
    if (!s.ok || s.stalled_steps > 0 || !std::isfinite(d)) {
      x = saved;  // undo
      if (h <= h_min) {
        result.ok = s.ok;
        result.reason = s.ok ? "" : s.reason;
        break;
      }
      h = std::max(h_min, h / 4);
      continue;
    }
    result.displacement = d;
    int node = -1;
    const double r_new = residual(&node);
    // (A residual a thousand times below the force tolerance is equilibrium at any pseudo step.)
    if (d <= options.tolerance * L && r_new <= options.force_tolerance * load &&
        (h >= h_conv || r_new <= 1e-3 * options.force_tolerance * load)) {
      result.converged = true;
      break;
    }
    // The step doubles after a step taken whole and halves after one the implicit step had to
    // split (ImplicitStepAdaptive).
    h = std::clamp(s.halvings == 0 ? 2 * h : 0.5 * h, h_min, h_max);
  }
  v.setZero();
  t.PlaceEnds(held, x, v);
  result.residual = residual(&result.node);
  if (result.ok) {
    StepStatus check;
    t.Check(ConstNodes(xp, 3, n), ConstNodes(vp, 3, n), held, held, &check);
    if (!check.ok) {
      result.ok = false;
      result.reason = check.reason;
      result.node = check.node;
    }
  }
  v.col(0) = ends.a.vel;
  if (!p_.free_end) v.col(N_) = ends.b.vel;
  return result;
}

}  // namespace mjtether
