// Small dense linear systems (a body's 3 or 6 degrees of freedom, the free bodies' coupling,
// a cell's least-squares gradient): Gauss elimination with partial pivoting.
#pragma once

#include <cmath>
#include <utility>

#include "view.hpp"

namespace mpmflow {

// A x = b for a small dense A (n x n, row-major, destroyed), x into b; false (b left part
// way) when a pivot is not larger than tiny in magnitude: A singular, or nearly so against
// the caller's scale.
inline bool solve_dense(index_t n, double* A, double* b, double tiny = 0.0) {
  for (index_t k = 0; k < n; ++k) {
    index_t best = k;
    for (index_t i = k + 1; i < n; ++i)
      if (std::abs(A[i * n + k]) > std::abs(A[best * n + k])) best = i;
    if (!(std::abs(A[best * n + k]) > tiny)) return false;
    if (best != k) {
      for (index_t j = 0; j < n; ++j) std::swap(A[k * n + j], A[best * n + j]);
      std::swap(b[k], b[best]);
    }
    for (index_t i = k + 1; i < n; ++i) {
      const double f = A[i * n + k] / A[k * n + k];
      for (index_t j = k; j < n; ++j) A[i * n + j] -= f * A[k * n + j];
      b[i] -= f * b[k];
    }
  }
  for (index_t k = n - 1; k >= 0; --k) {
    double v = b[k];
    for (index_t j = k + 1; j < n; ++j) v -= A[k * n + j] * b[j];
    b[k] = v / A[k * n + k];
  }
  return true;
}

}  // namespace mpmflow
