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
#include <cmath>
#include <cstdint>
#include <type_traits>
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

// The row kernels' element functions, one row each, on the host and (MPMFLOW_HD) the device
// (src/core/cuda/multigrid.cuh): the same sums in the same order on both.

// sum_s vals(r, s) x(cols(r, s)) over the row's filled slots (NS slots; 0: ns of them); I:
// the columns' type (a level's iteration form holds them as 32-bit: Multigrid's icols).
template <int NS, class I = index_t>
MPMFLOW_HD inline double ell_row_product(View<const I, 2> cols, View<const double, 2> vals,
                                         View<const double> x, index_t r, index_t ns) {
  const index_t width = NS > 0 ? NS : ns;
  const I* c = &cols(r, 0);
  const double* v = &vals(r, 0);
  double acc = 0.0;
  for (index_t s = 0; s < width; ++s)
    if (c[s] >= 0) acc += v[s] * x(c[s]);
  return acc;
}

// Gauss-Seidel update of row r (the diagonal in the middle slot); slots, nslots: only these
// off-diagonal slots (the first sweep from x = 0, gauss_seidel_first), or every slot
// (slots null).
template <int NS, class I = index_t>
MPMFLOW_HD inline void gs_row(View<const I, 2> cols, View<const double, 2> vals,
                              View<const double> b, View<double> x, index_t r, const int* slots,
                              int nslots) {
  constexpr int centre = NS / 2;
  const I* c = cols.data() + r * NS;
  const double* v = vals.data() + r * NS;
  double* X = x.data();
  double acc = b(r);
  if (slots) {
    for (int t = 0; t < nslots; ++t) {
      const int s = slots[t];
      if (c[s] >= 0) acc -= v[s] * X[c[s]];
    }
  } else {
    for (int s = 0; s < NS; ++s)
      if (c[s] >= 0 && s != centre) acc -= v[s] * X[c[s]];
  }
  X[r] = acc / v[centre];
}

// x_f(r) += (P e_c)(r).
template <int NP>
MPMFLOW_HD inline void prolong_row(View<const index_t, 2> pcols, View<const double, 2> pw,
                                   View<const double> ec, View<double> xf, index_t r) {
  double acc = 0.0;
  for (int a = 0; a < NP; ++a) {
    const index_t c = pcols(r, a);
    if (c >= 0) acc += pw(r, a) * ec(c);
  }
  xf(r) += acc;
}

// x = (L L^T)^-1 b with L the dense lower factor (n x n, row-major).
MPMFLOW_HD inline void cholesky_solve_dense(const double* L, index_t n, View<const double> b,
                                            View<double> x) {
  for (index_t i = 0; i < n; ++i) {
    double acc = b(i);
    for (index_t k = 0; k < i; ++k) acc -= L[i * n + k] * x(k);
    x(i) = acc / L[i * n + i];
  }
  for (index_t i = n - 1; i >= 0; --i) {
    double acc = x(i);
    for (index_t k = i + 1; k < n; ++k) acc -= L[k * n + i] * x(k);
    x(i) = acc / L[i * n + i];
  }
}

// The slots of the (2D + 1)-point star among a row's 3^D (the diagonal and its 2D face
// neighbours), ascending: a level whose rows fill no other slot (the volume correction's
// Laplacian on the cells) is also held in this compact form, which its iterations read
// (the same sums in the same order, on 2D + 1 slots a row instead of 3^D).
template <int D>
constexpr std::array<int, 2 * D + 1> star_slots() {
  std::array<int, 2 * D + 1> s{};
  const int centre = stencil_size(D) / 2;
  int p3 = 1;
  for (int k = 0; k < D; ++k, p3 *= 3) {
    s[D - 1 - k] = centre - p3;
    s[D + 1 + k] = centre + p3;
  }
  s[D] = centre;
  return s;
}

// The off-diagonal slots a row of colour ``colour`` reads in the first sweep from x = 0:
// those of colours before it (the neighbour at slot s has colour colour ^ odd(s), odd(s)
// the axes along which the offset of slot s is odd). Returns how many (into slots).
template <int D>
inline int first_sweep_slots(int colour, int* slots) {
  int nslots = 0;
  for (int s = 0, p3 = 1, odd = 0; s < stencil_size(D); ++s, odd = 0, p3 = 1) {
    for (int k = 0; k < D; ++k, p3 *= 3)
      if ((s / p3) % 3 != 1) odd |= 1 << k;
    if ((colour ^ odd) < colour) slots[nslots++] = s;
  }
  return nslots;
}

// The preconditioned CG iteration, written once for the host's Multigrid<D>::pcg and the
// device's (src/core/cuda/multigrid.cuh): ops does the vector work in its own memory,
//   ops.dot(a, b), ops.residual(x, b, r) (r = b - A x), ops.matvec(p, q) (q = A p),
//   ops.vcycle(r, z) (z = M^-1 r), ops.fill(v, value), ops.copy(from, to),
//   ops.cg_update(x, r, p, q, z, alpha, beta, step) (step: x += alpha p, r -= alpha q;
//   else p = z + beta p);
// r, p, q, z: scratch of n values. Stops when ||rhs - A x|| <= tol ||rhs||; x holds the
// initial guess.
template <class Ops>
SolveResult pcg_iterate(Ops& ops, View<const double> rhs, View<double> x, View<double> r,
                        View<double> p, View<double> q, View<double> z, double tol,
                        index_t maxiter) {
  const double bnorm = std::sqrt(ops.dot(rhs, rhs));
  if (bnorm == 0.0) {
    ops.fill(x, 0.0);
    return {0, 0.0};
  }
  ops.residual(x, rhs, r);
  double rnorm = std::sqrt(ops.dot(r, r));
  if (rnorm > bnorm) {
    // a warm start worse than zero (the right-hand side changed a lot) would only cost
    // accuracy: the residual would have to fall far below round-off of A x0
    ops.fill(x, 0.0);
    ops.copy(rhs, r);
    rnorm = bnorm;
  }
  if (rnorm <= tol * bnorm) return {0, rnorm / bnorm};
  ops.vcycle(r, z);
  ops.copy(z, p);
  double rz = ops.dot(r, z);
  index_t it = 0;
  while (it < maxiter) {
    ++it;
    ops.matvec(p, q);
    const double alpha = rz / ops.dot(p, q);
    ops.cg_update(x, r, p, q, z, alpha, 0.0, true);
    rnorm = std::sqrt(ops.dot(r, r));
    if (rnorm <= tol * bnorm) {
      // the recursive residual can drift from the true one: converged when the true one
      // meets the tolerance too; otherwise go on from it, with a restarted direction
      ops.residual(x, rhs, r);
      rnorm = std::sqrt(ops.dot(r, r));
      if (rnorm <= tol * bnorm) return {it, rnorm / bnorm};
      ops.vcycle(r, z);
      ops.copy(z, p);
      rz = ops.dot(r, z);
      continue;
    }
    ops.vcycle(r, z);
    const double rz_new = ops.dot(r, z);
    const double beta = rz_new / rz;
    rz = rz_new;
    ops.cg_update(x, r, p, q, z, 0.0, beta, false);
  }
  // the iterations ran out: report the true residual
  ops.residual(x, rhs, q);
  return {it, std::sqrt(ops.dot(q, q)) / bnorm};
}

template <int D>
class Multigrid {
 public:
  // Build the levels for the matrix (cols, vals: n x 3^D) whose row r sits on grid point
  // node(r) of a grid with dims points per axis. The views must stay valid until the
  // next setup (the finest level is not copied, but for a star's values: refresh), and
  // cols unchanged; vals may change in place between solves, followed by refresh() (the
  // pressure's contact rounds hold rows at 0 so). The storage of earlier setups is reused
  // (allocation only when the hierarchy outgrows it). Throws std::invalid_argument on
  // shapes that do not match, std::runtime_error when the coarsest operator is not positive
  // definite (its Cholesky factor fails, where np.linalg.cholesky raised LinAlgError).
  // period[k] > 0: axis k is periodic with that many points (the grid's points 0 to
  // period[k] - 1 carry rows; an even number): its rows' stencils wrap round it, and it is
  // coarsened while its coarse period stays even and at least 4 (then left as it is).
  void setup(View<const index_t, 2> cols, View<const double, 2> vals, View<const index_t> node,
             const std::array<index_t, D>& dims, index_t coarsest = COARSEST,
             const std::array<index_t, D>& period = {});
  // The finest level's values changed in place since the setup: its iteration form (a
  // star's copy of them) reads them again. The coarse levels stay those of the setup's.
  void refresh();
  // One V-cycle with zero initial guess: x = M^-1 b (finest level: n values each):
  // sweeps forward colour Gauss-Seidel sweeps down, the dense solve, sweeps backward up.
  void vcycle(View<const double> b, View<double> x, int sweeps);
  // Preconditioned CG from the initial guess in x; stops when ||rhs - A x|| <= tol ||rhs||.
  SolveResult pcg(View<const double> rhs, View<double> x, double tol, index_t maxiter, int sweeps);
  index_t levels() const;
  index_t rows() const;  // unknowns of the finest level

  // Level l of the last setup as views (a device copy of the hierarchy reads them:
  // src/core/cuda/multigrid.cuh): its rows, colours (rows[cstart[k]:cstart[k + 1]]),
  // operator and P to level l + 1 (empty on the coarsest).
  struct LevelView {
    index_t n = 0;
    std::array<index_t, (1 << D) + 1> cstart{};
    View<const index_t, 2> cols;
    View<const double, 2> vals;
    View<const index_t> rows;
    View<const index_t, 2> pcols;
    View<const double, 2> pw;
  };
  LevelView level(index_t l) const;
  // The coarsest level's dense Cholesky factor L (n x n, lower, row-major).
  View<const double, 2> coarsest_factor() const;

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
    // the iteration form, which the sweeps, residuals and products read: the columns as
    // 32-bit numbers (a quarter less to read a slot), on the star's slots only (star_slots,
    // kvals) when no row fills another, else on all 3^D (vals); empty on a level of 2^31
    // rows or more (cols, vals are read)
    View<const std::int32_t, 2> icols;
    View<const double, 2> kvals;
    View<const index_t> node;
    View<index_t> rows;
    View<index_t, 2> coord;  // n x D: the grid coordinates of node(r)
    View<index_t, 2> pcols;  // n x NP, columns on the next level (-1: none; entries first)
    View<double, 2> pw;      // n x NP
    // P's transpose by coarse row I: its fine rows trow[tstart[I]:tstart[I + 1]], ascending,
    // and their weights tw (the restriction's sums, each coarse row's on its own, in the
    // order of the fine rows)
    View<index_t> tstart, trow;
    View<double> tw;
    View<double> b, x, r;  // right-hand side, solution, residual (level 0: b, x given)
    Buffer<index_t> cols_store, node_store, rows_store, pcols_store, coord_store, tstart_store,
        trow_store;
    Buffer<std::int32_t> icols_store;
    Buffer<double> vals_store, pw_store, b_store, x_store, r_store, kvals_store, tw_store;
  };
  void compact(Level& lv);      // lv's iteration form (icols; kvals on a star)
  void star_values(Level& lv);  // a star's kvals from its vals (nothing on 3^D slots)
  // f(ns, cols, vals) on level lv's iteration form, the one place its three forms are told
  // apart: ns the slots of a row as a std::integral_constant (the star's 2D + 1, or 3^D),
  // cols 32-bit (icols), or index_t on a level of 2^31 rows or more
  template <class F>
  void with_form(const Level& lv, F&& f) const {
    if (lv.kvals.size() > 0)
      f(std::integral_constant<int, 2 * D + 1>{}, lv.icols, lv.kvals);
    else if (lv.icols.size() > 0)
      f(std::integral_constant<int, NS>{}, lv.icols, lv.vals);
    else
      f(std::integral_constant<int, NS>{}, lv.cols, lv.vals);
  }
  // y = A x (subtract: b - A x) with level lv's operator in its iteration form
  void iterate_apply(const Level& lv, View<const double> x, const double* b, View<double> y,
                     bool subtract) const;
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
