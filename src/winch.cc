// Variable deployed length for a tether with a winch at end A (docs/winch.md).
//
// Scheme: the state is allocated for the longest deployment (WHOI Cable's pre-allocated nodes);
// every deployed segment has the nominal rest length L0 except the winch segment at the drum,
// whose rest length r follows the payout continuously (r' = payout speed) between 0.5 and
// 1.5 L0; past 1.5 L0 a node is inserted at the drum, below 0.5 L0 one is removed (OrcaFlex's
// variable-segment winch, with its bounds). The lumped masses follow r at every step, so the
// deployed mass is mu L at every step.
#include <algorithm>
#include <cmath>

#include "detail/work.h"
#include "tether.h"

namespace mjtether {
using namespace detail;

Tether Tether::Deployed(int first, double rest, double speed) const {
  Tether d = *this;  // shares the node arrays and the window: no allocation
  d.N_ = N_ - first;
  d.mass_ += first;
  d.added_ += first;
  d.inv_mass_ += first;
  d.inv_mass_normal_ += first;
  d.share_ += first;
  d.weight_ += 3 * first;
  d.head_ = 2;
  d.rest_ = rest;
  d.speed_ = speed;
  d.p_.segments = d.N_;
  d.p_.length = (d.N_ - 1) * L0_ + rest;
  // Masses: nodes 0 and 1 lump half the winch segment each, node 1 also half the next segment
  // (if any). Loads (weight, buoyancy; drag in DragLength): the drum-exit node takes L0 of the
  // winch segment, node 1 the rest, r - L0/2 with its half of the next segment. The totals are
  // the same (r + L0/2), but node 1's load is then 0 when it is inserted (r = 0.5 L0 after the
  // insertion) and when it is removed, and node 0's is L0 throughout: the loads at the drum are
  // continuous across re-discretisations, so an inserted node, placed on the straight winch
  // segment, is in equilibrium and the drum force does not ring (docs/winch.md). With node 1
  // the far end (one segment), the plain halves.
  const double rho = env_.wet ? env_.water.density : 0;
  const double share[2] = {0.5 * rest, 0.5 * rest + (d.N_ >= 2 ? 0.5 * L0_ : 0)};
  const double load[2] = {d.N_ >= 2 ? L0_ : share[0], d.N_ >= 2 ? rest - 0.5 * L0_ : share[1]};
  for (int i = 0; i < 2; ++i) {
    const double m = p_.mass_per_length * share[i];
    const double ma = Has(kAddedMass) ? p_.Can * rho * area_ * share[i] : 0;
    d.head_share_[i] = share[i];
    d.head_mass_[i] = m;
    d.head_added_[i] = ma;
    d.head_inv_mass_[i] = 1 / m;
    d.head_inv_mass_normal_[i] = 1 / (m + ma);
    double w = 0;
    if (Has(kWeight)) w += p_.mass_per_length * load[i];
    if (Has(kBuoyancy)) w -= rho * area_ * load[i];
    d.head_weight_[i] = w * env_.gravity;
  }
  return d;
}

// Insertion (r > 1.5 L0): the new node goes on the winch segment at L0 from node first+1, so
// that the segment it closes has the rest length L0 and the winch segment keeps r - L0, both
// at the strain the winch segment had (no tension jump). Its position and velocity are the
// linear interpolation, at that point, of the segment's ends, with the drum end moving as the
// material that leaves the drum, u_e = v_drum + (l/r) r' t (the payout, stretched, along the
// segment's tangent t): the strain rate of both new segments is then that of the winch
// segment, and the momentum of the deployed tether, sum m_i v_i with the drum-exit node's
// lumped mass moving at u_e, is unchanged exactly: with m_exit = mu r/2 and m_1 = mu (r+L0)/2
// before, mu (r-L0)/2, mu r/2 and mu L0 (mu L0/2 at a last node) after, the interpolation
// weights are what makes the sums equal (docs/winch.md works it out).
//
// Removal (r < 0.5 L0): node first+1 goes, the winch segment reaches node first+2 with rest
// r + L0, and node first+2 takes the removed node's momentum: its velocity is set so that the
// momentum (same definition) is unchanged, v2' = (m_exit u_e + m1 v1 + m2 v2 - m_exit' u_e')
// / m2'. (Removing a node is inelastic: the relative motion of the two merged nodes is lost.)
int Tether::Regrid(double* xp, double* vp, const Ends& e, Payout* p) const {
  const int n = N_ + 1;
  Nodes x(xp, 3, n), v(vp, 3, n);
  const int f = p->first;
  const double r = p->rest, mu = p_.mass_per_length;
  const Vec3 d = e.a.pos, vd = e.a.vel;
  // Velocity of the material leaving the drum along the segment from the drum to node k.
  auto exit_velocity = [&](int k, double rest) -> Vec3 {
    const Vec3 chord = x.col(k) - d;
    const double l = chord.norm();
    if (!(l > kMinLengthRatio * L0_)) return vd;
    return vd + (p->speed / rest) * chord;  // (l/r) r' t
  };
  if (r > 1.5 * L0_ && f > 0) {
    const Vec3 ue = exit_velocity(f + 1, r);
    const double a = L0_ / r;
    const Vec3 x1 = x.col(f + 1), v1 = v.col(f + 1);
    // Position: the plain fraction of the chord. Both new segments have the winch segment's
    // strain, and the new node's load is 0 (Deployed: node 1's load r - L0/2 at r = 0.5 L0), so
    // it is in equilibrium on the straight segment and no force changes.
    const Vec3 chord = d - x1;
    const double frac = a;  // of the chord, from node first+1 towards the drum
    x.col(f) = x1 + frac * chord;
    v.col(f) = v1 + a * (ue - v1);
    x.col(f - 1) = d;
    v.col(f - 1) = vd;
    p->first = f - 1;
    p->rest = r - L0_;
    return 1;
  }
  if (r < 0.5 * L0_ && f + 2 <= N_) {
    const Vec3 ue = exit_velocity(f + 1, r);
    const Vec3 ue2 = exit_velocity(f + 2, r + L0_);
    const double m_exit = 0.5 * mu * r, m1 = 0.5 * mu * (r + L0_);
    const double m2 = mu * share_[f + 2];  // the dry lumped mass of node f+2 before
    const double m_exit2 = 0.5 * mu * (r + L0_), m2b = m2 + 0.5 * mu * r;
    if (f + 2 < N_ || p_.free_end) {
      v.col(f + 2) =
          (m_exit * ue + m1 * v.col(f + 1) + m2 * v.col(f + 2) - m_exit2 * ue2) / m2b;
    }
    x.col(f + 1) = d;
    v.col(f + 1) = vd;
    p->first = f + 1;
    p->rest = r + L0_;
    return -1;
  }
  return 0;
}

// Series springs from end B towards the drum, in 3-D: node i resists a displacement over the
// step with G_i = (m_i I + ma_i (I - t t^T))/he^2 (the implicit solve's inertia term, he its
// step; added mass normal to the line), segment j with its tangent stiffness
// K_j = (EA/L0 + damping/(L0 he)) t t^T + (T/l)(I - t t^T) (axial and geometric; EAc/L0 axially
// when compressed, 0 when slack). What segment j passes on towards the drum, with S behind it
// (node j+1's G plus what segment j+1 passes on), is K_j - K_j (K_j + S)^-1 K_j (the two in
// series); a held end B passes K_j. A payout d at the drum lengthens segment 0's rest length,
// as a drum moved by d towards node 1, so the drum tension drops by t^T P_0 t d, d = v dt. The
// geometric term lets a curved line take part of the pull sideways over the step. Left out:
// drag, bending, contact and the vehicle's mass (a body at end B is held). On world seed 861
// (bdf2, a hanging 34 m line of EA 1.4e7) the vehicle-end tension then converges at first
// order as the step halves (9.4, 10.5, 11.6 N at 4, 2, 1 ms against 11.8 at 0.2 ms), where the
// whole step's inertia (he = dt) rang by 1-3 N per step and the straight 1-D chain lagged.
double Tether::DrumImpedance(const double* xp, const Payout& p, double dt) const {
  if (!(dt > 0)) return 0;
  const Tether view = Deployed(p.first, p.rest, p.speed);
  const int n = view.N_;
  const ConstNodes x(xp + 3 * p.first, 3, n + 1);
  // The step the integrator's implicit solve takes (the inertia and damping it sees): bdf2's
  // is a backward-Euler step of 2 dt/3, implicit2's stages are of (1 - 1/sqrt 2) dt each.
  // explicit and rk4 follow the true dynamics over dt, which backward Euler's stands in for.
  // bdf2 and implicit2 on an overdamped segment mode take backward Euler's (StepsAsBackwardEuler).
  const double he = view.StepsAsBackwardEuler()                    ? dt
                    : view.p_.integrator == Integrator::kBdf2        ? dt * 2 / 3
                    : view.p_.integrator == Integrator::kImplicit2 ? dt * 0.29289321881345248
                                                                   : dt;
  const double inv_dt2 = 1 / (he * he);
  const bool added = view.Has(kAddedMass);
  const Mat3 I = Mat3::Identity();
  // Node i's inertia over the step, with tt = t t^T of a segment beside it.
  auto inertia = [&](int i, const Mat3& tt) -> Mat3 {
    const double ma = added ? view.Added(i) : 0.0;
    return inv_dt2 * ((view.Mass(i) + ma) * I - ma * tt);
  };
  const bool held = !view.p_.free_end;  // end B: a body or fixed (infinitely stiff over the step)
  Mat3 S = Mat3::Zero(), P = Mat3::Zero();
  Vec3 t0 = Vec3::UnitX();
  for (int j = n - 1; j >= 0; --j) {
    const Vec3 chord = x.col(j + 1) - x.col(j);
    const double l = chord.norm(), L0 = view.rest_length(j);
    if (!(l > kMinLengthRatio * L0_)) return 0;  // coincident nodes: no direction to pay along
    const Vec3 t = chord / l;
    const Mat3 tt = t * t.transpose();
    double axial = 0, T = 0;
    if (l > L0) {
      axial = view.p_.EA / L0 + view.p_.damping / (L0 * he);
      T = view.p_.EA * (l - L0) / L0;
    } else if (view.Has(kCompression)) {
      axial = view.p_.EAc / L0 + view.p_.damping / (L0 * he);
    }
    const double c = T / l;  // geometric stiffness normal to the segment
    if (j == n - 1 && !held) S = inertia(n, tt);
    if (axial == 0 && c == 0) {
      P.setZero();  // a slack segment passes nothing on
    } else {
      const Mat3 K = c * I + (axial - c) * tt;
      P = held && j == n - 1 ? K : Mat3(K - K * ((K + S).inverse() * K));
    }
    t0 = t;
    if (j > 0) S = inertia(j, tt) + P;  // node j, as segment j-1 sees it
  }
  const double Z = dt * t0.dot(P * t0);
  return std::isfinite(Z) && Z > 0 ? Z : 0;
}

// Without a caller's `history` a bdf2 tether's steps here are backward Euler.
StepStatus Tether::Advance(double* xp, double* vp, const Ends& from, const Ends& to, double dt,
                           double* work, Payout* p, double* history) const {
  if (!p) return Advance(xp, vp, from, to, dt, work, history);
  StepStatus status;
  const int steps = SubstepsFor(dt);
  if (steps == 0) return status;
  const double h = dt / steps;
  // bdf2's history over the whole allocation (as x and v), viewed from the drum exit like
  // the state. Without a caller's history the steps are backward Euler (the views' scratch
  // layouts differ from the whole tether's, so the workspace cannot hold one).
  const int n = N_ + 1;
  double unused = 0;
  double* hh = history ? history : &unused;
  double* hx = history ? history + 1 : nullptr;
  double* hv = history ? history + 1 + 3 * n : nullptr;
  Ends now = from;
  now.rest = p->rest;
  // explicit with a body at end B: end node B along MuJoCo's Euler path, as in Advance
  // without a winch (session 27).
  const bool euler_path = ExplicitWithBody(from);
  Eigen::Map<Vec3> x_b(xp + 3 * N_);
  const Eigen::Map<const Vec3> v_b(vp + 3 * N_);
  const Vec3 x_b0 = x_b;
  for (int k = 0; k < steps; ++k) {
    Ends next = k + 1 == steps ? to : Interpolate(from, to, dt, double(k + 1) / steps);
    next.rest = now.rest + p->speed * h;
    const Tether view = Deployed(p->first, now.rest, p->speed);
    const int na = view.nodes();
    Nodes x(xp + 3 * p->first, 3, na), v(vp + 3 * p->first, 3, na);
    view.PlaceEnds(now, x, v);
    const History hist{hh, history ? hx + 3 * p->first : nullptr,
                       history ? hv + 3 * p->first : nullptr};
    view.Step(x, v, now, next, h, work, &status, history ? &hist : nullptr);
    if (euler_path) x_b = x_b0 + ((k + 1) * h) * v_b;
    // Work of the end forces over the step, as Advance without a winch counts it (the
    // integrator's last force evaluation along the end's displacement): the coupling's work
    // balance reads it. Without it a winch tether's balance saw none of the tether's work and
    // stopped explicit and rk4 runs with a "coupling chatter" at omega h 0.05-0.8 (the scene
    // fuzzer's world draw, session 15: seeds 105, 276, 300, 489, 560, 756).
    const ConstNodes f(Work(work, view.N_).f, 3, na);
    status.work_a += f.col(0).dot(next.a.pos - now.a.pos);
    status.end_impulse_a += h * Vec3(f.col(0));
    status.end_impulse_b += h * Vec3(f.col(na - 1));
    // explicit with a body at end B (the consistent coupling): end A's impulse over the
    // substeps, as Advance without a winch sums it (the plugin reports its mean).
    if (ExplicitWithBody(next)) {
      status.impulse_a += h * Vec3(f.col(0));
      status.has_impulse_a = true;
    }
    if (!view.DynamicB()) status.work_b += f.col(na - 1).dot(next.b.pos - now.b.pos);
    p->rest = next.rest;
    // At most one node per step: a payout of more than L0/2 per tether step is refused at load.
    // A node inserted or removed restarts bdf2 (its history is not remapped: the new node
    // has none, and a removal changes a neighbour's velocity); docs/numerics.md.
    if (Regrid(xp, vp, next, p) != 0) *hh = 0;
    now = next;
    now.rest = p->rest;
  }
  const Tether view = Deployed(p->first, p->rest, p->speed);
  const int na = view.nodes();
  Ends last = to;
  last.rest = p->rest;
  view.Check(ConstNodes(xp + 3 * p->first, 3, na), ConstNodes(vp + 3 * p->first, 3, na), from,
             last, &status);
  if (!status.ok) status.node += p->first;
  return status;
}

}  // namespace mjtether
