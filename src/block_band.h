// Cholesky factorisation and solve of a symmetric positive definite block-band matrix of 3x3
// blocks, in place, in caller-owned storage (no allocation): the implicit integrator's
// M - h D - h^2 K, whose block row i couples node i with nodes i-1 and i-2 (bending) or with
// node i-1 only (no bending). Fixed-size 3x3 arithmetic keeps the inner work free of index
// computations and branches, which is what made the scalar band version (band_cholesky.h)
// slow at half-bandwidth 8.
//
// Storage: 27 doubles per block row, column-major 3x3 blocks: D(i) = A(i,i) (symmetric; only
// its lower triangle is read),
// L1(i) = A(i,i-1), L2(i) = A(i,i-2). Factor() overwrites them with the block Cholesky factor
// (A = L L^T): D(i) holds the inverse of the lower-triangular diagonal block, L1, L2 the
// off-diagonal blocks of L.
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
  static int Size(int n) { return 27 * n; }

  void SetZero() { std::fill(a_, a_ + Size(n_), 0.0); }
  Block D(int i) { return Block(a_ + 27 * i); }
  Block L1(int i) { return Block(a_ + 27 * i + 9); }
  Block L2(int i) { return Block(a_ + 27 * i + 18); }

  // Overwrites the blocks with the factor. Returns the first block row whose pivot is not
  // positive (not positive definite), or -1 on success.
  int Factor() {
    for (int i = 0; i < n_; ++i) {
      double* d = a_ + 27 * i;
      double* l1 = d + 9;
      double* l2 = d + 18;
      // Off-diagonal blocks of L in this row: L(i,k) = (A(i,k) - sum_j L(i,j) L(k,j)^T) Lkk^-T.
      if (bands_ == 2 && i >= 2) {
        TimesLowerTransposed(l2, a_ + 27 * (i - 2));  // D(i-2) holds L(i-2,i-2)^-1
      }
      if (i >= 1) {
        if (bands_ == 2 && i >= 2) {
          ConstBlock L2(l2), P(a_ + 27 * (i - 1) + 9);  // L(i-1,i-2)
          Block(l1).noalias() -= L2 * P.transpose();
        }
        TimesLowerTransposed(l1, a_ + 27 * (i - 1));
        SubtractLowerGram(d, l1);
        if (bands_ == 2 && i >= 2) SubtractLowerGram(d, l2);
      }
      // 3x3 Cholesky of d (lower triangle), then its inverse (lower triangular) in place.
      // Column-major: d[r + 3 c] = d(r, c).
      const double p0 = d[0];
      if (!(p0 > 0)) return i;
      const double i00 = 1 / std::sqrt(p0);
      const double l10 = d[1] * i00, l20 = d[2] * i00;
      const double p1 = d[4] - l10 * l10;
      if (!(p1 > 0)) return i;
      const double i11 = 1 / std::sqrt(p1);
      const double l21 = (d[5] - l20 * l10) * i11;
      const double p2 = d[8] - l20 * l20 - l21 * l21;
      if (!(p2 > 0)) return i;
      const double i22 = 1 / std::sqrt(p2);
      const double i10 = -l10 * i00 * i11;
      const double i21 = -l21 * i11 * i22;
      const double i20 = -(l20 * i00 + l21 * i10) * i22;
      d[0] = i00, d[1] = i10, d[2] = i20;
      d[3] = 0, d[4] = i11, d[5] = i21;
      d[6] = 0, d[7] = 0, d[8] = i22;
    }
    return -1;
  }

  // Solves L L^T x = b in place (b: 3n values, becomes x), after Factor().
  void Solve(double* b) const {
    using V = Eigen::Map<Eigen::Vector3d>;
    for (int i = 0; i < n_; ++i) {
      V y(b + 3 * i);
      if (i >= 1) y.noalias() -= ConstBlock(a_ + 27 * i + 9) * V(b + 3 * (i - 1));
      if (bands_ == 2 && i >= 2) y.noalias() -= ConstBlock(a_ + 27 * i + 18) * V(b + 3 * (i - 2));
      y = (ConstBlock(a_ + 27 * i) * y).eval();
    }
    for (int i = n_ - 1; i >= 0; --i) {
      V y(b + 3 * i);
      if (i + 1 < n_)
        y.noalias() -= ConstBlock(a_ + 27 * (i + 1) + 9).transpose() * V(b + 3 * (i + 1));
      if (bands_ == 2 && i + 2 < n_) {
        y.noalias() -= ConstBlock(a_ + 27 * (i + 2) + 18).transpose() * V(b + 3 * (i + 2));
      }
      y = (ConstBlock(a_ + 27 * i).transpose() * y).eval();
    }
  }

 private:
  // x = x T^T in place, T lower triangular (column-major 3x3): column c of the product takes
  // columns 0..c of x, so columns are formed from the last to the first.
  static void TimesLowerTransposed(double* x, const double* t) {
    for (int r = 0; r < 3; ++r) {
      const double x0 = x[r], x1 = x[r + 3], x2 = x[r + 6];
      x[r + 6] = x0 * t[2] + x1 * t[5] + x2 * t[8];
      x[r + 3] = x0 * t[1] + x1 * t[4];
      x[r] = x0 * t[0];
    }
  }
  // The lower triangle of d -= x x^T (the Cholesky step reads only the lower triangle).
  static void SubtractLowerGram(double* d, const double* x) {
    for (int c = 0; c < 3; ++c) {
      for (int r = c; r < 3; ++r) {
        d[r + 3 * c] -= x[r] * x[c] + x[r + 3] * x[c + 3] + x[r + 6] * x[c + 6];
      }
    }
  }

  double* a_;
  int n_, bands_;
};

}  // namespace mjtether

#endif  // MJTETHER_SRC_BLOCK_BAND_H_
