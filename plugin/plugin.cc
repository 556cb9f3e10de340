// MuJoCo 2.2 glue: declarations from <custom>, state in mjData::userdata, forces through
// mjcb_passive.
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <mutex>
#include <shared_mutex>
#include <sstream>
#include <unordered_map>
#include <vector>

#include "contact_glue.h"
#include "declaration.h"
#include "environment_glue.h"
#include "mjtether.h"
#include "model_files.h"
#include "text_check.h"
#include "vehicle_glue.h"
#include "winch_declaration.h"

namespace mjtether {
namespace {

// Layout of one tether's block in mjData::userdata.
enum Slot : int {
  kInitialized = 0,     // 1 once the initial shape is set (mj_resetData zeroes it)
  kTime,                // [s] the tether's own time
  kStatus,              // 0 ok, 1 non-finite, 2 strain beyond max_strain, 3 energy blow-up
  kBadNode,             // first offending node
  kBadTime,             // [s] when it diverged
  kEndA,                // pos(3) vel(3) axis(3) of end A at kTime
  kEndB = kEndA + 9,    // same for end B
  kForceA = kEndB + 9,  // last reactions: force A(3), torque A(3), force B(3), torque B(3)
  kTensionA = kForceA + 12,
  kTensionB,
  kPrevTime,  // [s] the tether's time one call before kTime (== kTime: none yet)
  kPrevPosA,  // position(3) of end A at kPrevTime (mocap velocity, second order)
  kPrevPosB = kPrevPosA + 3,
  kContactImpulse = kPrevPosB + 3,  // [N s] (3) contact impulse on the tether, last advance
  kContactCount = kContactImpulse + 3,  // reactions stored below (contact effect)
  kContactDropped,   // candidates beyond capacity at the last advance
  kContactEndA,      // [N] (3) contact force on end node A (passed to its site), last advance
  kContactEndB = kContactEndA + 3,  // [N] (3) the same for end B
  kStartTime = kContactEndB + 3,    // [s] when the initial shape was last set
  kStartStrain,                     // [-] strain of the chord at that moment (0 when not stretched)
  kStalled,                         // implicit steps accepted unconverged since the start
  kStalledTime,                     // [s] d->time of the call that first reported one
  kStallRun,                        // consecutive advances with a stalled step (kStallStop)
  kSnapTime,                        // [s] d->time of the first ringing snap (WatchSnaps)
  kSnapJump,                        // [N] the largest such snap's wave tension jump (0: none)
  kSwingStart,  // [s] WatchSwing: d->time at the start of the current block of two bounce periods
  kSwingMin,    // [N] the end tension's smallest in that block
  kSwingMax,    // [N] ... its largest
  kSwingSum,    // [N] ... its sum
  kSwingCount,  // [-] ... the steps in it (0: no block yet)
  kSwingBest,   // [-] the largest (max - min)/mean of a closed block
  kSwingTime,   // [s] the start of that block
  kAlternationSeen,  // [-] WatchAlternation: end tensions seen, up to 2 (a second difference
                     // needs three)
  kAlternationPrev,  // [N] (4) the last two tensions at end A, then at end B: T_{k-1}, T_{k-2}
  kAlternationD2 = kAlternationPrev + 4,    // [N] (2) per end, the sum of |T_k - 2 T_{k-1} +
                                            // T_{k-2}| over the current block ...
  kAlternationSum = kAlternationD2 + 2,     // [N] (2) ... and of T_k
  kAlternationCount = kAlternationSum + 2,  // [-] the steps in that block
  kAlternationStart,                        // [s] d->time at its start
  kAlternationRun,  // [-] (2) per end, the closed blocks in a row up to now that alternated
  kAlternationSince = kAlternationRun + 2,   // [s] (2) the start of the first of them
  kAlternationPeak = kAlternationSince + 2,  // [-] (2) their largest ratio
  kAlternationMean = kAlternationPeak + 2,   // [N] (2) the last one's mean tension
  kHeldMeanA = kAlternationMean + 2,  // [N] (3) implicit2: end A's held force (HeldMean) minus
                                      // the force at the state of the last advance, so that
                                      // calls between advances give the same
  kHeldMeanB = kHeldMeanA + 3,      // [N] (3) the same for end B where it is held
  kHeldPrevA = kHeldMeanB + 3,      // [N] (3) end A's stage mean over the advance before
  kHeldPrevB = kHeldPrevA + 3,      // [N] (3) the same for end B
  kHeldPrevStep = kHeldPrevB + 3,   // [s] that advance's length (0: none since the restart)
  kCoupleA,                         // end A on a body that moves: see CoupleSlot
  kCoupleB = kCoupleA + 9,  // (9 = kCoupleSize, below)
  kHeader = kCoupleB + 9,  // x (3 x n) then v (3 x n) follow, then the integrator's history
                           // (Tether::HistorySize, bdf2), then with contact `capacity` records
};
// A contact reaction record: body, force on it [N] (3), point of application [m] (3), applied
// at every callback until the next advance replaces them.
constexpr int kContactRecord = 7;
// With a winch, after the state: the drum's deployed length [m], payout speed [m/s] and the
// index of the drum-exit node (Payout::first).
enum WinchSlot : int { kWinchLength = 0, kWinchSpeed, kWinchFirst, kWinchSlots };

// Per end attached to a body that moves (docs/coupling.md), from kCoupleA or kCoupleB: the
// work balance of the coupling, for the chatter check.
enum CoupleSlot : int {
  kSpurious = 0,     // [J] energy the end gave the body beyond what the tether lost there,
                     // each step in the frame moving with the site (docs/coupling.md)
  kEnergyScale = 1,  // [J] largest energy of the end seen (kinetic of the site's velocity
                     // change over a step + elastic of the end segment)
  kBodyWork = 2,     // [J] work the end did on the body (for the message)
  kCoupleSteps = 3,  // [-] steps checked
  kDampingRate = 4,  // [-] h lambda of the end's damping on the body (CheckEndDamping)
  kLeadTime = 5,     // [s] end B of a lead tether: the time its state is at (see EvaluateLead)
  kStartVel = 6,     // [m/s] (3) the site's velocity when the balance started (its frame)
  // A lead tether's end A is not coupled: its block (kCoupleA) keeps, from kKnownAccel, the
  // site's acceleration [m/s^2] (3) from the passive forces at its last step (EvaluateLead).
  kKnownAccel = 0,
  // and from kSlowCorrection the slow-mode correction [N] (3) in the force end B's body got.
  kSlowCorrection = 3,
  kCoupleSize = 9,
};
static_assert(kCoupleB - kCoupleA == kCoupleSize && kHeader - kCoupleB == kCoupleSize,
              "the header's coupling blocks hold kCoupleSize slots each");

// Divergence codes in kStatus.
enum Divergence : int {
  kNonFinite = 1,
  kStrain = 2,
  kKinetic = 3,
  kChatter = 4,
  kEndDamping = 5,  // the end's velocity-dependent force too stiff for the body's step
  kStallStop = 6,   // every step of the last kStallSteps accepted with Newton not converged
  kSeabedEnd = 7,   // a held end's node on the seabed, stiff on its body's step (CheckSeabedEnd)
};

struct AttachedTether {
  AttachedTether(std::string n, Tether t) : name(std::move(n)), tether(std::move(t)) {}
  std::string name;
  Tether tether;
  int site[2] = {-1, -1};  // -1: free end
  int body[2] = {-1, -1};
  bool mocap[2] = {false, false};  // end on a mocap body: velocity by finite difference
  int offset = 0;                  // start of this tether's block in userdata
  bool contact = false;            // the contact effect is on
  TetherContacts contacts;         // the geoms it may touch (contact_glue.h)
  // End on a body with degrees of freedom (not the world, not mocap): the body feels the end
  // force explicitly over its step (docs/coupling.md).
  bool coupled[2] = {false, false};
  CouplingLimit limit[2];  // the time-step advisor's figures at load time
  // The body at that end bouncing on the whole taut line, a spring EA/L (BounceMode): watched
  // for snaps where the segment mode is not (WatchSnaps, RingWarnings' second message).
  BounceMode bounce[2];
  int bounce_end = -1;  // the end whose bounce WatchSnaps watches (-1: none)
  int swing_end = -1;   // the end whose bounce WatchSwing watches (-1: none)
  // The end's node on the seabed would be stiff on its body's step (max(omega_s h, h c_s/m_eff)
  // >= kLeadFromSeabed) and the end has the held force: CheckSeabedEnd stops the tether when the
  // node touches the seabed. seabed_cure: the consistent coupling would have been taken with
  // integrator=bdf2 or implicit (the stop's advice names them).
  bool seabed_watch[2] = {false, false};
  bool seabed_cure[2] = {false, false};
  // The consistent coupling (docs/coupling.md): end B on a free body, integrator implicit,
  // bdf2, implicit2 or explicit (from kLeadFrom, kLeadFromImplicit2, kLeadFromExplicit), no
  // winch, contact or clamp at B, MuJoCo's Euler or implicit integrator. The tether then steps
  // one MuJoCo step ahead with its end node B dynamic (this copy, Tether::WithDynamicEndB),
  // carrying the body's effective mass, and the body gets the force consistent with that step.
  std::optional<Tether> lead;
  // A winch (winch:NAME, docs/winch.md) at internal end A (sites swapped when declared at B).
  bool winch = false;
  bool swapped = false;            // the winch is at the declared end B
  WinchParams winch_params;
  int actuator = -1;               // whose ctrl commands it
  double initial_length = 0;       // [m] deployed at the start (the tether's `length`)
  int winch_offset = 0;            // start of the winch slots in userdata
  // start=static (docs/static_start.md): the relaxed shape at qpos0 (x, 3 x nodes) and the
  // ends it holds, computed at load; a restart with the ends at the same places copies it,
  // any other relaxes again (StartShape).
  std::vector<double> static_x;
  StaticResult static_result;  // how the load-time relaxation went
  Vec3 static_a = Vec3::Zero(), static_b = Vec3::Zero();
};

// The start shape at a restart: the initial shape (Tether::InitialShape), and with
// start=static that shape relaxed to static equilibrium with the ends held (the load-time
// shape when the ends are where they were at load). Velocities: zero inside, the sites' at
// the ends. `work`: WorkspaceSize() doubles.
void StartShape(const AttachedTether& at, const Tether& tether, const Ends& now, double* x,
                double* v, double* work) {
  tether.InitialShape(now, x, v);
  if (tether.params().start != Start::kStatic) return;
  const bool free_end = at.site[1] < 0;
  if (!at.static_x.empty() && now.a.pos == at.static_a &&
      (free_end || now.b.pos == at.static_b)) {
    std::copy(at.static_x.begin(), at.static_x.end(), x);
    return;
  }
  Ends held = now;
  held.contacts = nullptr;
  held.body_b = nullptr;
  if (!at.tether.RelaxToStatic(held, x, v, work).ok) {
    tether.InitialShape(now, x, v);  // unusable (load refused it at qpos0): the catenary
  }
}

// The deployed unstretched length [m]: the winch's, else the declared length.
double DeployedLength(const AttachedTether& at, const double* u) {
  return at.winch ? u[at.winch_offset - at.offset + kWinchLength] : at.tether.params().length;
}

// The deployment stored in d (a tether with a winch).
Payout LoadPayout(const AttachedTether& at, const double* u) {
  const double* w = u + (at.winch_offset - at.offset);
  Payout p;
  p.first = static_cast<int>(w[kWinchFirst]);
  p.speed = w[kWinchSpeed];
  const double L0 = at.tether.rest_segment_length();
  p.rest = w[kWinchLength] - (at.tether.segments() - p.first - 1) * L0;
  return p;
}

// The drum's impedance over the step [N s/m] for a winch in tension mode (its law takes the
// tension at the step's end, WinchSpeed); 0 in speed mode, where the tension is not read.
double DrumImpedanceFor(const AttachedTether& at, const Tether& tether, const double* x,
                        const Payout& p, double dt) {
  return at.winch_params.mode == WinchMode::kTension ? tether.DrumImpedance(x, p, dt) : 0;
}

// Doubles of mjData stack for one step's contact candidates.
int ContactWorkSize(const AttachedTether& at) {
  if (!at.contact) return 0;
  return ChunkBoxesSize(at.tether.segments()) +
         static_cast<int>((at.contacts.capacity * sizeof(ContactPoint) + sizeof(double) - 1) /
                          sizeof(double));
}

struct ModelTethers {
  std::string source;
  std::vector<AttachedTether> tethers;
  int work_size = 0;  // doubles of mjData stack the callback takes
  int nuserdata = 0;  // m->nuserdata after Attach, to catch a stale registration
  std::vector<std::string> warnings;  // time-step advisor (see Warnings in mjtether.h)
  Environment env;                    // gravity and water, for the divergence diagnosis
  int nv = 0;                         // m->nv: the coupling's Jacobian scratch is 6 nv doubles
  double timestep = 0;  // [s] m->opt.timestep at Attach, for which the coupling was chosen
};

// Coupling chatter (docs/coupling.md): the energy an end gave its body beyond what the tether
// lost at that end exceeds this multiple of the largest energy seen at the end (kinetic
// energy of the site's effective mass plus elastic energy of the end segment). A stable
// coupling keeps it below about one such energy (the modified energy of symplectic Euler
// oscillates around the true one); a chatter pumps it every step.
constexpr double kChatterRatio = 4;
constexpr double kChatterFloor = 1e-3;  // [J] below this nothing is reported
// Steps of a run (or since a reset) before the check starts: a chatter persists, a start-up
// transient (the first steps' tiny energy scale) does not.
constexpr double kChatterSteps = 50;

// More automatic explicit substeps per MuJoCo step than this is refused at load time: the
// run would take hours per simulated second (see the time-step advisor in Attach).
constexpr int kMaxAutoSubsteps = 100000;

std::shared_mutex g_mutex;
std::unordered_map<const mjModel*, std::unique_ptr<ModelTethers>> g_models;
mjfGeneric g_previous_passive = nullptr;
bool g_installed = false;

void Passive(const mjModel* m, mjData* d);

const ModelTethers* Lookup(const mjModel* m) {
  std::shared_lock<std::shared_mutex> lock(g_mutex);
  auto it = g_models.find(m);
  if (it == g_models.end() || it->second->nuserdata != m->nuserdata) return nullptr;
  return it->second.get();
}

const char* TextName(const mjModel* m, int i) { return m->names + m->name_textadr[i]; }
const char* TextData(const mjModel* m, int i) { return m->text_data + m->text_adr[i]; }

// Site position, velocity and x-axis now. A mocap-rooted body has no velocity in MuJoCo, so its
// velocity is the second-order backward difference (BDF2 on a non-uniform grid) of its
// positions at this call and the two before:
//   v2 = p2 (2 h2 + h1)/(h2 (h1 + h2)) - p1 (h1 + h2)/(h1 h2) + p0 h2/(h1 (h1 + h2)),
// h1 = t1 - t0, h2 = t2 - t1 (first order, (p2 - p1)/h2, after a start). The first-order
// difference is the mean velocity over the last step, h/2 late; through the axial damping
// that lag alone put a 0.13 N error on the fairlead tension of the fixed line at 2 ms.
EndState SiteState(const mjModel* m, const mjData* d, const AttachedTether& at, int end,
                   const double* u) {
  EndState e;
  const int s = at.site[end];
  const double* stored = u + (end == 0 ? kEndA : kEndB);
  e.pos = Vec3(d->site_xpos + 3 * s);
  const double* R = d->site_xmat + 9 * s;
  e.axis = Vec3(R[0], R[3], R[6]);
  if (at.mocap[end] && PrescribedVelocity(m, d, at.body[end], &e.vel)) {
    // moved by a motion: declaration: its exact velocity
  } else if (at.mocap[end]) {
    const double h2 = d->time - u[kTime], h1 = u[kTime] - u[kPrevTime];
    const Vec3 p1(stored), p0(u + (end == 0 ? kPrevPosA : kPrevPosB));
    if (u[kInitialized] != 0 && h2 > 0 && e.pos == p1) {
      // Not moved since the last call: MuJoCo's own RK4 calls at t + h/2 and t + h with the
      // mocap body where it was at t (it moves only between steps); the three-point formula
      // would read that pause as a reversal.
      e.vel = Vec3::Zero();
    } else if (u[kInitialized] != 0 && h2 > 0 && h1 > 0) {
      e.vel = e.pos * ((2 * h2 + h1) / (h2 * (h1 + h2))) - p1 * ((h1 + h2) / (h1 * h2)) +
              p0 * (h2 / (h1 * (h1 + h2)));
    } else if (u[kInitialized] != 0 && h2 > 0) {
      e.vel = (e.pos - p1) / h2;
    } else if (u[kInitialized] != 0) {
      e.vel = Vec3(stored + 3);
    }
  } else {
    mjtNum res[6];
    mj_objectVelocity(m, d, mjOBJ_SITE, s, res, 0);
    e.vel = Vec3(res[3], res[4], res[5]);
  }
  return e;
}

// Applies end `end`'s reaction on its body (force [N] and moment [N m], world frame) at the
// attachment site, so that the force's lever arm about the body's centre of mass is the
// site's. The one place every path (held force, consistent coupling) applies a reaction.
void ApplyEndReaction(const mjModel* m, mjData* d, const AttachedTether& at, int end,
                      const double* force, const double* torque) {
  mj_applyFT(m, d, force, torque, d->site_xpos + 3 * at.site[end], at.body[end],
             d->qfrc_passive);
}

void StoreEnd(const EndState& e, double* dst) {
  for (int i = 0; i < 3; ++i) {
    dst[i] = e.pos[i];
    dst[3 + i] = e.vel[i];
    dst[6 + i] = e.axis[i];
  }
}

EndState LoadEnd(const double* src) {
  EndState e;
  e.pos = Vec3(src);
  e.vel = Vec3(src + 3);
  e.axis = Vec3(src + 6);
  return e;
}

// The header's bookkeeping of a (re)start from the initial shape at `time`, the ends at `now`
// (start_strain: the chord's strain then, 0 when not stretched).
void RecordStart(double* u, const Ends& now, double time, double start_strain) {
  u[kInitialized] = 1;
  u[kStartTime] = time;
  u[kStartStrain] = start_strain;
  u[kStallRun] = 0;
  u[kTime] = u[kPrevTime] = time;
  StoreEnd(now.a, u + kEndA);
  StoreEnd(now.b, u + kEndB);
}

// The header's bookkeeping of an advance to `time`, the ends at `now`: the last time and end
// positions become the previous ones (mocap velocity, second order).
void RecordAdvance(double* u, const Ends& now, double time) {
  u[kPrevTime] = u[kTime];
  std::copy(u + kEndA, u + kEndA + 3, u + kPrevPosA);
  std::copy(u + kEndB, u + kEndB + 3, u + kPrevPosB);
  u[kTime] = time;
  StoreEnd(now.a, u + kEndA);
  StoreEnd(now.b, u + kEndB);
}

// A failed step: the divergence code from its reason, the node and the time, in the header
// (the tether then stays inert until a reset).
void RecordFailure(double* u, const StepStatus& status, double time) {
  u[kStatus] = status.reason.rfind("strain", 0) == 0    ? kStrain
               : status.reason.rfind("kinetic", 0) == 0 ? kKinetic
                                                        : kNonFinite;
  u[kBadNode] = status.node;
  u[kBadTime] = time;
}

// An end teleported by the user (qpos or mocap_pos set by hand): since the last call it moved
// farther than its velocity then explains, by more than max_strain segment lengths. No tether
// can follow that within max_strain, so the tether restarts from its initial shape instead of
// being reported as diverged.
// A body that MuJoCo moved was not teleported, however hard it accelerated: its step took it
// along its new velocity (x + h v_new, semi-implicit Euler and implicit; RK4 between the old
// and the new one), which explains the move. Without that, a vehicle flung by a 4e8 N
// stretched start (the scene fuzzer's seed 391: 33 m in one step, a dt^2/2 of 12 m) counted
// as teleported, and the tether restarted silently from a new initial shape. A mocap body's
// velocity is a finite difference of its positions, which a jump by hand also moves: its ends
// are judged by the velocity before the move only.
bool Teleported(const AttachedTether& at, const Ends& now, const double* u, double time) {
  const double dt = time - u[kTime];
  if (u[kInitialized] == 0 || !(dt > 0)) return false;
  const double jump = at.tether.params().max_strain * at.tether.rest_segment_length();
  for (int end = 0; end < 2; ++end) {
    if (at.site[end] < 0) continue;
    const double* stored = u + (end == 0 ? kEndA : kEndB);
    const EndState& e = end == 0 ? now.a : now.b;
    const Vec3 moved = e.pos - Vec3(stored), v_old(stored + 3);
    if ((moved - dt * v_old).norm() <= jump) continue;
    if (!at.mocap[end] && ((moved - dt * e.vel).norm() <= jump ||
                           (moved - 0.5 * dt * (v_old + e.vel)).norm() <= jump)) {
      continue;
    }
    return true;
  }
  return false;
}

// The inverse mass W = J M^-1 J^T [1/kg] (3x3) of site s's body at the site, from MuJoCo's
// factored mass matrix (armature, so the vehicle's added mass, included). jac: 6 nv doubles.
Mat3 SiteInverseMass(const mjModel* m, mjData* d, int s, double* jac) {
  const int nv = m->nv;
  double* J = jac;             // 3 x nv, row-major
  double* MiJ = jac + 3 * nv;  // 3 x nv: M^-1 J^T, row per direction
  mj_jacSite(m, d, J, nullptr, s);
  mj_solveM(m, d, MiJ, J, 3);
  Mat3 W;
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) W(a, b) = mju_dot(J + a * nv, MiJ + b * nv, nv);
  }
  return 0.5 * (W + W.transpose());
}

// A tether whose every advance over this many MuJoCo steps in a row had a step accepted with
// the Newton iteration not converged, even at 1/256 of the step, stops (kStallStop): its state
// is then no longer a solution of its steps, and it drifts where nothing holds it (fuzzer seeds
// 346 and 8180: the vehicle-end tension frozen at 76 and 118 N against 0.2 and 0.1 N at
// 0.2 ms, the largest tension growing to 7.7e6 N, at 130 and 50 s of CPU per simulated
// second). An isolated stall (a segment switching law at a tiny residual) is not stopped. 50:
// docs/numerics_slack.md, session 14 (of the long run's 44 scenes with stalls, those that
// stall this long disagree with their fine step or take minutes).
constexpr double kStallSteps = 50;

// Implicit steps accepted unconverged in an advance, counted with the time of the first; a
// run of them (kStallSteps advances in a row) stops the tether.
void CountStalls(const StepStatus& status, double time, double* u) {
  if (status.stalled_steps > 0) {
    if (u[kStalled] == 0) u[kStalledTime] = time;
    u[kStalled] += status.stalled_steps;
    u[kStallRun] += 1;
    if (u[kStallRun] >= kStallSteps && u[kStatus] == 0) {
      u[kStatus] = kStallStop;
      u[kBadNode] = -1;
      u[kBadTime] = time;
    }
  } else {
    u[kStallRun] = 0;
  }
}

// The consistent coupling is used from this coupling omega h on (docs/coupling.md): below it
// the held force is accurate (BlueROV2 at EA 6e4, omega h 0.26: 0.65% in tension) and the
// consistent one, which integrates the body-end mode with backward Euler, damps that mode
// (2.3%). integrator=implicit and bdf2 (whose end node B takes a backward-Euler step inside
// the BDF2 step: with BDF2's history the body kept accelerating after a snap, 0.68 N s from
// nothing); implicit2 from kLeadFromImplicit2 (below).
constexpr double kLeadFrom = 1;
// integrator=explicit from this omega h on (docs/coupling.md, "explicit and rk4 (session 10,
// s10exp)"): end node B steps in the explicit substeps with the body's inertia
// (Tether::ExplicitStep). On the scene fuzzer's long-run scenes with the held force failing
// (disagreeing with their 0.2 ms selves), it cut the failures from 23 of 123 to 17 at omega h
// 0.5-1 and from 26 of 103 to 17 at 1-2, and made no difference at 0.25-0.5 (18 of 128 to 16,
// six new failures). Not rk4: there it added failures (17 of 137 to 23 at 0.25-0.5, 17 of 90
// to 18 at 0.5-0.8), the held force being fourth order in the tether and the consistent
// coupling first order at the body.
// Session 26 tried 0.4 (with kLeadFromImplicit2 0.3): 8 failures fixed and 2 new on the
// tuned seeds 201-10000, but 1 fixed and 3 new on the held-out 10001-15000; not kept
// (docs/coupling.md, session 26).
constexpr double kLeadFromExplicit = 0.5;
// implicit2 (session 10, s10i2: end node B takes SDIRK's velocity stages and the body's
// position step, Sdirk2Step) from this omega h on: the scene fuzzer's implicit2 scenes failed
// in 14.3% of scenes at omega h 0.5-1 with the held force and 11.1% with this (18.7% -> 10.3%
// at 1-2, 26.4% -> 11.0% at 2-4, 8.8% at >= 4, refused before), but with it from 0.1 in 8.7% ->
// 13.7% at 0.1-0.25 and 16.2% -> 14.7% at 0.25-0.5; the BlueROV2 at omega h 0.26 (EA 6e4) is
// 1.5% off in tension with it, 0.58% without (docs/coupling.md, implicit2).
// Session 26's 0.3: not kept, as kLeadFromExplicit's 0.4 above.
constexpr double kLeadFromImplicit2 = 0.5;
// Every integrator that has the consistent coupling also takes it where the end segment's
// internal damping is stiff on the body's step, from h (damping/L0)/m_eff at this value on
// (session 13), whatever omega h. The held force gives the body the damper's force of the last
// step: its velocity then lags the end node's by a fraction of the relative velocity that
// h (damping/L0)/m_eff sets, and a damper of damping/L0 of 1e4 N s/m turns a lag of 1 mm/s into
// 10 N. The scene fuzzer's seed 1065 (implicit2, 240 segments of 4.7 cm, damping 618 N s on a
// 39 kg vehicle towed by a 1.7 m/s current: 0.66 at 2 ms) held 49 N at 0.8 s at 2 ms, 22 N at
// 0.2 ms and 5.2 N at 0.02 ms (0.0066); with the consistent coupling 4.9 N at 2 ms. On the
// 107 long-run scenes with h (damping/L0)/m_eff >= 0.01 (session 12's log; not rk4, which has
// no consistent coupling), the coupling from 0.01 turned 12 of the 15 failures into passes and
// 3 passes into failures, all three below 0.025 (0.011, 0.014 and 0.024; the nine fixed above
// 0.025 are at 0.033-1.9).
// Since session 42 only where the end's own mode is damped at least as much as the consistent
// coupling's step damps it (DamperTakesTheLead): that step damps the body-end mode (omega =
// sqrt(k_end/m_eff), z = omega h) numerically by a ratio of about kappa z/2 (SlowModeKappa),
// and the end damper gives it a ratio of (damping/L0)/(2 sqrt(k_end m_eff)) = d/(2 z), d = h
// (damping/L0)/m_eff. Where kappa z^2 > d the step's damping is the larger, and the held
// force, whose damper lag errs by O(d), is the closer of the two: seed 12117 with
// damping_ratio=1 (the ringing warning's advice; bdf2, 41 segments, a 101 kg vehicle, d 0.0995,
// z 0.465) read its vehicle-end tension 13% low with the consistent coupling and within 0.05%
// of its 0.2 ms self with the held force. 1065 (d 0.66, z 0.11) keeps the consistent coupling.
// Not from d = kHeldDamperMax on, where the held force's lag is no small error whatever the
// mode: held-out seed 14719 (bdf2, 58 segments, damping ratio 15.8, a 5.7 kg vehicle; d 0.546,
// z 0.821, kappa z^2 0.674) was 4 mm off its fine step with the consistent coupling and 157 mm
// with the held force. 0.25 lies between the two measured (0.0995 held, 0.546 consistent).
constexpr double kLeadFromDamping = 0.025;
constexpr double kHeldDamperMax = 0.25;
// Every integrator that has the consistent coupling also takes it where the seabed under end
// node B would be stiff on the body's step: from max(omega_s h, h c_s/m_eff) at this value on,
// omega_s = sqrt(k_s/m_eff) with k_s and c_s the seabed's penalty and damping over the node's
// share (Tether::EndSeabedStiffness, EndSeabedDamping; session 38). The held force gives the
// body the node's seabed contact at the start of its step; seed 9022 (bdf2, one 56 m segment, a
// 7.7 kg vehicle thrust onto the seabed: 0.97 and 1.34) read its end tension 38% above its
// 0.2 ms self, and agrees within 3% with the consistent coupling. Measured on the long runs
// (docs/coupling.md, session 38): taken from 0.025 of h c_s/m_eff (kLeadFromDamping) it fixed
// 12 scenes (most of them stopped by the end-damping check) and broke 17 passes (3 to failures),
// whose vehicle never reached the seabed and whose body mode the consistent coupling then damps;
// every scene it fixed with max above 0.7 gained and none lost, below 0.7 both (a fixed 0.59,
// failures at 0.51 and 0.32).
constexpr double kLeadFromSeabed = 0.7;

// A winch tether's start shape (a restart of Evaluate or EvaluateLead): the deployed part from
// the drum exit, the rest on the drum (at site A). A restart keeps the deployment; a reset
// (kInitialized = 0) restores the declared one. Sets now->rest to the winch segment's.
void StartWinchShape(const AttachedTether& at, const Tether& tether, double* u, Ends* now,
                     double* x, double* v) {
  double* wu = u + (at.winch_offset - at.offset);
  const double L0 = tether.rest_segment_length();
  if (u[kInitialized] == 0) {
    wu[kWinchLength] = at.initial_length;
    wu[kWinchSpeed] = 0;
    wu[kWinchFirst] = tether.segments() - std::lround(at.initial_length / L0);
  }
  const Payout p = LoadPayout(at, u);
  const Tether view = tether.Deployed(p.first, p.rest, 0);
  now->rest = p.rest;
  view.InitialShape(*now, x + 3 * p.first, v + 3 * p.first);
  for (int i = 0; i < p.first; ++i) {
    for (int c = 0; c < 3; ++c) {
      x[3 * i + c] = now->a.pos[c];
      v[3 * i + c] = now->a.vel[c];
    }
  }
}

// Snaps that ring the segment axial mode (docs/reference.md "Internal damping"). An implicit
// step damps that mode numerically (backward Euler by a ratio of about omega_n h / 2 for
// omega_n h < 1) and does not resolve it at all where omega_n h > 1, while a 10x smaller step
// keeps it; where the line goes slack again the ringing is clipped at zero tension and moves
// the mean, so the tensions after a snap depend on the step and on the segment count. The
// scene fuzzer's open-transient failures were mostly such scenes (session 25: of 58, 38
// agreed with their fine step at a damping ratio of 0.2; at 0.144 the ringing of
// models/seabed_hfield.xml dies within a period and its 2 ms run agrees with its 0.2 ms self).
// Before each advance the state is scanned for a slack segment closing to taut within the step
// (Tether::SnapJump); where the tether's damping ratio is below kRingDampingRatio and omega_n h
// above kRingOmegaH (mjtether.h), a wave tension jump of at least kRingBigJump, or of at least
// kRingJump and kRingRelative of the smaller end tension, is recorded (first time, largest jump),
// and RingWarnings says so at the end of the run. The smaller end's since session 42: a jump moves
// that end's mean most, and against the larger one seed 6260 (implicit, undamped, 0.83 N snaps with
// 47 N at the TMS and 20 N at the vehicle) exited 0 silent, 5.19 N at 2 ms against 5.71 N at 0.2 ms
// (SceneFuzzOracle.ASnapIsMeasuredAgainstTheSmallerEndTension). Not with a winch (its moving rest
// length). The explicit schemes too since session 33: their substeps keep the ringing (no numerical
// damping), but the energy a snap leaves in it, clipped where the line goes slack again, differs
// between steps as much (seed 3244, explicit, 4 segments of 9.8 m, EA 2.7e8 N, undamped:
// vehicle-end tension over 0.8-1 s 65.5 N at 2 ms, 15.9 N at 0.2 ms, 16.4 N at 0.02 ms; with
// damping_ratio=1 15.70, 15.76, 15.72 N, as every implicit scheme at 2 ms undamped). On session
// 32's long runs this watch turned 21 of the 30 explicit and rk4 failures into runs that warned and
// whose damped twin agrees, and no pass into a failure (docs/reference.md, "Internal damping").
// The warning's cure does not reach a line started near taut (session 44): the scene fuzzer's
// seeds 201-2200 with every tether as long as its span failed 13 of 1,066 runs, 10 of them
// warned here, none of the 10 agreeing with damping_ratio=1. Most of the line goes slack and
// snaps taut, the slower modes take the snap, and the tensions after it depend on the step
// damped or not: seed 491 at the span (implicit2, 65 segments, 14.1 m), damped, reads 10.7,
// 13.4, 23.24, 23.27 and 23.30 N at 2, 1, 0.5, 0.2 and 0.02 ms (mean vehicle-end tension over
// 0.8-1 s; tests/step_check_test.cc); others converge more slowly (seed 1910 damped: 35.5,
// 38.7, 41.0, 42.7, 43.8 N). The warning says so and asks for the comparison
// (docs/scene_fuzzer.md, session 44).
constexpr double kRingBigJump = 1.0;    // [N]
constexpr double kRingJump = 0.1;       // [N] below the fuzzer's 0.5 N tension tolerance
constexpr double kRingRelative = 0.02;  // [-] of the smaller end tension, below its 5%
}  // namespace

bool WatchesRinging(const Tether& t, double timestep) {
  if (t.params().winch || !(t.SegmentModeRatio() < kRingDampingRatio)) {
    return false;
  }
  const int substeps = t.SubstepsFor(timestep);
  return substeps > 0 && t.SegmentModeFrequency() * timestep / substeps > kRingOmegaH;
}

namespace {
// The swing of a body's bounce on the taut line (BounceMode::swing_watched, session 45): the
// end tension over blocks of two bounce periods, its peak-to-peak against its mean. Called before
// each advance, with the last advance's tension (none before the first: time at the start).
void WatchSwing(const AttachedTether& at, double time, double* u) {
  if (at.swing_end < 0 || !(time > u[kStartTime])) return;
  const double T = u[at.swing_end == 0 ? kTensionA : kTensionB];  // [N]
  const double block = 2 * 2 * M_PI / at.bounce[at.swing_end].omega;  // [s]
  if (u[kSwingCount] > 0 && time - u[kSwingStart] < block) {
    u[kSwingMin] = std::min(u[kSwingMin], T);
    u[kSwingMax] = std::max(u[kSwingMax], T);
    u[kSwingSum] += T;
    u[kSwingCount] += 1;
    return;
  }
  if (u[kSwingCount] > 0) {
    const double mean = u[kSwingSum] / u[kSwingCount], swing = u[kSwingMax] - u[kSwingMin];
    if (mean > 0 && swing >= kRingJump && swing / mean > u[kSwingBest]) {
      u[kSwingBest] = swing / mean;
      u[kSwingTime] = u[kSwingStart];
    }
  }
  u[kSwingStart] = time;
  u[kSwingMin] = u[kSwingMax] = u[kSwingSum] = T;
  u[kSwingCount] = 1;
}

// The alternation watch (session 46; plugin/mjtether.h, kAlternationRatio): each end's tension
// over blocks of kAlternationBlock advances, the mean of its second difference |T_k - 2 T_{k-1} +
// T_{k-2}| against its mean. Called before each advance, with the last advance's tensions.
// Implicit schemes only: they damp every mode the step does not resolve, so a tension that
// alternates at the step's own period is theirs; explicit and rk4 keep an undamped segment
// mode at their substeps, and its ringing sampled once per step alternates too (the ringing
// watch's case: at 2 ms, 56 of the 64 scenes of the fuzzer's 2,284 that alternated to their
// end, none of them off its fine step).
void WatchAlternation(const Tether& t, double time, double* u) {
  if (IsExplicit(t.params().integrator) || !(time > u[kStartTime])) return;
  const double T[2] = {u[kTensionA], u[kTensionB]};  // [N]
  if (u[kAlternationSeen] >= 2) {
    if (u[kAlternationCount] == 0) u[kAlternationStart] = time;
    for (int e = 0; e < 2; ++e) {
      const double* prev = u + kAlternationPrev + 2 * e;
      u[kAlternationD2 + e] += std::abs(T[e] - 2 * prev[0] + prev[1]);
      u[kAlternationSum + e] += T[e];
    }
    if (++u[kAlternationCount] >= kAlternationBlock) {
      for (int e = 0; e < 2; ++e) {
        const double d2 = u[kAlternationD2 + e] / u[kAlternationCount];     // [N]
        const double mean = u[kAlternationSum + e] / u[kAlternationCount];  // [N]
        const double ratio = mean > 0 && d2 >= kRingJump ? d2 / mean : 0;
        if (ratio >= kAlternationRatio) {
          if (u[kAlternationRun + e] == 0) {
            u[kAlternationSince + e] = u[kAlternationStart];
            u[kAlternationPeak + e] = 0;
          }
          u[kAlternationRun + e] += 1;
          u[kAlternationPeak + e] = std::max(u[kAlternationPeak + e], ratio);
          u[kAlternationMean + e] = mean;
        } else {
          u[kAlternationRun + e] = 0;
        }
        u[kAlternationD2 + e] = u[kAlternationSum + e] = 0;
      }
      u[kAlternationCount] = 0;
    }
  } else {
    u[kAlternationSeen] += 1;
  }
  for (int e = 0; e < 2; ++e) {
    u[kAlternationPrev + 2 * e + 1] = u[kAlternationPrev + 2 * e];
    u[kAlternationPrev + 2 * e] = T[e];
  }
}

void WatchSnaps(const AttachedTether& at, const double* x, const double* v, double dt,
                double time, double* u) {
  const Tether& t = at.tether;
  WatchSwing(at, time, u);
  WatchAlternation(t, time, u);
  if (at.bounce_end < 0 && !WatchesRinging(t, dt)) return;
  const double jump = t.SnapJump(x, v, dt);
  // A snap of kRingBigJump counts; a smaller one where it is kRingRelative of the smaller of
  // the ends' last tensions (0.1 N on a 1 MN line does not).
  const double scale = kRingRelative * std::min(u[kTensionA], u[kTensionB]);  // [N]
  if (!(jump >= kRingBigJump || jump >= std::max(kRingJump, scale))) return;
  if (!(u[kSnapJump] > 0)) u[kSnapTime] = time;
  u[kSnapJump] = std::max(u[kSnapJump], jump);
}

// The consistent coupling's slow-mode correction (docs/coupling.md, session 34). The body's
// force F depends on where end node B ends the step, and MuJoCo then moves the body by
// x+ = x + h v+: on a mode in which the line acts as a spring K (the body bouncing or swinging
// on the whole taut line, end A held, omega h = z) the step is v+ = v - h W K (kappa x+ +
// (1 - kappa) x), whose energy falls by 1/(1 + kappa z^2) per step, a numerical damping ratio
// of kappa z/2. kappa is where in the step the body's force is taken (SlowModeKappa): 1 where
// end node B takes backward Euler's step (implicit, bdf2), 1/2 with implicit2's stages,
// (n - 1)/(2n) with explicit's n substeps. The held force (kappa = 0, MuJoCo's symplectic
// Euler) has none. SlowModeCorrection gives the body kappa h K (I + kappa h^2 W K)^-1 (v_B -
// v_A) besides, with its reaction at end A, which makes the model step symplectic Euler on a
// slightly softer spring: no numerical damping, stable at every z. K is the line's
// quasi-static stiffness at end B (Tether::LineStiffness), far below the end segment's EA/L0
// on more than a few segments, so the fast body-end mode stays damped as before.
// Only on a slow mode, kappa z^2 <= kSlowModeMax (z <= 0.1 with backward Euler, 0.14 with the
// others), each mode of W K apart (since session 35; session 34 took the bound h^2 lambda_max(W)
// lambda_max(K) for all three, and a line's fast bounce along it then switched off the correction
// of the vehicle's slow swing across it): there a step's damping is small but adds up over many
// steps, while symplectic Euler's own energy error, which the correction brings back, is O(z) (at z
// = 0.45 a free body on a taut line gained 7.5% of its energy within a bounce, the held force 9%,
// where the dissipative step never rises: CouplingExplicit.FreeBodyOnTautTetherGainsNoEnergy), and
// the model stops holding (implicit2's spectral radius at z = 4 is 0.82, the model's 0.33). None
// where a segment is slack at the step's start or end (no first-order stiffness, or a snap or
// release within the step), where end node B outweighs the body (the line is no light spring then)
// or on a winch (its length changes within the step).
// Test: LightVehicle.BounceOnATautLineIsNotDampedByTheConsistentCoupling (a 667 kg body
// bouncing at z = 0.077: 51% of its amplitude left after 0.5 s with implicit, 72% with
// implicit2, without this; within 0.06% of the fine step's with it). Scene fuzzer seed 11700
// (implicit2, a 3.2 t vehicle thrust against a taut 5.8 m line): 7.6 cm off its fine-step
// self, the swing's amplitude 13% low; 0.6 cm with this. Mode by mode:
// LightVehicle.SwingAcrossATautLineIsNotDampedWhereItsBounceIsFast (a swing at z^2 = 4e-4 on a
// line whose bounce has z^2 = 0.08: 16% low after 2 s with the bound, within 0.5% now).
// Also where z^2 <= kSlowModeZ2Max, whatever kappa (session 36): symplectic Euler's energy error,
// which the correction brings back, depends on z, not on kappa z^2, and implicit2 and explicit
// (kappa <= 1/2) were corrected up to z^2 = 0.02 already; implicit and bdf2 (kappa 1) only to
// 0.01. LightVehicle.BounceJustAboveTheOldSlowModeBoundIsNotDamped (z^2 = 0.015: implicit and
// bdf2 kept 20% of the amplitude after 0.5 s, now within 0.3%); held-out seed 11384 (implicit, a
// bounce along the line at z^2 0.011-0.014) 8.2 cm off its fine-step self before, 3.2 cm now.
// Not beyond 0.02: carried on past kappa z^2 = 0.01 on a ramp to 0 (at 0.015 or at 0.04), the
// correction took explicit's yanked vehicle (a mode at z^2 = 0.0217, kappa 0.47, just above both
// bounds) to 1.24-1.25% of its work beyond it, tolerance 1% (Coupling.YankedVehicleGains...).
constexpr double kSlowModeMax = 0.01;
constexpr double kSlowModeZ2Max = 0.02;
double LargestEigenvalue(const Mat3& A) {
  return Eigen::SelfAdjointEigenSolver<Mat3>(A, Eigen::EigenvaluesOnly).eigenvalues().maxCoeff();
}
// W^1/2 (inverse: W^-1/2) of a symmetric positive semidefinite 3 x 3 matrix from its
// eigensolver, U diag(sqrt(w_i)) U^T, round-off below zero clipped to 0 (W^-1/2 needs every
// w_i > 0). The end-damping bound's and the slow-mode correction's mass scaling.
Mat3 SquareRoot(const Eigen::SelfAdjointEigenSolver<Mat3>& e, bool inverse = false) {
  Vec3 root = e.eigenvalues().cwiseMax(0).cwiseSqrt();
  if (inverse) root = root.cwiseInverse();
  return e.eigenvectors() * root.asDiagonal() * e.eigenvectors().transpose();
}
// kappa over an advance of n tether steps (StepStatus::substeps). The body's force is end node
// B's mean force over them, the node on MuJoCo's Euler path x + s v+: backward Euler takes each
// step's at its end, s = k h/n (k = 1 .. n), so kappa = (n + 1)/(2n), 1 for one step; explicit
// takes each at its start (k = 0 .. n - 1), (n - 1)/(2n), 0 with one substep (symplectic
// Euler, as the held force); implicit2's stages weigh (1 - gamma) at gamma h and gamma at h in
// each step, gamma (2 - gamma) = 1/2 of it, so 1/2 whatever n.
double SlowModeKappa(Integrator scheme, int substeps) {
  const double n = std::max(substeps, 1);
  switch (scheme) {
    case Integrator::kImplicit:
    case Integrator::kBdf2:
      return (n + 1) / (2 * n);
    case Integrator::kImplicit2:
      return 0.5;
    case Integrator::kExplicit:
      return (n - 1) / (2 * n);
    default:
      return 0;  // rk4 has no consistent coupling
  }
}

// Whether the end segment's internal damping makes the consistent coupling the closer model
// (kLeadFromDamping): d = h (damping/L0)/m_eff, z = the coupling omega h, kappa SlowModeKappa.
bool DamperTakesTheLead(double damping_h, double omega_h, double kappa) {
  return damping_h >= kLeadFromDamping &&
         (damping_h >= kappa * omega_h * omega_h || damping_h >= kHeldDamperMax);
}
// kappa h K (I + kappa h^2 W K)^-1 (v_B - v_A), K the line's stiffness at the step's start.
// The tether's step does not see the correction: the model step is v+ = v_B+ + h W K_c v, v_B+
// the uncorrected one, and K_c = kappa K/(1 + kappa z^2) per mode restores symplectic Euler's
// energy (without the inverse the bounce of the test grew 20% in 0.5 s with implicit).
// Mode by mode (session 35): with S = W^1/2 K W^1/2 = Q diag(lambda_i) Q^T, z_i^2 = h^2
// lambda_i, the correction is kappa h W^-1/2 Q diag(g_i) Q^T W^-1/2 (v_B - v_A), g_i =
// lambda_i/(1 + kappa z_i^2) on a slow mode (kappa z_i^2 <= kSlowModeMax or z_i^2 <=
// kSlowModeZ2Max) and 0 on the others;
// with every mode slow it is the expression above. A taut line's stiffness along it (EA/L) is
// far above its stiffness across it (T/l): the vehicle's swing is slow where its bounce is not.
Vec3 SlowModeCorrection(const Mat3& K, const Mat3& W, const Ends& now, double h, double kappa) {
  if (K.isZero(0) || !(kappa > 0)) return Vec3::Zero();
  const Eigen::SelfAdjointEigenSolver<Mat3> ew(W);
  if (!(ew.eigenvalues().minCoeff() > 0)) return Vec3::Zero();
  const Mat3 W_half = SquareRoot(ew), W_minus_half = SquareRoot(ew, true);
  const Eigen::SelfAdjointEigenSolver<Mat3> es(W_half * K * W_half);
  Vec3 g;
  for (int i = 0; i < 3; ++i) {
    const double lambda = std::max(es.eigenvalues()[i], 0.0);  // [1/s^2] the mode's omega^2
    const double kz2 = kappa * h * h * lambda, z2 = h * h * lambda;  // kappa z^2, z = omega h
    g[i] = kz2 <= kSlowModeMax || z2 <= kSlowModeZ2Max ? lambda / (1 + kz2) : 0;
  }
  const Mat3& Q = es.eigenvectors();
  return (kappa * h) * (W_minus_half * (Q * g.asDiagonal() * Q.transpose()) * W_minus_half *
                        (now.b.vel - now.a.vel));
}

// A tether with the consistent coupling at end B (AttachedTether::lead; docs/coupling.md).
// At a callback at a new time t the tether is at t (stepped there at the last callback): end
// node B is snapped to the site's actual position and velocity, and the tether steps ahead to
// t + h with end node B dynamic, its mass the body's effective mass at the site W^-1 (W = J
// M^-1 J^T, SiteInverseMass) plus its own, under the force W^-1 a_other, a_other the site's
// acceleration without the tether at the last step (J qacc - W F, MuJoCo's qacc of the last
// step is still in mjData at passive time; 0 at a restart). The body gets
//   F = W^-1 ((v_B(t + h) - v_site(t))/h - a_other)
// held over its step, which gives the site (MuJoCo's Euler: v+ = v + h M^-1 (f + J^T F)) the
// velocity change end node B had, so the body carries the end's response within the step and
// action and reaction match over it. A callback again at the time it stepped from (mj_forward
// then mj_step at the same t) re-applies that force; a time that went back, a reset or a
// teleported end restarts from the initial shape. With implicit2 end node B takes SDIRK's
// velocity stages and the body's position step (Sdirk2Step) and end A's reported force is the
// step's mean, its stages' impulse over the step.
void EvaluateLead(const mjModel* m, mjData* d, const AttachedTether& at, double* work,
                  double* jac) {
  double* u = d->userdata + at.offset;
  if (u[kStatus] != 0) return;
  const Tether& tether = *at.lead;
  const int N = tether.segments(), n = tether.nodes();
  Nodes x(u + kHeader, 3, n), v(u + kHeader + 3 * n, 3, n);
  double* history = tether.HistorySize() > 0 ? u + kHeader + tether.StateSize() : nullptr;
  double* c = u + kCoupleB;
  double* cache = u + kForceA;
  Ends now;
  now.a = SiteState(m, d, at, 0, u);
  now.b = SiteState(m, d, at, 1, u);
  const bool restart = u[kInitialized] == 0 || d->time < u[kTime] ||
                       Teleported(at, now, u, d->time);
  // End A is on the world, a mocap body or a body without degrees of freedom: only end B's
  // body moves under the tether.
  auto apply = [&]() {
    ApplyEndReaction(m, d, at, 1, cache + 6, cache + 9);
  };
  if (!restart && d->time == u[kTime]) return apply();  // the same step again
  const double h = m->opt.timestep;
  double* wu = u + (at.winch_offset - at.offset);  // winch slots (unused without a winch)
  if (restart) {
    if (at.winch) {
      StartWinchShape(at, tether, u, &now, x.data(), v.data());
    } else {
      StartShape(at, tether, now, x.data(), v.data(), work);
    }
    if (history) history[0] = 0;
    RecordStart(u, now, d->time,
                std::max(0.0, (now.b.pos - now.a.pos).norm() / DeployedLength(at, u) - 1));
    std::fill(u + kCoupleA, u + kCoupleA + kCoupleSize, 0.0);
    std::fill(u + kCoupleB, u + kCoupleB + kCoupleSize, 0.0);
    std::fill(cache, cache + 12, 0.0);
    c[kLeadTime] = d->time;
  } else {
    RecordAdvance(u, now, d->time);
  }
  // The step to take: to t + h from the tether's time (t, unless a call was skipped).
  const double dt = d->time + h - c[kLeadTime];
  if (!(dt > 0)) return apply();
  // End node B onto the site (its mismatch is O(h^2), from a_other's lag); bdf2's history of
  // it follows, so that its last change ends at the snapped state.
  const Vec3 dx = now.b.pos - Vec3(x.col(N)), dv = now.b.vel - Vec3(v.col(N));
  x.col(N) = now.b.pos;
  v.col(N) = now.b.vel;
  if (history && history[0] > 0) {
    Nodes xd(history + 1, 3, n), vd(history + 1 + 3 * n, 3, n);
    xd.col(N) += dx;
    vd.col(N) += dv;
  }
  const Mat3 W = SiteInverseMass(m, d, at.site[1], jac);  // jac: J (3 x nv) first
  const Mat3 W_inv = W.inverse();  // [kg] the body's effective mass at the site
  EndInertia body;
  body.mass = W_inv;
  // End node B's own inertia taken out: the node and the body then move as the body's mass
  // alone, so the body gets the node's forces (segment, weight, drag) and not minus its inertia
  // m_B a_B, as with the held force, which the scheme falls back to below lead_from and at the
  // fine step: with it, the consistent coupling converged (in h) to another answer than the
  // held force, by m_B a_B, the scene fuzzer's "coupling" class (docs/coupling.md, "session 11,
  // s11coup"). With explicit too since session 32 (it had kept the node's inertia: a run
  // 4.6 cm and 6 N off its fine-step self, the held force, on a 4.7 kg vehicle with a 2 kg end
  // node, fuzzer seed 10173's scene; docs/coupling.md). Kept only where the node outweighs the
  // body's lightest effective mass (session 23), decided here once per step for every scheme.
  body.node_inertia = tether.EndNodeOutweighs(W_inv);
  // The site's acceleration from the passive forces already applied at this call (MuJoCo's own,
  // the vehicles' buoyancy, damping and added-mass remainder, tethers evaluated before this
  // one): M^-1 J^T is in jac after SiteInverseMass, so each is a dot product with qfrc_passive.
  // These are known at t, so a_other takes them at t rather than lagged: the last step's
  // (kKnownAccel, end A's slots, unused by a lead tether, whose end A is not coupled) is taken
  // out of J qacc and this step's put in. Lagged, the vehicle's added-mass remainder, a force
  // -dA a on the body's own last acceleration, fed back through the end's stiffness: world
  // seed 530's draw-2 scene (implicit, an 8 kg vehicle with added masses 7.0, 3.0 and 5.3 kg on
  // EA 5.1e8 over 0.27 m segments, omega h 26) rang from 50 N to 30 kN in 0.17 s against 60 N
  // at 0.2 ms (docs/coupling.md, session 16).
  const double* MiJ = jac + 3 * m->nv;
  Vec3 a_known;
  for (int i = 0; i < 3; ++i) a_known[i] = mju_dot(MiJ + i * m->nv, d->qfrc_passive, m->nv);
  double* known_prev = u + kCoupleA + kKnownAccel;
  Vec3 a_other = Vec3::Zero();
  if (!restart) {
    for (int i = 0; i < 3; ++i) a_other[i] = mju_dot(jac + i * m->nv, d->qacc, m->nv);
    a_other -= W * Vec3(cache + 6);
    a_other += a_known - Vec3(known_prev);
  }
  for (int i = 0; i < 3; ++i) known_prev[i] = a_known[i];
  body.force = W_inv * a_other;
  Ends from = now, to = now;
  to.a.pos += dt * now.a.vel;
  to.b.pos += dt * now.b.vel;
  from.body_b = to.body_b = &body;
  // The interval's times: with bdf2 end node B steps over it by backward Euler, with implicit2
  // its position does (ImplicitStep's mixed step).
  from.time = c[kLeadTime];
  to.time = c[kLeadTime] + dt;
  WatchSnaps(at, x.data(), v.data(), dt, d->time, u);
  // The line's stiffness at the step's start for the slow-mode correction (none on a winch, nor
  // where end node B outweighs the body, which takes no correction below).
  const Mat3 K_line =
      at.winch || body.node_inertia ? Mat3::Zero() : tether.LineStiffness(x.data());
  StepStatus status;
  if (at.winch) {
    // The drum's speed over this step from ctrl, the tension at the drum (end A's last
    // reaction; the winch is at end A, never swapped here) and the limits, as in Evaluate.
    DrumState drum{wu[kWinchLength], wu[kWinchSpeed]};
    Payout p = LoadPayout(at, u);
    const double Z = DrumImpedanceFor(at, tether, x.data(), p, dt);
    const double speed =
        WinchSpeed(at.winch_params, drum, d->ctrl[at.actuator], u[kTensionA], dt, Z);
    p.speed = speed;
    status = tether.Advance(x.data(), v.data(), from, to, dt, work, &p, history);
    wu[kWinchLength] = drum.length + speed * dt;
    wu[kWinchSpeed] = speed;
    wu[kWinchFirst] = p.first;
  } else {
    status = tether.Advance(x.data(), v.data(), from, to, dt, work, history);
  }
  c[kLeadTime] = d->time + h;
  if (!status.ok) return RecordFailure(u, status, d->time);
  CountStalls(status, d->time, u);
  // The force on the body from end node B's velocity change; the reactions at end A (and the
  // torques) from the state at t + h with end B where its node is.
  // The slow-mode correction only over a step that ends as taut as it started: across a
  // release the line's stiffness changed within the step and the model above does not hold.
  // Nor where end node B outweighs the body (body.node_inertia): the line is then no light
  // spring, and the node, moving with the body, would take a share the tether's step never saw.
  const Vec3 slow =
      body.node_inertia || K_line.isZero(0) || !tether.AllTaut(x.data())
          ? Vec3::Zero()
          : SlowModeCorrection(K_line, W, now, dt,
                               SlowModeKappa(tether.params().integrator, status.substeps));
  const Vec3 F = W_inv * ((Vec3(v.col(N)) - now.b.vel) / dt - a_other) + slow;
  Ends after = to;
  after.b.pos = x.col(N);
  after.b.vel = v.col(N);
  after.body_b = nullptr;
  EndReactions r;
  if (at.winch) {
    const Payout p = LoadPayout(at, u);
    const Tether view = tether.Deployed(p.first, p.rest, p.speed);
    after.rest = p.rest;
    r = view.Reactions(x.data() + 3 * p.first, v.data() + 3 * p.first, after, work);
  } else {
    r = tether.Reactions(x.data(), v.data(), after, work);
  }
  // Where the scheme integrates end A's force over the step (implicit2's stages, explicit's
  // substeps), its mean: the force at t + h alone is not what its nodes' momentum took
  // (docs/coupling.md, implicit2; StepStatus::impulse_a).
  if (status.has_impulse_a) {
    r.force_a = status.impulse_a / dt;
    r.tension_a = r.force_a.norm();
  }
  // The slow-mode correction passes through the line: its reaction is at end A.
  for (int i = 0; i < 3; ++i) u[kCoupleA + kSlowCorrection + i] = slow[i];
  if (!slow.isZero(0)) {
    r.force_a -= slow;
    r.tension_a = r.force_a.norm();
  }
  for (int i = 0; i < 3; ++i) {
    cache[i] = r.force_a[i];
    cache[3 + i] = r.torque_a[i];
    cache[6 + i] = F[i];
    cache[9 + i] = 0;
  }
  u[kTensionA] = r.tension_a;
  u[kTensionB] = F.norm();
  apply();
}

// implicit2's held end force (session 40, docs/coupling.md). The force at the state SDIRK's
// step ends in is off where the site accelerates: the node next to the end, tied to it by a
// segment stiff on the step, follows the site's positions, and the second stage, a backward
// Euler step of gamma h from its extrapolated velocity, gives it an inertia several times its
// m a; the first stage carries the opposite (Tether::AddEndImpulse). Scene fuzzer seed 1423
// read its vehicle-end tension 15.19 N at 2 ms and 16.58 N at 0.1 ms, where implicit and bdf2
// read 16.590 N at every step. The stages' mean as the scheme weighs them, `mean` over an
// advance of `step` s, is the force the nodes' momentum took, exact to 0.001% on a dragged
// line, but it is the force at the advance's middle: applied over the next step it lags a
// further step/2, and the issue's BlueROV2 case at EA 6e4 went from within 1% of its 0.1 ms
// reference to 1.08%. So the mean is carried to the advance's end along the line through the
// advance before's mean `prev` (length prev_step, 0: none), 1.5 mean - 0.5 prev at a constant
// step, the held force's time as in the other schemes, without the stage inertia.
Vec3 HeldMean(const Vec3& mean, const Vec3& prev, double step, double prev_step) {
  if (prev_step <= 0 || step <= 0) return mean;
  return mean + (mean - prev) * (step / (step + prev_step));
}

// One tether at one callback: initialise or advance to d->time, then apply the reactions.
void Evaluate(const mjModel* m, mjData* d, const AttachedTether& at, double* work, double* jac) {
  double* u = d->userdata + at.offset;
  if (u[kStatus] != 0) return;  // diverged: stays inert until reset
  const Tether& tether = at.tether;
  const bool free_end = at.site[1] < 0;
  double* x = u + kHeader;
  double* v = x + 3 * tether.nodes();
  double* history = tether.HistorySize() > 0 ? x + tether.StateSize() : nullptr;
  Ends now;
  now.a = SiteState(m, d, at, 0, u);
  if (!free_end) now.b = SiteState(m, d, at, 1, u);

  // The ends' motion over the last step, for the coupling (read before it is overwritten).
  const Ends before{LoadEnd(u + kEndA), LoadEnd(u + kEndB)};
  const double step = d->time - u[kTime];
  bool advanced = false, restarted = false;
  double given[2] = {0, 0};  // [J] work the tether's end forces did on the sites this advance
  Vec3 given_impulse[2] = {Vec3::Zero(), Vec3::Zero()};  // [N s] and their impulse
  // implicit2: the end forces' mean over the advance as its stages weigh them (AddEndImpulse).
  Vec3 mean[2] = {Vec3::Zero(), Vec3::Zero()};
  bool has_mean[2] = {false, false};
  double* wu = u + (at.winch_offset - at.offset);  // winch slots (unused without a winch)
  if (u[kInitialized] == 0 || d->time < u[kTime] || Teleported(at, now, u, d->time)) {
    restarted = true;
    // First call, reset, time went back, or an end was teleported: start again from the
    // declared initial shape.
    if (at.winch) {
      StartWinchShape(at, tether, u, &now, x, v);
    } else {
      StartShape(at, tether, now, x, v, work);
    }
    // bdf2 starts again with a backward-Euler step (no history yet).
    if (history) history[0] = 0;
    const double chord = free_end ? 0 : (now.b.pos - now.a.pos).norm();
    RecordStart(u, now, d->time, std::max(0.0, chord / DeployedLength(at, u) - 1));
  } else if (d->time > u[kTime]) {
    Ends from{LoadEnd(u + kEndA), LoadEnd(u + kEndB)};
    const double dt = d->time - u[kTime];
    // Contact: candidates from the state at the tether's time and the geoms as they are now;
    // the planes move with their bodies in between (contact.h).
    ContactSet set;
    if (at.contact) {
      int dropped = 0;
      double* boxes = work + tether.WorkspaceSize();
      set.points = reinterpret_cast<ContactPoint*>(boxes + ChunkBoxesSize(tether.segments()));
      set.count = FindContacts(m, d, at.contacts, tether, x, v, dt, boxes, set.points,
                               at.contacts.capacity, &dropped);
      set.time_ref = d->time;
      u[kContactDropped] = dropped;
      from.time = u[kTime];
      now.time = d->time;
      from.contacts = now.contacts = &set;
    }
    WatchSnaps(at, x, v, dt, d->time, u);
    StepStatus status;
    if (at.winch) {
      // The drum's speed over this step from ctrl, the tension at the drum (last reaction)
      // and the limits; the length then grows by exactly speed dt.
      DrumState drum{wu[kWinchLength], wu[kWinchSpeed]};
      const double ctrl = d->ctrl[at.actuator];
      const double drum_tension = at.swapped ? u[kTensionB] : u[kTensionA];
      Payout p = LoadPayout(at, u);
      const double Z = DrumImpedanceFor(at, tether, x, p, dt);
      const double speed = WinchSpeed(at.winch_params, drum, ctrl, drum_tension, dt, Z);
      p.speed = speed;
      status = tether.Advance(x, v, from, now, dt, work, &p, history);
      wu[kWinchLength] = drum.length + speed * dt;
      wu[kWinchSpeed] = speed;
      wu[kWinchFirst] = p.first;
    } else {
      status = tether.Advance(x, v, from, now, dt, work, history);
    }
    if (!status.ok) return RecordFailure(u, status, d->time);
    // Each body gets the opposite of the impulse its geoms gave the tether, spread over the
    // next step as a constant force at the contact point.
    if (at.contact) {
      double* rec = x + tether.StateSize() + tether.HistorySize();
      Vec3 total = Vec3::Zero(), end_a = Vec3::Zero(), end_b = Vec3::Zero();
      int stored = 0;
      for (int k = 0; k < set.count; ++k) {
        const ContactPoint& c = set.points[k];
        if (c.impulse.isZero(0)) continue;
        total += c.impulse;
        // The attached end nodes' share reaches the sites' bodies.
        if (c.segment == 0) end_a += (c.impulse - c.impulse_b) / dt;
        if (c.segment == tether.segments() - 1 && !free_end) end_b += c.impulse_b / dt;
        double* r = rec + kContactRecord * stored++;
        r[0] = c.tag;
        for (int i = 0; i < 3; ++i) {
          r[1 + i] = -c.impulse[i] / dt;
          r[4 + i] = c.point[i];
        }
      }
      for (int i = 0; i < 3; ++i) {
        u[kContactImpulse + i] = total[i];
        u[kContactEndA + i] = end_a[i];
        u[kContactEndB + i] = end_b[i];
      }
      u[kContactCount] = stored;
    }
    CountStalls(status, d->time, u);
    given[0] = status.work_a;
    given[1] = status.work_b;
    given_impulse[0] = status.end_impulse_a;
    given_impulse[1] = status.end_impulse_b;
    if (!at.winch && dt > 0) {
      mean[0] = status.impulse_a / dt;
      mean[1] = status.impulse_b / dt;
      has_mean[0] = status.has_impulse_a;
      has_mean[1] = status.has_impulse_b;
    }
    RecordAdvance(u, now, d->time);
    advanced = true;
  }

  // Contact reactions of the last advance, at every call until the next one.
  if (at.contact) {
    const double* rec = x + tether.StateSize() + tether.HistorySize();
    const mjtNum zero[3] = {0, 0, 0};
    for (int k = 0; k < static_cast<int>(u[kContactCount]); ++k) {
      const double* r = rec + kContactRecord * k;
      const int body = static_cast<int>(r[0]);
      if (body <= 0 || m->body_mocapid[body] >= 0) continue;
      mj_applyFT(m, d, r + 1, zero, r + 4, body, d->qfrc_passive);
    }
  }
  // Reactions from the state and the sites as they are at this call (no contact candidates:
  // the end nodes' contact share is in the state's last advance, and in the records above).
  now.contacts = nullptr;
  EndReactions r;
  if (at.winch) {
    const Payout p = LoadPayout(at, u);
    const Tether view = tether.Deployed(p.first, p.rest, p.speed);
    now.rest = p.rest;
    r = view.Reactions(x + 3 * p.first, v + 3 * p.first, now, work);
  } else {
    r = tether.Reactions(x, v, now, work);
    // implicit2: the force the tether's nodes took (HeldMean), not the force at the state.
    if (restarted) std::fill(u + kHeldMeanA, u + kHeldPrevStep + 1, 0.0);
    const double prev_step = u[kHeldPrevStep];
    for (int end = 0; end < 2; ++end) {
      double* held = u + (end == 0 ? kHeldMeanA : kHeldMeanB);
      double* prev = u + (end == 0 ? kHeldPrevA : kHeldPrevB);
      Vec3& force = end == 0 ? r.force_a : r.force_b;
      if (has_mean[end]) {
        const Vec3 use = HeldMean(mean[end], Vec3(prev), step, prev_step);
        for (int i = 0; i < 3; ++i) {
          held[i] = use[i] - force[i];
          prev[i] = mean[end][i];
        }
      }
      force += Vec3(held);
    }
    if (has_mean[0] || has_mean[1]) u[kHeldPrevStep] = step;
    r.tension_a = r.force_a.norm();
    if (!free_end) r.tension_b = r.force_b.norm();
  }
  if (at.contact) {
    r.force_a += Vec3(u + kContactEndA);
    r.tension_a = r.force_a.norm();
    if (!free_end) {
      r.force_b += Vec3(u + kContactEndB);
      r.tension_b = r.force_b.norm();
    }
  }
  // Ends on bodies that move, explicit and rk4 tethers (the implicit ones damp what a chatter
  // would pump, docs/coupling.md): the coupling's work balance over the step.
  // The body received the force applied at the last call along its site's path (trapezoid of
  // the site velocity, as the body integrates it); the tether gave the work of its own end
  // force over its steps along the same path. Their difference S is energy the coupling
  // made, each step taken in the frame moving with the site's velocity at the step's start:
  // there a body's drift u does not add u . (applied h - impulse), the held force's lag on a
  // slowly varying force, which is no energy of the coupling (it changes sign with the frame).
  // Per step S then gains about -(h/2) F . dv (the staggered step's own offset), whose sum
  // is a bounded boundary term -(h/2) F . (v - v_start) plus the area of the end's (v, F)
  // loop, which a chatter grows and a stable coupling does not: the stop needs S above the
  // threshold both with and without that boundary term (a thrust that takes a body to speed
  // against its tether makes S alone grow by (h/2)|F||v - v_start|). The energy scale is that
  // of the end's motion in the same frame: the kinetic energy of the site's velocity change
  // over a step (a chatter's velocity, not a drift's) and the end segment's elastic energy.
  // Session 39 (docs/coupling.md): scene seed 6876 (explicit, held force at omega h 0.45, a
  // 2454 kg vehicle sinking at 0.1 m/s) grew from 51 N to 62 kN in 2 s unstopped, the
  // balance in the world frame a random walk of +-0.1 J on that drift, its scale the body's
  // kinetic energy (15-55 J); now it stops at 0.85 s.
  for (int end = 0; end < 2 && advanced; ++end) {
    if (!at.coupled[end] || !IsExplicit(tether.params().integrator)) continue;
    double* c = u + (end == 0 ? kCoupleA : kCoupleB);
    const EndState& e1 = end == 0 ? now.a : now.b;
    const EndState& e0 = end == 0 ? before.a : before.b;
    const Vec3& force = end == 0 ? r.force_a : r.force_b;
    const Vec3 applied(u + kForceA + (end == 0 ? 0 : 6));
    const double gained = applied.dot(0.5 * step * (e0.vel + e1.vel));
    if (c[kCoupleSteps] == 0) std::copy(e0.vel.data(), e0.vel.data() + 3, c + kStartVel);
    c[kSpurious] += gained - given[end] - e0.vel.dot(step * applied - given_impulse[end]);
    c[kBodyWork] += gained;
    c[kCoupleSteps] += 1;
    const Mat3 W = SiteInverseMass(m, d, at.site[end], jac);
    const Vec3 dv = e1.vel - e0.vel;
    const double energy =
        0.5 * dv.dot(W.ldlt().solve(dv)) + force.squaredNorm() / (2 * tether.EndStiffness());
    c[kEnergyScale] = std::max(c[kEnergyScale], energy);
    const double boundary = 0.5 * step * applied.dot(e1.vel - Vec3(c + kStartVel));  // [J]
    const double excess = std::min(c[kSpurious], c[kSpurious] + boundary);          // [J]
    if (c[kCoupleSteps] > kChatterSteps &&
        excess > kChatterRatio * c[kEnergyScale] + kChatterFloor) {
      c[kSpurious] = excess;  // the figure the message gives
      u[kStatus] = kChatter;
      u[kBadNode] = end == 0 ? 0 : tether.segments();
      u[kBadTime] = d->time;
      return;
    }
  }
  if (restarted) {
    std::fill(u + kCoupleA, u + kCoupleA + kCoupleSize, 0.0);
    std::fill(u + kCoupleB, u + kCoupleB + kCoupleSize, 0.0);
  }
  double* cache = u + kForceA;
  // Stored as declared: a winch at end B runs internally as end A.
  const EndReactions& ra = r;
  EndReactions rs;
  if (at.swapped) {
    rs.force_a = r.force_b;
    rs.torque_a = r.torque_b;
    rs.force_b = r.force_a;
    rs.torque_b = r.torque_a;
    rs.tension_a = r.tension_b;
    rs.tension_b = r.tension_a;
  }
  const EndReactions& stored = at.swapped ? rs : ra;
  for (int i = 0; i < 3; ++i) {
    cache[i] = stored.force_a[i];
    cache[3 + i] = stored.torque_a[i];
    cache[6 + i] = stored.force_b[i];
    cache[9 + i] = stored.torque_b[i];
  }
  u[kTensionA] = stored.tension_a;
  u[kTensionB] = stored.tension_b;
  if (at.body[0] > 0 && !at.mocap[0]) {
    ApplyEndReaction(m, d, at, 0, r.force_a.data(), r.torque_a.data());
  }
  if (!free_end && at.body[1] > 0 && !at.mocap[1]) {
    ApplyEndReaction(m, d, at, 1, r.force_b.data(), r.torque_b.data());
  }
}

// The velocity-dependent part of the force an end puts on its body (the end node's drag with
// its half-segments' length, the end segment's internal damping, the seabed's damping) enters
// MuJoCo's step explicitly, like every force from mjcb_passive: with D = -sym(dF/dv) at the
// site and W = J M^-1 J^T the body's inverse mass there, a body velocity mode decays by the
// factor 1 - h lambda per step, lambda the largest eigenvalue of W^1/2 D W^1/2, and grows
// (alternating in sign) once h lambda > 2 (semi-implicit Euler and MuJoCo's implicit
// integrator, which does not see the callback's derivatives; RK4: 2.785, the real-axis
// stability limit of the classical RK4). Quadratic drag makes D grow with the speed: a light
// vehicle driven fast across its tether (a thrust of the order of EA) reaches it, and before
// this check MuJoCo reported "Nan, Inf or huge value in QACC" and reset the data (the scene
// fuzzer's open-thrust-qacc class: h lambda crossed 2 3-48 steps before MuJoCo's warning on
// seeds 186, 255, 611, 977, 3806). D by central differences of Reactions in the end's velocity
// (a 3-node window: the cost of three reactions per moving end and call). The limit:
// ExplicitDampingLimit (vehicle_glue.h).

// h lambda for end `end` of `at` in its state at the tether's time, and D's largest eigenvalue
// [N s/m] and the speed of the site relative to the water [m/s] (for the message).
double EndDampingRate(const mjModel* m, mjData* d, const AttachedTether& at, int end,
                      double* work, double* jac, double* lambda_D = nullptr,
                      double* speed = nullptr) {
  double* u = d->userdata + at.offset;
  const double* x = u + kHeader;
  double* v = u + kHeader + 3 * at.tether.nodes();
  Ends e{LoadEnd(u + kEndA), LoadEnd(u + kEndB)};
  // With a winch, the deployed part as Evaluate sees it (the nodes from the drum exit on, the
  // first segment at the drum's rest length).
  std::optional<Tether> deployed;
  if (at.winch) {
    const Payout p = LoadPayout(at, u);
    deployed.emplace(at.tether.Deployed(p.first, p.rest, p.speed));
    e.rest = p.rest;
    x += 3 * p.first;
    v += 3 * p.first;
  }
  const Tether& t = deployed ? *deployed : at.tether;
  EndState& es = end == 0 ? e.a : e.b;
  const double dv = 1e-6 * (1 + es.vel.norm());  // [m/s]
  // The end node and its neighbour perturbed together (restored after): the end segment's
  // internal damping acts on their relative velocity, which the tether's own step relaxes
  // (its interior follows the end within the step), so only the end node's own laws (drag,
  // seabed) act on the body at the MuJoCo step. (The Drape test's body at rest on an implicit
  // tether with damping read h lambda = 2.02 from the internal damping alone, and is stable.)
  double* vn = v + 3 * (end == 0 ? 1 : t.segments() - 1);
  Mat3 J;
  for (int c = 0; c < 3; ++c) {
    const double keep = es.vel[c], keep_n = vn[c];
    es.vel[c] = keep + dv;
    vn[c] = keep_n + dv;
    const EndReactions rp = t.Reactions(x, v, e, work);
    es.vel[c] = keep - dv;
    vn[c] = keep_n - dv;
    const EndReactions rm = t.Reactions(x, v, e, work);
    es.vel[c] = keep;
    vn[c] = keep_n;
    J.col(c) = ((end == 0 ? rp.force_a : rp.force_b) - (end == 0 ? rm.force_a : rm.force_b)) /
               (2 * dv);
  }
  const Mat3 D = -0.5 * (J + J.transpose());
  const Mat3 W = SiteInverseMass(m, d, at.site[end], jac);
  const Mat3 Wh = SquareRoot(Eigen::SelfAdjointEigenSolver<Mat3>(W));
  const double lambda = LargestEigenvalue(Wh * D * Wh);
  if (lambda_D) *lambda_D = LargestEigenvalue(D);
  if (speed) {
    const Vec3 current = t.env().water.current;  // (a profile: its value at z = 0)
    *speed = (es.vel - current).norm();
  }
  return m->opt.timestep * lambda;
}

// An upper bound of D's largest eigenvalue at end `end` [N s/m], from the declared laws, so that
// the exact figure (six reactions, measured at 15-30 us a call against a 50-100 us step of a
// 10-segment tether) is computed only near the limit: the end node's drag, whose derivative is
// at most 2 max(kn, kt) (l/2) |v_r| (AddDrag: kn = rho Cdn d / 2, kt = rho Cdt pi d / 2, drag
// length l/2 for the end segment's length l now, v_r relative to the current), here with l;
// the end segment's internal damping, damping / L0; a flat seabed under the end node, its
// damping c over the node's share (< L0) and its friction's slope mu N / eps (tanh law, N at
// most L0 (k pen + c |v_z|)). Infinite (no bound: always the exact figure) with contact, a
// seabed geom or a current profile.
double EndDampingBound(const AttachedTether& at, const double* u, int end) {
  const Tether& t = at.tether;
  const TetherParams& p = t.params();
  const Environment& env = t.env();
  const Water& w = env.water;
  if ((p.effects & kContact) || ((p.effects & kSeabed) && w.surface.declared()) ||
      ((p.effects & kCurrent) && !w.profile.empty())) {
    return INFINITY;
  }
  const double* x = u + kHeader;
  const int e = end == 0 ? 0 : t.segments(), n = end == 0 ? 1 : t.segments() - 1;
  const Vec3 xe(x + 3 * e), xn(x + 3 * n);
  const double l = (xe - xn).norm(), L0 = t.rest_segment_length();  // [m]
  const EndState es = LoadEnd(u + (end == 0 ? kEndA : kEndB));
  const Vec3 current = (p.effects & kCurrent) ? w.current : Vec3::Zero();
  const double rho = env.wet ? w.density : 0;
  double D = 0;
  if (p.effects & kDrag) {
    const double k = 0.5 * rho * p.diameter * std::max(p.Cdn, 3.14159265358979323846 * p.Cdt);
    D += 2 * k * l * (es.vel - current).norm();
  }
  D += t.EndDamping();
  if ((p.effects & kSeabed) && xe.z() > w.seabed - 1e3 * L0) {
    const double c = w.seabed_damping >= 0 ? w.seabed_damping
                                            : 2 * std::sqrt(w.seabed_stiffness * p.mass_per_length);
    const double pen = std::max(0.0, w.seabed - xe.z());
    const double N = L0 * (w.seabed_stiffness * pen + c * std::abs(es.vel.z()));
    const double mu = std::max(w.seabed_friction, w.seabed_friction_axial);
    D += c * L0 + (mu > 0 ? mu * N / w.seabed_friction_speed : 0);
  }
  return D;
}

// After Evaluate: stops the tether (status kEndDamping) before its end's damping makes the body
// oscillate without bound. With a winch, the end away from the drum (internal end B), from the
// deployed part (EndDampingRate); until session 15 a winch tether was not checked at all, and
// the world draw of the scene fuzzer found a vehicle driven at its end run on with a reaction of
// 1.09e5 N at 2 ms against 1.40e4 N at 0.2 ms (seed 294, whose scene without the winch stops
// with this check). The drum's end reacts through the winch's own law, and is not checked.
void CheckEndDamping(const mjModel* m, mjData* d, const AttachedTether& at, double* work,
                     double* jac) {
  double* u = d->userdata + at.offset;
  if (u[kStatus] != 0 || u[kInitialized] == 0) return;
  const double limit = ExplicitDampingLimit(m);
  for (int end = 0; end < 2; ++end) {
    if (at.site[end] < 0 || !at.coupled[end] || (at.winch && end == 0)) continue;
    // The bound on the load-time effective mass (1 / the largest eigenvalue of W, the same in
    // every orientation of a free body), with a factor 2 for bodies whose W changes with their
    // joints' configuration.
    const double m_eff = at.limit[end].m_eff;
    if (m_eff > 0 && m->opt.timestep * EndDampingBound(at, u, end) / m_eff < 0.5 * limit) continue;
    const double rate = EndDampingRate(m, d, at, end, work, jac);
    if (rate > limit) {
      u[(end == 0 ? kCoupleA : kCoupleB) + kDampingRate] = rate;
      u[kStatus] = kEndDamping;
      u[kBadNode] = end == 0 ? 0 : at.tether.segments();
      u[kBadTime] = d->time;
      return;
    }
  }
}

// The seabed rate of CouplingLimit c at the step h [s]: max(omega_s h, h c_s/m_eff), from the
// figures at load (whose step is omega_h / omega).
double SeabedRate(const CouplingLimit& c, double h) {
  if (!(c.omega > 0)) return 0;
  return std::max(c.seabed_omega_h, c.seabed_damping_h) * h / (c.omega_h / c.omega);
}

// What cures a watched seabed end at the step h [s], for the load warning and the stop: the
// integrators that would take the consistent coupling there, a step that halves the rate, more
// segments (the end node's share is half the end segment).
double StepAtMost(double x);  // (below)
std::string SeabedCure(const AttachedTether& at, int end, double h) {
  std::ostringstream s;
  if (at.seabed_cure[end]) {
    s << "integrator=bdf2 (the default) or implicit (the end node is solved with the body), or ";
  }
  const double rate = SeabedRate(at.limit[end], h);  // [-]
  s << "<option timestep> <= " << StepAtMost(0.5 * kLeadFromSeabed * h / rate)
    << " s, or more segments (the end node's share is half the end segment)";
  return s.str();
}

// After Evaluate (the held end force): stops the tether (status kSeabedEnd) when the node of an
// end on a body touches the seabed where the seabed is stiff on the body's step, max(omega_s h,
// h c_s/m_eff) >= kLeadFromSeabed (AdviseCoupling). The body gets the node's seabed contact at
// the start of its step and bounces off: the bdf2 case of Coupling.TheSeabedUnderTheEndNode...
// rose 0.21 m off the seabed where its contact, damped at a ratio of 0.67, lets it rise 5 mm,
// and read its end tension 9.5% off its 0.2 ms self; rk4, which has no consistent coupling,
// reads the same (session 38). A winch's drum end is not checked.
void CheckSeabedEnd(const mjModel* m, mjData* d, const AttachedTether& at) {
  double* u = d->userdata + at.offset;
  if (u[kStatus] != 0 || u[kInitialized] == 0) return;
  for (int end = 0; end < 2; ++end) {
    if (!at.seabed_watch[end] || (at.winch && end == 0)) continue;
    if (SeabedRate(at.limit[end], m->opt.timestep) < kLeadFromSeabed) continue;
    const int node = end == 0 ? 0 : at.tether.segments();
    const double* x = u + kHeader + 3 * node;
    if (x[2] < at.tether.env().water.SeabedHeight(x[0], x[1])) {
      u[kStatus] = kSeabedEnd;
      u[kBadNode] = node;
      u[kBadTime] = d->time;
      return;
    }
  }
}

void Passive(const mjModel* m, mjData* d) {
  if (g_previous_passive) g_previous_passive(m, d);
  ApplyVehicles(m, d);  // vehicle:BODY declarations (plugin/vehicles.cc)
  const ModelTethers* set = Lookup(m);
  if (!set) return;
  mjMARKSTACK;
  double* work = mj_stackAlloc(d, set->work_size);
  double* jac = mj_stackAlloc(d, 6 * std::max(set->nv, 1));
  for (const AttachedTether& at : set->tethers) {
    if (at.lead) {
      EvaluateLead(m, d, at, work, jac);
    } else {
      Evaluate(m, d, at, work, jac);
    }
    // The end damping first: where both apply (the seabed's damping beyond h lambda = 2), its
    // stop measures the rate (world seed 294, WinchTest.FarEndDampingTooStiffForTheStepStops).
    CheckEndDamping(m, d, at, work, jac);
    if (!at.lead) CheckSeabedEnd(m, d, at);
  }
  mjFREESTACK;
}

void DefaultError(const char* message) {
  std::fprintf(stderr, "mjtether: MuJoCo error: %s\n", message);
  std::exit(3);
}

void DefaultWarning(const char* message) {
  std::fprintf(stderr, "mjtether: MuJoCo warning: %s\n", message);
}

const double* UserBlock(const mjModel* m, const mjData* d, int k) {
  const ModelTethers* set = Lookup(m);
  if (!set || k < 0 || k >= static_cast<int>(set->tethers.size())) return nullptr;
  return d->userdata + set->tethers[k].offset;
}

// A step to advise as "<= x" or "below x": x rounded down to three significant digits, so that
// the printed figure, taken literally, is within the bound (printed at six digits, 0.1 / omega
// for the BlueROV2 at EA 3e5 read 0.000344 s, omega h 0.100025, and the scene at that step still
// warned; session 28). Every advised step and max_step goes through it.
double StepAtMost(double x) {
  if (!(x > 0) || !std::isfinite(x)) return x;
  const double unit = std::pow(10.0, std::floor(std::log10(x)) - 2);
  return std::floor(x / unit) * unit;
}

// Time-step advisor for an explicit tether, from its stability limit (Tether::ExplicitStableStep,
// highest natural frequency of the axial, bending and seabed stiffness on the lightest node).
// A tether step fixed by `substeps` or `max_step` above the limit gets a warning naming the
// limit and the setting to change; an automatic substep count above kMaxAutoSubsteps per
// MuJoCo step is an error. Implicit tethers need no advice.
bool Advise(const Tether& t, double timestep, std::string* warning, std::string* error) {
  const TetherParams& p = t.params();
  if (p.max_step > 0 && t.SubstepsFor(timestep) > kMaxAutoSubsteps) {
    std::ostringstream s;
    s << "key 'max_step' = " << p.max_step << " s gives " << std::ceil(timestep / p.max_step)
      << " tether steps per MuJoCo step (<option timestep> " << timestep << " s), more than "
      << kMaxAutoSubsteps << ": set max_step >= " << timestep / kMaxAutoSubsteps << " s";
    *error = s.str();
    return false;
  }
  if (!IsExplicit(p.integrator)) return true;
  const char* name = IntegratorName(p.integrator);
  const double limit = t.ExplicitStableStep();
  const int steps = t.SubstepsFor(timestep);
  const double h = timestep / steps;
  std::ostringstream s;
  if (p.substeps > 0 || p.max_step > 0) {
    if (h <= limit) return true;
    s << "integrator=" << name << ": the tether step " << h << " s ("
      << (p.substeps > 0 ? "substeps=" + std::to_string(p.substeps) : "max_step")
      << ") exceeds the stable step " << limit << " s ("
      << limit / t.ExplicitStabilityLimit() << " of the stability limit "
      << t.ExplicitStabilityLimit() << " s"
      << (p.integrator == Integrator::kExplicit
              ? "; beyond it a slack tether gains energy at every slack-taut switch"
              : "")
      << "); set substeps >= " << static_cast<long long>(std::ceil(timestep / limit))
      << " or max_step <= " << StepAtMost(limit)
      << ", or remove both (automatic substeps), or use integrator=implicit";
    *warning = s.str();
    return true;
  }
  if (steps <= kMaxAutoSubsteps) return true;
  s << "integrator=" << name << " needs " << std::ceil(timestep / limit)
    << " substeps per MuJoCo step (stability limit " << limit << " s, <option timestep> "
    << timestep << " s), more than " << kMaxAutoSubsteps
    << ": use integrator=implicit, fewer segments or a smaller EA/EI";
  *error = s.str();
  return false;
}

// True when `body` moves with a mocap body: it is one, or is welded (no joint) to one through
// every body up to it. A body with a joint of its own below a mocap body is dynamic: it
// receives the tether's force like any other.
bool MovedByMocap(const mjModel* m, int body) {
  for (int b = body; b > 0; b = m->body_parentid[b]) {
    if (m->body_mocapid[b] >= 0) return true;
    if (m->body_jntnum[b] > 0) return false;
  }
  return false;
}

// The body with a free joint that carries `body` (itself or an ancestor), or -1.
int FreeCarrier(const mjModel* m, int body) {
  for (int b = body; b > 0; b = m->body_parentid[b]) {
    for (int j = m->body_jntadr[b]; j >= 0 && j < m->body_jntadr[b] + m->body_jntnum[b]; ++j) {
      if (m->jnt_type[j] == mjJNT_FREE) return b;
    }
  }
  return -1;
}

// Start-up checks at load time (README "Initial shape"). Thresholds:
// - in water, a mean density mass_per_length / (pi d^2/4) below kMinDensity, that of air: no
//   cable is lighter than air, while a diameter given in millimetres (the key's range stops at
//   10 m, so 1-10 for 1-10 mm) gives 1e-3-1e-2 kg/m^3, a buoyancy 1e5-1e6 times the weight
//   (dry, the diameter acts on nothing, and a near-massless dry line is a legitimate test);
// - a diameter larger than the length: no longer a slender line (Morison drag per length,
//   buoyancy of a cylinder);
// - a rest segment length below kMinSegmentPerDiameter d: a cable cannot bend over less than
//   several diameters (its minimum bend radius), so such nodes resolve nothing physical, and
//   the lumped cylinder per node is wider than it is long (the hard-case suite checks d/5
//   against Irvine's catenary; d/10 is the limit kept).
constexpr double kMinDensity = 1.2;            // [kg/m^3] air
constexpr double kMinSegmentPerDiameter = 0.1;  // [-] L0 / d
// A start stretched beyond this strain is far from equilibrium: warned with its tension. The
// warning says that the outcome depends on the step for seconds after the snap: of the 70
// stretched starts of session 9's long run that disagreed with their 0.2 ms selves at 1 s,
// 44 still disagreed at 3 s (snap trains that implicit2 and bdf2 damp at 2 ms, explicit
// coupling growth), 25 agreed (docs/scene_fuzzer.md, s10open). With EAc, a start compressed
// beyond this strain is refused or warned (CompressedStart).
constexpr double kStretchWarning = 1e-3;  // [-]

bool CheckParameters(const TetherParams& p, bool wet, std::string* error) {
  std::ostringstream s;
  const double area = 3.14159265358979323846 * p.diameter * p.diameter / 4;
  const double density = p.mass_per_length / area;
  if (p.diameter > p.length) {
    s << "key 'diameter' = " << p.diameter << " m is larger than the tether's length "
      << p.length << " m: a lumped-mass line needs a slender tether (diameter in metres, not "
      << "millimetres?)";
  } else if (wet && density < kMinDensity) {
    s << "key 'diameter' = " << p.diameter << " m with mass_per_length = " << p.mass_per_length
      << " kg/m means a mean density of " << density << " kg/m^3, below " << kMinDensity
      << " kg/m^3 (lighter than air; its buoyancy would be " << 1025 / density
      << " times its weight in water): give the diameter in metres";
  } else if (p.length / p.segments < kMinSegmentPerDiameter * p.diameter) {
    s << "key 'segments' = " << p.segments << " makes segments of " << p.length / p.segments
      << " m, shorter than " << kMinSegmentPerDiameter << " x the diameter " << p.diameter
      << " m (a cable cannot bend over less than several diameters): use at most "
      << static_cast<long long>(std::floor(p.length / (kMinSegmentPerDiameter * p.diameter)))
      << " segments";
  } else {
    return true;
  }
  *error = s.str();
  return false;
}

// The shortest chord of a tether's initial shape between ends at a and b, over L0 (1: no
// segment starts compressed); site A's x-axis for the shapes that use it.
double ShortestStartChord(const Tether& t, const Vec3& a, const Vec3& b, const Vec3& axis) {
  Ends ends;
  ends.a.pos = a;
  ends.a.axis = axis;
  ends.b.pos = b;
  std::vector<double> x(3 * t.nodes()), v(3 * t.nodes());
  t.InitialShape(ends, x.data(), v.data());
  const double L0 = t.params().length / t.params().segments;
  double shortest = INFINITY;
  for (int k = 0; k + 1 < t.nodes(); ++k) {
    shortest = std::min(shortest, (Vec3(&x[3 * k + 3]) - Vec3(&x[3 * k])).norm() / L0);
  }
  return shortest;
}

// A tether with EAc whose initial shape starts a segment compressed (Tether::InitialShape puts
// every chord at L0 where it can: by a walk along the catenary or the seabed path, else by
// projecting the arc spacing onto chords of L0; not with one segment on ends closer than its
// length, nor where the projection does not converge: on the long run's 9,800 scenes, never).
// Returns "" if no segment starts compressed by more than kStretchWarning; "refuse:" and the
// message if the compressive force EAc x strain exceeds the segment's Euler buckling load
// pi^2 EI / L0^2 (a straight segment cannot buckle, so the first steps launch the ends apart
// with that force, which the declared cable could not carry); else a warning.
// Measured (session 9's long run, seeds 201..10000): 196 scenes of one segment with EAc loaded
// with the ends closer than the length, at compressive strains 0.028-0.67 and forces 31-2e14 x
// the Euler load (none below it); 18 of them failed (17 disagreed with their fine-step selves,
// class open-one-two-segments: the 2 ms run resolves a launch by e.g. 8.6 MN into a 470 kg
// vehicle, seed 7190, only roughly, then rings undamped about the length; one bad qacc), 46
// stopped with a cause the fuzzer accepted (end damping too stiff at the launch speed, thrust,
// ends pulled apart), and the 132 that agreed are the same strut, well resolved.
std::string CompressedStart(const mjModel* m, const mjData* d, const Environment& env,
                            const AttachedTether& at, const Vec3& a, const Vec3& b) {
  if (!(at.tether.params().effects & kCompression)) return "";
  // With a winch the deployed part: the declared length in segments of the allocation's L0
  // (the fix below then is not a segment count). Until session 15 a winch tether was not
  // checked, and the scene fuzzer's world draw ran such starts (seeds 451 and 597, refused
  // without their winch) into a disagreement and a MuJoCo bad qacc.
  std::optional<Tether> deployed;
  if (at.winch) {
    TetherParams q = at.tether.params();
    q.length = at.initial_length;
    q.segments = std::max(1, static_cast<int>(std::lround(q.length / at.tether.rest_segment_length())));
    std::string ignored;
    deployed = Tether::Create(q, env, &ignored);
    if (!deployed) return "";
  }
  const Tether& t = deployed ? *deployed : at.tether;
  const TetherParams& p = t.params();
  const Vec3 axis(d->site_xmat[9 * at.site[0]], d->site_xmat[9 * at.site[0] + 3],
                  d->site_xmat[9 * at.site[0] + 6]);
  const double chord = ShortestStartChord(t, a, b, axis), strain = 1 - chord;
  if (!(strain > kStretchWarning)) return "";
  const double L0 = p.length / p.segments, force = p.EAc * strain;
  const double euler = 9.86960440108935862 * p.EI / (L0 * L0);  // [N] pi^2 EI / L0^2
  std::ostringstream s;
  s << "starts compressed: its " << p.segments << " segment" << (p.segments > 1 ? "s" : "")
    << " of " << L0 << " m cannot hang the length of " << p.length << " m between ends "
    << (b - a).norm() << " m apart (sites '" << mj_id2name(m, mjOBJ_SITE, at.site[0]) << "', '"
    << mj_id2name(m, mjOBJ_SITE, at.site[1]) << "'), so a segment starts at a chord of " << chord
    << " x its length, a compressive strain of " << strain << " and a force EAc x strain = "
    << force << " N";
  if (force <= euler) {
    s << ", below its Euler buckling load pi^2 EI / L0^2 = " << euler
      << " N (a straight strut), released within the first steps";
    return s.str();
  }
  s << ", beyond its Euler buckling load pi^2 EI / L0^2 = " << euler
    << " N: a straight segment cannot buckle, and the first steps would launch the ends apart "
    << "with that force; ";
  // The smallest segment count whose initial shape starts no segment compressed (and whose
  // segments are not refused as shorter than a tenth of the diameter), among the next 16 (each
  // try is one initial shape; the one-segment struts of the fuzzer take 2).
  int fix = 0;
  const int most = at.winch ? 0 : std::min<long long>(
      p.segments + 16,
      static_cast<long long>(std::floor(p.length / (kMinSegmentPerDiameter * p.diameter))));
  for (int k = p.segments + 1; k <= most && fix == 0; ++k) {
    TetherParams q = p;
    q.segments = k;
    std::string ignored;
    std::optional<Tether> candidate = Tether::Create(q, env, &ignored);
    if (candidate && !(1 - ShortestStartChord(*candidate, a, b, axis) > kStretchWarning)) fix = k;
  }
  if (fix > 0) {
    s << "use at least " << fix << " segments (every segment then starts at its length), or "
      << "remove EAc";
  } else {
    s << "remove EAc, or move the ends " << p.length << " m apart";
  }
  return "refuse:" + s.str();
}

// The positions of the ends at the start (qpos0, mocap bodies at their model positions):
// refuses an end below the seabed or ends farther apart than length (1 + max_strain); warns
// about a stretched start with the strain and the tension it means.
bool CheckStart(const mjModel* m, const mjData* d, const Environment& env,
                const AttachedTether& at, std::string* warning, std::string* error) {
  TetherParams p = at.tether.params();
  if (at.winch) p.length = at.initial_length;
  const char* end_name[2] = {"A", "B"};
  std::ostringstream s;
  for (int end = 0; end < 2; ++end) {
    if (at.site[end] < 0 || !env.water.has_seabed) continue;
    const mjtNum* xs = d->site_xpos + 3 * at.site[end];
    const double z = xs[2], zb = env.water.SeabedHeight(xs[0], xs[1]);
    if (z < zb) {
      s << "end " << end_name[end] << " (site '" << mj_id2name(m, mjOBJ_SITE, at.site[end])
        << "') starts at z = " << z << " m, " << zb - z
        << " m below the seabed (water key " << SeabedDescription(env.water)
        << "): move the site or its body above the seabed, or lower the seabed";
      *error = s.str();
      return false;
    }
  }
  if (at.site[1] < 0) return true;
  const Vec3 a(d->site_xpos + 3 * at.site[0]), b(d->site_xpos + 3 * at.site[1]);
  const double span = (b - a).norm(), strain = span / p.length - 1;
  if (!std::isfinite(span)) {
    s << "the end sites ('" << mj_id2name(m, mjOBJ_SITE, at.site[0]) << "', '"
      << mj_id2name(m, mjOBJ_SITE, at.site[1])
      << "') start at positions that are not finite: check the pos and quat of their bodies";
    *error = s.str();
    return false;
  }
  if (strain > p.max_strain) {
    s << "key 'length' = " << p.length << " m: the ends (sites '"
      << mj_id2name(m, mjOBJ_SITE, at.site[0]) << "', '" << mj_id2name(m, mjOBJ_SITE, at.site[1])
      << "') start " << span << " m apart, more than length x (1 + max_strain) = "
      << p.length * (1 + p.max_strain) << " m: the tether cannot start; make it at least "
      << span << " m long or move the sites closer";
    *error = s.str();
    return false;
  }
  if (std::string compressed = CompressedStart(m, d, env, at, a, b); !compressed.empty()) {
    if (compressed.rfind("refuse:", 0) == 0) {
      *error = compressed.substr(7);
      return false;
    }
    *warning = compressed;
    return true;
  }
  if (strain > kStretchWarning) {
    s << "starts stretched, far from equilibrium: the ends are " << span
      << " m apart for a length of " << p.length << " m, a strain of " << strain
      << " and a tension EA x strain = " << p.EA * strain
      << " N at the first step; make the tether at least " << span
      << " m long unless a pre-tensioned start is meant (the elastic energy EA x strain^2 x "
      << "length / 2 = " << 0.5 * p.EA * strain * strain * p.length
      << " J is released within the first steps, a snap whose outcome, and the slack-taut "
      << "bouncing it may start, depend on <option timestep> for seconds after: compare with "
      << "a smaller one)";
    *warning = s.str();
  }
  return true;
}

// A tether whose initial shape starts with its skin inside a geom it touches (contact=): the
// penalty (contact_stiffness k per metre of tether per metre of penetration) pushes it out in
// the first steps, an impulse that the step resolves only roughly, like a stretched start's
// snap. Found where the contact force sees it: FindContacts' planes at qpos0, the depth of a
// segment the skin's below its lower end's gap, r - min(n.(x_j - p), n.(x_j+1 - p)). Warned
// where the deepest is beyond kContactStartDepth d and beyond twice the depth at which the
// contact carries the tether's own net weight, |w|/k (a line that rests on a rock starts near
// that). The scene fuzzer's world draw found six such starts, 0.7-18 mm inside, that
// disagreed with their 0.2 ms selves, with no word at load (docs/scene_fuzzer.md, session 16).
constexpr double kContactStartDepth = 1e-3;  // [-] of the diameter

// An end site far outside the body that the tether pulls: farther from the centre of mass of
// its free body (the subtree's) than kSiteLeverFactor times the reach of that body's geoms plus
// kSiteLeverMargin. The tether then acts on that lever arm, and the body's effective mass at
// the site, which the coupling sees, falls with its square: the hostile-input generator's
// site moved 38 m off a 0.16 kg m^2 vehicle stopped at the first step, told to reduce the step
// below 1e-4 s. A pos in centimetres where metres were meant does this. A warning, since a long
// boom without geoms is legitimate. Needs d's kinematics and subtree centres of mass.
constexpr double kSiteLeverFactor = 3;    // [-]
constexpr double kSiteLeverMargin = 1;    // [m]
std::string SiteLeverWarning(const mjModel* m, const mjData* d, const AttachedTether& at) {
  std::ostringstream s;
  for (int end = 0; end < 2; ++end) {
    if (at.site[end] < 0 || !at.coupled[end]) continue;
    const int carrier = FreeCarrier(m, at.body[end]);
    if (carrier <= 0) continue;
    const Vec3 com(d->subtree_com + 3 * carrier);
    const double lever = (Vec3(d->site_xpos + 3 * at.site[end]) - com).norm();
    double reach = 0;  // [m] farthest point of the subtree's geoms from its centre of mass
    bool geoms = false;
    for (int g = 0; g < m->ngeom; ++g) {
      int b = m->geom_bodyid[g];
      while (b > 0 && b != carrier) b = m->body_parentid[b];
      if (b != carrier) continue;
      geoms = true;
      reach = std::max(reach, (Vec3(d->geom_xpos + 3 * g) - com).norm() + m->geom_rbound[g]);
    }
    if (!geoms || lever <= kSiteLeverFactor * reach + kSiteLeverMargin) continue;
    const char* site = mj_id2name(m, mjOBJ_SITE, at.site[end]);
    const char* body = mj_id2name(m, mjOBJ_BODY, carrier);
    s << "end " << "AB"[end] << " (site '" << (site ? site : "?") << "') is " << lever
      << " m from the centre of mass of body '" << (body ? body : "?")
      << "', whose geoms reach " << reach
      << " m from it: the tether pulls on that lever arm, and the body's effective mass at the "
         "site falls with its square (mjtether info prints it as m_eff); check the site's pos "
         "(metres, not centimetres?)";
    return s.str();
  }
  return "";
}

std::string ContactStartWarning(const mjModel* m, const mjData* d, const Environment& env,
                                const AttachedTether& at) {
  if (!at.contact || at.contacts.geoms.empty()) return "";
  const Tether& t = at.tether;
  const TetherParams& p = t.params();
  Ends ends;
  for (int end = 0; end < 2; ++end) {
    if (at.site[end] < 0) continue;
    EndState& e = end == 0 ? ends.a : ends.b;
    e.pos = Vec3(d->site_xpos + 3 * at.site[end]);
    const double* R = d->site_xmat + 9 * at.site[end];
    e.axis = Vec3(R[0], R[3], R[6]);
  }
  const int n = t.nodes();
  std::vector<double> x(3 * n), v(3 * n, 0.0);
  if (!at.static_x.empty()) {
    x = at.static_x;
  } else {
    t.InitialShape(ends, x.data(), v.data());
  }
  std::fill(v.begin(), v.end(), 0.0);
  std::vector<double> boxes(ChunkBoxesSize(t.segments()));
  std::vector<ContactPoint> points(at.contacts.capacity);
  int dropped = 0;
  const int count = FindContacts(m, d, at.contacts, t, x.data(), v.data(), 0.0, boxes.data(),
                                 points.data(), at.contacts.capacity, &dropped);
  const double r = 0.5 * p.diameter;
  const ConstNodes xs(x.data(), 3, n);
  double deepest = 0;
  const ContactPoint* at_deepest = nullptr;
  for (int k = 0; k < count; ++k) {
    const ContactPoint& c = points[k];
    const double gap = std::min(c.normal.dot(xs.col(c.segment) - c.point),
                                c.normal.dot(xs.col(c.segment + 1) - c.point));
    if (r - gap > deepest) {
      deepest = r - gap;
      at_deepest = &c;
    }
  }
  const double rho = env.wet ? env.water.density : 0;
  const double w = std::abs(p.mass_per_length - rho * 0.25 * M_PI * p.diameter * p.diameter) *
                   env.gravity.norm();  // [N/m] net weight per length
  const double k = p.contact_stiffness;
  if (!at_deepest || !(deepest > std::max(kContactStartDepth * p.diameter, 2 * w / k))) {
    return "";
  }
  // The geom: the one whose body the point is tagged with and whose plane it is (the first
  // geom of that body in the contact list when several are).
  std::string geom = "?";
  for (const ContactGeom& cg : at.contacts.geoms) {
    if (m->geom_bodyid[cg.geom] != at_deepest->tag) continue;
    const char* name = mj_id2name(m, mjOBJ_GEOM, cg.geom);
    geom = name ? std::string(name) : "#" + std::to_string(cg.geom);
    break;
  }
  const Vec3& q = at_deepest->point;
  std::ostringstream s;
  s << "starts inside a geom it touches, far from equilibrium: its skin is " << deepest
    << " m inside geom '" << geom << "' (segment " << at_deepest->segment << " of "
    << t.segments() << ", near (" << q.x() << ", " << q.y() << ", " << q.z()
    << ")), a contact force contact_stiffness x depth = " << k * deepest
    << " N per metre of tether at the first step; start it clear (move the geom, or the ends, by "
    << deepest << " m) unless a pressed start is meant (the line is pushed out within the "
    << "first steps, an impulse whose outcome depends on <option timestep>: compare with a "
    << "smaller one)";
  return s.str();
}

// The iteration cap of the static start: StaticOptions' unless the test hook
// MJTETHER_STATIC_MAX_ITERATIONS gives another (tests/static_start_test.cc, non-convergence).
StaticOptions StaticStartOptions() {
  StaticOptions o;
  if (const char* cap = std::getenv("MJTETHER_STATIC_MAX_ITERATIONS")) {
    o.max_iterations = std::max(1, std::atoi(cap));
  }
  return o;
}

// start=static at load: relaxes the initial shape at qpos0 (the kinematics in d) to static
// equilibrium and keeps it for the restarts (AttachedTether::static_x). Not converged within
// the cap: a warning naming the tether, the residual force and its node, the last shape kept.
// A shape that is not usable (non-finite, strain beyond max_strain): refused (exit 2).
bool StaticStartAtLoad(const mjModel* /*m*/, const mjData* d, AttachedTether* at,
                       std::string* warning, std::string* error) {
  warning->clear();
  const Tether& t = at->tether;
  Ends ends;
  for (int end = 0; end < 2; ++end) {
    if (at->site[end] < 0) continue;
    EndState& e = end == 0 ? ends.a : ends.b;
    e.pos = Vec3(d->site_xpos + 3 * at->site[end]);
    const double* R = d->site_xmat + 9 * at->site[end];
    e.axis = Vec3(R[0], R[3], R[6]);
  }
  std::vector<double> x(3 * t.nodes()), v(3 * t.nodes()), work(t.WorkspaceSize());
  t.InitialShape(ends, x.data(), v.data());
  const StaticResult r = t.RelaxToStatic(ends, x.data(), v.data(), work.data(),
                                         StaticStartOptions());
  std::ostringstream s;
  if (!r.ok) {
    s << "key 'start' = static: the relaxation to static equilibrium left an unusable shape ("
      << r.reason << ", node " << r.node << " of " << t.segments()
      << "): use start=catenary, or check the ends, length and loads";
    *error = s.str();
    return false;
  }
  if (!r.converged) {
    s << "key 'start' = static: not converged to static equilibrium in " << r.iterations
      << " iterations (the last moved a node by " << r.displacement << " m, tolerance "
      << StaticOptions().tolerance * t.params().length << " m); largest residual force "
      << r.residual << " N at node " << r.node << " of " << t.segments()
      << "; starting from the last shape, which is not at rest: expect a start transient";
    *warning = s.str();
  }
  at->static_result = r;
  at->static_x = std::move(x);
  at->static_a = ends.a.pos;
  at->static_b = ends.b.pos;
  return true;
}

// Vehicles (vehicle:BODY texts) whose body starts below the seabed.
bool CheckVehicles(const mjModel* m, const mjData* d, const Environment& env,
                   std::string* element, std::string* error) {
  if (!env.water.has_seabed) return true;
  for (int i = 0; i < m->ntext; ++i) {
    const std::string name = TextName(m, i);
    if (name.rfind("vehicle:", 0) != 0) continue;
    const int body = mj_name2id(m, mjOBJ_BODY, name.substr(8).c_str());
    if (body < 0) continue;  // AttachVehicles reports it
    const double z = d->xpos[3 * body + 2];
    const double zb = env.water.SeabedHeight(d->xpos[3 * body], d->xpos[3 * body + 1]);
    if (z < zb) {
      std::ostringstream s;
      s << "body '" << name.substr(8) << "' starts at z = " << z << " m, " << zb - z
        << " m below the seabed (water key " << SeabedDescription(env.water)
        << "): move it above the seabed, or lower the seabed";
      *element = name;
      *error = s.str();
      return false;
    }
  }
  return true;
}

// The translational actuator force on the free-joint root of `body` [N] (0 if none).
double ThrustOn(const mjModel* m, const mjData* d, int body) {
  const int dof = FreeRootDof(m, body);
  return dof >= 0 ? Vec3(d->qfrc_actuator + dof).norm() : 0;
}

// The thrust on a free body at one of the tether's ends against what the tether holds,
// holds = EA x max_strain [N], from d->qfrc_actuator; empty if below half of it (Diagnose's
// first cause).
std::string ThrustCause(const mjModel* m, const mjData* d, const AttachedTether& at,
                        double holds) {
  std::ostringstream s;
  for (int end = 0; end < 2; ++end) {
    if (at.site[end] < 0 || at.mocap[end] || at.body[end] <= 0) continue;
    const double thrust = ThrustOn(m, d, at.body[end]);
    const char* name = mj_id2name(m, mjOBJ_BODY, at.body[end]);
    if (thrust >= holds) {
      s << "thrust beyond what the tether holds: the actuators push body '"
        << (name ? name : "world") << "' with " << thrust << " N, more than EA x max_strain = "
        << holds << " N; reduce the thrust (or its schedule) below that, or raise EA";
      return s.str();
    }
    // A load taken up suddenly (slack pulled taut, a thrust stepped on) overshoots its static
    // strain up to twice (undamped spring under a step load).
    if (thrust >= 0.5 * holds) {
      s << "a snap load: the actuators push body '" << (name ? name : "world") << "' with "
        << thrust << " N, more than half of EA x max_strain = " << holds
        << " N, and a load taken up suddenly overshoots its static strain up to twice; reduce "
           "the thrust below "
        << 0.5 * holds << " N, ramp it in slowly, or raise EA";
      return s.str();
    }
  }
  return "";
}

// The most likely cause of a divergence, from the state of the scene when it was reported,
// with what to change; empty if none of the checkable causes applies (the step is then the
// likely one). In order: thrust beyond what the tether holds; within kStartSteps steps of a
// start stretched beyond kStretchWarning, the start (unless the ends were pulled apart mostly
// by a prescribed motion); ends pulled apart to a mean strain within the strain spread along
// the line of max_strain (or beyond it); an end moving more than half of max_strain L0 in one
// step; an end below the seabed; a divergence within kStartSteps steps of a stretched start.
std::string Diagnose(const mjModel* m, const mjData* d, const Environment& env,
                     const AttachedTether& at, const double* u) {
  constexpr int kStartSteps = 50;
  const Tether& t = at.tether;
  TetherParams p = t.params();
  p.length = DeployedLength(at, u);
  const double holds = p.EA * p.max_strain;  // [N] tension at max_strain
  const char* end_name[2] = {"A", "B"};
  std::ostringstream s;
  auto body_name = [&](int end) {
    const char* n = mj_id2name(m, mjOBJ_BODY, at.body[end]);
    return std::string(n ? n : "world");
  };
  // The thrust: schedules drive an end's body beyond what the tether holds, though the thrust
  // at this instant is below it: a smaller step diverges too, later, so the step is not the
  // cause (the scene fuzzer's long run, session 11: 26 runs blamed the step whose 0.2 ms runs
  // then diverged with "thrust beyond" or "a snap load").
  auto schedule_cause = [&](int end) -> std::string {
    if (at.site[end] < 0 || at.mocap[end] || at.body[end] <= 0) return "";
    const double peak = ScheduledThrust(m, d, at.body[end]);
    if (peak < 0.5 * holds) return "";
    // Only once the schedules act: a divergence before any thrust is not caused by it (the
    // fuzzer's seed 654 diverges at t = 0, its thrust starting at 0.1 s).
    const double now = ThrustOn(m, d, at.body[end]);
    if (now <= 0) return "";
    std::ostringstream c;
    if (peak >= holds) {
      c << "thrust beyond what the tether holds: the thrust: schedules push body '"
        << body_name(end) << "' with up to " << peak << " N (" << now
        << " N now), more than EA x max_strain = " << holds
        << " N, so a smaller step would probably diverge too, later; reduce the schedule below that, or raise EA";
    } else {
      c << "a snap load: the thrust: schedules push body '" << body_name(end) << "' with up to "
        << peak << " N (" << now << " N now), more than half of EA x max_strain = " << holds
        << " N, and a load taken up suddenly overshoots its static strain up to twice; reduce "
           "the schedule below "
        << 0.5 * holds << " N, ramp it in slowly, or raise EA";
    }
    return c.str();
  };
  if (std::string thrust = ThrustCause(m, d, at, holds); !thrust.empty()) return thrust;
  const bool both = at.site[1] >= 0;
  // Positions now; velocities as the tether last saw them (a motion's exact velocity).
  Vec3 pos[2], vel[2];
  for (int end = 0; end < (both ? 2 : 1); ++end) {
    pos[end] = Vec3(d->site_xpos + 3 * at.site[end]);
    vel[end] = Vec3(u + (end == 0 ? kEndA : kEndB) + 3);
  }
  auto moved_by_motion = [&](int end) {
    return at.mocap[end] && mj_name2id(m, mjOBJ_TEXT, ("motion:" + body_name(end)).c_str()) >= 0;
  };
  auto free_body = [&](int end) { return at.body[end] > 0 && !at.mocap[end]; };
  // Ends pulled apart. The strain is not uniform along a pulled line: where it first crosses
  // max_strain, the mean strain span / length - 1 can still be below it by the strain spread
  // along the line (issue 11: a mocap end pulled at 0.5 m/s diverged at a mean strain of
  // 0.0998 < max_strain 0.1 and was told to reduce the step). Two contributions, summed:
  //  - weight: along a static line under its net weight w per length the tension changes by
  //    w dz between two points dz apart along gravity (the catenary's T = T0 + w (z - z0),
  //    Irvine 1981, ch. 1), so the strain spread between the ends is w |dz| / EA;
  //  - pulling speed: an end separating at v starts a strain step v / c, c = sqrt(EA / mu) the
  //    axial wave speed, which doubles where it reflects at the other end: 2 v / c.
  // Drag along the line (a current) is not included. The pull is the cause when the mean
  // strain is positive (the ends farther apart than the length) and within that spread of
  // max_strain; beyond length x (1 + max_strain) it always is.
  double mean_strain = -1, spread = 0, weight_spread = 0, wave_spread = 0, separating = 0;
  if (both) {
    const Vec3 chord = pos[1] - pos[0];
    mean_strain = chord.norm() / p.length - 1;
    const Vec3 g = t.env().gravity.norm() > 0 ? Vec3(t.env().gravity.normalized()) : Vec3::Zero();
    const double w = 2 * t.node_weight(0).norm() / t.rest_segment_length();  // [N/m] net weight
    weight_spread = w * std::abs(chord.dot(g)) / p.EA;
    separating = chord.norm() > 0 ? std::max(0.0, (vel[1] - vel[0]).dot(chord.normalized())) : 0;
    wave_spread = 2 * separating / std::sqrt(p.EA / p.mass_per_length);
    spread = weight_spread + wave_spread;
  }
  const double h = m->opt.timestep;
  // A stretched start whose release diverged within kStartSteps steps (the start-up strain,
  // below, without anything else to blame).
  const bool start_up =
      u[kStartStrain] > 0 && u[kBadTime] - u[kStartTime] <= kStartSteps * h * (1 + 1e-9);
  auto start_up_cause = [&]() {
    s << "start-up strain: the tether started stretched by " << u[kStartStrain]
      << " (tension EA x strain = " << p.EA * u[kStartStrain] << " N) and diverged "
      << u[kBadTime] - u[kStartTime]
      << " s later; make it at least as long as the distance between its ends ("
      << p.length * (1 + u[kStartStrain]) << " m)";
    return s.str();
  };
  // Ends found far apart right after a stretched start, but not moved apart by a motion: the
  // start's release flung a body (the scene fuzzer's seeds 391, 617 and 657: 87% stretched,
  // the vehicle thrown 25-90 m in two steps, a TMS moving 0.7 m, and the stop blamed on the
  // TMS's motion or on "forces on body 'rov'"; at 0.2 ms they run). The prescribed motions
  // must account for at least half of the chord's growth since the start to be the cause.
  // The same holds for a body thrown faster than the step resolves (below): right after a
  // stretched start that Attach warned about (kStretchWarning), the start is named first.
  if (start_up && u[kStartStrain] > kStretchWarning) {
    const double growth = (pos[1] - pos[0]).norm() - p.length * (1 + u[kStartStrain]);
    double moved = 0;  // [m] the mocap ends' displacement since the start
    for (int end = 0; end < 2; ++end) {
      int b = at.body[end];  // the mocap body that carries the end (MovedByMocap)
      while (b > 0 && m->body_mocapid[b] < 0) b = m->body_parentid[b];
      if (!at.mocap[end] || b <= 0) continue;
      moved += mju_dist3(d->mocap_pos + 3 * m->body_mocapid[b], m->body_pos + 3 * b);
    }
    if (!(mean_strain > 0 && mean_strain >= p.max_strain - spread) || moved < 0.5 * growth) {
      return start_up_cause();
    }
  }
  if (both && mean_strain > 0 && mean_strain >= p.max_strain - spread) {
    s << "the ends were pulled " << (pos[1] - pos[0]).norm() << " m apart, a mean strain of "
      << mean_strain << " against max_strain = " << p.max_strain;
    if (mean_strain <= p.max_strain) {
      s << " (length x (1 + max_strain) = " << p.length * (1 + p.max_strain)
        << " m); the strain along a pulled line exceeds its mean by up to " << spread
        << " here (net weight w |dz| / EA = " << weight_spread << ", the ends separating at "
        << separating << " m/s: 2 v / c = " << wave_spread << ")";
    } else {
      s << ", more than length x (1 + max_strain) = " << p.length * (1 + p.max_strain) << " m";
    }
    for (int end = 0; end < 2; ++end) {
      if (moved_by_motion(end)) {
        s << ", by the prescribed motion of body '" << body_name(end)
          << "'; reduce its amplitude (motion:" << body_name(end) << ") or lengthen the tether";
        return s.str();
      }
    }
    for (int end = 0; end < 2; ++end) {
      if (free_body(end)) {
        s << ", by forces on body '" << body_name(end) << "' larger than EA x max_strain = "
          << holds << " N; lengthen the tether or reduce them";
        return s.str();
      }
    }
    s << ", by the motion of the ends' bodies; lengthen the tether or limit that motion";
    return s.str();
  }
  for (int end = 0; end < (both ? 2 : 1); ++end) {
    const double travel = vel[end].norm() * h;
    if (travel > 0.5 * p.max_strain * t.rest_segment_length()) {
      // A body thrown that fast by a thrust schedule beyond what the tether holds: the
      // schedule is the cause, and a smaller step would not cure it (startup_test's
      // ThrustScheduleBeyondWhatTheTetherHolds: 2.7 km/s after 0.08 s of its ramp).
      if (std::string c = schedule_cause(end); !c.empty()) return c;
      s << "end " << end_name[end] << " (body '" << body_name(end) << "') moves at "
        << vel[end].norm() << " m/s, " << travel << " m per <option timestep> " << h
        << " s, more than half of max_strain x the segment length "
        << p.max_strain * t.rest_segment_length()
        << " m: that motion is too fast for the step; reduce <option timestep> below "
        << StepAtMost(0.5 * p.max_strain * t.rest_segment_length() / vel[end].norm()) << " s";
      // A free body that nothing prescribes (a schedule beyond what the tether holds was named
      // above) was thrown by the tether or a force on it. Test:
      // LightVehicle.ThrownFreeBodyIsToldWhatThrewIt (explicit at coupling omega h 1.64 on an
      // undamped line, the body thrown at 78 m/s; it ran with damping_ratio=1 or implicit, and
      // "slow the motion" named nothing the user could slow).
      const bool thrown = free_body(end);
      if (thrown) {
        s << "; nothing prescribes body '" << body_name(end)
          << "', so the tether (or a force on it) threw it: where the load warnings say the "
             "coupling may chatter use integrator=implicit or bdf2, and where a snap rang the "
             "line declare damping_ratio=1";
      } else {
        s << " or slow the motion";
      }
      return s.str();
    }
  }
  // An explicit tether forced (substeps, max_step) beyond its stability limit: the step.
  if (IsExplicit(p.integrator) && h / t.SubstepsFor(h) > t.ExplicitStableStep()) return "";
  if (env.water.has_seabed) {
    for (int end = 0; end < (both ? 2 : 1); ++end) {
      const double zb = env.water.SeabedHeight(pos[end].x(), pos[end].y());
      if (pos[end].z() < zb) {
        s << "seabed penetration: end " << end_name[end] << " (body '" << body_name(end)
          << "') is " << zb - pos[end].z() << " m below the seabed (z = " << zb
          << " m), pressing the tether into it; keep the body above the seabed";
        return s.str();
      }
    }
  }
  if (start_up) return start_up_cause();
  for (int end = 0; end < 2; ++end) {
    if (std::string c = schedule_cause(end); !c.empty()) return c;
  }
  return "";
}

// Degrees of freedom of the bodies between b and the world (a body without joints welded to a
// moving parent moves with it).
int DofsAbove(const mjModel* m, int b) {
  int n = 0;
  for (int p = m->body_parentid[b]; p > 0; p = m->body_parentid[p]) n += m->body_dofnum[p];
  return n;
}

// Estimated CPU time of a tether per simulated second [s], from the substeps and the node
// count, with the costs per node and tether step measured on this project's machine (README,
// Accuracy and cost: explicit 25 ns, rk4 96 ns, implicit 136 ns per node and step at 80
// segments; implicit2 two implicit solves).
double CostPerSecond(const Tether& t, double timestep) {
  // In Integrator order: explicit, implicit, implicit2, rk4, bdf2.
  static constexpr double kNsPerNodeStep[] = {25e-9, 136e-9, 272e-9, 96e-9, 140e-9};
  const int steps = t.SubstepsFor(timestep);
  return steps / timestep * t.nodes() * kNsPerNodeStep[static_cast<int>(t.params().integrator)];
}

// Thrust schedules that push an end's body beyond what its tether holds, EA x max_strain [N]
// (max_strain: where a run is declared diverged), or beyond half of it: warned at load, not
// refused (the body's drag may take part of the thrust, a schedule may be meant to break the
// run). At run time such a scene usually stops with "thrust beyond what the tether holds" or
// "a snap load" (Diagnose); one that goes on runs near max_strain, where the snaps' peaks
// depend on the step: an implicit scheme at 2 ms damps a peak that the same scene at 0.2 ms
// resolves and diverges on (the scene fuzzer's seeds 9136 and 9153, thrust 0.82 and 1.88 x
// EA x max_strain, which ran to their end at 2 ms; session 14's "fine step failed"). The peak
// is ScheduledThrust's (the schedules' largest |ctrl|, through the actuators' moments at
// qpos0), as Diagnose reads it.
void WarnThrustBeyondHolds(const mjModel* m, ModelTethers* set) {
  mjData* scratch = nullptr;
  for (const AttachedTether& at : set->tethers) {
    const TetherParams& p = at.tether.params();
    const double holds = p.EA * p.max_strain;  // [N]
    for (int end = 0; end < 2; ++end) {
      if (at.site[end] < 0 || at.mocap[end] || at.body[end] <= 0) continue;
      if (!scratch) {
        scratch = mj_makeData(m);
        if (!scratch) return;
        mj_kinematics(m, scratch);
        mj_comPos(m, scratch);
        mj_transmission(m, scratch);
      }
      const double peak = ScheduledThrust(m, scratch, at.body[end]);  // [N]
      if (!(peak >= 0.5 * holds)) continue;
      const char* body = mj_id2name(m, mjOBJ_BODY, at.body[end]);
      std::ostringstream s;
      s.precision(6);
      s << set->source << ": <text name=\"tether:" << at.name << "\">: the thrust: schedules push body '"
        << (body ? body : "?") << "' (end " << "AB"[end] << ") with up to " << peak << " N, ";
      if (peak >= holds) {
        s << "more than EA x max_strain = " << holds
          << " N, what this tether holds: the run stops when the tether strains past max_strain, "
             "unless the body's drag takes the rest; a run that goes on is near that strain, and "
             "its snaps and peak tensions depend on <option timestep>: compare with a smaller "
             "one (or reduce the schedule below "
          << holds << " N, or raise EA)";
      } else {
        s << "more than half of EA x max_strain = " << holds
          << " N: a load taken up suddenly (a slack tether pulled taut) overshoots its static "
             "strain up to twice, so its peak may reach max_strain, and that peak depends on "
             "<option timestep>: compare with a smaller one (or reduce the schedule below "
          << 0.5 * holds << " N, ramp it in slowly, or raise EA)";
      }
      set->warnings.push_back(s.str());
    }
  }
  if (scratch) mj_deleteData(scratch);
}

// What the scene fuzzer measured where the coupling warnings below apply, on session 43's long
// run of seeds 201..15000 (session 33's until then; `tools/scene_fuzz_classify.py --bands`,
// runs that went to their end; docs/coupling.md, sessions 33 and 43): how many were off their
// 10x smaller step, and how many of those no other warning named (a stretched start, thrust
// beyond what the tether holds, a snap ringing the undamped segment mode: the fuzzer's warned
// outcomes). Said only where measured: the fuzzer's ends are end B on a free body. The held
// force's warning said "1 in 20" from session 19 (34 of 668 failures then) to 32; above half
// the limit rk4 had 6 failures in 138 and explicit 5 in 90 (session 28) before the ringing of
// explicit schemes was watched; rk4 at 0.5-0.8, refused since session 29, had 7 of 85, one of
// them seed 913 growing its vehicle-end tension from 11 N to 47 kN in 3 s without a stop.
struct FuzzerRate {
  int off;     // runs off their 10x smaller step
  int runs;    // runs that went to their end
  int silent;  // of the off ones, those no other warning named
};
constexpr FuzzerRate kHeldExplicit{17, 357, 1};       // held force, omega h 0.1-0.5
constexpr FuzzerRate kHeldRk4{8, 227, 1};             // held force, 0.1-0.25
constexpr FuzzerRate kHeldImplicit2{24, 338, 0};      // held force, 0.1-0.5
constexpr FuzzerRate kHeldBelow{16, 2645, 0};         // the three, below kCouplingAccurate
// bdf2, which the two warnings below advise against a chatter, has no coupling limit, but below
// kLeadFrom it holds the end force too (unless its end damper, the seabed or a heavy node calls
// for the consistent coupling): its own rates in their bands.
constexpr FuzzerRate kHeldBdf2{13, 355, 0};           // bdf2, 0.1-0.5
constexpr FuzzerRate kHeldBdf2Upper{11, 129, 0};      // bdf2, 0.5-1
constexpr FuzzerRate kConsistentExplicit{10, 131, 1};  // consistent coupling, 0.5-1
constexpr FuzzerRate kChatterRk4{11, 140, 1};         // above half the limit, 0.25-0.5
constexpr FuzzerRate kChatterExplicit{13, 89, 1};     // above half the limit, 1-2

// "the scene fuzzer finds N in M such WHAT off their 10x smaller step (F of them with no other
// warning)"
std::string Finds(const FuzzerRate& r, const std::string& what) {
  return "the scene fuzzer finds " + std::to_string(r.off) + " in " + std::to_string(r.runs) +
         " such " + what + " off their 10x smaller step (" + std::to_string(r.silent) +
         " of them with no other warning)";
}

// The rate above half the limit, for the chatter warning; empty where not measured.
std::string ChatterRate(Integrator integrator, bool consistent) {
  if (integrator == Integrator::kRK4) return "; " + Finds(kChatterRk4, "rk4 runs");
  if (integrator == Integrator::kExplicit && consistent) {
    return "; " + Finds(kChatterExplicit, "explicit runs");
  }
  return "";
}

// The held force's rate below half the limit (only rk4, explicit and implicit2 have a limit and
// get that warning: CouplingLimit::applies).
std::string HeldRate(Integrator integrator) {
  const FuzzerRate& r = integrator == Integrator::kRK4        ? kHeldRk4
                        : integrator == Integrator::kImplicit2 ? kHeldImplicit2
                                                               : kHeldExplicit;
  return Finds(r, std::string(IntegratorName(integrator)) + " runs");
}

// Why a refusal in a band that loaded until session 29 is one: rk4 between its limit and 0.8
// (the fuzzer's rate there, above). Empty elsewhere.
std::string RefusedBandRate(Integrator integrator, double omega_h) {
  if (integrator == Integrator::kRK4 && omega_h < kCouplingLimitRk4BeforeSession29) {
    return " (the scene fuzzer found 7 in 85 rk4 runs at omega h 0.5-0.8 off their 10x smaller "
           "step, one growing from 11 N to 47 kN in 3 s without a stop)";
  }
  return "";
}

// The coupling part of the time-step advisor (docs/coupling.md): for each end on a free body,
// the coupling frequency omega = sqrt(k_end / m_eff), k_end = EA/L0 (or the bending's EI/(L0^2
// w) across the line where larger, session 37), m_eff = 1/lambda_max(W)
// the smallest effective mass of the body at the site (W = J M^-1 J^T at the model's initial
// configuration). An explicit coupling (coupling=explicit, or MuJoCo's RK4, with which the
// implicit end is not available) is refused at omega h >= its limit and warned about above
// half of it. Also warns where automatic substeps make a tether slower than real time.
bool AdviseCoupling(const mjModel* m, ModelTethers* set, std::string* error) {
  const double h = m->opt.timestep;
  mjData* d = nullptr;
  std::vector<double> jac(6 * std::max(m->nv, 1));
  bool ok = true;
  for (AttachedTether& at : set->tethers) {
    const Tether& t = at.tether;
    const std::string where = set->source + ": <text name=\"tether:" + at.name + "\">: ";
    const TetherParams& p = t.params();
    // implicit2 with contact and an end on a body that moves: measured wrong, not refined. A
    // drape over a frictionless drum with a 5 kg mass on slide joints at end B (tests/
    // drape_test.cc) settles at the right place but with end tensions of 19, 25 and 67 N at
    // steps of 2, 1 and 0.5 ms where statics give 46.6 N (bdf2, implicit, explicit and rk4
    // within 0.1%); a wrap against a slider read 48 N for 80 N. Refused rather than silently
    // wrong until the cause is found (docs/contact.md).
    if (p.integrator == Integrator::kImplicit2 && at.contact && (at.coupled[0] || at.coupled[1])) {
      const int end = at.coupled[0] ? 0 : 1;
      const char* body = mj_id2name(m, mjOBJ_BODY, at.body[end]);
      *error = where + "key 'integrator' = implicit2 is not supported with 'contact' and end " +
               (end == 0 ? "A" : "B") + " on body '" + (body ? body : "?") +
               "' (a body with degrees of freedom): its end tensions were measured wrong "
               "there (docs/contact.md); use integrator=bdf2 (the default) or implicit";
      ok = false;
      break;
    }
    // Automatic substeps slower than real time: name the cheaper setting.
    if (IsExplicit(p.integrator) && p.substeps == 0 && p.max_step == 0) {
      const double cost = CostPerSecond(t, h);
      if (cost > 1) {
        std::ostringstream s;
        s << where << "integrator=" << IntegratorName(p.integrator) << " takes " << t.SubstepsFor(h)
          << " substeps per MuJoCo step (stable step " << t.ExplicitStableStep() << " s) on "
          << t.nodes() << " nodes: about " << cost
          << " s of CPU per simulated second, slower than real "
          << "time; integrator=implicit takes one step per MuJoCo step (about "
          << t.nodes() * 136e-9 / h << " s)";
        set->warnings.push_back(s.str());
      }
    }
    // bdf2 and implicit2 on an overdamped segment mode step as backward Euler (Tether::Step):
    // say so, with the damping that keeps their second order.
    if (t.StepsAsBackwardEuler()) {
      const double limit = t.SecondOrderMaxDampingRatio();  // [-]
      std::ostringstream s;
      s << where << "integrator=" << IntegratorName(p.integrator)
        << " steps as backward Euler (integrator=implicit) here: the segment axial mode's "
           "damping ratio "
        << t.SegmentModeRatio() << " is above " << limit << ", where "
        << IntegratorName(p.integrator)
        << "'s steps read tensions several times too high (docs/limitations.md); set "
           "integrator=implicit to say so, or damping <= "
        << p.damping * limit / t.SegmentModeRatio() << " N s (damping_ratio <= " << limit
        << ") to keep " << IntegratorName(p.integrator) << "'s second order";
      set->warnings.push_back(s.str());
    }
    for (int end = 0; end < 2; ++end) {
      if (!at.coupled[end]) continue;
      if (!d) {
        d = mj_makeData(m);
        mj_kinematics(m, d);
        mj_comPos(m, d);
        mj_crb(m, d);
        mj_factorM(m, d);
      }
      const Mat3 W = SiteInverseMass(m, d, at.site[end], jac.data());
      const double lambda = LargestEigenvalue(W);
      CouplingLimit& c = at.limit[end];
      c.body = at.body[end];
      // A stiff rod's end is stiffer across the line than along it (EI/(L0^2 w) > EA/L0):
      // held-out seed 12434 (EI 467 N m^2 on 3.6 cm segments of EA 3.2e3 N, a 2.3 kg body)
      // read omega h 0.35 from EA/L0, took the held end force, and ended 0.31 m off its fine
      // step; its bending gives omega h 3.6, and the consistent coupling 6 mm (session 37).
      const double k_axial = t.EndStiffness(), k_bending = t.EndBendingStiffness(end == 1);
      c.k_end = std::max(k_axial, k_bending);  // [N/m]
      c.bending = k_bending > k_axial;
      c.m_eff = 1 / lambda;
      c.omega = std::sqrt(c.k_end * lambda);
      c.omega_h = c.omega * h;
      // The body bouncing on the whole taut line (BounceMode): a spring EA/L on m_eff and a
      // third of the line's mass (Rayleigh's spring mass; seed 1920's single 125 m segment has
      // a 42 kg end node on a 20 kg m_eff), damped by the line's internal damping, damping/L
      // (EndDamping() is damping/L0; 0 without it).
      BounceMode& bounce = at.bounce[end];
      bounce.mass = c.m_eff + p.mass_per_length * p.length / 3;
      bounce.omega = std::sqrt(p.EA / p.length / bounce.mass);
      bounce.omega_h = bounce.omega * h;
      bounce.ratio = t.EndDamping() / t.segments() / (2 * bounce.mass * bounce.omega);
      bounce.swing_watched = !at.winch && bounce.ratio < kRingDampingRatio &&
                             bounce.omega_h >= kBounceOmegaH;
      // Its snaps only where the segment mode's are not watched (RingWarnings' first message).
      bounce.watched = bounce.swing_watched && !WatchesRinging(t, h);
      if (bounce.watched &&
          (at.bounce_end < 0 || bounce.omega_h > at.bounce[at.bounce_end].omega_h)) {
        at.bounce_end = end;
      }
      if (bounce.swing_watched &&
          (at.swing_end < 0 || bounce.omega_h > at.bounce[at.swing_end].omega_h)) {
        at.swing_end = end;
      }
      c.limit = p.integrator == Integrator::kRK4        ? kCouplingLimitRk4
                : p.integrator == Integrator::kExplicit  ? kCouplingLimitExplicit
                : p.integrator == Integrator::kImplicit2 ? kCouplingLimitImplicit2
                                                         : 0;
      // The consistent coupling (EvaluateLead) where the held force is not resolved.
      // implicit2 and explicit from their own thresholds. implicit2's refusal limit is then
      // lifted (the limit is the held force's); explicit's stays (with the consistent coupling
      // its tension swung by kN at omega h 3.36 on the BlueROV2 case, docs/coupling.md).
      const bool implicit_lead =
          p.integrator == Integrator::kImplicit || p.integrator == Integrator::kBdf2;
      const double lead_from = implicit_lead                             ? kLeadFrom
                               : p.integrator == Integrator::kImplicit2 ? kLeadFromImplicit2
                               : p.integrator == Integrator::kExplicit  ? kLeadFromExplicit
                                                                         : INFINITY;
      // The end segment's internal damping on the body's effective mass over the step.
      c.damping_h = h * t.EndDamping() / c.m_eff;
      // The seabed under the end node, where it touches (kLeadFromSeabed).
      c.seabed_omega_h = std::sqrt(t.EndSeabedStiffness(end == 1) * lambda) * h;
      c.seabed_damping_h = h * t.EndSeabedDamping(end == 1) / c.m_eff;
      const double seabed_h = std::max(c.seabed_omega_h, c.seabed_damping_h);  // [-]
      const bool has_lead = std::isfinite(lead_from);  // rk4 has no consistent coupling
      // An end node heavier than the body's lightest effective mass: the held force gives the
      // body the node's forces without its inertia m_B a_B, which then is no small correction,
      // and the consistent coupling keeps it there (ImplicitStep, EndInertia): at any omega h
      // the two are then two models, and a run's fine-step self (below lead_from) was the other.
      c.m_node = t.NodeInertiaMax(end == 0 ? 0 : t.segments());
      c.heavy_node = c.m_node > c.m_eff;
      const double kappa = SlowModeKappa(p.integrator, t.SubstepsFor(h));
      const bool stiff = c.omega_h >= lead_from ||
                         (has_lead && (DamperTakesTheLead(c.damping_h, c.omega_h, kappa) ||
                                       c.heavy_node || seabed_h >= kLeadFromSeabed));
      // Where the consistent coupling can be taken, whatever the integrator.
      const bool lead_possible = end == 1 && !at.coupled[0] && !at.contact && !p.clamp_b &&
                                 FreeCarrier(m, at.body[1]) > 0 &&
                                 m->opt.integrator != mjINT_RK4;
      if (stiff && lead_possible &&
          // On a winch (at end A) explicit only: with implicit and bdf2 the world draw's
          // winch scenes lost accuracy with it (docs/coupling.md, session 16).
          (!at.winch || (!at.swapped && p.integrator == Integrator::kExplicit))) {
        at.lead = t.WithDynamicEndB();
        c.consistent = true;
        if (p.integrator == Integrator::kImplicit2) c.limit = 0;
      }
      at.seabed_watch[end] = !c.consistent && seabed_h >= kLeadFromSeabed;
      at.seabed_cure[end] = lead_possible && !at.winch;
      if (at.seabed_watch[end]) {
        const char* name = mj_id2name(m, mjOBJ_BODY, c.body);
        std::ostringstream w;
        w << where << "end " << (end == 0 ? "A" : "B") << " on body '" << (name ? name : "?")
          << "': the seabed under its end node is stiff on the body's step (omega h = "
          << c.seabed_omega_h << ", h c/m_eff = " << c.seabed_damping_h << ", at or above "
          << kLeadFromSeabed << ") and the body gets the held end force: the run stops if the "
          << "node touches the seabed; to avoid that use " << SeabedCure(at, end, h);
        set->warnings.push_back(w.str());
      }
      if (c.heavy_node && !c.consistent) {
        // The held force here (rk4, end A, or a condition of the consistent coupling not met):
        // the body moves as if the node weighed nothing. A modelling error, not the step's:
        // named with the segment count that makes the node lighter than the body.
        const char* name = mj_id2name(m, mjOBJ_BODY, c.body);
        std::ostringstream w;
        w << where << "end " << (end == 0 ? "A" : "B") << " on body '" << (name ? name : "?")
          << "': the end node (" << c.m_node << " kg: half a segment with its normal added "
          << "mass) is heavier than the body's smallest effective mass " << c.m_eff
          << " kg, and the body gets the held end force, which leaves the node's inertia out "
          << "(the body accelerates as if the node weighed nothing); use segments >= "
          << static_cast<long>(std::ceil(c.m_node * t.segments() / c.m_eff))
          << (!has_lead && lead_possible && !at.winch
                  ? " or integrator=bdf2 (the default), implicit, implicit2 or explicit, which "
                    "carry the node with the body (docs/coupling.md)"
                  : "");
        set->warnings.push_back(w.str());
      }
      c.applies = c.limit > 0;
      if (!c.applies) continue;
      const char* body = mj_id2name(m, mjOBJ_BODY, c.body);
      // Both warnings and the refusal start with the integrator, the end and its body.
      const std::string head = std::string("integrator=") + IntegratorName(p.integrator) +
                               " with end " + (end == 0 ? "A" : "B") + " on body '" +
                               (body ? body : "?") + "': ";
      // The refusal and the chatter warning above half the limit advise kCouplingAccurate /
      // omega, as the warnings below it and the chatter stop do; the refusal also gives the
      // limit's step. Until session 28 both advised limit / omega, the largest step that loads:
      // a refused user who took it landed in the warned band, and the warning's step was often
      // the very step that warned (rk4 seed 913 at omega h 0.71 was told "<= 0.00226 s" at
      // 0.002 s, and grew from 11 N to 47 kN in 3 s).
      const bool refused = c.omega_h >= c.limit;
      const double advised = StepAtMost(kCouplingAccurate / c.omega);  // [s] every warning's
      std::ostringstream s;
      s << head << "coupling omega h = " << c.omega_h
        << " (omega = sqrt(k_end/m_eff) = sqrt(" << c.k_end << " N/m / " << c.m_eff
        << " kg) = " << c.omega << " rad/s, k_end = " << EndStiffnessName(c)
        << ", <option timestep> " << h << " s), limit " << c.limit;
      if (!refused) {
        s << " (above half the limit: may chatter" << ChatterRate(p.integrator, c.consistent)
          << ")";
      } else {
        s << RefusedBandRate(p.integrator, c.omega_h);
      }
      s << (p.integrator == Integrator::kImplicit2
                ? "; use integrator=bdf2 (the default) or implicit (measured within 1% at "
                  "omega h 10.6), or <option "
                : "; use integrator=implicit or bdf2 (stable at any omega h measured) or "
                  "implicit2 (not limited on a free body at end B with end A fixed, up to "
                  "omega h 1 elsewhere), or <option ")
        << "timestep> <= " << advised << " s (omega h " << kCouplingAccurate;
      if (refused) s << "; the limit is at " << c.limit / c.omega << " s";
      s << "), or fewer segments or a smaller " << (c.bending ? "EI" : "EA");
      if (refused) {
        *error = where + s.str();
        ok = false;
        break;
      }
      if (c.omega_h >= 0.5 * c.limit) {
        set->warnings.push_back(where + s.str());
      } else if (!c.consistent && c.omega_h >= kCouplingAccurate) {
        // Below half the limit, but where the held force is often off (kCouplingAccurate).
        std::ostringstream w;
        w << where << head << "held end force at coupling omega h = " << c.omega_h
          << " (omega = " << c.omega
          << " rad/s, <option timestep> " << h << " s), at or above " << kCouplingAccurate
          << ", where " << HeldRate(p.integrator) << ", against " << kHeldBelow.off << " in "
          << kHeldBelow.runs << " below " << kCouplingAccurate
          << " (an end-force chatter can grow without a stop); use integrator=bdf2 (the "
          << "default) or implicit (no coupling limit, so no chatter to grow; below omega h "
          << kLeadFrom << " they hold the end force too, and "
          << Finds(kHeldBdf2, "bdf2 runs at omega h 0.1-0.5") << "), or <option timestep> <= "
          << advised << " s";
        set->warnings.push_back(w.str());
      } else if (c.consistent && p.integrator == Integrator::kExplicit &&
                 c.omega_h >= kCouplingAccurate) {
        // explicit's consistent coupling below half its limit (from kLeadFromExplicit = 0.5):
        // the scene fuzzer's runs at coupling omega h 0.5-1 that ran to the end are off their
        // 10x smaller step 13 times in 131 on seeds 201..15000 in session 33, 3 with no other
        // warning (failures: 5 in session 32, 4 of 129 in session 27, 7 of 127 before its Euler
        // path for end node B, Tether::Advance), against 6 in 948, 0, below 0.1.
        // Before that path held-out seed 14999 (7 substeps of the 2 ms
        // step, omega h 0.92, a 14 kg vehicle, Can 1) went from 10 N to 40 kN in 3 s and
        // exited 0 (docs/coupling.md, session 27).
        const int n = t.SubstepsFor(h);
        std::ostringstream w;
        w << where << head << "consistent coupling at coupling omega h = " << c.omega_h
          << " (omega = " << c.omega << " rad/s, <option timestep> " << h << " s, " << n
          << " tether substep(s)), at or above " << kCouplingAccurate
          << ", where " << Finds(kConsistentExplicit, "runs")
          << ", which the run-time coupling checks do not see; use "
          << "integrator=bdf2 (the default) or implicit (no coupling limit; below omega h "
          << kLeadFrom << " they hold the end force, and "
          << Finds(kHeldBdf2Upper, "bdf2 runs at omega h 0.5-1") << "), or <option timestep> <= "
          << advised << " s";
        set->warnings.push_back(w.str());
      }
    }
    if (!ok) break;
  }
  if (d) mj_deleteData(d);
  return ok;
}

}  // namespace

void InstallErrorHandlers() {
  mju_user_error = DefaultError;
  mju_user_warning = DefaultWarning;
}

bool Attach(mjModel* m, const std::string& source, std::string* error) {
  auto fail = [&](const std::string& element, const std::string& message) {
    if (error) *error = source + ": <text name=\"" + element + "\">: " + message;
    return false;
  };
  if (!mju_user_error) mju_user_error = DefaultError;
  {
    std::shared_lock<std::shared_mutex> lock(g_mutex);
    if (g_models.count(m)) return fail("", "this model is already attached");
  }
  // A text named like one of our declarations but not quite ("Tether:x", "tether_x", "Water")
  // would otherwise be ignored silently.
  for (int i = 0; i < m->ntext; ++i) {
    if (std::optional<std::string> near = NearMissDeclaration(TextName(m, i))) {
      return fail(TextName(m, i), *near);
    }
  }
  // The environment: gravity from <option>, water from <text name="water">.
  Environment env;
  env.gravity = (m->opt.disableflags & mjDSBL_GRAVITY) ? Vec3::Zero() : Vec3(m->opt.gravity);
  for (int i = 0; i < m->ntext; ++i) {
    if (std::strcmp(TextName(m, i), "water") != 0) continue;
    DeclarationError e;
    std::optional<Water> water = ParseWater(TextData(m, i), &e);
    if (!water) return fail("water", e.message);
    env.wet = true;
    env.water = *water;
    // current_profile=FILE.csv and seabed=GEOMNAME (plugin/environment_glue.cc).
    std::string message;
    if (!ResolveWater(m, source, &env.water, &message)) return fail("water", message);
  }

  // Winches (winch:NAME), keyed by the tether's name; each must name a tether.
  std::unordered_map<std::string, std::pair<std::string, WinchParams>> winches;
  for (int i = 0; i < m->ntext; ++i) {
    const std::string name = TextName(m, i);
    if (name.rfind("winch:", 0) != 0) continue;
    DeclarationError e;
    std::optional<WinchParams> w = ParseWinch(TextData(m, i), &e);
    if (!w) return fail(name, e.message);
    const std::string tether = name.substr(6);
    if (mj_name2id(m, mjOBJ_TEXT, ("tether:" + tether).c_str()) < 0) {
      return fail(name, "no <text name=\"tether:" + tether +
                            "\"> in the model: a winch names the tether it pays out");
    }
    if (mj_name2id(m, mjOBJ_ACTUATOR, w->actuator.c_str()) < 0) {
      return fail(name, "key 'actuator': no actuator named '" + w->actuator +
                            "' in the model (its ctrl commands the winch; declare one, e.g. "
                            "<general name=\"" + w->actuator + "\" joint=... gear=\"0\"/>)");
    }
    winches[tether] = {name, *w};
  }

  auto set = std::make_unique<ModelTethers>();
  set->source = source;
  set->env = env;
  std::string message_for_coupling;
  int offset = m->nuserdata;
  for (int i = 0; i < m->ntext; ++i) {
    const std::string name = TextName(m, i);
    if (name.rfind("tether:", 0) != 0) continue;
    DeclarationError e;
    std::optional<TetherDeclaration> decl = ParseTether(TextData(m, i), env, &e);
    if (!decl) return fail(name, e.message);
    if (name.size() == 7) return fail(name, "a tether needs a name after 'tether:'");
    std::string message;
    // A winch: the state is allocated for max_length (docs/winch.md).
    const auto winch = winches.find(name.substr(7));
    double initial_length = 0;
    if (winch != winches.end()) {
      const std::string& wname = winch->second.first;
      const WinchParams& w = winch->second.second;
      TetherParams& p = decl->params;
      const double L0 = p.length / p.segments;
      std::ostringstream s;
      if (w.end == 1 && decl->site_b.empty()) {
        return fail(wname, "key 'end' = B: end B of tether '" + name.substr(7) +
                               "' is free; the winch's end must be attached (end=A)");
      }
      if (p.effects & kContact) {
        // The contact candidate lists are sized at load for the tether's declared segments,
        // not for max_length, and an inserted node has no candidates yet (docs/winch.md).
        return fail(wname, "the tether's key 'contact' is not supported with a winch: "
                           "remove contact= from <text name=\"" + name +
                               "\"> or remove the winch");
      }
      if (!(p.length >= w.min_length && p.length <= w.max_length)) {
        s << "key 'min_length'/'max_length': the tether's length " << p.length
          << " m (the deployed length at the start) is outside [" << w.min_length << ", "
          << w.max_length << "] m";
        return fail(wname, s.str());
      }
      if (!(w.min_length >= L0)) {
        s << "key 'min_length' = " << w.min_length << " m is shorter than one segment, "
          << L0 << " m (length / segments of the tether); allowed: [" << L0 << ", "
          << w.max_length << "] m";
        return fail(wname, s.str());
      }
      const double nmax = std::floor(w.max_length / L0 + 0.5) + 2;
      if (!(nmax <= 1e5)) {
        s << "key 'max_length' = " << w.max_length << " m needs " << nmax
          << " segments of " << L0 << " m, more than 100000; allowed: [" << w.min_length
          << ", " << 1e5 * L0 << "] m, or longer segments";
        return fail(wname, s.str());
      }
      // At most one node inserted or removed per tether step (Tether::Advance).
      if (!(w.max_speed * m->opt.timestep <= 0.25 * L0)) {
        s << "key 'max_speed' = " << w.max_speed << " m/s pays out "
          << w.max_speed * m->opt.timestep << " m per <option timestep> " << m->opt.timestep << " s, more than a quarter segment ("
          << 0.25 * L0 << " m); allowed: (0, " << 0.25 * L0 / m->opt.timestep << "] m/s";
        return fail(wname, s.str());
      }
      initial_length = p.length;
      p.segments = static_cast<int>(nmax);
      p.length = p.segments * L0;
      p.winch = true;
      if (w.end == 1) {
        std::swap(decl->site_a, decl->site_b);
        std::swap(p.clamp_a, p.clamp_b);
      }
    }
    std::optional<Tether> tether = Tether::Create(decl->params, env, &message);
    if (!tether) return fail(name, message);
    if (!CheckParameters(decl->params, env.wet, &message)) return fail(name, message);
    std::string advice;
    if (!Advise(*tether, m->opt.timestep, &advice, &message)) return fail(name, message);
    if (!advice.empty()) {
      set->warnings.push_back(source + ": <text name=\"" + name + "\">: " + advice);
    }
    // Bending without compression: at zero tension the bending shear shortens slack segments
    // (README, Known limitations); EAc lets them keep their length.
    if ((tether->params().effects & kBending) && !(tether->params().effects & kCompression)) {
      set->warnings.push_back(source + ": <text name=\"" + name +
                              "\">: EI > 0 without EAc: slack segments can shorten under "
                              "bending; declare EAc (e.g. EAc = EA) for zero-tension loops");
    }
    AttachedTether at(name.substr(7), *tether);
    at.contact = (tether->params().effects & kContact) != 0;
    if (winch != winches.end()) {
      at.winch = true;
      at.winch_params = winch->second.second;
      at.swapped = at.winch_params.end == 1;
      at.actuator = mj_name2id(m, mjOBJ_ACTUATOR, at.winch_params.actuator.c_str());
      at.initial_length = initial_length;
    }
    const std::string sites[2] = {decl->site_a, decl->site_b};
    for (int end = 0; end < 2; ++end) {
      if (sites[end].empty()) continue;  // free end B
      at.site[end] = mj_name2id(m, mjOBJ_SITE, sites[end].c_str());
      if (at.site[end] < 0) {
        return fail(name, "key 'ends': no site named '" + sites[end] + "' in the model");
      }
      at.body[end] = m->site_bodyid[at.site[end]];
      at.mocap[end] = MovedByMocap(m, at.body[end]);
      // A body that moves under forces: one with degrees of freedom (weld-rooted bodies
      // without joints have none).
      at.coupled[end] = at.body[end] > 0 && !at.mocap[end] &&
                        m->body_dofnum[at.body[end]] + DofsAbove(m, at.body[end]) > 0;
      // A free body at a tether end in water gets buoyancy, drag and current only from a
      // vehicle: declaration; without one it is dry apart from the tether.
      const int carrier = FreeCarrier(m, at.body[end]);
      const char* carrier_name = carrier > 0 ? mj_id2name(m, mjOBJ_BODY, carrier) : nullptr;
      if (env.wet && carrier > 0 &&
          (!carrier_name ||
           mj_name2id(m, mjOBJ_TEXT, (std::string("vehicle:") + carrier_name).c_str()) < 0)) {
        const std::string body = carrier_name ? carrier_name : "body " + std::to_string(carrier);
        set->warnings.push_back(source + ": <text name=\"" + name + "\">: end " + "AB"[end] +
                                " is on free body '" + body +
                                "' in water, which has no <text name=\"vehicle:" + body +
                                "\">: it gets no buoyancy, drag, added mass or current; "
                                "declare the vehicle (README, Vehicles)");
      }
    }
    if (tether->params().start == Start::kStatic && (at.contact || at.winch)) {
      // The relaxation holds the ends and steps the tether alone: the contact candidates come
      // from MuJoCo's geoms at each step, and a winch changes the deployed length.
      return fail(name, std::string("key 'start' = static is not supported with ") +
                            (at.contact ? "key 'contact'" : "a winch") +
                            " yet (docs/static_start.md): use start=catenary (the default)");
    }
    if (at.contact) {
      std::vector<std::string> notes;
      if (!ResolveContactGeoms(m, decl->contact, at.site, *tether, &at.contacts, &notes,
                               &message)) {
        return fail(name, message);
      }
      for (const std::string& n : notes) {
        set->warnings.push_back(source + ": <text name=\"" + name + "\">: " + n);
      }
    }
    const long long block = kHeader + static_cast<long long>(tether->StateSize()) +
                            tether->HistorySize() +
                            (at.contact ? kContactRecord * at.contacts.capacity : 0) +
                            (at.winch ? kWinchSlots : 0);
    if (offset + block > 1'000'000'000LL) {
      return fail(name, "the tethers need more than 1e9 doubles of state: fewer segments");
    }
    at.offset = offset;
    at.winch_offset = offset + static_cast<int>(block) - (at.winch ? kWinchSlots : 0);
    offset += static_cast<int>(block);
    set->work_size =
        std::max(set->work_size, tether->WorkspaceSize() + ContactWorkSize(at));
    set->tethers.push_back(std::move(at));
  }
  // Start-up checks on the geometry at qpos0 (a scratch mjData, kinematics only).
  if (!set->tethers.empty() || env.water.has_seabed) {
    mjData* scratch = mj_makeData(m);
    if (!scratch) return fail("", "cannot allocate mjData for the start-up checks");
    mj_kinematics(m, scratch);
    mj_comPos(m, scratch);  // subtree centres of mass (SiteLeverWarning)
    std::string message, element;
    bool ok = true;
    for (AttachedTether& at : set->tethers) {
      std::string warning;
      if (!CheckStart(m, scratch, env, at, &warning, &message)) {
        element = "tether:" + at.name;
        ok = false;
        break;
      }
      if (!warning.empty()) {
        set->warnings.push_back(source + ": <text name=\"tether:" + at.name + "\">: " + warning);
      }
      if (at.tether.params().start == Start::kStatic &&
          !StaticStartAtLoad(m, scratch, &at, &warning, &message)) {
        element = "tether:" + at.name;
        ok = false;
        break;
      }
      if (!warning.empty() && at.tether.params().start == Start::kStatic) {
        set->warnings.push_back(source + ": <text name=\"tether:" + at.name + "\">: " + warning);
      }
      if (std::string inside = ContactStartWarning(m, scratch, env, at); !inside.empty()) {
        set->warnings.push_back(source + ": <text name=\"tether:" + at.name + "\">: " + inside);
      }
      if (std::string lever = SiteLeverWarning(m, scratch, at); !lever.empty()) {
        set->warnings.push_back(source + ": <text name=\"tether:" + at.name + "\">: " + lever);
      }
    }
    if (ok) ok = CheckVehicles(m, scratch, env, &element, &message);
    mj_deleteData(scratch);
    if (!ok) return fail(element, message);
  }
  // Vehicles, motions and thrust schedules (plugin/vehicles.cc) use the same callback.
  bool vehicles = false;
  if (!AttachVehicles(m, source, env, &offset, &vehicles, error)) return false;
  if (set->tethers.empty() && !vehicles) return true;
  // The coupling advisor, with the vehicles' added mass already in the armature.
  if (!AdviseCoupling(m, set.get(), &message_for_coupling)) {
    if (error) *error = message_for_coupling;
    return false;
  }
  set->nv = m->nv;
  set->timestep = m->opt.timestep;
  m->nuserdata = offset;
  m->nstack += set->work_size + 6 * std::max(m->nv, 1) + 64;
  set->nuserdata = m->nuserdata;
  // After the state's size is final: the vehicles' lookup checks it (ScheduledThrust).
  WarnThrustBeyondHolds(m, set.get());
  {
    std::unique_lock<std::shared_mutex> lock(g_mutex);
    g_models[m] = std::move(set);
    if (!g_installed) {
      g_previous_passive = mjcb_passive;
      mjcb_passive = Passive;
      g_installed = true;
    }
  }
  return true;
}

void Detach(const mjModel* m) {
  DetachVehicles(m);
  std::unique_lock<std::shared_mutex> lock(g_mutex);
  g_models.erase(m);
}

mjModel* LoadModel(const std::string& path, std::string* error) {
  if (!mju_user_error) mju_user_error = DefaultError;
  char buffer[1000] = "";
  mjModel* m = mj_loadXML(path.c_str(), nullptr, buffer, sizeof(buffer));
  if (!m) {
    if (error) *error = path + ": " + buffer;
    return nullptr;
  }
  if (!Attach(m, path, error)) {
    if (error) *error = NameIncludedFile(path, *error);  // the element may be in an <include>
    mj_deleteModel(m);
    return nullptr;
  }
  return m;
}

mjModel* LoadModelFromString(const std::string& xml, const std::string& name,
                             std::string* error) {
  if (!mju_user_error) mju_user_error = DefaultError;
  auto vfs = std::make_unique<mjVFS>();  // about 2 MB: not on the stack
  mj_defaultVFS(vfs.get());
  if (mj_makeEmptyFileVFS(vfs.get(), name.c_str(), static_cast<int>(xml.size())) != 0) {
    if (error) *error = name + ": cannot create an in-memory file";
    return nullptr;
  }
  const int f = mj_findFileVFS(vfs.get(), name.c_str());
  std::memcpy(vfs->filedata[f], xml.data(), xml.size());
  char buffer[1000] = "";
  mjModel* m = mj_loadXML(name.c_str(), vfs.get(), buffer, sizeof(buffer));
  mj_deleteVFS(vfs.get());
  if (!m) {
    if (error) *error = name + ": " + buffer;
    return nullptr;
  }
  if (!Attach(m, name, error)) {
    mj_deleteModel(m);
    return nullptr;
  }
  return m;
}

int TetherCount(const mjModel* m) {
  const ModelTethers* set = Lookup(m);
  return set ? static_cast<int>(set->tethers.size()) : 0;
}

std::vector<std::string> Warnings(const mjModel* m) {
  const ModelTethers* set = Lookup(m);
  return set ? set->warnings : std::vector<std::string>();
}

int FindTether(const mjModel* m, const std::string& name) {
  const ModelTethers* set = Lookup(m);
  if (!set) return -1;
  for (size_t k = 0; k < set->tethers.size(); ++k) {
    if (set->tethers[k].name == name) return static_cast<int>(k);
  }
  return -1;
}

std::string TetherName(const mjModel* m, int k) {
  const ModelTethers* set = Lookup(m);
  return set && k >= 0 && k < static_cast<int>(set->tethers.size()) ? set->tethers[k].name : "";
}

const Tether* GetTether(const mjModel* m, int k) {
  const ModelTethers* set = Lookup(m);
  if (!set || k < 0 || k >= static_cast<int>(set->tethers.size())) return nullptr;
  return &set->tethers[k].tether;
}

CouplingLimit GetCouplingLimit(const mjModel* m, int k, int end) {
  const ModelTethers* set = Lookup(m);
  if (!set || k < 0 || k >= static_cast<int>(set->tethers.size()) || end < 0 || end > 1) {
    return {};
  }
  return set->tethers[k].limit[end];
}

BounceMode GetBounceMode(const mjModel* m, int k, int end) {
  const ModelTethers* set = Lookup(m);
  if (!set || k < 0 || k >= static_cast<int>(set->tethers.size()) || end < 0 || end > 1) {
    return {};
  }
  return set->tethers[k].bounce[end];
}

StaticResult GetStaticStart(const mjModel* m, int k) {
  const ModelTethers* set = Lookup(m);
  if (!set || k < 0 || k >= static_cast<int>(set->tethers.size())) return {};
  return set->tethers[k].static_result;
}

double EstimatedCostPerSecond(const Tether& t, double timestep) {
  return CostPerSecond(t, timestep);
}

int EndBody(const mjModel* m, int k, int end) {
  const ModelTethers* set = Lookup(m);
  if (!set || k < 0 || k >= static_cast<int>(set->tethers.size()) || end < 0 || end > 1) {
    return -1;
  }
  return set->tethers[k].site[end] < 0 ? -1 : set->tethers[k].body[end];
}

const double* NodePositions(const mjModel* m, const mjData* d, int k) {
  const double* u = UserBlock(m, d, k);
  return u && u[kInitialized] != 0 ? u + kHeader : nullptr;
}

const double* NodeVelocities(const mjModel* m, const mjData* d, int k) {
  const double* x = NodePositions(m, d, k);
  return x ? x + 3 * GetTether(m, k)->nodes() : nullptr;
}

double TetherTime(const mjModel* m, const mjData* d, int k) {
  const double* u = UserBlock(m, d, k);
  if (u && Lookup(m)->tethers[k].lead) return u[kCoupleB + kLeadTime];  // one step ahead
  return u ? u[kTime] : 0;
}

EndReactions GetReactions(const mjModel* m, const mjData* d, int k) {
  EndReactions r;
  const double* u = UserBlock(m, d, k);
  if (!u || u[kInitialized] == 0) return r;
  const double* c = u + kForceA;
  r.force_a = Vec3(c);
  r.torque_a = Vec3(c + 3);
  r.force_b = Vec3(c + 6);
  r.torque_b = Vec3(c + 9);
  r.tension_a = u[kTensionA];
  r.tension_b = u[kTensionB];
  if (Lookup(m)->tethers[k].lead) r.correction_b = Vec3(u + kCoupleA + kSlowCorrection);
  return r;
}

void GetTensions(const mjModel* m, const mjData* d, int k, double* T) {
  const Tether* tether = GetTether(m, k);
  const double* x = NodePositions(m, d, k);
  if (!tether) return;
  if (!x) {
    std::fill(T, T + tether->segments(), 0.0);
    return;
  }
  const ModelTethers* set = Lookup(m);
  const AttachedTether& at = set->tethers[k];
  if (at.winch) {
    // Segments on the drum read 0; the deployed ones from the Deployed view.
    const Payout p = LoadPayout(at, d->userdata + at.offset);
    std::fill(T, T + p.first, 0.0);
    const Tether view = tether->Deployed(p.first, p.rest, p.speed);
    view.Tensions(x + 3 * p.first, x + 3 * tether->nodes() + 3 * p.first, T + p.first);
    return;
  }
  tether->Tensions(x, x + 3 * tether->nodes(), T);
}

WinchState GetWinch(const mjModel* m, const mjData* d, int k) {
  WinchState w;
  const ModelTethers* set = Lookup(m);
  if (!set || k < 0 || k >= static_cast<int>(set->tethers.size())) return w;
  const AttachedTether& at = set->tethers[k];
  const double* u = d->userdata + at.offset;
  w.length = DeployedLength(at, u);
  w.segments = at.tether.segments();
  if (!at.winch) return w;
  w.present = true;
  if (u[kInitialized] == 0) {
    w.length = at.initial_length;
    w.segments = static_cast<int>(std::lround(at.initial_length / at.tether.rest_segment_length()));
    w.first_node = at.tether.segments() - w.segments;
    return w;
  }
  const Payout p = LoadPayout(at, u);
  w.payout_speed = p.speed;
  w.first_node = p.first;
  w.segments = at.tether.segments() - p.first;
  return w;
}

Vec3 ContactImpulse(const mjModel* m, const mjData* d, int k) {
  const double* u = UserBlock(m, d, k);
  if (!u || !GetTether(m, k) || !(GetTether(m, k)->params().effects & kContact)) {
    return Vec3::Zero();
  }
  return Vec3(u + kContactImpulse);
}

int ContactDropped(const mjModel* m, const mjData* d, int k) {
  const double* u = UserBlock(m, d, k);
  if (!u || !GetTether(m, k) || !(GetTether(m, k)->params().effects & kContact)) return 0;
  return static_cast<int>(u[kContactDropped]);
}

namespace {
// What to change where implicit steps stall: the end-of-run warning's and the stop's advice.
std::string StallAdvice(const mjModel* m, const Tether& t) {
  std::ostringstream s;
  s << "Reduce <option timestep> (now " << m->opt.timestep
    << " s) or set max_step, use fewer segments (now " << t.segments() << "), or use integrator="
    << (t.params().integrator == Integrator::kImplicit2 ? "implicit" : "implicit2")
    << " or explicit (automatic substeps)";
  return s.str();
}
}  // namespace

std::vector<std::string> StallWarnings(const mjModel* m, const mjData* d, bool early) {
  std::vector<std::string> out;
  const ModelTethers* set = Lookup(m);
  if (!set) return out;
  for (const AttachedTether& at : set->tethers) {
    const double* u = d->userdata + at.offset;
    // A tether stopped by its stalls (kStallStop) is not listed: CheckDivergence's message
    // says it, with the same count and advice (session 14's note: said twice).
    if (u[kStalled] <= 0 || u[kStatus] == kStallStop) continue;
    const Tether& t = at.tether;
    std::ostringstream s;
    if (early) {
      s << set->source << ": tether '" << at.name << "': its " << IntegratorName(t.params().integrator)
        << " steps began to stall at t = " << u[kStalledTime]
        << " s (a stalled step is retried down to 1/256 of the step, so the run slows down); it "
           "goes on, and says at its end how many stalled and what to change";
      out.push_back(s.str());
      continue;
    }
    s << set->source << ": tether '" << at.name << "': " << static_cast<long long>(u[kStalled])
      << " " << IntegratorName(t.params().integrator)
      << " step(s) were accepted with the Newton iteration not converged (it stalled even at "
         "1/256 of the step), the first in the step to t = "
      << u[kStalledTime] << " s; the tether's motion near then may be wrong. "
      << StallAdvice(m, t);
    out.push_back(s.str());
  }
  return out;
}

std::vector<std::string> StepWarnings(const mjModel* m) {
  std::vector<std::string> out;
  const ModelTethers* set = Lookup(m);
  if (!set || m->opt.timestep == set->timestep) return out;
  std::ostringstream s;
  s << set->source << ": <option timestep> is " << m->opt.timestep << " s, not the "
    << set->timestep << " s the tethers were attached with: the coupling at each end on a body "
    << "that moves was chosen, and the advisor's limits, refusals and warnings were computed, "
    << "for " << set->timestep << " s";
  for (const AttachedTether& at : set->tethers) {
    for (int end = 0; end < 2; ++end) {
      const CouplingLimit& c = at.limit[end];
      if (at.site[end] < 0 || !at.coupled[end] || !(c.omega > 0)) continue;
      s << "; tether '" << at.name << "' end " << "AB"[end] << ": "
        << (c.consistent ? "consistent coupling" : "held end force") << " at coupling omega h "
        << c.omega * set->timestep << ", now " << c.omega * m->opt.timestep;
    }
  }
  s << ". Load the model at the step it runs at (<option timestep> in the MJCF, or LoadModel "
       "with the override option.timestep; the command line's --set option.timestep does so): "
       "a changed step is checked only by the run-time stops (chatter, divergence), and the "
       "results may differ from the same scene loaded at that step (docs/coupling.md)";
  out.push_back(s.str());
  return out;
}

namespace {
// RingWarnings' words for body `end`'s bounce on the taut line (BounceMode): what it is, with
// its figures at the step of Attach, and what the integrator's step does to it.
std::string BounceWords(const mjModel* m, const ModelTethers& set, const AttachedTether& at,
                        int end) {
  const BounceMode& b = at.bounce[end];
  const CouplingLimit& c = at.limit[end];
  const char* body = mj_id2name(m, mjOBJ_BODY, c.body);
  std::ostringstream s;
  s << "body '" << (body ? body : "?") << "' at end " << "AB"[end]
    << " bouncing on the whole line (the line a spring EA/L on the body's effective mass "
    << c.m_eff << " kg and a third of the line's, " << b.mass << " kg: omega = " << b.omega
    << " rad/s, omega h = " << b.omega_h << " at <option timestep> " << set.timestep
    << " s, damping ratio " << b.ratio << ")";
  return s.str();
}

// ... and the cure both messages end with.
std::string BounceCureWords(const BounceMode& b) {
  std::ostringstream s;
  s << "compare with a smaller <option timestep> (the bounce's period is " << 2 * M_PI / b.omega
    << " s; docs/reference.md, \"Internal damping\")";
  return s.str();
}

const char* BounceStepWords(const Tether& t, const BounceMode& b) {
  return IsExplicit(t.params().integrator) ? "keeps that bounce with an energy error"
         : b.omega_h > 1                   ? "does not resolve that bounce and damps it"
                                           : "damps that bounce numerically";
}
}  // namespace

std::vector<std::string> RingWarnings(const mjModel* m, const mjData* d) {
  std::vector<std::string> out;
  const ModelTethers* set = Lookup(m);
  if (!set) return out;
  for (const AttachedTether& at : set->tethers) {
    const double* u = d->userdata + at.offset;
    const Tether& t = at.tether;
    // The end that has alternated longest up to now, over kAlternationBlocks or more.
    const int e = u[kAlternationRun + 1] >= u[kAlternationRun] ? 1 : 0;
    if (u[kAlternationRun + e] >= kAlternationBlocks) {
      // The alternation watch (WatchAlternation): independent of the snaps and swings below.
      std::ostringstream c;
      c << set->source << ": tether '" << at.name << "': the tension at end " << "AB"[e]
        << " has alternated from step to step since t = " << u[kAlternationSince + e]
        << " s to t = " << d->time << " s (" << u[kAlternationRun + e] << " blocks of "
        << kAlternationBlock << " steps in a row whose second difference averaged at least "
        << kAlternationRatio << ", up to " << u[kAlternationPeak + e]
        << ", times their mean tension; " << u[kAlternationMean + e]
        << " N in the last): an oscillation at the step's own period that no step resolves, so "
           "the tensions there are the scheme's, not the line's";
      if (t.StepsAsBackwardEuler()) {
        c << " (this line's segment mode is overdamped, damping ratio " << t.SegmentModeRatio()
          << ", and steps as backward Euler: its stiff damping makes the tension follow the "
             "nodes' velocities closely)";
      }
      c << "; such chatter comes and goes with the step (a bdf2 line stepping as backward "
           "Euler read 5.0 N at 1 ms, 4.0 N at 2, 0.5 and 0.02 ms): compare with a smaller "
           "<option timestep> (this run's is "
        << set->timestep << " s)";
      out.push_back(c.str());
    }
    std::ostringstream s;
    if (!(u[kSnapJump] > 0) && at.swing_end >= 0 && u[kSwingBest] >= kSwingRatio) {
      // The swing watch (WatchSwing): a bounce that did not snap, or whose snaps were not watched.
      s << set->source << ": tether '" << at.name << "': the tension at end "
        << "AB"[at.swing_end] << " swung by " << u[kSwingBest]
        << " times its mean within two bounce periods from t = " << u[kSwingTime] << " s, "
        << BounceWords(m, *set, at, at.swing_end) << ": the step "
        << BounceStepWords(t, at.bounce[at.swing_end])
        << ", and a swing that large moves the mean tension (quadratic drag, the line's "
           "geometry, slack), so the tensions may depend on the step (a 12 kg vehicle on one "
           "taut segment, bounce omega h 0.16: 3.5 N at 2 ms, 21.7 N at 0.2 ms, 32.7 N at "
           "0.02 ms; of the scene fuzzer's runs so warned with lines started as long as their "
           "span, 3 in 130 were off their 10x smaller step): "
        << BounceCureWords(at.bounce[at.swing_end]);
      out.push_back(s.str());
      continue;
    }
    if (!(u[kSnapJump] > 0)) continue;
    if (!WatchesRinging(t, set->timestep) && at.bounce_end >= 0) {
      // The bounce watch (BounceMode): the segment mode is damped, the body's bounce is not.
      s << set->source << ": tether '" << at.name << "': a slack segment snapped taut at t = "
        << u[kSnapTime] << " s (largest axial wave tension jump " << u[kSnapJump] << " N), and "
        << BounceWords(m, *set, at, at.bounce_end);
      if (t.SegmentModeRatio() >= kRingDampingRatio) {
        s << " is damped far less than the segment mode (damping ratio "
          << t.SegmentModeRatio() << ")";
      } else {  // the segment mode not watched: resolved by the step (kRingOmegaH)
        s << " rings, where the segment mode is resolved by the step";
      }
      s << ": the step "
        << BounceStepWords(t, at.bounce[at.bounce_end])
        << ", so the tensions after the snap depend on the step (a 166 kg vehicle on a 2.2 m "
           "line in a 3 m/s current, bounce omega h 0.86: 1490 N at 2 ms, 1811 N at 0.2 ms, "
           "1892 N at 0.02 ms). More line damping does not reach the bounce; "
        << BounceCureWords(at.bounce[at.bounce_end]);
      out.push_back(s.str());
      continue;
    }
    const double h = m->opt.timestep / std::max(1, t.SubstepsFor(m->opt.timestep));
    const double wh = t.SegmentModeFrequency() * h;
    s << set->source << ": tether '" << at.name << "': a slack segment snapped taut at t = "
      << u[kSnapTime] << " s (largest axial wave tension jump " << u[kSnapJump]
      << " N), and its segment axial mode (omega_n = " << t.SegmentModeFrequency()
      << " rad/s, omega_n h = " << wh << " with the " << IntegratorName(t.params().integrator)
      << " step " << h << " s) has damping ratio " << t.SegmentModeRatio() << ": the step "
      << (IsExplicit(t.params().integrator)
              ? "keeps the ringing after a snap undamped, with an energy that depends on the step"
          : wh > 1 ? "does not resolve the ringing after a snap and damps it"
                   : "damps the ringing after a snap numerically")
      << ", and where the line goes slack again the ringing, clipped at zero tension, moves the "
         "mean tension, so the tensions after the snap depend on the step and on the segment "
         "count. Declare damping_ratio=1 (MoorDyn's BA=-1) to damp that mode physically "
         "(docs/reference.md, \"Internal damping\"). Where most of the line went slack and "
         "snapped taut (a line started near taut), its slower modes take the snap too, and "
         "damped or not the tensions after it depend on the step (a 14 m line started as long "
         "as its span, damping_ratio=1: 10.7 N at 2 ms, 13.4 N at 1 ms, 23.2 N at 0.5 ms and "
         "0.2 ms): compare with a smaller <option timestep>";
    out.push_back(s.str());
  }
  return out;
}

std::optional<std::string> CheckDivergence(const mjModel* m, const mjData* d) {
  const ModelTethers* set = Lookup(m);
  if (!set) return VehicleStopped(m, d);  // vehicles without a tether
  for (const AttachedTether& at : set->tethers) {
    const double* u = d->userdata + at.offset;
    if (u[kStatus] == 0) continue;
    const Tether& t = at.tether;
    std::ostringstream s;
    if (u[kStatus] == kChatter) {
      const int end = u[kBadNode] == 0 ? 0 : 1;
      const CouplingLimit& c = at.limit[end];
      const double* cp = u + (end == 0 ? kCoupleA : kCoupleB);
      const char* body = mj_id2name(m, mjOBJ_BODY, at.body[end]);
      s << set->source << ": tether '" << at.name << "': coupling chatter at end "
        << (end == 0 ? "A" : "B") << " on body '" << (body ? body : "?")
        << "' at t = " << u[kBadTime] << " s: the end gave the body " << cp[kSpurious]
        << " J more than the tether lost there (the work balance does not explain it; "
        << "largest energy at the end " << cp[kEnergyScale] << " J, " << cp[kCoupleSteps]
        << " steps). The end segment's "
        << "stiffness " << EndStiffnessName(c) << " = " << c.k_end
        << " N/m on the body's effective mass " << c.m_eff
        << " kg gives omega h = " << c.omega * m->opt.timestep << " at <option timestep> "
        << m->opt.timestep << " s. ";
      // (Checked for explicit and rk4 tethers only, which are refused at load at omega h >=
      // c.limit: a chatter is below that stability limit.) The step advised is the one that
      // brings omega h to kCouplingAccurate (0.1; 0.25 until session 19, the very step at
      // which seed 3244 rang), below which the scene fuzzer finds the held end force about as
      // accurate as the other integrators (docs/coupling.md, session 19), and never more than
      // half the step that chattered.
      // (omega h is that of the step now: c.omega_h is the one checked at load, and a caller
      // may have changed <option timestep> since.)
      const double advised = std::min(kCouplingAccurate / c.omega, 0.5 * m->opt.timestep);
      if (c.omega * m->opt.timestep >= c.limit) {
        s << "That is above the integrator's stability limit omega h = " << c.limit
          << " (checked at load with <option timestep> " << c.omega_h / c.omega << " s). ";
      } else {
        s << "The held end force chatters here below the integrator's stability limit omega h = "
          << c.limit << ". ";
      }
      s << "Use integrator=bdf2 (the default) or implicit (no coupling limit, stable at every "
        << "omega h measured; the end node is solved with the body from omega h " << kLeadFrom
        << "), or <option timestep> <= " << StepAtMost(advised) << " s.";
      return s.str();
    }
    if (u[kStatus] == kSeabedEnd) {
      const int end = u[kBadNode] == 0 ? 0 : 1;
      const CouplingLimit& c = at.limit[end];
      const char* body = mj_id2name(m, mjOBJ_BODY, at.body[end]);
      const double h = m->opt.timestep, scale = h / (c.omega_h / c.omega);  // [-]
      s << set->source << ": tether '" << at.name << "' stopped at t = " << u[kBadTime]
        << " s: its end node " << (end == 0 ? "A" : "B") << " touched the seabed, and body '"
        << (body ? body : "?") << "' gets the node's seabed contact as the held end force: "
        << "seabed_stiffness x the node's share = " << t.EndSeabedStiffness(end == 1)
        << " N/m and its damping " << t.EndSeabedDamping(end == 1)
        << " N s/m on the body's effective mass " << c.m_eff << " kg give omega h = "
        << c.seabed_omega_h * scale << " and h c/m_eff = " << c.seabed_damping_h * scale
        << " at <option timestep> " << h << " s, at or above " << kLeadFromSeabed
        << ", where the body bounces off the seabed and its end force depends on the step "
           "(docs/coupling.md, session 38). Use "
        << SeabedCure(at, end, h)
        << ", or a smaller 'seabed_stiffness' or 'seabed_damping' in <text name=\"water\">.";
      return s.str();
    }
    if (u[kStatus] == kEndDamping) {
      const int end = u[kBadNode] == 0 ? 0 : 1;
      const double rate = u[(end == 0 ? kCoupleA : kCoupleB) + kDampingRate];
      std::vector<double> work(set->work_size), jac(6 * std::max(m->nv, 1));
      double lambda_D = 0, speed = 0;
      // The state is as it was stopped (the tether stays inert): the figures again, for the text.
      EndDampingRate(m, const_cast<mjData*>(d), at, end, work.data(), jac.data(), &lambda_D,
                     &speed);
      const char* body = mj_id2name(m, mjOBJ_BODY, at.body[end]);
      const double limit = ExplicitDampingLimit(m);
      s << set->source << ": tether '" << at.name << "' stopped at t = " << u[kBadTime]
        << " s: its end " << (end == 0 ? "A" : "B") << " damping too stiff for the step of body '"
        << (body ? body : "?") << "': moving at " << speed
        << " m/s through the water, the end node's own velocity-dependent force (its drag, "
           "seabed damping and friction) changes by "
        << lambda_D << " N per m/s, which the body, through MuJoCo's explicit step, feels as h "
        << "lambda = " << rate << " > " << limit
        << " (the body's velocity would reverse every step, and grow where a force such as a "
           "thrust holds it at that speed, until MuJoCo reports a huge QACC and resets). ";
      if (at.limit[end].omega_h >= 1) {
        s << "The end segment's stiffness also couples strongly: omega h = "
          << at.limit[end].omega_h << " >= 1 at this body (docs/coupling.md). ";
      }
      const std::string cause = Diagnose(m, d, set->env, at, u);
      if (!cause.empty()) {
        s << "It was driven there by: " << cause << ". ";
      } else if (const double thrust = ThrustOn(m, d, at.body[end]); thrust > 0) {
        s << "The actuators push body '" << (body ? body : "?") << "' with " << thrust << " N. ";
      }
      // A thrust schedule beyond what the tether holds drives the body ever faster: a smaller
      // step only delays the stop (Diagnose says so), so the step is not offered as the cure.
      // The cause names its cure and says so already; the message ends with it (until session
      // 19 it went on to repeat both, scene fuzzer seed 227).
      if (cause.rfind("thrust beyond what the tether holds", 0) == 0) {
        std::string text = s.str();
        text.pop_back();  // the space after the cause's full stop
        return text;
      }
      s << "Reduce <option timestep> below " << StepAtMost(m->opt.timestep * limit / rate)
        << " s, or reduce what drives the body that fast (thrust, motion), or make the body "
           "heavier.";
      return s.str();
    }
    if (u[kStatus] == kStallStop) {
      // The first of the stalled steps (a difference of multiples of h: 0.098 - 49 x 0.002
      // reads 7e-17, printed as 0).
      double since = u[kBadTime] - (kStallSteps - 1) * m->opt.timestep;
      if (std::abs(since) < 1e-9 * m->opt.timestep) since = 0;
      s << set->source << ": tether '" << at.name << "' stopped at t = " << u[kBadTime]
        << " s: its " << IntegratorName(t.params().integrator) << " steps did not converge in "
        << static_cast<int>(kStallSteps) << " MuJoCo steps in a row (since t = "
        << since
        << " s), even at 1/256 of the step, so the tether's state is no longer a solution of "
           "its steps (" << static_cast<long long>(u[kStalled]) << " stalled steps since t = "
        << u[kStalledTime] << " s). ";
      // (No Diagnose: a stall is the Newton iteration's, and a cause it would name, such as a
      // thrust schedule not yet ramping, need not have acted: fuzzer seed 5355 stalled from
      // t = 0.002 s, its thrust starting at 0.1 s.)
      s << StallAdvice(m, t) << ".";
      return s.str();
    }
    s << set->source << ": tether '" << at.name << "' diverged at t = " << u[kBadTime]
      << " s at node " << static_cast<int>(u[kBadNode]) << " of " << t.nodes() << " ("
      << (u[kStatus] == 2   ? "strain beyond max_strain"
          : u[kStatus] == 3 ? "kinetic energy blow-up"
                            : "non-finite position or velocity")
      << "). ";
    const std::string cause = Diagnose(m, d, set->env, at, u);
    if (!cause.empty()) {
      s << "Most likely cause: " << cause << ".";
    } else if (IsExplicit(t.params().integrator)) {
      s << "The " << IntegratorName(t.params().integrator) << " integrator's stable step is "
        << t.ExplicitStableStep() << " s";
      const int n = t.SubstepsFor(m->opt.timestep);
      if (n > 1 && t.params().substeps == 0 && !(t.params().max_step > 0)) {
        // Automatic substeps already at the estimate: a smaller MuJoCo step takes substeps of
        // the same length, so it is no cure. The estimate (Gershgorin's, at the straight
        // shape) can be high where the line bends sharply: fuzzer seed 12472, rk4 with EI
        // on a seabed touchdown of 90 degrees, runs from 0.62x of it (docs/scene_fuzzer.md).
        const double sub = m->opt.timestep / n;  // [s]
        // DragSubsteps may have raised the count for a fast drag: "at least".
        s << " (estimated at the straight line), and it took at least " << n << " substeps of "
          << sub
          << " s per MuJoCo step (a smaller <option timestep> shortens them only once it is "
             "below that); use integrator=implicit, or fewer segments (now "
          << t.segments() << "), or max_step=" << StepAtMost(0.5 * sub)
          << " (half the substep: the estimate can be high where the line bends sharply, "
             "as at a seabed touchdown).";
      } else {
        s << "; use integrator=implicit, or fewer segments (now " << t.segments()
          << "), or a smaller <option timestep> (now " << m->opt.timestep << " s).";
      }
    } else {
      s << "Reduce <option timestep> (now " << m->opt.timestep
        << " s) or set max_step for tether substeps, or use fewer segments (now "
        << t.segments() << ")";
      // implicit2 keeps what backward Euler and BDF2 damp: scene fuzzer seed 9828 with its
      // bending doubled (EI/(EA L0^2) = 4.4; as drawn, 2.1, it stopped until session 40)
      // stops with it at 1, 0.5 and 0.2 ms and runs with both of them at every step.
      if (t.params().integrator == Integrator::kImplicit2) {
        s << ", or use integrator=bdf2 (the default) or implicit, whose steps damp what "
             "implicit2's keep";
      }
      s << ".";
    }
    return s.str();
  }
  int body = -1;
  if (std::optional<std::string> stopped = VehicleStopped(m, d, &body)) {
    // What else drives it: the tethers' ends on that body, their last reactions.
    std::ostringstream s;
    s << (set->source.empty() ? "" : set->source + ": ") << *stopped;
    for (const AttachedTether& at : set->tethers) {
      const double* u = d->userdata + at.offset;
      for (int end = 0; end < 2; ++end) {
        if (at.body[end] != body) continue;
        const TetherParams& p = at.tether.params();
        s << " Tether '" << at.name << "' pulled it at end " << (end == 0 ? "A" : "B")
          << " with " << u[end == 0 ? kTensionA : kTensionB]
          << " N (EA x max_strain = " << p.EA * p.max_strain << " N)";
        if (at.limit[end].omega_h >= 1) {
          s << "; its end segment couples strongly to the body: omega h = "
            << at.limit[end].omega_h << " (docs/coupling.md)";
        }
        s << ".";
      }
    }
    return s.str();
  }
  return std::nullopt;
}

}  // namespace mjtether
