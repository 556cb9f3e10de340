#include "tether.h"

#include <algorithm>
#include <cmath>
#include <type_traits>

#include "detail/work.h"

namespace mjtether {
using namespace detail;

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
                      Nodes f, const Start* start, double rest0) const {
  (void)x;
  const double inv_L0 = 1 / L0_;  // [1/m]
  const double L0sq = L0_ * L0_;
  const bool engaging = start && Has(kDamping);
  if (head_) {
    // The winch segment, rest length r = rest0 growing at the payout speed s: strain
    // l/r - 1, strain rate d(l/r)/dt = t.(dv - (l/r) s t)/r: the velocity difference
    // relative to the material leaving the drum, (l/r) s along t (docs/winch.md). The rate
    // goes to AxialForce as L0 deps/dt.
    double engage_h = 0;
    const double r = rest0, lr = l[0] / r;
    Vec3 dv = (L0_ / r) * (Vec3(v.col(1) - v.col(0)) - (lr * speed_) * t.col(0));
    if (engaging) {
      const double rs = std::max(r - speed_ * start->h, 1e-9 * L0_);  // rest at the start
      const double es = (start->at(1) - start->at(0)).norm() / rs - 1;
      const double e = lr - 1;
      if (e > 0 ? es <= 0 : e < 0 && es >= 0) engage_h = start->h;
      if (start->discrete) {
        const double from = e > 0 ? std::max(es, 0.0) : std::min(es, 0.0);
        dv = t.col(0) * (L0_ * (e - from) / start->h);
        engage_h = 0;
      }
    }
    const double Tj = AxialForce(lr - 1, t.col(0), dv, engage_h);
    T[0] = std::max(Tj, 0.0);
    f.col(0) += Tj * t.col(0);
    f.col(1) -= Tj * t.col(0);
  }
  for (int j = head_ ? 1 : 0; j < N_; ++j) {
    double engage_h = 0;
    Vec3 dv = v.col(j + 1) - v.col(j);
    if (engaging) {
      // On the other side of L0 at the start of the step than now?
      const double ls2 = (start->at(j + 1) - start->at(j)).squaredNorm();
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
    M.col(i) = moment(t.col(i - 1), t.col(i), CurvatureWeight(i));
  }
  if (Has(kClamp) && p_.clamp_a) {
    M.col(0) = moment(ends.a.axis, t.col(0), 0.5 * rest_length(0));
  }
  if (Has(kClamp) && p_.clamp_b) {
    M.col(N_) = moment(t.col(N_ - 1), ends.b.axis, 0.5 * rest_length(N_ - 1));
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
//   f_n = 1/2 rho Cdn d |vn| vn,   f_t = 1/2 rho Cdt pi d |vt| vt,   v_r = u(z_i) - v_i.
// With a current profile each node sees the current at its own height z_i.
void Tether::AddDrag(ConstNodes x, ConstNodes v, ConstNodes q, const double* l, Nodes f,
                     double* vn_norm) const {
  const bool current = Has(kCurrent);
  const bool profile = current && !env_.water.profile.empty();
  const Vec3 u0 = current ? env_.water.current : Vec3::Zero();
  // The loop compiled twice, with and without keeping |v_n|: the explicit step's force
  // evaluation (no vn) keeps the code it had.
  auto nodes = [&](auto keep) {
    for (int i = 0; i <= N_; ++i) {
      const double li = DragLength(i, l);
      const Vec3 u = profile ? env_.water.profile.At(x(2, i)) : u0;
      const Vec3 vr = u - v.col(i);
      const Vec3 qi = q.col(i);
      const double vq = vr.dot(qi);  // |vt| = |vq|: q is a unit vector
      const Vec3 vn = vr - vq * qi;
      const double vnn = vn.norm();
      if constexpr (decltype(keep)::value) vn_norm[i] = vnn;
      f.col(i) += li * (kn_ * vnn * vn + (kt_ * std::abs(vq) * vq) * qi);
    }
  };
  if (vn_norm) {
    nodes(std::true_type{});
  } else {
    nodes(std::false_type{});
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
  if (w.surface.declared()) {
    AddSeabedSurface(x, v, q, f, start);
    return;
  }
  for (int i = 0; i <= N_; ++i) {
    const double pen = w.seabed - x(2, i);
    if (pen <= 0) continue;
    double sink = -v(2, i);  // [m/s]
    if (start && start->x(2, i) >= w.seabed) sink = std::min(sink, pen / start->h);
    const double N = std::max(0.0, Share(i) * (seabed_k_ * pen + seabed_c_ * sink));
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

// Seabed that is a geom (a tilted plane or a height field, seabed.h): the same law with the
// surface's height zs and upward normal n under the node. The penetration is the distance to
// the surface's tangent plane, pen = (zs - z) n_z (exact for a plane and for the height
// field's triangle under the node); N_i = max(0, k l_i pen - c l_i v.n) acts along n, and the
// friction acts on the velocity in the tangent plane, split along and across the tether's
// tangent projected on that plane.
void Tether::AddSeabedSurface(ConstNodes x, ConstNodes v, ConstNodes q, Nodes f,
                              const Start* start) const {
  const Water& w = env_.water;
  for (int i = 0; i <= N_; ++i) {
    double zs;
    Vec3 n;
    w.surface.Under(x(0, i), x(1, i), &zs, &n);
    const double pen = (zs - x(2, i)) * n.z();
    if (pen <= 0) continue;
    double sink = -v.col(i).dot(n);  // [m/s]
    if (start) {
      // Above the surface at the step's start: the sink rate limited to pen/h (see AddSeabed).
      double zs0;
      Vec3 n0;
      w.surface.Under(start->x(0, i), start->x(1, i), &zs0, &n0);
      if (start->x(2, i) >= zs0) sink = std::min(sink, pen / start->h);
    }
    const double Nk = std::max(0.0, Share(i) * (seabed_k_ * pen + seabed_c_ * sink));
    f.col(i) += Nk * n;
    if (w.seabed_friction == 0 && w.seabed_friction_axial == 0) continue;
    Vec3 qh = q.col(i) - q.col(i).dot(n) * n;
    qh = qh.norm() > 1e-12 ? Vec3(qh.normalized()) : Vec3::Zero();
    const Vec3 vh = v.col(i) - v.col(i).dot(n) * n;
    const Vec3 va = vh.dot(qh) * qh, vc = vh - va;
    const double eps = w.seabed_friction_speed;
    const double mu_a = w.seabed_friction_axial, mu_c = w.seabed_friction;
    if (va.norm() > 0) f.col(i) -= (mu_a * Nk * std::tanh(va.norm() / eps) / va.norm()) * va;
    if (vc.norm() > 0) f.col(i) -= (mu_c * Nk * std::tanh(vc.norm() / eps) / vc.norm()) * vc;
  }
}

// Contact with another body's surface (contact.h): the plane of candidate c against the whole
// segment j. Along the segment the gap is linear, g(s) = (1 - s) g_a + s g_b, with
// g_a = n.(x_j - p(t)) - d/2 and g_b the same at x_{j+1}; the penalty is k per unit length on
// the penetration -g(s) where positive, integrated over the segment with the linear shape
// functions (the gradient of the energy k L0/2 int max(0, -g)^2 ds, so it is conservative
// while the plane holds):
//   F_el = k L0 P0 n, shared (P0 - P1), P1 to the two nodes,
//   P0 = int max(0, -g) ds, P1 = int s max(0, -g) ds,
// i.e. acting at sbar = P1/P0. (Taking the force at the candidate's fixed fraction c.s, the
// deepest point when it was found, instead pumped energy into a sliding or vibrating tether:
// each new candidate starts at the deepest penetration, and the force jumped from node to
// node as segments rocked; a tether wound on a pile by an orbiting vehicle reached 5 J of
// kinetic energy with explicit and rk4, tests/wrap_test.cc.) Damping on the normal approach
// speed at sbar over the length in contact, never pulling:
//   N = max(0, L0 (k P0 - c lambda vn)),  vn = n.(v_sbar - v_b),
// and Coulomb friction on the slip velocity vt = (v_sbar - v_b) - vn n, smoothed like the
// seabed's: -mu N tanh(|vt|/eps) vt/|vt|. dt_ref = t - time_ref.
Tether::ContactEval Tether::ContactForce(const ContactPoint& c, const double* xp, const double* vp,
                                         double dt_ref) const {
  ConstNodes x(xp, 3, N_ + 1), v(vp, 3, N_ + 1);
  const int j = c.segment;
  ContactEval e;
  const Vec3 p = c.point + dt_ref * c.velocity;
  const double ga = c.normal.dot(x.col(j) - p) - 0.5 * p_.diameter;
  const double gb = c.normal.dot(x.col(j + 1) - p) - 0.5 * p_.diameter;
  if (!(ga < 0) && !(gb < 0)) return e;
  // P0, P1 and the length in contact; K: d(P0 - P1, P1)/d(g_a, g_b) with the sign of a force.
  double P0, P1;
  if (ga < 0 && gb < 0) {
    P0 = -0.5 * (ga + gb);
    P1 = -(ga / 6 + gb / 3);
    e.length = 1;
    e.K[0] = 1.0 / 3, e.K[1] = 1.0 / 6, e.K[2] = 1.0 / 3;
  } else if (ga < 0) {
    // In contact on [0, s0], s0 = ga/(ga - gb): P0 = -ga s0/2, P1 = -ga s0^2/6.
    const double D = ga - gb, s0 = ga / D;
    P0 = -0.5 * ga * s0;
    P1 = -ga * s0 * s0 / 6;
    e.length = s0;
    // d/dga of P0 and of P1 = -ga^3/(6 D^2), d/dgb of P1 (K needs no more).
    const double dP0a = -ga * (ga - 2 * gb) / (2 * D * D);
    const double dP1a = -ga * ga * (ga - 3 * gb) / (6 * D * D * D),
                 dP1b = -ga * ga * ga / (3 * D * D * D);
    e.K[0] = -(dP0a - dP1a), e.K[1] = -dP1a, e.K[2] = -dP1b;
  } else {
    // In contact on [1 - s1, 1], s1 = gb/(gb - ga): mirrored.
    const double D = gb - ga, s1 = gb / D;
    P0 = -0.5 * gb * s1;
    const double Q = -gb * s1 * s1 / 6;  // int (1 - s) max(0, -g) ds
    P1 = P0 - Q;
    e.length = s1;
    const double dQb = -gb * gb * (gb - 3 * ga) / (6 * D * D * D),
                 dQa = -gb * gb * gb / (3 * D * D * D);
    const double dP0b = -gb * (gb - 2 * ga) / (2 * D * D);
    e.K[0] = -dQa, e.K[1] = -dQb, e.K[2] = -(dP0b - dQb);
  }
  e.sbar = P0 > 0 ? P1 / P0 : (ga < 0 ? 0.0 : 1.0);
  const double s = e.sbar;
  const Vec3 vrel = (1 - s) * v.col(j) + s * v.col(j + 1) - c.velocity;
  const double vn = c.normal.dot(vrel);
  const double N = std::max(0.0, rest_length(j) * (contact_k_ * P0 - contact_c_ * e.length * vn));
  e.N = N;
  e.F = N * c.normal;
  if (p_.contact_friction > 0 && N > 0) {
    const Vec3 vt = vrel - vn * c.normal;
    const double slip = vt.norm();
    if (slip > 0) {
      e.F -= (p_.contact_friction * N * std::tanh(slip / p_.contact_friction_speed) / slip) * vt;
    }
  }
  return e;
}

void Tether::AddContact(ConstNodes x, ConstNodes v, const Ends& ends, Nodes f) const {
  const ContactSet& set = *ends.contacts;
  const double dt_ref = ends.time - set.time_ref;
  for (int k = 0; k < set.count; ++k) {
    const ContactPoint& c = set.points[k];
    const ContactEval e = ContactForce(c, x.data(), v.data(), dt_ref);
    if (e.N == 0) continue;
    f.col(c.segment) += (1 - e.sbar) * e.F;
    f.col(c.segment + 1) += e.sbar * e.F;
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
    const ContactEval e = ContactForce(c, x, v, dt_ref);
    (to_stage ? c.stage : c.impulse) += weight * e.F;
    (to_stage ? c.stage_b : c.impulse_b) += (weight * e.sbar) * e.F;
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
  if (Has(kAxial)) {
    // Writes every T[j].
    AddAxial(x, v, tc, w.l, T, f, start, head_ ? (ends.rest > 0 ? ends.rest : rest_) : L0_);
  } else {
    std::fill(T, T + N_, 0.0);
  }
  if (Has(kBending)) {
    BendingMoments(tc, ends, M);
    AddBending(tc, w.l, Mc, f);
  }
  if (Has(kWeight) || Has(kBuoyancy)) {
    if (head_) {
      for (int i = 0; i <= N_; ++i) f.col(i) += Weight(i);
    } else {
      f += WeightMatrix();
    }
  }
  if (Has(kDrag) || Has(kAddedMass) || Has(kSeabed)) NodeTangents(x, tc, q);
  // |v_n| is kept for the implicit drag Jacobian in an implicit step's residual (start given);
  // AddDrag writes it unless the pointer is null.
  if (Has(kDrag)) AddDrag(x, v, qc, w.l, f, start ? w.vn : nullptr);
  if (Has(kSeabed)) AddSeabed(x, v, qc, f, start);
  if (Has(kContact) && ends.contacts) AddContact(x, v, ends, f);
}

EndReactions Tether::Reactions(const double* xp, const double* vp, const Ends& ends,
                               double* work) const {
  Work w(work, N_);
  const int n = N_ + 1;
  if (window_ && N_ >= 3) {
    // Each end from its 3-node window: the force on an end node involves only its segment,
    // the curvature at its neighbour (the segment after) and its own drag, weight and seabed.
    // With a winch, end A's window has the winch segment's rest length.
    std::optional<Tether> wa;
    if (head_) wa.emplace(window_->Deployed(0, rest_, speed_));
    const Tether& wt = head_ ? *wa : *window_;
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
        const ContactEval e = ContactForce(c, x.data(), v.data(), ends.time - set.time_ref);
        F += (c.segment == i ? 1 - e.sbar : e.sbar) * e.F;
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
    const Tether& wt_b = *window_;
    r.force_a = F.col(0) + contact_on_node(0);
    r.tension_a = r.force_a.norm();
    if (Has(kClamp) && p_.clamp_a) r.torque_a = M.col(0);
    X.leftCols(2) = x.middleCols(N_ - 2, 2);
    V.leftCols(2) = v.middleCols(N_ - 2, 2);
    X.col(2) = p_.free_end ? Vec3(x.col(N_)) : ends.b.pos;
    V.col(2) = p_.free_end ? Vec3(v.col(N_)) : ends.b.vel;
    we.rest = 0;
    wt_b.ComputeForces(wx, wv, we, wf, wT, scratch);
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

double Tether::EndStiffness() const {
  return (Has(kCompression) ? std::max(p_.EA, p_.EAc) : p_.EA) / L0_;
}

double Tether::EndBendingStiffness(bool end_b) const {
  if (!Has(kBending)) return 0;
  const double l = rest_length(end_b ? N_ - 1 : 0);  // [m] the end segment
  const double k_clamp = 2 * p_.EI / (l * l * l);     // [N/m] a clamp's moment, weight l/2
  auto clamped = [&](bool b) { return Has(kClamp) && (b ? p_.clamp_b : p_.clamp_a); };
  // The next node's moment; on a single segment the next node is the other end, with a
  // moment only where that end is clamped. And a clamped end's own.
  const double next = N_ > 1 ? p_.EI / (l * l * CurvatureWeight(end_b ? N_ - 1 : 1))
                             : (clamped(!end_b) ? k_clamp : 0);
  return next + (clamped(end_b) ? k_clamp : 0);
}

double Tether::EndSeabedStiffness(bool end_b) const {
  return Has(kSeabed) ? seabed_k_ * Share(end_b ? N_ : 0) : 0.0;
}

double Tether::EndSeabedDamping(bool end_b) const {
  return Has(kSeabed) ? seabed_c_ * Share(end_b ? N_ : 0) : 0.0;
}

double Tether::EndDamping() const { return Has(kDamping) ? p_.damping / L0_ : 0.0; }

Mat3 Tether::LineStiffness(const double* xp) const {
  ConstNodes x(xp, 3, N_ + 1);
  Mat3 compliance = Mat3::Zero();  // [m/N]
  for (int j = 0; j < N_; ++j) {
    const Vec3 d = x.col(j + 1) - x.col(j);
    const double l = d.norm(), rest = rest_length(j);
    const double T = p_.EA * (l / rest - 1);  // [N]
    if (!(T > 0)) return Mat3::Zero();  // slack (or not finite): no first-order stiffness
    const Vec3 t = d / l;
    const Mat3 along = t * t.transpose();
    compliance += along * (rest / p_.EA) + (Mat3::Identity() - along) * (l / T);
  }
  return N_ > 0 ? Mat3(compliance.inverse()) : Mat3::Zero();
}

bool Tether::AllTaut(const double* xp) const {
  ConstNodes x(xp, 3, N_ + 1);
  for (int j = 0; j < N_; ++j) {
    const double rest = rest_length(j);
    if (!((x.col(j + 1) - x.col(j)).squaredNorm() > rest * rest)) return false;
  }
  return N_ > 0;
}

double Tether::SnapJump(const double* xp, const double* vp, double dt) const {
  ConstNodes x(xp, 3, N_ + 1), v(vp, 3, N_ + 1);
  double fastest = 0;  // [m/s]
  for (int j = 0; j < N_; ++j) {
    const double rest = rest_length(j);
    const Vec3 d = x.col(j + 1) - x.col(j);
    const double l2 = d.squaredNorm();
    if (!(l2 < rest * rest)) continue;  // taut (or not finite: Check reports that)
    const double closing = (v.col(j + 1) - v.col(j)).dot(d);  // [m^2/s] = l x separation speed
    if (!(closing > 0)) continue;
    const double l = std::sqrt(l2), speed = closing / l;
    if (l + dt * speed >= rest) fastest = std::max(fastest, speed);
  }
  return std::sqrt(p_.EA * p_.mass_per_length) * fastest;
}

// Tension only: a compressed segment (compression effect) reads 0, like a slack one.
void Tether::Tensions(const double* xp, const double* vp, double* T) const {
  ConstNodes x(xp, 3, N_ + 1), v(vp, 3, N_ + 1);
  const double inv_L0 = 1 / L0_;  // [1/m]
  for (int j = 0; j < N_; ++j) {
    const Vec3 dx = x.col(j + 1) - x.col(j);
    const double l = dx.norm();
    T[j] = 0;
    if (j == 0 && head_) {
      // The winch segment (see AddAxial), at the view's rest length.
      if (Has(kAxial) && l > rest_) {
        const Vec3 t = dx * (1 / l);
        const Vec3 dv = (L0_ / rest_) * (v.col(1) - v.col(0) - (l / rest_ * speed_) * t);
        T[0] = AxialForce(l / rest_ - 1, t, dv, 0);
      }
      continue;
    }
    if (Has(kAxial) && l > L0_) {
      T[j] = AxialForce(l * inv_L0 - 1, dx * (1 / l), v.col(j + 1) - v.col(j), 0);
    }
  }
}

double Tether::KineticEnergy(const double* xp, const double* vp) const {
  ConstNodes x(xp, 3, N_ + 1), v(vp, 3, N_ + 1);
  double E = 0;
  for (int i = 0; i <= N_; ++i) {
    E += 0.5 * Mass(i) * v.col(i).squaredNorm();
    if (Added(i) > 0) {
      Vec3 s = x.col(std::min(i + 1, N_)) - x.col(std::max(i - 1, 0));
      Vec3 q = s.norm() > 0 ? Vec3(s.normalized()) : Vec3::Zero();
      Vec3 vn = v.col(i) - v.col(i).dot(q) * q;
      E += 0.5 * Added(i) * vn.squaredNorm();
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
    const double L0 = rest_length(j);
    if (Has(kAxial) && l > L0) E += 0.5 * p_.EA / L0 * (l - L0) * (l - L0);
    if (Has(kCompression) && l < L0) E += 0.5 * p_.EAc / L0 * (l - L0) * (l - L0);
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
      if (j > 0) E += energy(t_prev, t, CurvatureWeight(j));
      if (j == 0 && Has(kClamp) && p_.clamp_a) E += energy(ends.a.axis, t, 0.5 * L0);
      if (j == N_ - 1 && Has(kClamp) && p_.clamp_b) E += energy(t, ends.b.axis, 0.5 * L0);
    }
    t_prev = t;
  }
  for (int i = 0; i <= N_; ++i) E -= Weight(i).dot(x.col(i));
  return E;
}

}  // namespace mjtether
