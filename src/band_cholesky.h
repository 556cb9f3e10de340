// Cholesky factorisation and solve of a symmetric positive definite band matrix, in place, in
// caller-owned storage (no allocation). The implicit integrator's matrix M - h D - h^2 K is
// block-banded: 3x3 blocks, two blocks either side of the diagonal with bending (one without),
// so its scalar half-bandwidth is at most 3*2 + 2 = 8.
//
// Storage: row-major n x (p+1), band(i, k) = A(i, i - p + k) for the lower triangle, i.e. the
// diagonal is the last column. Cost: n p^2 / 2 multiply-adds to factor, 2 n p to solve.
#ifndef MJTETHER_SRC_BAND_CHOLESKY_H_
#define MJTETHER_SRC_BAND_CHOLESKY_H_

#include <algorithm>
#include <cmath>

namespace mjtether {

class BandMatrix {
 public:
  BandMatrix(double* data, int n, int p) : a_(data), n_(n), p_(p) {}
  static int Size(int n, int p) { return n * (p + 1); }

  void SetZero() { std::fill(a_, a_ + Size(n_, p_), 0.0); }
  // Adds to A(i, j), j <= i and i - j <= p (the lower triangle).
  void Add(int i, int j, double value) { a_[i * (p_ + 1) + p_ - (i - j)] += value; }
  double Get(int i, int j) const { return a_[i * (p_ + 1) + p_ - (i - j)]; }

  // Overwrites the band with L (A = L L^T). Returns the first row whose pivot is not positive
  // (the matrix is not positive definite), or -1 on success.
  int Factor() {
    for (int i = 0; i < n_; ++i) {
      double* row_i = a_ + i * (p_ + 1);
      int j0 = std::max(0, i - p_);
      for (int j = j0; j <= i; ++j) {
        const double* row_j = a_ + j * (p_ + 1);
        // L(i,j) = (A(i,j) - sum_k L(i,k) L(j,k)) / L(j,j), k from max(i,j)-p to j-1
        double s = row_i[p_ - (i - j)];
        for (int k = std::max(j0, j - p_); k < j; ++k) {
          s -= row_i[p_ - (i - k)] * row_j[p_ - (j - k)];
        }
        if (j == i) {
          if (!(s > 0)) return i;
          row_i[p_] = std::sqrt(s);
        } else {
          row_i[p_ - (i - j)] = s / row_j[p_];
        }
      }
    }
    return -1;
  }

  // Solves L L^T x = b in place (b becomes x), after Factor().
  void Solve(double* b) const {
    for (int i = 0; i < n_; ++i) {
      const double* row_i = a_ + i * (p_ + 1);
      double s = b[i];
      for (int k = std::max(0, i - p_); k < i; ++k) s -= row_i[p_ - (i - k)] * b[k];
      b[i] = s / row_i[p_];
    }
    for (int i = n_ - 1; i >= 0; --i) {
      double s = b[i];
      for (int k = i + 1; k <= std::min(n_ - 1, i + p_); ++k) {
        s -= a_[k * (p_ + 1) + p_ - (k - i)] * b[k];
      }
      b[i] = s / a_[i * (p_ + 1) + p_];
    }
  }

 private:
  double* a_;
  int n_, p_;
};

}  // namespace mjtether

#endif  // MJTETHER_SRC_BAND_CHOLESKY_H_
