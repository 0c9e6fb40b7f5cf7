#include "viscous.hpp"

#include <algorithm>
#include <cmath>

#include "parallel.hpp"
#include "periodic.hpp"
#include "rheology.hpp"
#include "stencil.hpp"

namespace mpmflow {

namespace {

// the rows of the system before numbering: an unknown; a component kept at its value in u
constexpr index_t FREE = 0;
constexpr index_t HELD = -1;

// The rows of node i (one per unknown component): the Numba _node_rows.
template <int D>
void node_rows(const Grid<D>& g, index_t i, const std::array<index_t, D>& ix,
               const StencilTables<D>& st, View<const double, 4> T,
               const std::array<double, (1 << D) * (1 << D)>& Kg, View<const double> weight,
               View<const double> node_mass, double dt, View<const double, 2> u,
               View<const index_t, 2> row, View<const index_t> off, View<index_t, 3> cols,
               View<double, 3> vals, View<double> rhs, View<index_t> node, double grad_div) {
  constexpr int NC = 1 << D;
  constexpr int NS = stencil_size(D);
  constexpr int centre = NS / 2;
  std::array<double, D * NS> S;
  for (int k = 0; k < D; ++k) {
    const index_t r = row(i, k);
    if (r < 0) continue;
    S.fill(0.0);
    for (int b = 0; b < NC; ++b) {
      const NodeCell cell = node_cell<D>(g, ix, b);
      const index_t c = cell.c;
      const int a = cell.a;
      if (c < 0) continue;
      const double w = weight(c);
      if (w == 0.0) continue;
      for (int bb = 0; bb < NC; ++bb) {
        const int s = st.slot[a][bb];
        for (int m = 0; m < D; ++m) {
          double val = T(a, bb, m, k) + grad_div * T(a, bb, k, m);
          if (m == k) val += Kg[a * NC + bb];
          S[m * NS + s] += w * val;
        }
      }
    }
    S[k * NS + centre] += node_mass(i) / dt;
    rhs(r) = node_mass(i) / dt * u(i, k);
    node(r) = i;
    for (int m = 0; m < D; ++m)
      for (int s = 0; s < NS; ++s) {
        const double sv = S[m * NS + s];
        const index_t j = neighbour_node<D>(g, i, ix, s, st);
        if (sv != 0.0 && row(j, m) >= 0) {
          cols(m, r, s) = row(j, m) - off(m);
          vals(m, r, s) = sv;
        } else {
          cols(m, r, s) = -1;
          vals(m, r, s) = 0.0;
          if (sv != 0.0) rhs(r) -= sv * u(j, m);
        }
      }
  }
}

// Block (k, m) of the system: the rows lo..hi of component k, couplings to component m.
template <class T>
View<T, 2> block(View<T, 3> a, index_t m, index_t lo, index_t hi) {
  const index_t ns = a.extent(2);
  return View<T, 2>(a.data() + (m * a.extent(1) + lo) * ns, {hi - lo, ns});
}
template <class T>
View<T> part(View<T> a, index_t lo, index_t hi) {
  return View<T>(a.data() + lo, {hi - lo});
}

}  // namespace

template <int D>
void gauss_gradients(const Grid<D>& g, View<double, 4> T) {
  constexpr int NC = 1 << D;
  for (index_t i = 0; i < T.size(); ++i) T[i] = 0.0;
  const double gp = 0.5 / std::sqrt(3.0);
  std::array<double, D> frac;
  const double w = int_power(g.h, D) / NC;
  for (int q = 0; q < NC; ++q) {
    for (int k = 0; k < D; ++k) frac[k] = ((q >> k) & 1) ? 0.5 + gp : 0.5 - gp;
    for (int a = 0; a < NC; ++a)
      for (int b = 0; b < NC; ++b)
        for (int m = 0; m < D; ++m) {
          const double ga = g.corner_gradient(a, m, frac.data());
          for (int k = 0; k < D; ++k)
            T(a, b, m, k) += w * ga * g.corner_gradient(b, k, frac.data());
        }
  }
}

template <int D>
void cell_viscosity(const Grid<D>& g, View<const double> theta, View<const double> open_,
                    View<const bool> enclosed, double full, View<const double, 2> v,
                    View<const double> p_node, int model, View<const double> par, View<double> eta,
                    View<double> weight) {
  constexpr int NC = 1 << D;
  parallel_for(theta.size(), [&](index_t c) {
    if (!(theta(c) > 0.0 || enclosed(c))) {
      eta(c) = 0.0;
      weight(c) = 0.0;
      return;
    }
    std::array<double, D> centre;
    centre.fill(0.5);
    std::array<double, D * D> grad{};
    const index_t first = g.cell_first_node(c);
    double p = 0.0;
    for (int a = 0; a < NC; ++a) {
      const index_t i = first + g.corner[a];
      p += std::max(p_node(i), 0.0);
      for (int m = 0; m < D; ++m) {
        const double gr = g.corner_gradient(a, m, centre.data());
        for (int k = 0; k < D; ++k) grad[m * D + k] += gr * v(i, k);
      }
    }
    double rate2 = 0.0;
    for (int m = 0; m < D; ++m)
      for (int k = 0; k < D; ++k) {
        const double d = 0.5 * (grad[m * D + k] + grad[k * D + m]);
        rate2 += 2.0 * d * d;
      }
    const double e = viscosity(model, par, std::sqrt(rate2), p / NC);
    const double fraction = (theta(c) >= full || enclosed(c)) ? 1.0 : theta(c);
    eta(c) = e;
    weight(c) = e * fraction * open_(c);
  });
}

template <int D>
void rate_velocity(View<const double, 2> v, View<const index_t> wall_node,
                   View<const index_t> wall_axis, View<const bool> wall_no_slip,
                   View<const bool, 2> contact, View<const index_t> onode,
                   View<const bool> ocontact, View<const bool> ono_slip, View<double, 2> out,
                   View<const double, 2> held, View<const double, 2> oheld) {
  const bool moving = held.size() > 0, omoving = oheld.size() > 0;
  for (index_t i = 0; i < v.size(); ++i) out[i] = v[i];
  for (index_t e = 0; e < wall_node.size(); ++e) {
    const index_t i = wall_node(e), k = wall_axis(e);
    if (wall_no_slip(e) && contact(i, k))
      for (int m = 0; m < D; ++m) out(i, m) = moving ? held(i, m) : 0.0;
  }
  for (index_t e = 0; e < onode.size(); ++e) {
    const index_t i = onode(e);
    if (ono_slip(e) && ocontact(i))
      for (int m = 0; m < D; ++m) out(i, m) = omoving ? oheld(i, m) : 0.0;
  }
}

template <int D>
index_t number_unknowns(View<const double> node_mass, View<const index_t> wall_node,
                        View<const index_t> wall_axis, View<const bool> wall_no_slip,
                        View<const bool, 2> contact, View<const index_t> onode,
                        View<const bool> ocontact, View<const bool> ono_slip,
                        View<const double, 2> vstar, View<double, 2> u, View<index_t, 2> row,
                        View<index_t> off, const Grid<D>* grid, View<const double, 2> held,
                        View<const double, 2> oheld) {
  const index_t nn = u.extent(0);
  const bool moving = held.size() > 0, omoving = oheld.size() > 0;
  for (index_t i = 0; i < u.size(); ++i) u[i] = vstar[i];
  for (index_t i = 0; i < nn; ++i)
    for (int k = 0; k < D; ++k) row(i, k) = node_mass(i) > 0.0 ? FREE : HELD;
  // The no-slip hold is the pressure step's contact, not a rule of its own: the corrector
  // leaves a node that contact holds at rest, so a component solved here as free at a held
  // node (or the reverse) would be a different wall in each half of the step. (A rule on
  // the sign of v*.n, holding where v*.n >= 0, decided the nodes at rest on the wall by the
  // sign of their FLIP noise; the wall then unzipped and a block in a no-slip corner blew
  // up at small steps.) A held node is at rest in the solve too, its normal component
  // included, as at a no-slip obstacle: keeping the normal of v* less the last pressure
  // gradient there (what is left of FLIP noise) sheared the neighbours by a velocity the
  // corrector then removed (the split error of a block on a no-slip floor: 9% -> 3% between
  // dt = 6e-4 and 1.5e-4 s).
  for (index_t e = 0; e < wall_node.size(); ++e) {
    const index_t i = wall_node(e), k = wall_axis(e);
    if (node_mass(i) <= 0.0) continue;
    row(i, k) = HELD;
    if (wall_no_slip(e) && contact(i, k))
      for (int m = 0; m < D; ++m) {
        row(i, m) = HELD;
        u(i, m) = moving ? held(i, m) : 0.0;
      }
  }
  for (index_t e = 0; e < onode.size(); ++e) {
    const index_t i = onode(e);
    if (!ono_slip(e) || node_mass(i) <= 0.0) continue;
    if (ocontact(i))
      for (int k = 0; k < D; ++k) {
        row(i, k) = HELD;
        u(i, k) = omoving ? oheld(i, k) : 0.0;
      }
  }
  const bool periodic = grid != nullptr && grid->any_periodic;
  if (periodic) {  // an image's unknowns are its master's (numbered below, then copied)
    std::array<index_t, D> ix;
    for (index_t i = 0; i < nn; ++i) {
      grid->node_coords(i, ix.data());
      if (grid->is_image(ix.data()))
        for (int k = 0; k < D; ++k) row(i, k) = HELD;
    }
  }
  index_t n = 0;
  for (int k = 0; k < D; ++k) {
    off(k) = n;
    for (index_t i = 0; i < nn; ++i)
      if (row(i, k) == FREE) row(i, k) = n++;
  }
  off(D) = n;
  if (periodic) copy_images<D, index_t>(*grid, row.data(), D);
  return n;
}

template <int D>
void assemble(const Grid<D>& g, View<const double, 4> T, View<const double> weight,
              View<const double> node_mass, double dt, View<const double, 2> u,
              View<const index_t, 2> row, View<const index_t> off, View<index_t, 3> cols,
              View<double, 3> vals, View<double> rhs, View<index_t> node, double grad_div) {
  constexpr int NC = 1 << D;
  const StencilTables<D> st = tables<D>(g);
  std::array<double, NC * NC> Kg{};
  for (int a = 0; a < NC; ++a)
    for (int b = 0; b < NC; ++b)
      for (int m = 0; m < D; ++m) Kg[a * NC + b] += T(a, b, m, m);
  // every node writes only its own rows: any order gives the same bits
  parallel_for(g.nnodes, [&](index_t i) {
    std::array<index_t, D> ix;
    g.node_coords(i, ix.data());
    if (g.is_image(ix.data())) return;  // an image's rows are its master's
    node_rows<D>(g, i, ix, st, T, Kg, weight, node_mass, dt, u, row, off, cols, vals, rhs, node,
                 grad_div);
  });
}

template <int D>
double operator_force(const Grid<D>& g, View<const double, 4> T, View<const double> weight,
                      double grad_div, View<const double, 2> x, index_t i, int k) {
  constexpr int NC = 1 << D;
  std::array<index_t, D> ix;
  g.node_coords(i, ix.data());
  double f = 0.0;
  for (int b = 0; b < NC; ++b) {
    const NodeCell cell = node_cell<D>(g, ix, b);
    if (cell.c < 0 || weight(cell.c) == 0.0) continue;
    const int a = cell.a;
    for (int bb = 0; bb < NC; ++bb) {
      const index_t j = cell.first + g.corner[bb];
      double kg = 0.0;
      for (int m = 0; m < D; ++m) kg += T(a, bb, m, m);
      for (int m = 0; m < D; ++m) {
        double val = T(a, bb, m, k) + grad_div * T(a, bb, k, m);
        if (m == k) val += kg;
        f += weight(cell.c) * val * x(j, m);
      }
    }
  }
  return f;
}

void apply_blocks(View<const index_t, 3> cols, View<const double, 3> vals, View<const index_t> off,
                  View<const double> x, View<double> y, View<double> tmp) {
  const index_t D = cols.extent(0);
  for (index_t k = 0; k < D; ++k) {
    const index_t lo = off(k), hi = off(k + 1);
    parallel_for(hi - lo, [&](index_t i) { y(lo + i) = 0.0; });
    for (index_t m = 0; m < D; ++m) {
      if (hi > lo && off(m + 1) > off(m)) {
        matvec(block(cols, m, lo, hi), block(vals, m, lo, hi), part(x, off(m), off(m + 1)),
               part(tmp, 0, hi - lo));
        parallel_for(hi - lo, [&](index_t i) { y(lo + i) += tmp(i); });
      }
    }
  }
}

index_t worst_row(View<const index_t, 3> cols, View<const double, 3> vals, View<const index_t> off,
                  View<const double> x, View<const double> rhs, View<double> r, View<double> tmp) {
  apply_blocks(cols, vals, off, x, r, tmp);
  const index_t n = rhs.size();
  for (index_t i = 0; i < n; ++i) r(i) = rhs(i) - r(i);
  return largest_magnitude(r.head(n));
}

template <int D>
SolveResult solve(const Grid<D>& g, View<const index_t, 3> cols, View<const double, 3> vals,
                  View<const index_t> node, View<const index_t> off, View<const double> rhs,
                  View<double> x, double tol, index_t maxiter, int sweeps,
                  std::array<Multigrid<D>, D>& mg, View<double, 2> work) {
  const index_t n = rhs.size();
  std::array<index_t, D> dims, period{};
  for (int k = 0; k < D; ++k) {
    dims[k] = g.cells[k] + 1;
    if (g.periodic[k]) period[k] = g.cells[k];
  }
  for (int k = 0; k < D; ++k) {
    const index_t lo = off(k), hi = off(k + 1);
    // a component without unknowns has no hierarchy: it is never applied
    if (hi > lo)
      mg[k].setup(block(cols, k, lo, hi), block(vals, k, lo, hi), part(node, lo, hi), dims,
                  COARSEST, period);
  }
  View<double> r = work.row(0).head(n), zz = work.row(1).head(n), p = work.row(2).head(n),
               q = work.row(3).head(n), tmp = work.row(4).head(n);
  const double bnorm = std::sqrt(dot(rhs, rhs));
  if (bnorm == 0.0) {
    parallel_for(n, [&](index_t i) { x(i) = 0.0; });
    return {0, 0.0};
  }
  apply_blocks(cols, vals, off, x, r, tmp);
  parallel_for(n, [&](index_t i) { r(i) = rhs(i) - r(i); });
  const double rnorm = std::sqrt(dot(r, r));
  if (rnorm <= tol * bnorm) return {0, rnorm / bnorm};
  index_t it = 0;
  double rz = 0.0;
  bool restart = true;  // the first direction, or one restarted from the true residual
  while (true) {
    for (int k = 0; k < D; ++k) {
      const index_t lo = off(k), hi = off(k + 1);
      if (hi == lo) continue;
      mg[k].vcycle(part(r, lo, hi), part(zz, lo, hi), sweeps);
    }
    const double rz_new = dot(r, zz);
    if (restart) {
      parallel_for(n, [&](index_t i) { p(i) = zz(i); });
      restart = false;
    } else {
      const double beta = rz_new / rz;
      parallel_for(n, [&](index_t i) { p(i) = zz(i) + beta * p(i); });
    }
    rz = rz_new;
    if (it >= maxiter) break;
    ++it;
    apply_blocks(cols, vals, off, p, q, tmp);
    const double alpha = rz / dot(p, q);
    parallel_for(n, [&](index_t i) {
      x(i) += alpha * p(i);
      r(i) -= alpha * q(i);
    });
    if (std::sqrt(dot(r, r)) <= tol * bnorm) {
      // the recursive residual can drift from the true one: converged when the true one
      // meets the tolerance too; otherwise go on from it, with a restarted direction
      apply_blocks(cols, vals, off, x, q, tmp);
      parallel_for(n, [&](index_t i) { r(i) = rhs(i) - q(i); });
      const double true_norm = std::sqrt(dot(r, r));
      if (true_norm <= tol * bnorm) return {it, true_norm / bnorm};
      restart = true;
    }
  }
  // the iterations ran out: report the true residual
  apply_blocks(cols, vals, off, x, q, tmp);
  parallel_for(n, [&](index_t i) { q(i) = rhs(i) - q(i); });
  return {it, std::sqrt(dot(q, q)) / bnorm};
}

#define MPMFLOW_VISCOUS(D)                                                                        \
  template void gauss_gradients<D>(const Grid<D>&, View<double, 4>);                              \
  template void cell_viscosity<D>(const Grid<D>&, View<const double>, View<const double>,         \
                                  View<const bool>, double, View<const double, 2>,                \
                                  View<const double>, int, View<const double>, View<double>,      \
                                  View<double>);                                                  \
  template void rate_velocity<D>(View<const double, 2>, View<const index_t>, View<const index_t>, \
                                 View<const bool>, View<const bool, 2>, View<const index_t>,      \
                                 View<const bool>, View<const bool>, View<double, 2>,             \
                                 View<const double, 2>, View<const double, 2>);                   \
  template index_t number_unknowns<D>(                                                            \
      View<const double>, View<const index_t>, View<const index_t>, View<const bool>,             \
      View<const bool, 2>, View<const index_t>, View<const bool>, View<const bool>,               \
      View<const double, 2>, View<double, 2>, View<index_t, 2>, View<index_t>, const Grid<D>*,    \
      View<const double, 2>, View<const double, 2>);                                              \
  template void assemble<D>(const Grid<D>&, View<const double, 4>, View<const double>,            \
                            View<const double>, double, View<const double, 2>,                    \
                            View<const index_t, 2>, View<const index_t>, View<index_t, 3>,        \
                            View<double, 3>, View<double>, View<index_t>, double);                \
  template double operator_force<D>(const Grid<D>&, View<const double, 4>, View<const double>,    \
                                    double, View<const double, 2>, index_t, int);                 \
  template SolveResult solve<D>(const Grid<D>&, View<const index_t, 3>, View<const double, 3>,    \
                                View<const index_t>, View<const index_t>, View<const double>,     \
                                View<double>, double, index_t, int, std::array<Multigrid<D>, D>&, \
                                View<double, 2>);

MPMFLOW_VISCOUS(2)
MPMFLOW_VISCOUS(3)
#undef MPMFLOW_VISCOUS

}  // namespace mpmflow
