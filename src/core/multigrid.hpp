// Geometric multigrid-preconditioned conjugate gradients on a structured grid (2D, 3D):
// the pressure system on the node grid, the volume correction's on the cell grid, and each
// velocity component of the viscous system.
//
// Matrices are in ELL form: row r has 3^D entries cols(r, s), vals(r, s) (col -1: empty),
// slot s = sum_k (d_k + 1) 3^k for the neighbour at offset d, the diagonal in the middle
// slot. node(r) is the grid point of row r on a grid of dims points per axis (axis 0
// fastest). See src/mpmflow/kernels/multigrid.py (the Numba original) for the levels,
// the Galerkin products, the 2^D-colour Gauss-Seidel and the dense coarsest solve.
//
// A Multigrid object owns its hierarchy's storage and reuses it from one setup to the
// next (no allocation once it has grown to a run's size).
#pragma once

#include <array>

#include "parallel.hpp"
#include "view.hpp"

namespace mpmflow {

constexpr index_t COARSEST = 64;  // unknowns at which the hierarchy stops (dense factor)

struct SolveResult {
  index_t iterations = 0;
  double residual = 0.0;  // true relative residual ||b - A x|| / ||b||
};

// y = A x, and r = b - A x (ELL rows of width cols.extent(1)).
void matvec(View<const index_t, 2> cols, View<const double, 2> vals, View<const double> x,
            View<double> y);
void residual(View<const index_t, 2> cols, View<const double, 2> vals, View<const double> x,
              View<const double> b, View<double> r);
// a . b summed chunk by chunk (CHUNKS) when long: the same bits on any thread count.
double dot(View<const double> a, View<const double> b);
// The row of the largest |b - A x| (NaN counts as largest); r: scratch of n values.
index_t worst_row(View<const index_t, 2> cols, View<const double, 2> vals, View<const double> x,
                  View<const double> b, View<double> r);

template <int D>
class Multigrid {
 public:
  // Build the levels for the matrix (cols, vals: n x 3^D) whose row r sits on grid point
  // node(r) of a grid with dims points per axis. The views must stay valid until the
  // next setup (the finest level is not copied).
  void setup(View<const index_t, 2> cols, View<const double, 2> vals, View<const index_t> node,
             const std::array<index_t, D>& dims, index_t coarsest = COARSEST);
  // One V-cycle with zero initial guess: x = M^-1 b (finest level: n values each).
  void vcycle(View<const double> b, View<double> x, int sweeps);
  // Preconditioned CG from the initial guess in x; stops when ||rhs - A x|| <= tol ||rhs||.
  SolveResult pcg(View<const double> rhs, View<double> x, double tol, index_t maxiter, int sweeps);
  index_t levels() const;
  index_t rows() const;  // unknowns of the finest level

 private:
  struct Impl;
  // storage of all levels (owned here, reused between setups); filled in by multigrid.cpp
  Buffer<index_t> index_store_[8];
  Buffer<double> value_store_[8];
  std::array<index_t, 64> level_info_{};
};

}  // namespace mpmflow
