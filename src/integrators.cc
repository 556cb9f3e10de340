#include "tether.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include <Eigen/Eigenvalues>

#include "detail/work.h"

namespace mjtether {
using namespace detail;
namespace {

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

// The lower triangle of a 3x3 block, column-major (m[r + 3 c] = m(r, c)): its 6 elements'
// indices, rows and columns. BlockBand::Factor reads only the lower triangle of a diagonal
// block (it is symmetric), so the implicit assembly computes and adds only these there.
constexpr int kLowK[6] = {0, 1, 2, 4, 5, 8};
constexpr int kLowR[6] = {0, 1, 2, 1, 2, 2};
constexpr int kLowC[6] = {0, 0, 0, 1, 1, 2};

// The tether's force on end A [N] with end node B dynamic (its state from the node, not the
// site): Reactions at the state x, v and the ends e.
Vec3 EndForceA(const Tether& t, const double* x, const double* v, const Ends& e, double* work) {
  const int N = t.segments();
  Ends at = e;
  at.b.pos = Eigen::Map<const Vec3>(x + 3 * N);
  at.b.vel = Eigen::Map<const Vec3>(v + 3 * N);
  at.body_b = nullptr;
  return t.Reactions(x, v, at, work).force_a;
}

}  // namespace

Ends Interpolate(const Ends& from, const Ends& to, double dt, double s) {
  return {Interpolate(from.a, to.a, dt, s), Interpolate(from.b, to.b, dt, s),
          from.time + s * (to.time - from.time), to.contacts,
          from.rest + s * (to.rest - from.rest), to.body_b};
}

// ---------------------------------------------------------------------------------------------
// Integrators

// The attached end nodes at the ends' positions and velocities `e` (end B only if attached).
void Tether::PlaceEnds(const Ends& e, Nodes x, Nodes v) const {
  x.col(0) = e.a.pos;
  v.col(0) = e.a.vel;
  if (!DynamicB()) {
    x.col(N_) = e.b.pos;
    v.col(N_) = e.b.vel;
  }
}

// Acceleration of dynamic node i under force fi [N], node tangent qi: with normal added mass
// the node mass matrix is m I + ma (I - q q^T), whose inverse is q q^T/m + (I - q q^T)/(m + ma).
inline Vec3 Tether::Acceleration(int i, const Vec3& fi, const Vec3& qi) const {
  if (!Has(kAddedMass)) return InvMass(i) * fi;
  const Vec3 ft = fi.dot(qi) * qi;
  return InvMass(i) * ft + InvMassNormal(i) * (fi - ft);
}

// Acceleration of end node B carrying a body (the consistent coupling, docs/coupling.md):
//   (m I + ma (I - q q^T) + W^-1) a = f + W^-1 a_other,
// the node's mass matrix (as in Acceleration) plus the body's effective mass at the site W^-1
// [kg], under the node's force plus the force W^-1 a_other [N] that gives the site the
// acceleration it has without the tether. The explicit schemes' share of what ImplicitStep
// assembles for the same node; one 3x3 SPD solve (Cholesky).
Vec3 Tether::BodyEndAcceleration(const Vec3& fi, const Vec3& qi, const EndInertia& body) const {
  Mat3 M = body.mass;
  if (body.node_inertia) {  // EndInertia::node_inertia (EndNodeOutweighs)
    M += Mass(N_) * Mat3::Identity();
    if (Has(kAddedMass)) M += Added(N_) * (Mat3::Identity() - qi * qi.transpose());
  }
  return M.llt().solve(fi + body.force);
}

bool Tether::EndNodeOutweighs(const Mat3& body_mass) const {
  using Eigen::EigenvaluesOnly;
  const double body_min_mass =  // [kg]
      Eigen::SelfAdjointEigenSolver<Mat3>(body_mass, EigenvaluesOnly).eigenvalues().minCoeff();
  return NodeInertiaMax(N_) > body_min_mass;
}

// Symplectic (semi-implicit) Euler: v += h M^-1 f(x, v); x += h v. With a body at end B
// (WithDynamicEndB), end node B steps the same way with the body's inertia and force
// (BodyEndAcceleration): it only gets heavier, so the stable step of the chain stands.
void Tether::ExplicitStep(Nodes x, Nodes v, const Ends& now, const Ends& next, double h,
                          double* work) const {
  Work w(work, N_);
  ComputeForces(x.data(), v.data(), now, w.f, nullptr, work);
  AccumulateContactImpulse(x.data(), v.data(), now, h, false);  // v+ = v + h M^-1 f(x, v)
  ConstNodes f(w.f, 3, N_ + 1), q(w.q, 3, N_ + 1);
  const EndInertia* body = dynamic_b_ ? now.body_b : nullptr;
  for (int i = 1; i <= N_; ++i) {
    if (!Dynamic(i)) continue;
    v.col(i) += h * (body && i == N_ ? BodyEndAcceleration(f.col(i), q.col(i), *body)
                                     : Acceleration(i, f.col(i), q.col(i)));
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
  // A body at end B (WithDynamicEndB): end node B carries its inertia in every stage.
  const EndInertia* body = dynamic_b_ ? now.body_b : nullptr;
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
      const Vec3 ai = body && i == N_ ? BodyEndAcceleration(f.col(i), q.col(i), *body)
                                      : Acceleration(i, f.col(i), q.col(i));
      const Vec3 vi = vk.col(i);
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
                          double* work, StepStatus* stats, bool scheme_start) const {
  Work w(work, N_);
  const int n = N_ + 1;
  const int nu = N_ - 1 + (DynamicB() ? 1 : 0);  // dynamic nodes 1..nu, unknown u = i - 1
  // A body at end B (consistent coupling): its effective mass and force join end node B's.
  const EndInertia* body = dynamic_b_ ? next.body_b : nullptr;
  // The step of each node [s]: h, but with bdf2 and a body at end B the interval's own length,
  // next.time - now.time, for end node B (the mixed step, see Bdf2Step: the other nodes take
  // BDF2's backward-Euler step of he from their extrapolated state, end node B a plain
  // backward-Euler step over the interval from its own state; EvaluateLead sets the times).
  // implicit2's second stage (Sdirk2Step) is mixed too: end node B's velocity takes SDIRK's
  // stage of h (gamma h here) from its v~, M_B (v_B+ - v~_B) = h (f_B + W^-1 a_other), and its
  // position x_B+ = x_B + hN v_B+ from its own start, as the body's Euler step does. Its row
  // is scaled by cN = hN/h, cN M_B (v_B+ - v~_B) = hN (f_B + W^-1 a_other), so that the matrix
  // has the per-node steps s_i of the bdf2 mixed step (symmetric in K) and end node B the mass
  // cN M_B (cN = 1 with bdf2).
  const double span = next.time - now.time;  // [s]
  const bool sdirk = p_.integrator == Integrator::kImplicit2;
  const bool mixed = body && (p_.integrator == Integrator::kBdf2 || sdirk) && span > 0 &&
                     std::abs(span - h) > 1e-9 * h;
  const double hN = mixed ? span : h;
  const double cN = mixed && sdirk ? hN / h : 1;  // [-] end node B's mass scale
  auto step = [&](int i) { return i == N_ ? hN : h; };
  Nodes xk(w.x2, 3, n), vk(w.v2, 3, n);
  // Initial iterate: velocities unchanged, ends at the end of the step.
  vk = v;
  vk.col(0) = next.a.vel;
  if (!DynamicB()) vk.col(N_) = next.b.vel;
  auto place = [&]() {
    xk = x + h * vk;
    if (mixed) xk.col(N_) = x.col(N_) + hN * vk.col(N_);
    xk.col(0) = next.a.pos;
    if (!DynamicB()) xk.col(N_) = next.b.pos;
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
  // scheme_start: the dynamic nodes start from the scheme's own point, not from the state at
  // now (bdf2's extrapolated x-hat with its step he, implicit2's second stage from x~ with
  // gamma h). The prescribed ends then start where that step puts them, x(t + h) - he v(t + h),
  // so that the damping's backward difference of an end segment's length (the Newton
  // iterations past the first) reads t . (v_end - v_node) at convergence, the rate of the
  // first iteration and of Reactions, whose force the body receives. From their true position
  // (bdf2) or their position at t + gamma h (implicit2) they read a rate of v/2 or 1.4 v
  // along the end segment that neither node has: scene fuzzer seed 658 (bdf2, damping 16.8 N s
  // on 5.8 cm segments, a vehicle towed at 1.5 m/s) put 50 N for 16 N on its vehicle, growing
  // (docs/numerics.md, "The ends' start in bdf2 and implicit2"). Backward Euler starts from the
  // state at now: its ends' true start is its own.
  if (scheme_start) {
    start.end_a = next.a.pos - h * next.a.vel;
    if (!DynamicB()) start.end_b = next.b.pos - h * next.b.vel;
  }
  const double body_min_mass =
      body ? Eigen::SelfAdjointEigenSolver<Mat3>(body->mass, Eigen::EigenvaluesOnly)
                 .eigenvalues()
                 .minCoeff()
           : 0;  // [kg]
  // End node B's own inertia in its row (EndInertia::node_inertia): without it the node moves
  // with the body's mass alone.
  const bool node_b_mass = !body || body->node_inertia;

  // Forces at the iterate, and the residual -G = h f - M (v+ - v) (node mass with normal added
  // mass) into rhs. Returns phi*2 and, in *err, the largest |G_i|/m_i [m/s].
  auto residual = [&](double* err) {
    place();
    Forces(w.x2, w.v2, next, w.f, w.T, work, &start);
    double phi = 0, worst = 0;
    for (int i = 1; i <= nu; ++i) {
      // (End node B of an implicit2 mixed stage: its mass scaled by cN, above.)
      const Vec3 dvi =
          i == N_ && cN != 1 ? Vec3(cN * (vk.col(i) - v.col(i))) : Vec3(vk.col(i) - v.col(i));
      const bool own = i != N_ || node_b_mass;
      Vec3 r = step(i) * f.col(i) - (own ? Mass(i) : 0.0) * dvi;
      if (added && own) {
        const Vec3 qi = q.col(i);
        r -= Added(i) * (dvi - qi.dot(dvi) * qi);
      }
      double inv = InvMass(i);
      if (body && i == N_) {
        // The body's share: (W^-1 + m) dv = h (f + W^-1 a_other); G weighted by the inverse
        // of the smallest total mass along a direction.
        r += hN * body->force - body->mass * dvi;
        inv = 1 / (cN * ((own ? Mass(i) : 0.0) + body_min_mass));
      }
      rhs.col(i - 1) = r;
      const double r2 = r.squaredNorm();
      phi += r2 * inv;
      worst = std::max(worst, r2 * inv * inv);
    }
    *err = std::sqrt(worst);
    return phi;
  };

  // The matrix M - h D - h^2 K at the iterate of the last residual, factored; the Newton
  // correction replaces the residual in rhs. False if the factorisation failed.
  bool newton = false;  // past the first iteration
  // In those iterations, a segment that is slack at the iterate but that the last full Newton
  // step left taut is predicted taut: see `extend` below.
  // (Not on a mixed step, whose damping is not in the discrete form the prediction uses.)
  const bool predict = Has(kAxial) && !Has(kCompression) && !mixed;
  double* const predicted = w.taut;
  std::fill(predicted, predicted + N_, 0.0);
  auto solve = [&]() {
    // The mass blocks are assigned, the coupling blocks zeroed or assigned: no pass over the
    // whole band.
    // The diagonal blocks are symmetric and Factor reads their lower triangle only: the mass,
    // axial and drag terms compute and add those 6 elements (kLowK), each with the expression
    // the full 3x3 product had for it (the same bits); the upper triangle is left as it was.
    // With the axial term, its loop below assigns the coupling block L1(j) of every segment j
    // between two dynamic nodes (0 - B, the bits the zeroed block minus B had; zero where the
    // segment adds nothing), so only L2 is zeroed here.
    if (Has(kAxial)) {
      A.SetZeroL2();
    } else {
      A.SetZeroCoupling();
    }
    for (int i = 1; i <= nu; ++i) {
      double* d = A.D(i - 1).data();
      const double m = Mass(i);
      if (added) {
        // M I + ma (I - q q^T), written out with the expressions of the full product:
        // m + ma (1 - q_r q_r) on the diagonal, 0 + ma (0 - q_r q_c) off it (m 0 = +0).
        const double ma = Added(i);
        const double* qi = w.q + 3 * i;
        d[0] = m + ma * (1 - qi[0] * qi[0]);
        d[1] = 0 + ma * (0 - qi[1] * qi[0]);
        d[2] = 0 + ma * (0 - qi[2] * qi[0]);
        d[4] = m + ma * (1 - qi[1] * qi[1]);
        d[5] = 0 + ma * (0 - qi[2] * qi[1]);
        d[8] = m + ma * (1 - qi[2] * qi[2]);
      } else {
        d[0] = m, d[1] = 0, d[2] = 0, d[4] = m, d[5] = 0, d[8] = m;
      }
      if (body && i == N_) {
        if (!node_b_mass) d[0] = d[1] = d[2] = d[4] = d[5] = d[8] = 0;
        for (int e = 0; e < 6; ++e) d[kLowK[e]] += body->mass.data()[kLowK[e]];
        if (cN != 1) {
          for (int e = 0; e < 6; ++e) d[kLowK[e]] *= cN;
        }
      }
    }
    // Axial stiffness and damping of taut segments: B = h D + h^2 K with
    // K = EA/L0 t t^T + T/l (I - t t^T), D = damping/L0 t t^T; +B on both diagonal blocks,
    // -B on the coupling block. With per-node steps s_i (mixed): dG_i/dv_j = M_i d_ij -
    // s_i K_ij s_j - s_i D_ij, symmetric in K but not in D on the end segment: the band holds
    // s_{N-1} D there on both sides, and the rest, (s_N - s_{N-1}) D = (hN - h) ca t t^T in
    // block row N, column N-1, is a rank-one term solved exactly by Sherman-Morrison below.
    Vec3 end_t = Vec3::Zero();
    double end_c = 0;  // [kg/s] the damping coefficient of that rank-one term
    // A compressed segment (compression effect, 0 < l < L0) adds h^2 EAc/L0 t t^T and its
    // damping while it pushes, without the geometric term -|T|/l (I - t t^T): that negative
    // stiffness (buckling) would make the matrix indefinite, and bending carries it instead.
    if (Has(kAxial)) {
      const bool compression = Has(kCompression);
      // The stiffness and damping per rest length, divided once, not per segment (the winch
      // segment has its own rest length, divided at its turn).
      const double ka0 = p_.EA / L0_, kc0 = p_.EAc / L0_;
      const double ca0 = Has(kDamping) ? p_.damping / L0_ : 0;
      for (int j = 0; j < N_; ++j) {
        // The winch segment (a Deployed view) at its rest length at the end of the step.
        const bool winch = j == 0 && head_;
        const double L0 = winch ? WinchRest(next) : L0_;
        const double ka = winch ? p_.EA / L0 : ka0;
        const double kc = winch ? p_.EAc / L0 : kc0;
        const double ca = !Has(kDamping) ? 0 : winch ? p_.damping / L0 : ca0;
        const bool taut = w.l[j] > L0;
        // A slack segment predicted taut (Newton iterations after the first, without a
        // compression law) is linearised on the taut piece, extended below L0: the tension
        // of the engaged, discrete law, (EA + damping/h) eps - (damping/h) eps+ at the start
        // (negative here), joins the right-hand side and its stiffness the matrix, so that
        // the Newton step lands where that piece puts the segment instead of overshooting
        // L0 by the ratio of the stiffnesses (a primal-dual active-set step: Hintermueller,
        // Ito & Kunisch, SIAM J. Optim. 13, 2003). G, the velocity tolerance and the line
        // search are unchanged, and the piece test below compares with the piece the segment
        // was linearised on: the steps' equations and tolerances are those of before, only
        // the path the iteration takes to them changes. Likewise a taut segment whose damped
        // tension is clipped at zero (it is on the law's zero piece, below the kink l* of the
        // piece test) but predicted on the positive piece (not the winch segment, whose rest
        // length changes within the step).
        const bool extend = newton && predict && predicted[j] > 0 &&
                            (!taut || (!winch && !(w.T[j] > 0))) && w.l[j] > 0;
        const bool d0 = Dynamic(j), d1 = Dynamic(j + 1);
        // A segment that adds nothing: its coupling block is zero.
        auto none = [&]() {
          if (d0 && d1) std::fill_n(A.L1(j).data(), 9, 0.0);
        };
        if (!taut && !extend && !(compression && w.l[j] > 0 && w.l[j] < L0)) {
          none();
          continue;
        }
        const double* tj = w.t + 3 * j;
        // B = s t t^T + geo I; full (the coupling block is not symmetric to the bit: the
        // products (s t_r) t_c and (s t_c) t_r may round apart).
        double s, geo = 0;
        double cd = 0;  // [kg/s] the damping along t in B (for the mixed step's end segment)
        if (extend) {
          const double eps_start = std::max(0.0, (x.col(j + 1) - x.col(j)).norm() / L0 - 1);
          const double T_ext =
              (p_.EA + ca * L0 / h) * (w.l[j] / L0 - 1) - ca * L0 / h * eps_start;  // [N]
          if (Dynamic(j)) rhs.col(j - 1) += h * T_ext * t.col(j);
          if (Dynamic(j + 1)) rhs.col(j) -= h * T_ext * t.col(j);
          cd = ca;
          s = h2 * ka + h * ca;
        } else if (taut) {
          // In the Newton iterations after the first, a taut segment whose damped tension is
          // clipped at zero (it shortens faster than EA eps/damping) is on the piece where
          // the law is 0: its Jacobian there is 0 (the first keeps the linearly implicit step's
          // matrix of before).
          if (newton && !(w.T[j] > 0)) {
            none();
            continue;
          }
          geo = h2 * w.T[j] / w.l[j];
          cd = w.T[j] > 0 ? ca : 0;
          s = h2 * ka + h * cd - geo;
        } else {
          const double rate = t.col(j).dot(vk.col(j + 1) - vk.col(j)) / L0;  // [1/s] deps/dt
          const bool pushes = p_.EAc * (w.l[j] / L0 - 1) + ca * L0 * rate < 0;
          cd = pushes ? ca : 0;
          s = h2 * kc + h * cd;
        }
        double B[9];
        for (int c = 0; c < 3; ++c) {
          for (int r = 0; r < 3; ++r) B[r + 3 * c] = s * tj[r] * tj[c];
        }
        // geo I on the diagonal only (geo 0 = +0 added off it changed no bits: those elements
        // go into sums that start from +0 or a nonzero value).
        if (taut) B[0] += geo, B[4] += geo, B[8] += geo;
        if (mixed && j + 1 == N_) {
          // The end segment of a mixed step, node j stepping h and end node B hN: B = h^2 K +
          // h c t t^T, so K = (B - h c t t^T)/h^2; the blocks s_i s_j K + s_i c t t^T (full
          // blocks: Factor reads the lower triangle of the diagonal ones).
          const Vec3 te = t.col(j);
          const Mat3 Bm = Eigen::Map<const Mat3>(B);
          const Mat3 ct = cd * te * te.transpose();
          const Mat3 K = (Bm - h * ct) / h2;
          if (d0) A.D(j - 1) += Bm;
          A.D(j) += hN * hN * K + hN * ct;
          if (d0) {
            none();
            A.L1(j) -= h * hN * K + h * ct;
            end_t = te;
            end_c = (hN - h) * cd;
          }
          continue;
        }
        if (d0) {
          double* d = A.D(j - 1).data();
          for (int e = 0; e < 6; ++e) d[kLowK[e]] += B[kLowK[e]];
        }
        if (d1) {
          double* d = A.D(j).data();
          for (int e = 0; e < 6; ++e) d[kLowK[e]] += B[kLowK[e]];
        }
        if (d0 && d1) {
          double* c = A.L1(j).data();
          for (int k = 0; k < 9; ++k) c[k] = 0 - B[k];
        }
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
            // With per-node steps s_i: s_ia s_ib K, i.e. h^2 K scaled where end node B is in.
            const double scale = mixed ? step(ia) * step(first + b) / h2 : 1;
            band0[3 * (ia - 1) + (a - b)] += scale * k * g[a] * g[b];
          }
        }
      };
      const double g3[3] = {1, -2, 1}, g2[2] = {-1, 1};
      for (int i = 1; i < N_; ++i) stencil(i - 1, g3, 3, CurvatureWeight(i));
      if (Has(kClamp) && p_.clamp_a) stencil(0, g2, 2, 0.5 * rest_length(0));
      if (Has(kClamp) && p_.clamp_b) stencil(N_ - 1, g2, 2, 0.5 * rest_length(N_ - 1));
      for (int u = 0; u < nu; ++u) {
        A.D(u).diagonal().array() += band0[3 * u];
        if (u >= 1) A.L1(u).diagonal().array() += band0[3 * u + 1];
        if (u >= 2) A.L2(u).diagonal().array() += band0[3 * u + 2];
      }
    }
    // Drag: d(|vn| vn)/dv_r = |vn| P + vn vn^T/|vn|, d(|vt| vt)/dv_r = 2 |vt| q q^T; B = -h D.
    // With a current profile u(z): the current at the node's height, and its derivative
    // du/dz (a stiffness h^2 df/dz through z) left out of the Jacobian: it changes the Newton
    // iteration's rate, not its fixed point (docs/environment.md).
    if (Has(kDrag)) {
      const bool current = Has(kCurrent);
      const bool profile = current && !env_.water.profile.empty();
      const Vec3 u0 = current ? env_.water.current : Vec3::Zero();
      for (int i = 1; i <= nu; ++i) {
        const double li = DragLength(i, w.l);
        const Vec3 u = profile ? env_.water.profile.At(xk(2, i)) : u0;
        const Vec3 qi = q.col(i);
        const Vec3 vr = u - vk.col(i);
        const double vq = vr.dot(qi);
        const Vec3 vn = vr - vq * qi;
        const double vnn = w.vn[i];  // vn.norm(), from AddDrag at this iterate (the residual)
        const double ht = step(i) * li;
        // J = s q q^T + ht kn |vn| I + (ht kn/|vn|) vn vn^T, lower triangle.
        const double s = ht * (kt_ * 2 * std::abs(vq) - kn_ * vnn);
        const double diag = ht * kn_ * vnn;
        const double sn = vnn > 0 ? ht * kn_ / vnn : 0;
        double* d = A.D(i - 1).data();
        for (int e = 0; e < 6; ++e) {
          const int r = kLowR[e], c = kLowC[e];
          double J = s * qi[r] * qi[c];
          if (r == c) J += diag;
          if (vnn > 0) J += sn * vn[r] * vn[c];
          d[kLowK[e]] += J;
        }
      }
    }
    // Seabed: normal stiffness and damping, friction secant.
    if (Has(kSeabed) && env_.water.surface.declared()) {
      // A geom seabed: the same along the surface's normal n, (h^2 k + h c) l_i n n^T, and the
      // friction secant in its tangent plane, (I - n n^T).
      const Water& wt = env_.water;
      for (int i = 1; i <= nu; ++i) {
        double zs;
        Vec3 n;
        wt.surface.Under(xk(0, i), xk(1, i), &zs, &n);
        const double pen = (zs - xk(2, i)) * n.z();
        if (pen <= 0) continue;
        BlockBand::Block d = A.D(i - 1);
        const Mat3 nn = n * n.transpose();
        const double si = step(i);
        d += (si * si * seabed_k_ * Share(i) + si * seabed_c_ * Share(i)) * nn;
        const double N =
            std::max(0.0, Share(i) * (seabed_k_ * pen - seabed_c_ * vk.col(i).dot(n)));
        const double mu = std::max(wt.seabed_friction, wt.seabed_friction_axial);
        const double vh = (vk.col(i) - vk.col(i).dot(n) * n).norm();
        const double eps = wt.seabed_friction_speed;
        const double secant = vh > 1e-9 * eps ? mu * N * std::tanh(vh / eps) / vh : mu * N / eps;
        d += (si * secant) * (Mat3::Identity() - nn);
      }
    } else if (Has(kSeabed)) {
      const Water& wt = env_.water;
      for (int i = 1; i <= nu; ++i) {
        const double pen = wt.seabed - xk(2, i);
        if (pen <= 0) continue;
        BlockBand::Block d = A.D(i - 1);
        const double si = step(i);
        d(2, 2) += si * si * seabed_k_ * Share(i) + si * seabed_c_ * Share(i);
        const double N = std::max(0.0, Share(i) * (seabed_k_ * pen - seabed_c_ * vk(2, i)));
        const double mu = std::max(wt.seabed_friction, wt.seabed_friction_axial);
        const double vh = std::hypot(vk(0, i), vk(1, i));
        const double eps = wt.seabed_friction_speed;
        const double secant = vh > 1e-9 * eps ? mu * N * std::tanh(vh / eps) / vh : mu * N / eps;
        d(0, 0) += si * secant;
        d(1, 1) += si * secant;
      }
    }
    // Contact: the penalty's stiffness k L0 K n n^T (K the 2 x 2 of ContactEval over the two
    // nodes), and the damping L0 c lambda n n^T and the friction's derivative in the tangent
    // plane at sbar, shared by the nodes with the weights (1 - sbar), sbar of the force.
    if (Has(kContact) && next.contacts) {
      const ContactSet& set = *next.contacts;
      const double dt_ref = next.time - set.time_ref;
      for (int k = 0; k < set.count; ++k) {
        const ContactPoint& c = set.points[k];
        const ContactEval ce = ContactForce(c, xk.data(), vk.data(), dt_ref);
        if (ce.length == 0) continue;
        const Mat3 nn = c.normal * c.normal.transpose();
        const double L0c = rest_length(c.segment);
        Mat3 B = (L0c * h * contact_c_ * ce.length) * nn;
        const double N = ce.N;
        if (p_.contact_friction > 0 && N > 0) {
          const double sb = ce.sbar;
          const Vec3 vrel = (1 - sb) * vk.col(c.segment) + sb * vk.col(c.segment + 1) - c.velocity;
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
        const double wa = 1 - ce.sbar, wb = ce.sbar;
        const Mat3 S = (h2 * contact_k_ * L0c) * nn;
        const bool d0 = Dynamic(j), d1 = Dynamic(j + 1);
        if (d0) A.D(j - 1) += (wa * wa) * B + ce.K[0] * S;
        if (d1) A.D(j) += (wb * wb) * B + ce.K[2] * S;
        if (d0 && d1) A.L1(j) += (wa * wb) * B + ce.K[1] * S;
      }
    }
    if (A.Factor() >= 0) return false;
    A.Solve(w.rhs);
    if (end_c != 0) {
      // (A + u w^T) z = r with u = -end_c (e_N x t), w = e_{N-1} x t: z = A^-1 r - y (w.A^-1 r)
      // / (1 + w.y), y = A^-1 u (Sherman-Morrison). Scratch: vb (the line search's start,
      // set after each solve).
      Nodes y(w.vb, 3, nu);
      y.setZero();
      y.col(nu - 1) = -end_c * end_t;
      A.Solve(w.vb);
      const double wy = end_t.dot(y.col(nu - 2)), wz = end_t.dot(rhs.col(nu - 2));
      rhs -= (wz / (1 + wy)) * y;
    }
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
  // The tension test without a square root: EA/L0 (|d| - t . d) <= bound is |d| <= r with
  // r = t . d + bound L0/EA, that is r >= 0 and |d|^2 <= r^2 (|d| >= t . d always, so r < 0
  // misses more than the bound). A NaN passes the tension test, as it passed the max() before
  // (the divergence check reports it). One pass over the segments does both tests with one d.
  const double L0sq = L0_ * L0_;
  // A segment predicted taut (see `extend`) was linearised on the taut piece. Every segment's
  // piece at the new iterate is recorded for the next iteration's prediction (where the test
  // passes, that is the piece each segment was linearised on, which the turning test below
  // reads).
  // In the Newton iterations with the prediction, the pieces are those of the discrete damped
  // law, T = max(0, (EA + c/h) (l - L0)/L0 - (c/h) eps+(start)) for l > L0 and 0 below: a
  // segment taut at the start of the step (length ls > L0) has its kink not at L0 but at
  // l* = L0 + c/h / (EA + c/h) (ls - L0) (for c = 200 N s, EA = 2e5 N, h = 2 ms a third of the
  // way from L0 to ls), the tension being 0 on both sides of L0 below it. The test compares
  // the side of l* (the positive piece or the zero piece) with the piece the segment was
  // linearised on: positive (w.T > 0 at the iterate) or predicted positive (`extend`). Where
  // the test of L0 would fail a segment crossing L0 within the zero piece (no tension missed),
  // this one does not; where it would pass a clipped segment moved beyond l* (its tension
  // missed) or a predicted one left between L0 and l* (a compression the law does not have),
  // this one fails it. Without damping l* = L0 and w.T > 0 means l > L0: the test of L0.
  const double kink = Has(kDamping) ? (p_.damping / h) / (p_.EA + p_.damping / h) : 0;  // [-]
  auto linearisation_held = [&]() {
    const bool axial = Has(kAxial);
    const bool pieces = newton && predict && kink > 0;  // (kink 0: the test of L0 below)
    double T_max = 0;
    if (axial) {
      for (int j = 0; j < N_; ++j) T_max = std::max(T_max, w.T[j]);
    }
    const double bound = std::max(kLinearisationTolerance * T_max, 1e-6 * p_.EA);  // [N]
    bool held = true;
    for (int j = 0; j < N_; ++j) {
      const bool winch = j == 0 && head_;
      const double L0 = winch ? WinchRest(next) : L0_;
      const Vec3 d = xk.col(j + 1) - xk.col(j);
      const double d2 = d.squaredNorm();
      // Linearised on the taut piece: taut at the iterate (positive, with the kink), or
      // predicted taut (`extend`); now beyond L0 (l* with the kink, see above).
      const bool kinked = pieces && !winch;
      double edge2 = winch ? L0 * L0 : L0sq;  // [m^2]
      if (kinked) {
        const double ls = (x.col(j + 1) - x.col(j)).norm();  // [m] at the start of the step
        if (ls > L0_) edge2 = (L0_ + kink * (ls - L0_)) * (L0_ + kink * (ls - L0_));
      }
      const bool now_taut = d2 > edge2;
      const bool was_taut =
          (kinked ? w.T[j] > 0 : w.l[j] > L0) || (predicted[j] > 0 && w.l[j] > 0);
      if (newton && predict) predicted[j] = now_taut ? 1 : 0;
      bool ok = now_taut == was_taut;
      if (ok && axial && was_taut) {
        const double r = t.col(j).dot(d) + bound * L0 / p_.EA;  // [m]
        ok = r >= 0 && d2 <= r * r;
      }
      if (!ok) {
        held = false;
        if (!newton || !predict) break;  // (the prediction needs every segment's piece)
      }
    }
    if (!held) return false;
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
        const double sb = ContactForce(c, xk.data(), vk.data(), next.time - set.time_ref).sbar;
        auto slip = [&](bool after) {
          const Vec3 vr =
              (1 - sb) * node_v(c.segment, after) + sb * node_v(c.segment + 1, after) - c.velocity;
          return (vr - c.normal.dot(vr) * c.normal).norm();
        };
        if (std::abs(std::tanh(slip(true) / eps) - std::tanh(slip(false) / eps)) > 0.1) {
          return false;
        }
      }
    }
    return true;
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
    W_max = std::max(W_max, Weight(i).norm());
    m_min = std::min(m_min, Mass(i));
  }
  for (int j = 0; j < N_; ++j) T_max = std::max(T_max, w.T[j]);
  const double tolerance =
      kNewtonTolerance * std::sqrt(dv_max) + 1e-12 * h * (2 * T_max + W_max) / m_min;
  // The first iteration's taut set carried into the Newton iterations (with damping): every
  // segment that it linearised on the taut piece (w.l still holds the first iterate's lengths)
  // is predicted on the positive piece of the discrete law. Such segments, taut at the start
  // of the step and near L0, were the most frequent piece changes: the first iteration's full
  // step (with the instantaneous damping rate t . dv/L0) took them below l*, and from the zero
  // piece, whose Jacobian is nothing, the next full step overshot l* again, one more solve to
  // learn what the first iteration had (dry, zero g, damping 200: 3.84 solves per step with
  // the set learned from full Newton steps only, 1.92 with this; docs/numerics_slack.md).
  if (predict && Has(kDamping)) {
    for (int j = 0; j < N_; ++j) {
      const double L0 = j == 0 && head_ ? WinchRest(next) : L0_;
      predicted[j] = w.l[j] > L0 ? 1 : 0;
    }
  }
  // Not on a mixed step: the end segment's backward difference of the strain would need a
  // common start, which its two nodes (stepping he from x-hat and h from x) do not have; the
  // damping stays on the node velocities there, as in the first iteration.
  start.discrete = !mixed;
  phi = residual(&err);
  newton = true;
  for (int iter = 1; err > tolerance; ++iter) {
    if (iter == kMaxNewton) return false;
    dv = rhs;  // -G at the iterate, for E'(0) below
    if (!solve()) return fail();
    double g0 = 0;  // E'(0) = d . G(v) = -d^T A d < 0
    for (int u = 0; u < nu; ++u) g0 -= rhs.col(u).dot(dv.col(u));
    dv = rhs;
    for (int i = 1; i <= nu; ++i) vb.col(i - 1) = vk.col(i);
    for (int i = 1; i <= nu; ++i) vk.col(i) += dv.col(i - 1);
    place();
    if (linearisation_held()) break;
    // Line search: backtracking (Armijo, sigma = 1e-4) on phi, phi(alpha) <= (1 - 2 sigma
    // alpha) phi(0), the directional derivative of phi along an exact Newton step being
    // -2 phi(0), halving alpha from 1 down to kMinLineSearchStep.
    // Where that fails, on the incremental potential instead: for the conservative forces, and
    // the damping in its discrete form (a function of the lengths), G is the gradient of
    // E(v+) = 1/2 (v+ - v)^T M (v+ - v) + U(x + h v+) (backward Euler as a minimisation: Gast
    // et al., IEEE TVCG 21, 2015), whose derivative along the Newton direction d is
    // E'(alpha) = d . G(v + alpha d), E'(0) = -d^T A d < 0. A Newton step that crosses a kink
    // (a slack segment coming taut, with the matrix of the slack piece) overshoots by the ratio
    // of the stiffnesses, ~(h^2 EA/L0 + h damping/L0)/m, up to 1e3 on short heavily damped
    // segments: phi rises within a fraction of the step below kMinLineSearchStep. E' is
    // still monotone along the ray (E convex there), so the minimum of E along d is bracketed
    // by the alphas tried, and regula falsi (Illinois) on E' finds a point where
    // |E'(alpha)| <= kCurvature |E'(0)| (the strong Wolfe curvature condition; Nocedal &
    // Wright, ch. 3), which lowers E. Steps that Armijo takes are taken as before.
    double alpha = 1, trial = 0;
    double lo = 0, g_lo = g0, hi = 1, g_hi = NAN;  // the bracket on E' from the alphas tried
    // E'(alpha) from the residual just evaluated.
    auto slope = [&]() {
      double g = 0;
      for (int u = 0; u < nu; ++u) g -= dv.col(u).dot(rhs.col(u));
      return g;
    };
    bool armijo = false;
    for (;;) {
      trial = residual(&err);
      if (trial <= (1 - 2e-4 * alpha) * phi) {
        armijo = true;
        break;
      }
      const double g = slope();
      if (g < 0 && alpha > lo) lo = alpha, g_lo = g;
      if (g >= 0 && alpha <= hi) hi = alpha, g_hi = g;
      alpha *= 0.5;
      if (alpha < kMinLineSearchStep) break;
      for (int i = 1; i <= nu; ++i) vk.col(i) = vb.col(i - 1) + alpha * dv.col(i - 1);
    }
    if (!armijo) {
      if (!std::isfinite(g_hi) || !(lo < hi)) return false;  // no bracket: retry in halves
      // Illinois: which end of the bracket was kept last.
      int side = 0;
      for (int evaluations = 0;; ++evaluations) {
        if (evaluations == kMaxLineSearch) return false;
        alpha = lo + (hi - lo) * g_lo / (g_lo - g_hi);
        if (!(alpha > 0)) return false;
        for (int i = 1; i <= nu; ++i) vk.col(i) = vb.col(i - 1) + alpha * dv.col(i - 1);
        trial = residual(&err);
        const double g = slope();
        if (std::abs(g) <= kCurvature * std::abs(g0)) break;
        if (g < 0) {
          lo = alpha, g_lo = g;
          if (side == -1) g_hi *= 0.5;
          side = -1;
        } else {
          hi = alpha, g_hi = g;
          if (side == 1) g_lo *= 0.5;
          side = 1;
        }
      }
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
    if (p_.integrator == Integrator::kImplicit2) {
      AddEndImpulse(x.data(), v.data(), next, impulse_weight * h, work, stats);
    }
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
  const bool mixed = dynamic_b_ && next.body_b && next.time > now.time;
  // The end forces' impulse (StepStatus::impulse_a, _b): the stage Y1's share, kept aside until
  // the second stage settles (a fallback takes the whole step's).
  StepStatus stage1;
  AddEndImpulse(x.data(), v.data(), mid, (1 - kGamma) * h, work, &stage1);
  // Contact impulse: y+ = y + (1 - gamma) h F(Y1) + gamma h F(Y2); the first part is kept
  // aside until the second stage settles (a fallback replaces both).
  if (Has(kContact) && mid.contacts) {
    for (int k = 0; k < mid.contacts->count; ++k) {
      mid.contacts->points[k].stage.setZero();
      mid.contacts->points[k].stage_b.setZero();
    }
    AccumulateContactImpulse(x.data(), v.data(), mid, (1 - kGamma) * h, true);
  }
  // x, v hold Y1; form y~ on the dynamic nodes (the ends are set by the next stage).
  // A body at end B (the consistent coupling, docs/coupling.md): end node B carries the body,
  // whose Euler step moves it to x + h v+; end node B takes SDIRK's velocity, v~ and a stage of
  // gamma h, but its position from its own start, x_B+ = x_B + h v_B+ (the mixed stage of
  // ImplicitStep, which takes end node B's position step from the stage's times: `from`
  // starts at t). Both stages weigh its forces as every other node's, (1 - gamma) h at Y1 and
  // gamma h at Y2, so the end segment's impulse on the body and on the tether match.
  const double a = (1 - kGamma) / kGamma;
  for (int i = 0; i < n; ++i) {
    if (!Dynamic(i)) continue;
    x.col(i) = x0.col(i);
    if (!(mixed && i == N_)) x.col(i) += (1 - kGamma) * h * v.col(i);
    v.col(i) = v0.col(i) + a * (v.col(i) - v0.col(i));
  }
  Ends from = mid;
  if (mixed) from.time = now.time;
  if (!ImplicitStep(x, v, from, next, kGamma * h, work, stats, true)) return fall_back();
  stats->impulse_a += stage1.impulse_a;
  stats->impulse_b += stage1.impulse_b;
  AddEndImpulse(x.data(), v.data(), next, kGamma * h, work, stats);
  if (Has(kContact) && next.contacts) {
    for (int k = 0; k < next.contacts->count; ++k) {
      ContactPoint& c = next.contacts->points[k];
      c.impulse += c.stage;
      c.impulse_b += c.stage_b;
    }
    AccumulateContactImpulse(x.data(), v.data(), next, kGamma * h, false);
  }
}

// implicit2's end forces as its momentum takes them (StepStatus::impulse_a, impulse_b). With
// end node B carrying a body (the consistent coupling) end A's force, as EndForceA reads it.
// Held ends (sessions 39-40, docs/coupling.md): the force on each from the state at the
// stage. Where an end's site accelerates, a node tied to it by a segment stiff on the step
// follows the site's positions, and SDIRK's second stage, a backward-Euler step of gamma h
// from its extrapolated v~, gives it more inertia than its m a (the stage's velocity change
// over gamma h); the first stage's share carries the opposite, and the two weighted as the
// scheme weighs them sum to m a. So the end force at the step's end is off by several m a
// (5.3 m a in Momentum.Implicit2sEndForceIsTheMeanOfItsStages), and the mean of the stages
// is not: scene fuzzer seed 1423 (a 3.9 t vehicle sinking at 0.1 m/s^2 on 5 segments of EA
// 4.3e8 N) read 15.19 N at 2 ms, 16.54 at 0.2 ms, 16.58 at 0.1 ms, where implicit and bdf2
// read 16.590 N at every step (their last force is their impulse's), and its stage mean
// reads 16.590 N at 2 ms. Contact forces are left out (the plugin adds each end node's
// contact share apart).
void Tether::AddEndImpulse(const double* x, const double* v, const Ends& e, double weight_h,
                           double* work, StepStatus* stats) const {
  if (p_.integrator != Integrator::kImplicit2) return;
  if (dynamic_b_) {
    if (!e.body_b) return;
    stats->impulse_a += weight_h * EndForceA(*this, x, v, e, work);
    stats->has_impulse_a = true;
    return;
  }
  Ends held = e;
  held.contacts = nullptr;
  const EndReactions r = Reactions(x, v, held, work);
  stats->impulse_a += weight_h * r.force_a;
  stats->has_impulse_a = true;
  if (!p_.free_end) {
    stats->impulse_b += weight_h * r.force_b;
    stats->has_impulse_b = true;
  }
}

// BDF2, the two-step backward differentiation formula (Curtiss & Hirschfelder 1952; Hairer &
// Wanner, Solving ODEs II, ch. III.1 and V.1: A-stable and L-stable, order 2), on
// y = (x, v), y' = F(y) = (v, a(x, v)), with variable steps (ratio w = h/h_prev; Hairer,
// Norsett & Wanner, Solving ODEs I, eq. III.5.18, k = 2):
//   y_{n+1} - yhat = he F(y_{n+1}),  yhat = y_n + w^2/(1 + 2 w) (y_n - y_{n-1}),
//   he = h (1 + w)/(1 + 2 w)        (w = 1: yhat = (4 y_n - y_{n-1})/3, he = 2 h/3).
// That is a backward-Euler step of size he from yhat, with the ends at t + h: ImplicitStep
// solves it (one factorisation per Newton iteration, the matrix M - he D - he^2 K, the same
// non-smooth handling), so a step costs what a backward-Euler step costs. It is the
// generalized-alpha scheme of Jansen, Whiting & Hulbert (CMAME 190, 2000) at rho_inf = 0 with
// a constant step; on the fixed line rho_inf = 0.5-0.95 left the axial modes above the
// resolved ones ringing where the line's internal damping kills them, 26-29x the time error
// of rho_inf = 0 at 2 ms (docs/numerics.md).
// The history is the last step's difference y_n - y_{n-1} and its length h_prev. Without it
// (the first step, after a reset, a winch regrid, or a step more than kBdf2MaxRatio times the
// last), and where the Newton iteration does not settle, the step is backward Euler (retried
// in halves as the implicit scheme does), whose local error O(h^2) once keeps the scheme second
// order. Contact impulse: h times the final contact force; the BDF2 momentum balance
// M (3 v_{n+1} - 4 v_n + v_{n-1})/2 = h f_{n+1} sums to that over the steps.
void Tether::Bdf2Step(Nodes x, Nodes v, const Ends& now, const Ends& next, double h,
                      double* work, StepStatus* stats, const History& hist) const {
  Work w(work, N_);
  const int n = N_ + 1;
  Nodes dx(hist.xd, 3, n), dv(hist.vd, 3, n), xs(w.xs, 3, n), vs(w.vs, 3, n);
  // Backward Euler from y_n, the difference y_{n+1} - y_n kept.
  auto backward_euler = [&]() {
    dx = x;
    dv = v;
    ImplicitStepAdaptive(x, v, now, next, h, 0, work, stats);
    dx = x - dx;
    dv = v - dv;
    *hist.h_prev = h;
  };
  const double ratio = h / *hist.h_prev;
  if (!(*hist.h_prev > 0) || !(ratio <= kBdf2MaxRatio)) return backward_euler();
  const double c = ratio * ratio / (1 + 2 * ratio);       // [-] yhat = y_n + c (y_n - y_{n-1})
  const double he = h * (1 + ratio) / (1 + 2 * ratio);   // [s]
  xs = x;
  vs = v;
  // A body at end B (the consistent coupling, docs/coupling.md): end node B carries the body,
  // which must not take on BDF2's history (its spurious root kept a body accelerating after
  // the tether went slack); it takes a backward-Euler step of h from its own state, the other
  // nodes BDF2's (the mixed step of ImplicitStep, which takes the interval from the ends'
  // times).
  const bool mixed = dynamic_b_ && next.body_b && next.time > now.time;
  for (int i = 0; i < n; ++i) {
    if (!Dynamic(i) || (mixed && i == N_)) continue;
    x.col(i) += c * dx.col(i);
    v.col(i) += c * dv.col(i);
  }
  if (!ImplicitStep(x, v, now, next, he, work, stats, true)) {
    x = xs;
    v = vs;
    return backward_euler();
  }
  AccumulateContactImpulse(x.data(), v.data(), next, h, false);
  dx = x - xs;
  dv = v - vs;
  *hist.h_prev = h;  // BDF2 again next step
}

void Tether::Step(Nodes x, Nodes v, const Ends& now, const Ends& next, double h, double* work,
                  StepStatus* status, const History* history) const {
  if (StepsAsBackwardEuler()) {
    // bdf2 or implicit2 on an overdamped segment mode (SecondOrderMaxDampingRatio).
    ImplicitStepAdaptive(x, v, now, next, h, 0, work, status);
  } else if (p_.integrator == Integrator::kBdf2) {
    // Without a history (a winch tether advanced without one): backward Euler.
    if (history) {
      Bdf2Step(x, v, now, next, h, work, status, *history);
    } else {
      ImplicitStepAdaptive(x, v, now, next, h, 0, work, status);
    }
  } else if (p_.integrator == Integrator::kExplicit) {
    ExplicitStep(x, v, now, next, h, work);
  } else if (p_.integrator == Integrator::kRK4) {
    Rk4Step(x, v, now, next, h, work);
  } else if (p_.integrator == Integrator::kImplicit2) {
    Sdirk2Step(x, v, now, next, h, work, status);
  } else {
    ImplicitStepAdaptive(x, v, now, next, h, 0, work, status);
  }
}

int Tether::HistorySize() const {
  return p_.integrator == Integrator::kBdf2 ? 1 + 6 * (N_ + 1) : 0;  // h_prev, dx, dv
}

StepStatus Tether::Advance(double* xp, double* vp, const Ends& from, const Ends& to, double dt,
                           double* work, double* history) const {
  const int n = N_ + 1;
  Nodes x(xp, 3, n), v(vp, 3, n);
  StepStatus status;
  int steps = SubstepsFor(dt);
  if (steps == 0) return status;
  PlaceEnds(from, x, v);
  // explicit and rk4: more substeps where the drag at this advance's speeds needs them.
  steps = DragSubsteps(xp, vp, from, to, dt, steps);
  status.substeps = steps;
  const double h = dt / steps;
  // bdf2 without a caller's history: one in the workspace for this call (x0, v0 are
  // implicit2's), starting with a backward-Euler step.
  double h_prev = 0;
  const Work w(work, N_);
  const History hist = history ? History{history, history + 1, history + 1 + 3 * n}
                               : History{&h_prev, w.x0, w.v0};
  Ends now = from;
  // explicit with a body at end B (the consistent coupling): end node B's position follows
  // MuJoCo's Euler path for the body, x_B(t + s) = x_B(t) + s v_B(t + s), so that after the last
  // substep it is where the body will be (x + dt v+, the velocity being the node's), and the
  // plugin's move of the node onto the site at the next call is a_other's lag only. With the
  // node's own path (x + sum h v_k) the two parted by dt (v_mean - v+) each step, and that move
  // changed the end segment's stretch by energy no force did: held-out seed 14999 (7 substeps,
  // coupling omega h 0.92, Can 1) grew from 10 N to 40 kN in 3 s (docs/coupling.md, session 27).
  // With one substep this is symplectic Euler's own position step.
  const bool euler_path = ExplicitWithBody(from);
  const Vec3 x_b0 = x.col(N_);
  for (int k = 0; k < steps; ++k) {
    const Ends next = k + 1 == steps ? to : Interpolate(from, to, dt, double(k + 1) / steps);
    Step(x, v, now, next, h, work, &status, &hist);
    if (euler_path) x.col(N_) = x_b0 + ((k + 1) * h) * v.col(N_);
    // Work of the end forces over the step: the integrator's last force evaluation (explicit:
    // start of the step; implicit: the last Newton iterate; rk4: the last stage).
    const ConstNodes f(Work(work, N_).f, 3, n);
    status.work_a += f.col(0).dot(next.a.pos - now.a.pos);
    status.end_impulse_a += h * Vec3(f.col(0));
    status.end_impulse_b += h * Vec3(f.col(N_));
    if (!DynamicB()) status.work_b += f.col(N_).dot(next.b.pos - now.b.pos);
    now = next;
  }
  // explicit with a body at end B (the consistent coupling): end A's impulse over the substeps,
  // each of which took the force at its start, is the plugin's end A force (its mean). Every
  // substep's `next` carries to.body_b (Interpolate), so this is the sum above.
  if (ExplicitWithBody(to)) {
    status.impulse_a = status.end_impulse_a;
    status.has_impulse_a = true;
  }
  Check(ConstNodes(xp, 3, n), ConstNodes(vp, 3, n), from, to, &status);
  return status;
}

namespace {
// A figure in a divergence reason with nine significant digits: std::to_string's six decimals
// printed a strain just beyond max_strain 1 as "1.000000 exceeds 1.000000" (session 11).
std::string Digits(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%.9g", x);
  return text;
}
}  // namespace

// Divergence: a non-finite value, a strain no tether survives, or a kinetic energy no tether
// holds. Each check is one pass without square roots or divisions (x - x is 0 for every finite
// x and NaN otherwise; the strain is compared squared); the node and the value reported are
// looked up only when a check fails.
void Tether::Check(ConstNodes x, ConstNodes v, const Ends& from, const Ends& to,
                   StepStatus* out) const {
  const int n = N_ + 1;
  StepStatus& status = *out;
  if (!((x - x).sum() == 0 && (v - v).sum() == 0)) {
    for (int i = 0; i < n; ++i) {
      if (!x.col(i).allFinite() || !v.col(i).allFinite()) {
        status.ok = false;
        status.node = i;
        status.reason = "non-finite position or velocity";
        return;
      }
    }
  }
  // |dx| > (1 + max_strain) L0, squared (rest_length differs only for a winch view's first).
  const double stretch = 1 + p_.max_strain;
  const double limit2 = stretch * stretch * L0_ * L0_;  // [m^2]
  for (int j = 0; j < N_; ++j) {
    const double l2 = (x.col(j + 1) - x.col(j)).squaredNorm();
    if (!(l2 > (j == 0 && head_ ? stretch * stretch * rest_ * rest_ : limit2))) continue;
    const double strain = std::sqrt(l2) / rest_length(j) - 1;
    if (strain > p_.max_strain) {
      status.ok = false;
      status.node = j + 1;
      status.reason = "strain " + Digits(strain) + " of segment " + std::to_string(j) +
                      " exceeds max_strain " + Digits(p_.max_strain);
      return;
    }
  }
  // Energy blow-up: more kinetic energy than the tether could hold physically (an unstable
  // mode grows geometrically and crosses this long before it overflows to NaN).
  double kinetic = 0;
  for (int i = 0; i < n; ++i) {
    if (!Dynamic(i)) continue;
    kinetic += 0.5 * (Mass(i) + Added(i)) * v.col(i).squaredNorm();
  }
  const double bound = kEnergyBlowUp * EnergyBound(from, to);
  if (kinetic > bound) {
    double node_max = -1;
    int fastest = -1;
    for (int i = 0; i < n; ++i) {
      if (!Dynamic(i)) continue;
      const double e = 0.5 * (Mass(i) + Added(i)) * v.col(i).squaredNorm();
      if (e > node_max) node_max = e, fastest = i;
    }
    status.ok = false;
    status.node = fastest;
    status.reason = "kinetic energy " + Digits(kinetic) + " J exceeds " + Digits(bound) +
                    " J, " + Digits(kEnergyBlowUp) +
                    " times the most the tether can physically hold";
  }
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
  if (Has(kCurrent)) v += env_.water.MaxCurrentSpeed();
  // [kg] with added mass, [N] net weight without sign: a Deployed view sums its own nodes.
  double M = total_mass_, W = total_weight_;
  if (head_) {
    M = W = 0;
    for (int i = 0; i <= N_; ++i) M += Mass(i) + Added(i), W += Weight(i).norm();
  }
  double E = 0.5 * p_.EA * p_.max_strain * p_.max_strain * L + 0.5 * M * v * v;
  if (Has(kBending)) E += 0.5 * p_.EI * (4 / (L0_ * L0_)) * L;
  if (Has(kCompression)) E += 0.5 * p_.EAc * L;
  return E + W * L;
}

}  // namespace mjtether
