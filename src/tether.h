// A lumped-mass tether: N+1 point masses joined by N massless viscoelastic segments, with
// bending from nodal curvature (Buckham & Nahon, "Dynamics simulation of low tension tethers",
// OCEANS '99; Buckham, Driscoll & Nahon, "Formulation and validation of a lumped mass model
// for low-tension ROV tethers", ISOPE 2003), Morison drag and added mass, weight and buoyancy,
// and a flat seabed.
//
// The object holds only what never changes (masses, coefficients, stability limit). The state
// (node positions x and velocities v, each 3 x (N+1), column per node) lives in a buffer the
// caller owns, and all scratch memory comes from a caller-supplied workspace of
// WorkspaceSize() doubles, so that stepping allocates nothing and one Tether serves any number
// of states and threads.
//
// End A (node 0) is attached to a site; end B (node N) is attached to a site or free. Attached
// end nodes follow their site; the force the tether exerts on a site is the total force on its
// end node (segment tension, bending shear, and the node's share of weight, buoyancy, drag and
// seabed contact). The end node's inertia is not passed on.
#ifndef MJTETHER_SRC_TETHER_H_
#define MJTETHER_SRC_TETHER_H_

#include <cmath>
#include <memory>
#include <optional>
#include <string>

#include <Eigen/Core>

#include "contact.h"
#include "params.h"

namespace mjtether {

using Mat3 = Eigen::Matrix3d;
using Nodes = Eigen::Map<Eigen::Matrix3Xd>;             // 3 x n, one column per node
using ConstNodes = Eigen::Map<const Eigen::Matrix3Xd>;  // 3 x n

// The kinematics of one attached end at one instant.
struct EndState {
  Vec3 pos = Vec3::Zero();   // [m] site position, world frame
  Vec3 vel = Vec3::Zero();   // [m/s] site velocity, world frame
  Vec3 axis = Vec3::UnitX();  // [-] site x-axis (clamp direction, pointing into the tether)
};

// A body at end B whose inverse mass at the site is W [1/kg] (docs/coupling.md, consistent
// coupling): with it, a tether made by Tether::WithDynamicEndB() steps its end node B as a
// dynamic node carrying the body's effective mass W^-1 besides its own, under the force
// W^-1 a_other that gives the site the acceleration a_other it has without the tether.
// node_inertia false: end node B's own inertia (mass, normal added mass) is left out of its
// step, so that the node and the body move as the body's mass alone, as the held force has them
// (docs/coupling.md, "session 11, s11coup"); its forces (segment, weight, drag) stay.
// EvaluateLead sets it once per MuJoCo step to Tether::EndNodeOutweighs(W^-1), for every
// scheme: the node keeps its inertia only where it is heavier than the body.
struct EndInertia {
  Eigen::Matrix3d mass = Eigen::Matrix3d::Zero();  // [kg] W^-1
  Vec3 force = Vec3::Zero();                       // [N] W^-1 a_other
  bool node_inertia = true;
};

struct Ends {
  EndState a;
  EndState b;  // unused when end B is free
  // With the contact effect: the time of this instant [s] and the contact candidates
  // (contact.h), shared by every instant of one Advance; null: no contact this step.
  double time = 0;
  const ContactSet* contacts = nullptr;
  // With a winch (a view from Tether::Deployed): the rest length of the winch segment (segment
  // 0, from the drum at end A) at this instant [m]; 0 without a winch.
  double rest = 0;
  // A body at end B (a tether from WithDynamicEndB(); null otherwise): see EndInertia.
  const EndInertia* body_b = nullptr;
};

// The deployment of a tether with a winch at end A (docs/winch.md). Nodes 0..first-1 are on
// the drum (at end A's site, inert); node `first` is the drum exit (the attached end A); the
// winch segment from it to node first+1 has rest length `rest` (between 0.5 and 1.5 L0 after
// every step), every other deployed segment L0. Deployed unstretched length:
// (segments() - first - 1) L0 + rest.
struct Payout {
  int first = 0;     // [-] index of the drum-exit node
  double rest = 0;   // [m] rest length of the winch segment
  double speed = 0;  // [m/s] payout speed d rest/dt over this Advance (> 0 pays out)
};

// What the tether does to the sites it is attached to.
struct EndReactions {
  Vec3 force_a = Vec3::Zero();   // [N] force on site A
  Vec3 torque_a = Vec3::Zero();  // [N m] moment on site A's body (clamped end only)
  Vec3 force_b = Vec3::Zero();   // [N] force on site B (zero when B is free)
  Vec3 torque_b = Vec3::Zero();  // [N m]
  double tension_a = 0;          // [N] |force_a|
  double tension_b = 0;          // [N] |force_b|, or the last segment's tension when B is free
  // [N] of force_b, the consistent coupling's slow-mode correction (a numerical force, not the
  // line's; its reaction is in force_a), zero elsewhere: the line's own forces on the sites are
  // force_a + correction_b and force_b - correction_b (docs/coupling.md, session 34).
  Vec3 correction_b = Vec3::Zero();
};

// Outcome of Advance: ok, or where the state stopped making sense.
struct StepStatus {
  bool ok = true;
  int node = -1;         // first offending node
  std::string reason;    // "non-finite position", "strain 1.3 > max_strain 1", ...
  // How the implicit schemes' Newton iterations went over this Advance (zero otherwise).
  int substeps = 0;           // tether steps taken over the advance (explicit, rk4: with drag's)
  int newton_iterations = 0;  // linear solves, over all steps and stages
  int halvings = 0;           // steps (or half steps) redone as two halves
  int stalled_steps = 0;      // steps accepted with the Newton iteration not converged
  // [J] work the tether's force on each attached end did on its site over the advance: the
  // sum over tether steps of the end node's force (at the step's evaluation) times the end's
  // displacement. What the tether gave the bodies, for the coupling's work balance.
  double work_a = 0, work_b = 0;
  // [N s] The impulse of those same forces over the advance (the sum over tether steps of the
  // end node's force times the step): with work_a and work_b, the balance in the frame moving
  // with the site, where a body's drift does not multiply the held force's lag (plugin.cc).
  Vec3 end_impulse_a = Vec3::Zero(), end_impulse_b = Vec3::Zero();
  // [N s] For the schemes whose end forces at the end of the step are not what their nodes'
  // momentum took: the impulse of the tether's force on each attached end over the advance as
  // the scheme integrates it. implicit2: (1 - gamma) h and gamma h times the force at its two
  // stages (h times the force at the end of a backward-Euler step where it falls back), on
  // both ends (end B only where it is held: a site's path, not the body's node); explicit with
  // a body at end B (WithDynamicEndB): end A, h times the force at the start of each substep.
  // Set with has_impulse_a, has_impulse_b; EvaluateLead then reports end A's force as
  // impulse_a over the advance, and a held end's force is its impulse's mean carried to the
  // advance's end (plugin.cc, HeldMean). Without contact forces (the plugin adds each end
  // node's contact share apart).
  Vec3 impulse_a = Vec3::Zero(), impulse_b = Vec3::Zero();
  bool has_impulse_a = false, has_impulse_b = false;
};

// Options and outcome of Tether::RelaxToStatic (docs/static_start.md).
struct StaticOptions {
  int max_iterations = 1000;  // [-] pseudo-time steps at most
  // [-] converged when the largest node displacement of one pseudo-time step is below
  // tolerance x the tether's length (at the largest pseudo-time step, see tether.cc)
  double tolerance = 1e-8;
  // [-] and the largest net force on a node of the shape at rest is below force_tolerance x the
  // load (the net weight and the current's drag at rest, summed over the nodes)
  double force_tolerance = 1e-3;
};
struct StaticResult {
  bool converged = false;  // the displacement fell below the tolerance
  bool ok = true;          // the shape is usable: finite, within max_strain (else *reason)
  int iterations = 0;      // [-] pseudo-time steps taken
  double displacement = 0;  // [m] largest node displacement of the last step
  double residual = 0;      // [N] largest net force on a dynamic node of the final shape at rest
  double load = 0;          // [N] the scale of force_tolerance (StaticOptions)
  int node = -1;            // [-] that node
  double final_step = 0;    // [s] the last pseudo-time step
  std::string reason;       // why the shape is unusable (!ok)
};

// [-] The segment axial mode's damping ratio (Tether::SegmentModeRatio) above which bdf2 and
// implicit2 step as backward Euler (Tether::StepsAsBackwardEuler), each at its own onset. A
// tether of 39 segments of 7.5 cm between two fixed ends, axial damping far above critical
// (scene fuzzer seed 10116, reduced; docs/limitations.md, session 29): bdf2 read its tension 6x
// too high at damping ratio 15.5 (right at 10.9, at every step from 0.05 to 2 ms), implicit2
// 2.2x at 4.7 (right at 3.1); backward Euler right at each. The fuzzer scenes this fixed had
// ratios of 22-320. Session 29 took 3 for both; that made bdf2 first order on the
// accuracy/cost line at 320 segments (ratio 3.2: the fairlead error at 10 ms 1.35 N where its
// own step reads 0.047 N), so bdf2's limit is 10 since session 30.
constexpr double kSecondOrderMaxDampingRatioBdf2 = 10;
constexpr double kSecondOrderMaxDampingRatioImplicit2 = 3;

class Tether {
 public:
  // Precomputes masses, coefficients and the explicit stability limit. Returns nothing (and
  // sets *error) if the parameters are inconsistent (they are range-checked by the parser).
  static std::optional<Tether> Create(const TetherParams& params, const Environment& env,
                                      std::string* error);
  // The same tether with its end node B stepped as a dynamic node (the consistent coupling,
  // docs/coupling.md): Advance places only end A, and end node B moves under its forces plus
  // Ends::body_b's (its mass and force added to the node's), in every integrator's step (the
  // explicit schemes solve the node's 3x3 mass in each substep or stage); params().free_end
  // stays false, so InitialShape and Reactions are the attached tether's.
  Tether WithDynamicEndB() const {
    Tether t = *this;
    t.dynamic_b_ = true;
    return t;
  }

  const TetherParams& params() const { return p_; }
  const Environment& env() const { return env_; }
  int segments() const { return N_; }
  int nodes() const { return N_ + 1; }
  double rest_segment_length() const { return L0_; }  // [m]
  // Doubles in one state: x then v, 3 x (N+1) each.
  int StateSize() const { return 6 * (N_ + 1); }
  // Doubles of scratch memory that Advance, ComputeForces and Reactions need.
  int WorkspaceSize() const;

  // Stability limit of the explicit scheme [s]: 2/omega_max with the highest natural
  // frequency bounded node by node from axial stiffness, bending, seabed and contact
  // stiffness and the node masses, reduced for damping (see tether.cc); with integrator=rk4,
  // the limit of RK4 (about 2.8/w).
  double ExplicitStabilityLimit() const { return explicit_limit_; }
  // The step the explicit schemes take [s]: the limit times a safety factor (src/detail/
  // work.h), 0.8 with rk4, which covers the geometric stiffness T/l and drag that the bound
  // leaves out, and 0.5 with explicit, at which symplectic Euler keeps a slack chain's energy
  // within the work of its ends (kExplicitSafety).
  double ExplicitStableStep() const { return explicit_dt_; }
  // Number of tether steps to cover dt [s] with the configured integrator.
  int SubstepsFor(double dt) const;
  // explicit and rk4 with drag: the substeps over dt that the drag at the state's speeds
  // needs (state x, v with the ends placed at `from`; the ends' speeds at from and to count),
  // given `steps` from SubstepsFor: steps where the substep is within 0.9 of the drag's limit,
  // more where it is not (see tether.cc).
  int DragSubsteps(const double* x, const double* v, const Ends& from, const Ends& to,
                   double dt, int steps) const;

  // Initial shape: a straight line when the ends are at least `length` apart, otherwise an
  // inextensible catenary of the right length in the vertical plane through both ends (sagging
  // with the net weight); a free end hangs along gravity (or along site A's axis without
  // gravity). With the seabed effect, a shape that would dip below the seabed hangs from each
  // end down to it and lays the rest of its length on it (see RestOnSeabed): no node starts
  // below the seabed. Velocities: zero inside, the sites' at the ends.
  void InitialShape(const Ends& ends, double* x, double* v) const;

  // Relaxes the state x (3 x (N+1), e.g. from InitialShape) to static equilibrium with the
  // attached ends held at ends.a.pos, ends.b.pos (a free end B moves): weight, buoyancy, the
  // current's drag on the still tether, EA/EAc/EI and the seabed (contact, friction), by
  // pseudo-transient continuation (backward-Euler steps of a growing pseudo-time step with the
  // velocities reset to zero after each; tether.cc). On return v is zero inside and the
  // sites' velocities at the ends. Without contact (Ends::contacts) and winch; `work` is
  // WorkspaceSize() doubles. Allocates (a load-time call).
  StaticResult RelaxToStatic(const Ends& ends, double* x, double* v, double* work,
                             const StaticOptions& options = {}) const;

  // Doubles of integrator history a state carries besides x and v: with integrator=bdf2, the
  // last step h_prev [s] (0: none yet) and the last step's change of x and v (3 x (N+1) each),
  // 1 + 6 (N+1); 0 with the one-step schemes. All zero is a valid history (no step yet): the
  // next step is then a backward-Euler step, which starts the scheme (docs/numerics.md).
  int HistorySize() const;

  // Advances the state by dt [s]; the attached ends move from `from` to `to` (cubic Hermite in
  // time between the two, so positions and velocities at both instants are matched).
  // `history` (HistorySize() doubles, see above) carries bdf2's last step from one call to the
  // next; without it each call starts again with a backward-Euler step (first order when a
  // call is a single step), the later steps of the same call being BDF2.
  StepStatus Advance(double* x, double* v, const Ends& from, const Ends& to, double dt,
                     double* work, double* history = nullptr) const;
  // The same for a tether with a winch at end A (params().winch): the winch segment's rest
  // length grows by payout->speed dt over the advance (linearly), and whenever it leaves
  // [0.5, 1.5] L0 a node is inserted at or removed from the drum (Regrid); *payout is updated.
  // x and v hold the whole allocation, segments() + 1 nodes.
  // With bdf2, a node inserted or removed restarts the scheme (one backward-Euler step).
  StepStatus Advance(double* x, double* v, const Ends& from, const Ends& to, double dt,
                     double* work, Payout* payout, double* history = nullptr) const;

  // The deployed part of a tether with a winch as a tether of its own: segments() - first
  // segments, the first of rest length `rest` [m], the nodes' lumped masses, weights and
  // curvature weights following it, state at x + 3 first. No allocation (it shares the node
  // arrays), so it can be made at every step.
  Tether Deployed(int first, double rest, double speed) const;
  // Inserts (rest > 1.5 L0) or removes (rest < 0.5 L0) one node at the drum, conserving the
  // deployed mass mu L and the momentum (docs/winch.md); ends `e` (the drum at end A).
  // Returns +1 (inserted), -1 (removed) or 0.
  int Regrid(double* x, double* v, const Ends& e, Payout* payout) const;
  // The drum's impedance over a step of dt [N s/m]: by how much the tension at the drum (end A)
  // drops at the step's end per m/s of payout speed added over the step, the deployed nodes
  // (state x, the whole allocation) responding along the line as backward Euler steps them:
  // each node a spring to its place of stiffness m/dt^2 (its mass; added mass is normal only),
  // each taut segment EA/L0 + damping/(L0 dt) in series (EAc/L0 if compressed, 0 if slack), end
  // B held (a body) or free. The winch's tension mode takes it implicitly (WinchSpeed).
  // On a long taut line it is sqrt(mu EA), the axial wave impedance; docs/winch.md.
  double DrumImpedance(const double* x, const Payout& payout, double dt) const;

  // Forces on every node f (3 x n) [N], and segment tensions T (N) [N], >= 0 (a compression
  // reads 0), when T is not null, from the state as it is (ends as stored in x, v).
  void ComputeForces(const double* x, const double* v, const Ends& ends, double* f, double* T,
                     double* work) const;

  // Forces and moments on the sites, with the end nodes placed at the sites given (so a
  // caller can evaluate the reaction at an intermediate state of its own integrator).
  EndReactions Reactions(const double* x, const double* v, const Ends& ends,
                         double* work) const;

  // Segment tensions T (N) [N] of the state as it is, >= 0 (slack or compressed: 0).
  void Tensions(const double* x, const double* v, double* T) const;

  // Energies [J] for conservation checks: kinetic (with added mass), elastic (axial, with
  // compression when declared, and bending) and gravitational (weight minus buoyancy,
  // relative to z = 0).
  double KineticEnergy(const double* x, const double* v) const;
  double PotentialEnergy(const double* x, const Ends& ends) const;
  // The most energy the tether can hold physically while its ends move from `from` to `to`
  // [J] (see tether.cc); Advance reports a kinetic energy above 10 times this as divergence.
  double EnergyBound(const Ends& from, const Ends& to) const;

  // The largest inertia node i moves with along any direction [kg]: its mass plus, with added
  // mass, its normal added mass.
  double NodeInertiaMax(int i) const { return Mass(i) + (Has(kAddedMass) ? Added(i) : 0.0); }
  // Whether end node B (mass and normal added mass) outweighs the lightest effective mass of a
  // body at end B, body_mass = W^-1 [kg]: the consistent coupling then keeps the node's inertia
  // in its step (EndInertia::node_inertia; session 23: without that rule seed 2499, bdf2, a
  // 27 kg end node of 4 segments on a 6 kg vehicle, read 408 N for 2.4 N, not diagnosed).
  bool EndNodeOutweighs(const Mat3& body_mass) const;

  // Stiffness the end segment presents to a site [N/m]: k_end = EA/L0 (the larger of EA and
  // EAc when compressed segments push back). The time-step advisor's coupling frequency at an
  // attached body of effective mass m_eff is sqrt(k_end/m_eff) (docs/coupling.md).
  double EndStiffness() const;
  // Stiffness the bending presents to a site across a straight line at end A or B [N/m], 0
  // without the bending effect: moving a pinned end node by d turns the end segment by d/L0,
  // which gives the next node the moment EI (d/L0)/w (w its curvature weight, L0 on equal
  // segments; BendingMoments) and the end node the segment's shear EI d/(L0^2 w) (AddBending);
  // a clamped end's own moment EI (d/L0)/(L0/2) adds 2 EI/L0^3 (on a single segment the next
  // node is the other end: 2 EI/L0^3 where it is clamped, else 0). On a short segment of a stiff
  // rod it exceeds EA/L0, and the coupling advisor takes the larger (docs/coupling.md, session
  // 37).
  double EndBendingStiffness(bool end_b) const;
  // Stiffness a flat or geom seabed presents to a site through its end node in contact [N/m],
  // 0 without the seabed effect: the penalty seabed_stiffness [N/m^2] over the node's share of
  // the tether's length (half the end segment), normal to the seabed. A body whose end node
  // touches the seabed feels it through the end force, as it feels the end segment; the
  // coupling advisor takes the consistent coupling where it is stiff on the body's step, and
  // stops a held end whose node lands there (docs/coupling.md, session 38: seed 9022, one
  // segment of 56 m on a 7.7 kg vehicle driven into the seabed).
  double EndSeabedStiffness(bool end_b) const;
  // Damping the seabed presents to a site through its end node in contact [N s/m]: its damping
  // per length (critical for the tether's mass unless declared) over the node's share.
  double EndSeabedDamping(bool end_b) const;
  // Internal damping the end segment presents to a site [N s/m]: damping/L0, 0 without the
  // damping effect. The coupling advisor's h damping/(L0 m_eff) (docs/coupling.md) and the
  // end-damping bound read it.
  double EndDamping() const;
  // Quasi-static stiffness of the whole line at end B with end A held [N/m] (3 x 3, symmetric):
  // the interior nodes in equilibrium under loads that do not move with them (weight,
  // buoyancy), so that every segment carries the same force increment and the compliances add,
  // K = (sum_j K_j^-1)^-1 with K_j = EA/L0 t t^T + T_j/l_j (I - t t^T), segment j's tangent
  // stiffness along its direction t (axial) and across it (geometric), T_j = EA (l_j/L0 - 1).
  // Zero where a segment is not in tension (the line then has no stiffness at its ends to first
  // order). Bending, the seabed and the drag are left out, so it is never above the line's own.
  // The consistent coupling's slow-mode correction reads it (docs/coupling.md, session 34).
  Mat3 LineStiffness(const double* x) const;
  // Every segment longer than its rest length (LineStiffness is not zero exactly then; false
  // where a length is not finite). The slow-mode correction's check that a step ended as taut
  // as it began, without LineStiffness's 3 x 3 sums (session 37).
  bool AllTaut(const double* x) const;

  // The segment axial mode (docs/reference.md "Internal damping"): adjacent nodes moving in
  // opposite directions along the line, omega_n = (2/L0) sqrt(EA/mu) [rad/s], and its damping
  // ratio damping / (L0 sqrt(EA mu)) [-] (0 without the damping effect).
  double SegmentModeFrequency() const { return segment_mode_w_; }
  double SegmentModeRatio() const { return segment_mode_ratio_; }
  // integrator=bdf2 or implicit2 whose segment axial mode is overdamped beyond
  // its SecondOrderMaxDampingRatio steps as backward Euler (integrator=implicit), every step:
  // there the two-step history of BDF2, and SDIRK's stages, against the damped law's clip at
  // zero tension made a period-2 alternation that grew (docs/limitations.md, session 29).
  bool StepsAsBackwardEuler() const { return segment_mode_ratio_ > SecondOrderMaxDampingRatio(); }
  // [-] The damping ratio above which this tether's integrator steps as backward Euler:
  // kSecondOrderMaxDampingRatioBdf2 or ...Implicit2; infinity for the others.
  double SecondOrderMaxDampingRatio() const {
    return p_.integrator == Integrator::kBdf2        ? kSecondOrderMaxDampingRatioBdf2
           : p_.integrator == Integrator::kImplicit2 ? kSecondOrderMaxDampingRatioImplicit2
                                                     : INFINITY;
  }
  // [N] The largest snap a step of dt from the state (x, v) would start: over the slack
  // segments whose nodes separate fast enough to reach the rest length within dt, the axial
  // wave's tension jump sqrt(EA mu) times the separation speed (0 if none). A cheap look-ahead
  // (one pass of squared lengths; a root only for such segments) for the plugin's snap check.
  double SnapJump(const double* x, const double* v, double dt) const;

  // The terms of the explicit stability limit (see Create), each the largest over the dynamic
  // nodes of its node-by-node bound: natural frequencies of the axial chain, the bending
  // operator and the seabed [rad/s] (0 when the effect is off), and the damping rate [1/s]
  // (internal, seabed, friction, contact).
  struct StabilityTerms {
    double w_axial = 0, w_bending = 0, w_seabed = 0, rate = 0;
  };
  const StabilityTerms& stability_terms() const { return terms_; }

  // Node masses [kg] (dry, lumped) and net weight force [N] per node.
  double node_mass(int i) const { return Mass(i); }
  Vec3 node_weight(int i) const { return Weight(i); }
  // Rest length of segment j [m] (L0, or the winch segment's in a Deployed view; in a view the
  // winch segment's rest length changes within a step, see Ends::rest).
  double rest_length(int j) const { return j == 0 && head_ ? rest_ : L0_; }
  double mass_per_length() const { return p_.mass_per_length; }

 private:
  Tether() = default;

  // The start of an implicit step of length h [s] (state x at its start): segments and seabed
  // contacts that engage within the step take the engaged damping law (see AxialForce).
  struct Start {
    ConstNodes x;  // 3 x n
    double h;      // [s]
    bool discrete;  // damping on the backward difference of the strain over the step
                    // (the Newton iterations past the first, see ImplicitStep)
    // [m] Where set (not NaN), the prescribed ends' start instead of x.col(0) and x.col(N):
    // see ImplicitStep's `scheme_start`.
    Vec3 end_a = Vec3::Constant(NAN), end_b = Vec3::Constant(NAN);
    Vec3 at(int i) const {
      if (i == 0 && !std::isnan(end_a.x())) return end_a;
      if (i == x.cols() - 1 && !std::isnan(end_b.x())) return end_b;
      return x.col(i);
    }
  };
  // ComputeForces, with the implicit step's start when `start` is not null.
  void Forces(const double* x, const double* v, const Ends& ends, double* f, double* T,
              double* work, const Start* start) const;
  // Per-effect terms; each adds to f (3 x n). See tether.cc for the equations.
  void SegmentGeometry(ConstNodes x, Nodes t, double* l) const;
  double AxialForce(double eps, const Vec3& t, const Vec3& dv, double engage_h) const;
  void AddAxial(ConstNodes x, ConstNodes v, ConstNodes t, const double* l, double* T,
                Nodes f, const Start* start, double rest0) const;
  void BendingMoments(ConstNodes t, const Ends& ends, Nodes M) const;
  void AddBending(ConstNodes t, const double* l, ConstNodes M, Nodes f) const;
  void NodeTangents(ConstNodes x, ConstNodes t, Nodes q) const;
  // Also writes each node's |v_n| [m/s] to vn (n values; ImplicitStep's drag Jacobian reads it).
  void AddDrag(ConstNodes x, ConstNodes v, ConstNodes q, const double* l, Nodes f,
               double* vn) const;
  void AddSeabed(ConstNodes x, ConstNodes v, ConstNodes q, Nodes f, const Start* start) const;
  void AddSeabedSurface(ConstNodes x, ConstNodes v, ConstNodes q, Nodes f,
                        const Start* start) const;
  // One candidate's force on its segment (forces.cc): the total F, the normal force N, the
  // fraction sbar of the segment at which it acts (F goes (1 - sbar) to node j, sbar to node
  // j+1), the fraction of the segment in contact, and the elastic stiffness blocks
  // dF_j/dg_a, dF_j/dg_b (= dF_{j+1}/dg_a), dF_{j+1}/dg_b per k L0 (times n n^T).
  struct ContactEval {
    Vec3 F = Vec3::Zero();
    double N = 0, sbar = 0.5, length = 0;
    double K[3] = {0, 0, 0};
  };
  ContactEval ContactForce(const ContactPoint& c, const double* xp, const double* vp,
                           double dt_ref) const;
  void AddContact(ConstNodes x, ConstNodes v, const Ends& ends, Nodes f) const;
  void AccumulateContactImpulse(const double* x, const double* v, const Ends& ends, double weight,
                                bool to_stage) const;

  bool HangChain(const Vec3& A, const Vec3& eh, const Vec3& up, double h, double vspan,
                 bool elastic, Nodes x) const;
  void RestOnSeabed(const Ends& ends, Nodes x) const;
  // Replaces a shape below the level zb (true), or leaves it (false).
  bool RestOnLevel(const Ends& ends, double zb, Nodes x) const;

  // Integrators (one step of size h; ends already set at the start, `next` at the end).
  void PlaceEnds(const Ends& e, Nodes x, Nodes v) const;
  Vec3 Acceleration(int i, const Vec3& fi, const Vec3& qi) const;
  Vec3 BodyEndAcceleration(const Vec3& fi, const Vec3& qi, const EndInertia& body) const;
  void ExplicitStep(Nodes x, Nodes v, const Ends& now, const Ends& next, double h,
                    double* work) const;
  void Rk4Step(Nodes x, Nodes v, const Ends& now, const Ends& next, double h,
               double* work) const;
  bool ImplicitStep(Nodes x, Nodes v, const Ends& now, const Ends& next, double h,
                    double* work, StepStatus* stats, bool scheme_start = false) const;
  void ImplicitStepAdaptive(Nodes x, Nodes v, const Ends& now, const Ends& next, double h,
                            int depth, double* work, StepStatus* stats,
                            double impulse_weight = 1) const;

  void Sdirk2Step(Nodes x, Nodes v, const Ends& now, const Ends& next, double h,
                  double* work, StepStatus* stats) const;
  // implicit2: adds weight_h times the end forces at the state x, v with the ends e to the
  // advance's impulses (StepStatus::impulse_a, impulse_b).
  void AddEndImpulse(const double* x, const double* v, const Ends& e, double weight_h,
                     double* work, StepStatus* stats) const;
  // The BDF2 history of the nodes being stepped (a Deployed view's nodes): the step that made
  // the state [s] (0: none) and the change of x and v over it (3 x n).
  struct History {
    double* h_prev;
    double* xd;
    double* vd;
  };
  void Bdf2Step(Nodes x, Nodes v, const Ends& now, const Ends& next, double h,
                    double* work, StepStatus* stats, const History& history) const;

  bool Has(unsigned effect) const { return (p_.effects & effect) != 0; }
  bool Dynamic(int i) const { return i > 0 && (i < N_ || p_.free_end || dynamic_b_); }
  // End node B is stepped (free, or a body's end in a WithDynamicEndB() tether).
  bool DynamicB() const { return p_.free_end || dynamic_b_; }
  // explicit carrying a body at end B over an advance from `e` (the consistent coupling): its
  // Advance puts end node B on MuJoCo's Euler path and sums end A's impulse over the substeps.
  bool ExplicitWithBody(const Ends& e) const {
    return p_.integrator == Integrator::kExplicit && dynamic_b_ && e.body_b;
  }

  TetherParams p_;
  Environment env_;
  bool dynamic_b_ = false;  // see WithDynamicEndB
  int N_ = 0;
  double L0_ = 0;               // [m] rest length of a segment
  double segment_mode_w_ = 0;      // [rad/s] SegmentModeFrequency
  double segment_mode_ratio_ = 0;  // [-] SegmentModeRatio
  double area_ = 0;             // [m^2] pi d^2 / 4
  double kn_ = 0, kt_ = 0;      // [kg/m^2] 1/2 rho Cdn d, 1/2 rho Cdt pi d (per length)
  // [1/m] the largest drag rate per unit speed of a dynamic node, 2 max(kn/(m + ma), kt/m) l_i
  // with l_i its rest share stretched to max_strain (DragSubsteps' quick test)
  double drag_rate_per_speed_ = 0;
  double seabed_k_ = 0, seabed_c_ = 0;  // [N/m^2], [N s/m^2] per length
  double contact_k_ = 0, contact_c_ = 0;  // [N/m^2], [N s/m^2] per length
  double explicit_limit_ = 0;   // [s]
  double explicit_dt_ = 0;      // [s]
  StabilityTerms terms_;
  double damping_per_L0_ = 0;  // [N s/m] internal damping / rest segment length
  // Per-node arrays, owned by the tether and shared (not copied) by its Deployed views, which
  // point at their first node.
  struct NodeArrays {
    Eigen::VectorXd mass;             // [kg] (n) dry lumped mass
    Eigen::VectorXd added;            // [kg] (n) normal added mass Can rho A l_i
    Eigen::VectorXd inv_mass;         // [1/kg] (n) 1/m_i (multiplying is cheaper than dividing)
    Eigen::VectorXd inv_mass_normal;  // [1/kg] (n) 1/(m_i + ma_i)
    Eigen::VectorXd share;            // [m] (n) rest length lumped at each node
    Eigen::Matrix3Xd weight;          // [N] (3 x n) weight minus buoyancy per node
    // The explicit stable step's terms per dynamic node (Create; 0 elsewhere): the bound on
    // w [rad/s], the damping rate [1/s] and the node's limit [s] (DragSubsteps scales it).
    Eigen::VectorXd stab_w, stab_rate, stab_h;
  };
  std::shared_ptr<const NodeArrays> arrays_;
  const double* mass_ = nullptr;  // arrays_ from this tether's node 0 on
  const double* added_ = nullptr;
  const double* inv_mass_ = nullptr;
  const double* inv_mass_normal_ = nullptr;
  const double* share_ = nullptr;
  const double* weight_ = nullptr;  // 3 x n
  // Sums over the nodes for EnergyBound (the whole tether; a Deployed view sums its own):
  double total_mass_ = 0;    // [kg] mass and added mass
  double total_weight_ = 0;  // [N] |net weight| per node
  // A Deployed view: nodes 0 (drum exit) and 1 have the lumped values of the winch segment's
  // rest length rest_ instead of the arrays' (head_ = 2; 0 in the tether itself).
  int head_ = 0;
  double rest_ = 0;   // [m]
  double speed_ = 0;  // [m/s] payout speed, d rest_/dt
  double head_mass_[2] = {0, 0}, head_added_[2] = {0, 0}, head_inv_mass_[2] = {0, 0},
         head_inv_mass_normal_[2] = {0, 0}, head_share_[2] = {0, 0};
  Vec3 head_weight_[2] = {Vec3::Zero(), Vec3::Zero()};
  // Whether node i takes the head's lumped values (head_ is 0 or 2). Written with i < 2 so
  // that GCC sees the head arrays' bounds: with i < head_ its -Warray-bounds flags an inlined
  // constant index (head_mass_[17]) on the branch that is never taken.
  bool InHead(int i) const { return head_ != 0 && i < 2; }
  double Mass(int i) const { return InHead(i) ? head_mass_[i] : mass_[i]; }
  double Added(int i) const { return InHead(i) ? head_added_[i] : added_[i]; }
  double InvMass(int i) const { return InHead(i) ? head_inv_mass_[i] : inv_mass_[i]; }
  double InvMassNormal(int i) const {
    return InHead(i) ? head_inv_mass_normal_[i] : inv_mass_normal_[i];
  }
  double Share(int i) const { return InHead(i) ? head_share_[i] : share_[i]; }
  Vec3 Weight(int i) const { return InHead(i) ? head_weight_[i] : Vec3(weight_ + 3 * i); }
  ConstNodes WeightMatrix() const { return ConstNodes(weight_, 3, N_ + 1); }
  // Stretched length over which node i collects the distributed drag [m]: half of each
  // adjacent segment (l the stretched segment lengths). In a Deployed view (winch), the
  // drum-exit node takes the fraction L0/r of the winch segment and node 1 the rest, as for
  // the weight (Tether::Deployed): node 1's share is about r - L0/2, 0 when it is inserted and
  // when it is removed, so the loads at the drum are continuous across re-discretisations.
  double DragLength(int i, const double* l) const {
    const double a = i > 0 ? l[i - 1] : 0, b = i < N_ ? l[i] : 0;
    if (head_ && N_ >= 2 && i < 2) {
      const double c = L0_ / rest_;
      return i == 0 ? c * b : std::max(0.0, (1 - c) * a + 0.5 * b);
    }
    return 0.5 * (a + b);
  }
  // The winch segment's rest length at the instant of `e` [m] (a Deployed view).
  double WinchRest(const Ends& e) const { return e.rest > 0 ? e.rest : rest_; }
  // Galerkin curvature weight at interior node i: the mean of its two segments' rest lengths.
  double CurvatureWeight(int i) const {
    return i == 1 && head_ ? 0.5 * (rest_ + L0_) : L0_;
  }
  // One tether step of the configured integrator (the body of Advance's loop).
  void Step(Nodes x, Nodes v, const Ends& now, const Ends& next, double h, double* work,
            StepStatus* status, const History* history) const;
  // The divergence checks at the end of an Advance.
  void Check(ConstNodes x, ConstNodes v, const Ends& from, const Ends& to,
             StepStatus* status) const;
  // The same tether cut to its first two segments (N >= 3): the end reactions depend only on
  // the end node's two neighbours, so Reactions evaluates this 3-node window at each end
  // instead of the whole tether (same operations in the same order, so the same bits).
  std::shared_ptr<const Tether> window_;
};

}  // namespace mjtether

#endif  // MJTETHER_SRC_TETHER_H_
