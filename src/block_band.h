// Block LDL^T factorisation and solve of a symmetric positive definite block-band matrix of
// 3x3 blocks, in place, in caller-owned storage (no allocation): the implicit integrator's
// M - h D - h^2 K, whose block row i couples node i with nodes i-1 and i-2 (bending) or with
// node i-1 only (no bending). Fixed-size 3x3 arithmetic keeps the inner work free of index
// computations and branches, which is what made the scalar band version (band_cholesky.h)
// slow at half-bandwidth 8.
//
// A = L S L^T with unit block-lower L and block-diagonal S (Golub & Van Loan, Matrix
// Computations, 4th ed., 4.1-4.3, blocked). Row by row, with Ak = the row's blocks:
//   B2 = A(i,i-2),                     L(i,i-2) = B2 S(i-2)^-1,
//   B1 = A(i,i-1) - B2 L(i-1,i-2)^T,   L(i,i-1) = B1 S(i-1)^-1,
//   S(i) = A(i,i) - L(i,i-2) B2^T - L(i,i-1) B1^T.
// Each S(i)^-1 is formed from cofactors with one division. The factorisation is a chain from
// row to row, so its cost is the latency of that chain: a cofactor inverse is a few dependent
// multiplications and one division, where the 3x3 Cholesky it replaced had three dependent
// square roots and divisions (measured: 2x faster factorisation at 100 blocks).
//
// Except where S(i) is ill-conditioned (session 14): the cofactors of S = m I + b t t^T (a
// node of mass m on a segment of stiffness b = h^2 EA/L0) cancel to a relative error of
// eps b/m, and the Schur complement of the next row, m (2b + m)/(m + b) along t, is taken
// from b^2 t^T S^-1 t: an error of eps (b/m)^2 relative to it. At b/m = 1.2e7 (fuzzer seed 654: 148 segments of 1.7 cm
// at EA 1.7e8 N, 3.4 g nodes, h = 2 ms) it came out negative and the step failed at t = 0.
// Such a row (trace(S) trace(S^-1) above kIllConditioned, or a cofactor test that fails) is
// factored instead by the 3x3 LDL^T S = P E P^T (unit lower P, diagonal E; backward stable,
// no square roots), and its L blocks and its part of Solve take triangular solves with it,
// never the explicit inverse. Rows below the bound keep the cofactor inverse, to the bit (the
// test costs 15% more instructions in Factor, 1.5% of a bdf2 run's, and no CPU time measured:
// models/rov_tether.xml for 200 s, 1.29-1.30 s either way).
//
// Storage: 28 doubles per block row: column-major 3x3 blocks D(i) = A(i,i) (symmetric; only
// its lower triangle is read), L1(i) = A(i,i-1), L2(i) = A(i,i-2), then after all rows one
// flag per row. Factor() overwrites the blocks with S(i)^-1 (full) or, on a flagged row, the
// LDL^T factor of S(i) (1/E on the diagonal, P below it), L(i,i-1) and L(i,i-2).
#ifndef MJTETHER_SRC_BLOCK_BAND_H_
#define MJTETHER_SRC_BLOCK_BAND_H_

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

namespace mjtether {

class BlockBand {
 public:
  using Block = Eigen::Map<Eigen::Matrix3d>;
  using ConstBlock = Eigen::Map<const Eigen::Matrix3d>;

  BlockBand(double* data, int n, int bands) : a_(data), n_(n), bands_(bands) {}
  static int Size(int n) { return 28 * n; }
  // A row whose S(i) has trace(S) trace(S^-1) (>= its condition number, <= 3 times it) above
  // this takes the LDL^T path (above): there the cofactor inverse's error in the next row's
  // pivot, eps kappa^2, reaches 1e-6 of it.
  static constexpr double kIllConditioned = 1e5;

  void SetZero() { std::fill(a_, a_ + Size(n_), 0.0); }
  // Rows factored by the LDL^T path at the last Factor() (for tests and statistics).
  int StableRows() const {
    int k = 0;
    for (int i = 0; i < n_; ++i) k += flag(i) != 0;
    return k;
  }
  // Zeroes the coupling blocks L1 (and L2 with two bands) only, for a caller that assigns
  // every diagonal block.
  void SetZeroCoupling() {
    for (int i = 0; i < n_; ++i) std::fill(a_ + 27 * i + 9, a_ + 27 * i + 9 * (1 + bands_), 0.0);
  }
  // Zeroes the second coupling blocks L2 only (with two bands), for a caller that assigns
  // every diagonal block and every L1 block it uses.
  void SetZeroL2() {
    if (bands_ != 2) return;
    for (int i = 0; i < n_; ++i) std::fill(a_ + 27 * i + 18, a_ + 27 * i + 27, 0.0);
  }
  Block D(int i) { return Block(a_ + 27 * i); }
  Block L1(int i) { return Block(a_ + 27 * i + 9); }
  Block L2(int i) { return Block(a_ + 27 * i + 18); }

  // Overwrites the blocks with the factor. Returns the first block row whose pivot block S(i)
  // is not positive definite (leading minors of S(i) not all positive), or -1 on success.
  int Factor() {
    double b1[9], b2[9], l[9];
    bool flag1 = false, flag2 = false;  // rows i-1 and i-2 took the LDL^T path
    for (int i = 0; i < n_; ++i) {
      double* d = a_ + 27 * i;
      double* l1 = d + 9;
      double* l2 = d + 18;
      // S = A(i,i), symmetric from its lower triangle.
      double S[9] = {d[0], d[1], d[2], d[1], d[4], d[5], d[2], d[5], d[8]};
      if (bands_ == 2 && i >= 2) {
        std::copy(l2, l2 + 9, b2);
        if (flag2) {
          RightSolve(b2, a_ + 27 * (i - 2), l2);      // L(i,i-2) = B2 S(i-2)^-1
        } else {
          Mul(b2, a_ + 27 * (i - 2), l2);
        }
        SubMulTransposed(S, l2, b2);                  // S -= L(i,i-2) B2^T
        SubMulTransposed(l1, b2, a_ + 27 * (i - 1) + 9);  // B1 = A(i,i-1) - B2 L(i-1,i-2)^T
      }
      if (i >= 1) {
        std::copy(l1, l1 + 9, b1);
        if (flag1) {
          RightSolve(b1, a_ + 27 * (i - 1), l);       // L(i,i-1) = B1 S(i-1)^-1
        } else {
          Mul(b1, a_ + 27 * (i - 1), l);
        }
        SubMulTransposed(S, l, b1);                   // S -= L(i,i-1) B1^T
        std::copy(l, l + 9, l1);
      }
      // S^-1 = adj(S)/det(S); S is symmetric, so are its cofactors (read lower, write both).
      const double c00 = S[4] * S[8] - S[5] * S[5];
      const double c10 = S[5] * S[2] - S[1] * S[8];
      const double c20 = S[1] * S[5] - S[4] * S[2];
      const double c11 = S[0] * S[8] - S[2] * S[2];
      const double c21 = S[2] * S[1] - S[0] * S[5];
      const double c22 = S[0] * S[4] - S[1] * S[1];
      const double det = S[0] * c00 + S[1] * c10 + S[2] * c20;
      // Sylvester: S is positive definite iff its leading minors S00, c22, det are positive;
      // computed from cofactors that cancel, so on an ill-conditioned S the LDL^T decides.
      const bool sylvester = S[0] > 0 && c22 > 0 && det > 0;
      if (!sylvester || (S[0] + S[4] + S[8]) * (c00 + c11 + c22) > kIllConditioned * det) {
        if (!FactorPivot(S, d)) return i;
        flag(i) = 1;
        flag2 = flag1, flag1 = true;
        continue;
      }
      flag(i) = 0;
      flag2 = flag1, flag1 = false;
      const double r = 1 / det;
      d[0] = c00 * r, d[1] = c10 * r, d[2] = c20 * r;
      d[3] = d[1], d[4] = c11 * r, d[5] = c21 * r;
      d[6] = d[2], d[7] = d[5], d[8] = c22 * r;
    }
    return -1;
  }

  // Solves L S L^T x = b in place (b: 3n values, becomes x), after Factor().
  void Solve(double* b) const {
    using V = Eigen::Map<Eigen::Vector3d>;
    for (int i = 1; i < n_; ++i) {
      V y(b + 3 * i);
      y.noalias() -= ConstBlock(a_ + 27 * i + 9) * V(b + 3 * (i - 1));
      if (bands_ == 2 && i >= 2) y.noalias() -= ConstBlock(a_ + 27 * i + 18) * V(b + 3 * (i - 2));
    }
    for (int i = n_ - 1; i >= 0; --i) {
      V y(b + 3 * i);
      if (flag(i) != 0) {
        PivotSolve(a_ + 27 * i, b + 3 * i);
      } else {
        y = (ConstBlock(a_ + 27 * i) * y).eval();
      }
      if (i + 1 < n_)
        y.noalias() -= ConstBlock(a_ + 27 * (i + 1) + 9).transpose() * V(b + 3 * (i + 1));
      if (bands_ == 2 && i + 2 < n_) {
        y.noalias() -= ConstBlock(a_ + 27 * (i + 2) + 18).transpose() * V(b + 3 * (i + 2));
      }
    }
  }

 private:
  double& flag(int i) { return a_[27 * n_ + i]; }
  double flag(int i) const { return a_[27 * n_ + i]; }

  // The LDL^T factor of a symmetric 3x3 S (full, column-major) into f: f[0], f[4], f[8] the
  // reciprocal pivots 1/E, f[1], f[2], f[5] the unit lower factor's P10, P20, P21. False if a
  // pivot is not positive (S not positive definite).
  static bool FactorPivot(const double* S, double* f) {
    const double e0 = S[0];
    if (!(e0 > 0)) return false;
    const double p10 = S[1] / e0, p20 = S[2] / e0;
    const double e1 = S[4] - p10 * S[1];
    if (!(e1 > 0)) return false;
    const double p21 = (S[5] - p20 * S[1]) / e1;
    const double e2 = S[8] - p20 * S[2] - p21 * p21 * e1;
    if (!(e2 > 0)) return false;
    f[0] = 1 / e0, f[4] = 1 / e1, f[8] = 1 / e2;
    f[1] = p10, f[2] = p20, f[5] = p21;
    f[3] = f[6] = f[7] = 0;
    return true;
  }
  // y = S^-1 y (3 values) with the factor f of FactorPivot.
  static void PivotSolve(const double* f, double* y) {
    const double z0 = y[0], z1 = y[1] - f[1] * z0, z2 = y[2] - f[2] * z0 - f[5] * z1;
    const double w2 = z2 * f[8], w1 = z1 * f[4] - f[5] * w2;
    y[2] = w2, y[1] = w1, y[0] = z0 * f[0] - f[1] * w1 - f[2] * w2;
  }
  // c = b S^-1 with the factor f of FactorPivot: each row of b solved with it (S is
  // symmetric: (b S^-1)^T = S^-1 b^T).
  static void RightSolve(const double* b, const double* f, double* c) {
    for (int r = 0; r < 3; ++r) {
      double y[3] = {b[r], b[r + 3], b[r + 6]};
      PivotSolve(f, y);
      c[r] = y[0], c[r + 3] = y[1], c[r + 6] = y[2];
    }
  }
  // c = a b (3x3, column-major: m[r + 3 c] = m(r, c)).
  static void Mul(const double* a, const double* b, double* c) {
    for (int j = 0; j < 3; ++j) {
      for (int r = 0; r < 3; ++r) {
        c[r + 3 * j] = a[r] * b[3 * j] + a[r + 3] * b[1 + 3 * j] + a[r + 6] * b[2 + 3 * j];
      }
    }
  }
  // c -= a b^T.
  static void SubMulTransposed(double* c, const double* a, const double* b) {
    for (int j = 0; j < 3; ++j) {
      for (int r = 0; r < 3; ++r) {
        c[r + 3 * j] -= a[r] * b[j] + a[r + 3] * b[j + 3] + a[r + 6] * b[j + 6];
      }
    }
  }

  double* a_;
  int n_, bands_;
};

}  // namespace mjtether

#endif  // MJTETHER_SRC_BLOCK_BAND_H_
