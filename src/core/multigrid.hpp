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
#include <vector>

#include "grid.hpp"
#include "parallel.hpp"
#include "view.hpp"

namespace mpmflow {

constexpr index_t COARSEST = 64;  // unknowns at which the hierarchy stops (dense factor)
// Levels of at least this many rows run their row loops and dot products on all threads
// (the same bits on any thread count); smaller ones run on the calling thread.
constexpr index_t PARALLEL_ROWS = 4096;

struct SolveResult {
  index_t iterations = 0;
  double residual = 0.0;  // true relative residual ||b - A x|| / ||b||
};

// y = A x, and r = b - A x (ELL rows of width cols.extent(1)).
void matvec(View<const index_t, 2> cols, View<const double, 2> vals, View<const double> x,
            View<double> y);
void residual(View<const index_t, 2> cols, View<const double, 2> vals, View<const double> x,
              View<const double> b, View<double> r);
// a . b summed chunk by chunk (CHUNKS) when long (>= PARALLEL_ROWS): the same bits on any
// thread count; shorter vectors are summed in index order (the Numba kernel called np.dot
// there, which sums in BLAS's order: the two differ by rounding, ~1e-16 relative).
double dot(View<const double> a, View<const double> b);
// The index of the largest |r_i| (NaN counts as largest; the first of equals).
index_t largest_magnitude(View<const double> r);
// The row of the largest |b - A x| (NaN counts as largest); r: scratch of n values.
index_t worst_row(View<const index_t, 2> cols, View<const double, 2> vals, View<const double> x,
                  View<const double> b, View<double> r);

template <int D>
class Multigrid {
 public:
  // Build the levels for the matrix (cols, vals: n x 3^D) whose row r sits on grid point
  // node(r) of a grid with dims points per axis. The views must stay valid until the
  // next setup (the finest level is not copied). The storage of earlier setups is reused
  // (allocation only when the hierarchy outgrows it). Throws std::invalid_argument on
  // shapes that do not match, std::runtime_error when the coarsest operator is not positive
  // definite (its Cholesky factor fails, where np.linalg.cholesky raised LinAlgError).
  // period[k] > 0: axis k is periodic with that many points (the grid's points 0 to
  // period[k] - 1 carry rows; an even number): its rows' stencils wrap round it, and it is
  // coarsened while its coarse period stays even and at least 4 (then left as it is).
  void setup(View<const index_t, 2> cols, View<const double, 2> vals, View<const index_t> node,
             const std::array<index_t, D>& dims, index_t coarsest = COARSEST,
             const std::array<index_t, D>& period = {});
  // One V-cycle with zero initial guess: x = M^-1 b (finest level: n values each):
  // sweeps forward colour Gauss-Seidel sweeps down, the dense solve, sweeps backward up.
  void vcycle(View<const double> b, View<double> x, int sweeps);
  // Preconditioned CG from the initial guess in x; stops when ||rhs - A x|| <= tol ||rhs||.
  SolveResult pcg(View<const double> rhs, View<double> x, double tol, index_t maxiter, int sweeps);
  index_t levels() const;
  index_t rows() const;  // unknowns of the finest level

 private:
  static constexpr int NS = stencil_size(D);  // stencil slots of a row
  static constexpr int NP = 1 << D;           // entries of a row of P (coarse parents)
  // One level: its operator (level 0: the caller's views), its place on its grid, the rows
  // by colour, P to the next coarser level, and its V-cycle vectors. The storage grows
  // with the hierarchy and is reused by later setups.
  struct Level {
    index_t n = 0;
    std::array<index_t, D> dims{};
    std::array<index_t, D> period{};       // 0: not periodic
    std::array<index_t, NP + 1> cstart{};  // colour k: rows[cstart[k]:cstart[k + 1]]
    View<const index_t, 2> cols;
    View<const double, 2> vals;
    View<const index_t> node;
    View<index_t> rows;
    View<index_t, 2> coord;  // n x D: the grid coordinates of node(r)
    View<index_t, 2> pcols;  // n x NP, columns on the next level (-1: none; entries first)
    View<double, 2> pw;      // n x NP
    View<double> b, x, r;    // right-hand side, solution, residual (level 0: b, x given)
    Buffer<index_t> cols_store, node_store, rows_store, pcols_store, coord_store;
    Buffer<double> vals_store, pw_store, b_store, x_store, r_store;
  };
  void coarse_level(index_t l);  // level l + 1's unknowns and P of level l
  void galerkin(index_t l);      // level l + 1's operator P^T A P
  void coordinates(Level& lv);   // lv.coord from lv.node (the only divisions of a setup)
  void colour_rows(Level& lv);
  void factor();  // dense Cholesky factor of the coarsest level
  void cholesky_solve(View<const double> b, View<double> x);

  std::vector<Level> level_;  // grown, never shrunk; the first nlev_ are in use
  index_t nlev_ = 0;
  Buffer<index_t> crow_store_, ccoord_store_, row_cum_store_;  // setup scratch (ccoord: h(I))
  Buffer<double> factor_store_;                                // coarsest: L, n x n
  Buffer<double> r_store_, p_store_, q_store_, z_store_;       // CG vectors
};

}  // namespace mpmflow
