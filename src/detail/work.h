// Internal to the engine (not installed): the tuning constants and the scratch layout that the
// force terms (forces.cc) and the integrators (integrators.cc) share.
#pragma once

#include "block_band.h"
#include "tether.h"

namespace mjtether {
namespace detail {

constexpr double kPi = 3.14159265358979323846;
// A segment shorter than this fraction of its rest length has no direction: it carries no
// tension, no bending shear and no tangent (coincident nodes must not produce NaN).
constexpr double kMinLengthRatio = 1e-9;
// Fraction of the stability limit actually used. RK4: 0.8 (the estimate ignores drag and the
// geometric stiffness T/l, both small against EA/L0 in practice). Symplectic Euler: 0.5, for
// slack tethers. On each law (taut, slack) it conserves a modified energy that differs from
// the true one by up to h w/2 of it; a segment that goes slack or taut switches law at an
// arbitrary phase of its highest modes, so each switch may change the true energy by up to that
// fraction, and a slack chain, which switches all the time, gained energy near the limit: at
// 0.8 (h w 1.5) the scene fuzzer's seed 1279 gained 2.8 J in 1 s beyond the 1.1 J its ends did
// on it (tests/engine_test.cc, Energy.ExplicitSlackSwitching...), at 0.7 0.12 J, at 0.6 and
// 0.5 nothing. On the fuzzer's explicit scenes 0.5 cut the failures from 59 to 38 of 997
// (docs/scene_fuzzer.md, session 13). RK4 damps its highest modes near its limit and gained
// nothing on the same scene at 0.8.
constexpr double kExplicitSafety = 0.5;
constexpr double kRk4Safety = 0.8;
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
// Where that backtracking fails, the line search takes a point along the Newton direction
// where the derivative of the step's incremental potential has fallen to this fraction of its
// value at the start (the strong Wolfe curvature condition; see ImplicitStep), with at most
// kMaxLineSearch more residual evaluations.
constexpr double kCurvature = 0.5;
constexpr int kMaxLineSearch = 8;
// bdf2 restarts with a backward-Euler step when the step grows by more than this ratio over
// the last (variable-step BDF2 is zero-stable below 1 + sqrt(2); docs/numerics.md).
constexpr double kBdf2MaxRatio = 2;
// Kinetic energy above this multiple of EnergyBound() is a blow-up (the bound is already
// generous; the factor keeps a violent but physical transient, e.g. a whipping free end,
// clear of it).
constexpr double kEnergyBlowUp = 10;

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
  double* taut;  // N       implicit: 1 where the last full Newton step left the segment taut
  double* vn;    // n       |v_n| of each node's relative normal velocity at the last AddDrag [m/s]
                 //         (the implicit drag Jacobian reads it: no second square root)
  static int Size(int N) {
    const int n = N + 1;
    return 3 * n + 3 * N + N + N + 3 * n + 3 * n + 3 * n + 3 * n + 3 * n + BlockBand::Size(n) +
           18 * n + N + n;
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
    taut = vb + 3 * n;
    vn = taut + N;
  }
};

}  // namespace detail
// The ends at fraction s of a step of dt [s] between `from` and `to` (cubic Hermite; the
// winch segment's rest length linearly).
Ends Interpolate(const Ends& from, const Ends& to, double dt, double s);
namespace detail {

// The window's inputs (x, v 3 x 3 each), outputs (f 3 x 3, T 2) and its own scratch follow
// the tether's scratch.
constexpr int kWindowIo = 9 + 9 + 9 + 2;

}  // namespace detail
}  // namespace mjtether
