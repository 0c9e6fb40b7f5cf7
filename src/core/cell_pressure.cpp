#include "cell_pressure.hpp"

#include <array>
#include <cmath>

#include "dense.hpp"
#include "parallel.hpp"
#include "stencil.hpp"

namespace mpmflow {

index_t number_cells(View<const index_t> cell_slot, View<index_t> cell_row, View<index_t> rows) {
  index_t n = 0;
  for (index_t c = 0; c < cell_slot.size(); ++c) {
    if (cell_slot(c) >= 0) {
      cell_row(c) = n;
      rows(n) = c;
      n += 1;
    } else {
      cell_row(c) = -1;
    }
  }
  return n;
}

template <int D>
void cell_gradients(const Grid<D>& g, View<const index_t> cell_slot, View<const double, 4> C,
                    View<const index_t> rows, View<double, 3> G) {
  constexpr int NC = 1 << D;
  parallel_for(rows.size(), [&](index_t r) {
    const index_t s = cell_slot(rows(r));
    for (int a = 0; a < NC; ++a)
      for (int k = 0; k < D; ++k) {
        double sum = 0.0;
        for (int b = 0; b < NC; ++b) sum += C(s, b, a, k);
        G(r, a, k) = sum;
      }
  });
}

// Calls f(c, a) for each cell c of node i (coordinates ix) in the domain, a the node's corner
// in it (periodic axes wrapped).
template <int D, class F>
inline void node_cells_each(const Grid<D>& g, const std::array<index_t, D>& ix, F&& f) {
  for (int b = 0; b < (1 << D); ++b) {
    const NodeCell nc = node_cell<D>(g, ix, b);
    if (nc.c >= 0) f(nc.c, nc.a);
  }
}

// f (D entries) = sum_c g_ci p_c: the cells' pressure as node i's force (coordinates ix)
template <int D>
inline void node_cell_force(const Grid<D>& g, const std::array<index_t, D>& ix,
                            View<const index_t> cell_row, View<const double, 3> G,
                            View<const double> p_cell, double* f) {
  node_cells_each<D>(g, ix, [&](index_t c, int a) {
    const index_t r = cell_row(c);
    if (r < 0) return;
    for (int k = 0; k < D; ++k) f[k] += G(r, a, k) * p_cell(c);
  });
}

template <int D>
void node_volumes(const Grid<D>& g, View<const index_t> cell_slot, View<const double> node_mass,
                  double rho, View<double> vol) {
  parallel_for(g.nnodes, [&](index_t i) {
    std::array<index_t, D> ix;
    g.node_coords(i, ix.data());
    bool counted = false;
    node_cells_each<D>(g, ix, [&](index_t c, int) { counted = counted || cell_slot(c) >= 0; });
    vol(i) = counted ? node_mass(i) / rho : 0.0;
  });
}

void hold_projector(View<const index_t> wall_node, View<const index_t> wall_axis,
                    View<const bool> wall_no_slip, View<const bool, 2> contact,
                    View<const index_t> onode, View<const double, 2> onormal,
                    View<const bool> ono_slip, View<const bool> ocontact, View<double, 3> P) {
  const index_t nn = P.extent(0), D = P.extent(1);
  parallel_for(nn, [&](index_t i) {
    for (index_t k = 0; k < D; ++k)
      for (index_t m = 0; m < D; ++m) P(i, k, m) = k == m ? 1.0 : 0.0;
  });
  const auto zero = [&](index_t i) {
    for (index_t k = 0; k < D; ++k)
      for (index_t m = 0; m < D; ++m) P(i, k, m) = 0.0;
  };
  for (index_t e = 0; e < wall_node.size(); ++e) {
    const index_t i = wall_node(e), k = wall_axis(e);
    if (!contact(i, k)) continue;
    if (wall_no_slip(e)) {
      zero(i);
      continue;
    }
    for (index_t m = 0; m < D; ++m) P(i, k, m) = P(i, m, k) = 0.0;
  }
  for (index_t e = 0; e < onode.size(); ++e) {
    const index_t i = onode(e);
    if (!ocontact(i)) continue;
    if (ono_slip(e)) {
      zero(i);
      continue;
    }
    // less the normal as the wall's projector leaves it (P n): P - (P n)(P n)^T / |P n|^2,
    // still a symmetric projector
    double Pn[3] = {0.0, 0.0, 0.0};
    for (index_t k = 0; k < D; ++k)
      for (index_t m = 0; m < D; ++m) Pn[k] += P(i, k, m) * onormal(e, m);
    double nn2 = 0.0;
    for (index_t k = 0; k < D; ++k) nn2 += Pn[k] * Pn[k];
    if (nn2 <= 0.0) continue;
    for (index_t k = 0; k < D; ++k)
      for (index_t m = 0; m < D; ++m) P(i, k, m) -= Pn[k] * Pn[m] / nn2;
  }
}

template <int D>
void assemble_cells(const Grid<D>& g, View<const index_t> cell_row, View<const index_t> rows,
                    View<const double, 3> G, View<const double, 3> P, View<const double> vol,
                    View<index_t, 2> cols, View<double, 2> vals) {
  constexpr int NC = 1 << D;
  constexpr int NS = stencil_size(D);
  parallel_for(rows.size(), [&](index_t r) {
    for (int s = 0; s < NS; ++s) {
      cols(r, s) = -1;
      vals(r, s) = 0.0;
    }
    const index_t c = rows(r);
    std::array<index_t, D> cx;
    g.cell_coords(c, cx.data());
    for (int a = 0; a < NC; ++a) {
      std::array<index_t, D> ix;
      for (int k = 0; k < D; ++k) ix[k] = cx[k] + ((a >> k) & 1);
      const index_t i = g.cell_first_node(c) + g.corner[a];
      if (!(vol(i) > 0.0)) continue;
      // P_i g_ci / V_i
      double pg[D];
      for (int k = 0; k < D; ++k) {
        pg[k] = 0.0;
        for (int m = 0; m < D; ++m) pg[k] += P(i, k, m) * G(r, a, m);
        pg[k] /= vol(i);
      }
      for (int b = 0; b < NC; ++b) {
        const NodeCell nc = node_cell<D>(g, ix, b);
        if (nc.c < 0) continue;
        const index_t r2 = cell_row(nc.c);
        if (r2 < 0) continue;
        int slot = 0, stride = 1;
        for (int k = 0; k < D; ++k) {
          // the neighbour's offset along k: -1, 0 or 1 (from the corner bits)
          const int d = ((a >> k) & 1) + ((b >> k) & 1) - 1;
          slot += (d + 1) * stride;
          stride *= 3;
        }
        double v = 0.0;
        for (int k = 0; k < D; ++k) v += pg[k] * G(r2, nc.a, k);
        cols(r, slot) = r2;
        vals(r, slot) += v;
      }
    }
    vals(r, NS / 2) *= 1.0 + 1e-12;
    // a cell whose every corner is held whole (its material moves with a tool) constrains
    // nothing: its row decouples with p_c = 0 (its right-hand side vanishes with the
    // held velocities' divergence)
    if (vals(r, NS / 2) == 0.0) vals(r, NS / 2) = 1.0;
  });
}

template <int D>
void cell_rhs(const Grid<D>& g, View<const index_t> rows, View<const double, 3> G,
              View<const double, 2> v, double rho_over_dt, View<double> rhs) {
  constexpr int NC = 1 << D;
  parallel_for(rows.size(), [&](index_t r) {
    const index_t first = g.cell_first_node(rows(r));
    double div = 0.0;
    for (int a = 0; a < NC; ++a) {
      const index_t i = first + g.corner[a];
      for (int k = 0; k < D; ++k) div += G(r, a, k) * v(i, k);
    }
    rhs(r) = -rho_over_dt * div;
  });
}

namespace {

// f(axis, side (-1 or 1), neighbour's row (-1: none), wp, wg) for each face of row r's cell
// through which pore water flows, wp and wg the weights of its pressure difference and of
// its gravity term (cell_pressure.hpp): between two cells of soil (1, 1); between soil and
// free water (2, 2: the water's half of the path has no resistance, its pressure
// hydrostatic to the face); from soil to a cell without material (drained: the neighbour's
// row -1, p = 0 at the face; 2, 1). Not through a wall, into a cell an obstacle closes,
// between two cells of free water (its own velocity carries it) or from free water to an
// empty cell. water: each cell's share of free water (empty: none; half or more: the free
// water's cell).
template <int D, class F>
void darcy_faces(const Grid<D>& g, View<const index_t> cell_row, View<const index_t> rows,
                 View<const double> open, View<const double> water, index_t r, F&& f) {
  std::array<index_t, D> cx;
  const index_t c = rows(r);
  g.cell_coords(c, cx.data());
  const bool wet = water.size() > 0 && water(c) >= 0.5;
  for (int k = 0; k < D; ++k)
    for (int side = -1; side <= 1; side += 2) {
      const index_t j = g.wrap_cell(k, cx[k] + side);
      if (j < 0) continue;  // a wall
      index_t c2 = 0;
      for (int m = 0; m < D; ++m) c2 += (m == k ? j : cx[m]) * g.cs[m];
      const index_t r2 = cell_row(c2);
      if (r2 >= 0) {
        const bool wet2 = water.size() > 0 && water(c2) >= 0.5;
        if (wet && wet2) continue;
        const double w = wet == wet2 ? 1.0 : 2.0;
        f(k, side, r2, w, w);
      } else if (!wet && (open.size() == 0 || open(c2) > 0.0)) {
        f(k, side, index_t(-1), 2.0, 1.0);
      }
    }
}

}  // namespace

template <int D>
void darcy_matrix(const Grid<D>& g, View<const index_t> cell_row, View<const index_t> rows,
                  View<const double> open, View<const double> water, double coef,
                  View<index_t, 2> cols, View<double, 2> vals) {
  constexpr int NS = stencil_size(D);
  if (coef == 0.0) return;
  const double tau = coef * int_power(g.h, D - 2);  // coef h^(D-1) / h
  parallel_for(rows.size(), [&](index_t r) {
    darcy_faces<D>(g, cell_row, rows, open, water, r,
                   [&](int k, int side, index_t r2, double wp, double) {
                     vals(r, NS / 2) += wp * tau;
                     if (r2 < 0) return;
                     int stride = 1;
                     for (int m = 0; m < k; ++m) stride *= 3;
                     const int slot = NS / 2 + side * stride;
                     cols(r, slot) = r2;
                     vals(r, slot) -= wp * tau;
                   });
  });
}

template <int D>
void darcy_gravity(const Grid<D>& g, View<const index_t> cell_row, View<const index_t> rows,
                   View<const double> open, View<const double> water, double coef, double rho_w,
                   const std::array<double, D>& gravity, View<double> rhs) {
  if (coef == 0.0) return;
  const double face = coef * rho_w * int_power(g.h, D - 1);
  parallel_for(rows.size(), [&](index_t r) {
    double sum = 0.0;
    darcy_faces<D>(
        g, cell_row, rows, open, water, r,
        [&](int k, int side, index_t, double, double wg) { sum += wg * side * gravity[k]; });
    rhs(r) -= face * sum;
  });
}

template <int D>
void darcy_apply(const Grid<D>& g, View<const index_t> cell_row, View<const index_t> rows,
                 View<const double> open, View<const double> water, double coef,
                 View<const double> y, View<double> out) {
  if (coef == 0.0) return;
  const double tau = coef * int_power(g.h, D - 2);
  parallel_for(rows.size(), [&](index_t r) {
    double sum = 0.0;
    darcy_faces<D>(g, cell_row, rows, open, water, r, [&](int, int, index_t r2, double wp, double) {
      sum += wp * (r2 < 0 ? y(r) : y(r) - y(r2));
    });
    out(r) += tau * sum;
  });
}

template <int D>
void darcy_magnitude(const Grid<D>& g, View<const index_t> cell_row, View<const index_t> rows,
                     View<const double> open, View<const double> water, double coef, double rho_w,
                     const std::array<double, D>& gravity, View<const double> y, View<double> out) {
  if (coef == 0.0) return;
  const double tau = int_power(g.h, D - 2), face = rho_w * int_power(g.h, D - 1);
  parallel_for(rows.size(), [&](index_t r) {
    double sum = 0.0;
    darcy_faces<D>(g, cell_row, rows, open, water, r,
                   [&](int k, int side, index_t r2, double wp, double wg) {
                     const double dp = r2 < 0 ? y(r) : y(r) - y(r2);
                     sum += std::abs(wp * tau * dp + wg * face * side * gravity[k]);
                   });
    out(r) += coef * sum;
  });
}

template <int D>
void add_cell_forces(const Grid<D>& g, View<const index_t> cell_row, View<const double, 3> G,
                     View<const double> p_cell, View<double, 2> f) {
  parallel_for(g.nnodes, [&](index_t i) {
    std::array<index_t, D> ix;
    g.node_coords(i, ix.data());
    double fi[D] = {};
    node_cell_force<D>(g, ix, cell_row, G, p_cell, fi);
    for (int k = 0; k < D; ++k) f(i, k) += fi[k];
  });
}

template <int D>
void correct_cells(const Grid<D>& g, View<const index_t> cell_row, View<const double, 3> G,
                   View<const double, 3> P, View<const double> vol, View<const double> p_cell,
                   View<const double, 2> vstar, double dt_over_rho, View<double, 2> v_new) {
  parallel_for(g.nnodes, [&](index_t i) {
    std::array<index_t, D> ix;
    g.node_coords(i, ix.data());
    double f[D] = {};
    node_cell_force<D>(g, ix, cell_row, G, p_cell, f);
    for (int k = 0; k < D; ++k) {
      double pf = 0.0;
      for (int m = 0; m < D; ++m) pf += P(i, k, m) * f[m];
      v_new(i, k) = vstar(i, k) + (vol(i) > 0.0 ? dt_over_rho * pf / vol(i) : 0.0);
    }
  });
}

template <int D>
void cell_slopes(const Grid<D>& g, View<const index_t> cell_slot, View<const double, 2> V,
                 View<const index_t> cell_row, View<const index_t> rows, View<const double> p_cell,
                 View<double, 2> X, View<double, 2> grad) {
  constexpr int NC = 1 << D;
  const index_t n = X.size() > 0 ? rows.size() : 0;
  // each cell's material centroid
  parallel_for(n, [&](index_t r) {
    const index_t c = rows(r), s = cell_slot(c);
    std::array<index_t, D> cx;
    g.cell_coords(c, cx.data());
    double w = 0.0, x[D] = {};
    for (int a = 0; a < NC; ++a) {
      w += V(s, a);
      for (int k = 0; k < D; ++k)
        x[k] += V(s, a) * g.h * static_cast<double>(cx[k] + ((a >> k) & 1));
    }
    for (int k = 0; k < D; ++k) X(r, k) = w > 0.0 ? x[k] / w : g.h * (cx[k] + 0.5);
  });
  // the least-squares gradient over the neighbours in the system (periodic axes: the
  // neighbour's centroid moved by the period)
  parallel_for(n, [&](index_t r) {
    const index_t c = rows(r);
    std::array<index_t, D> cx;
    g.cell_coords(c, cx.data());
    double A[D][D] = {}, b[D] = {};
    const int total = stencil_size(D);
    for (int q = 0; q < total; ++q) {
      index_t c2 = 0;
      double shift[D] = {};
      bool inside = true;
      int rem = q;
      for (int k = 0; k < D; ++k) {
        const index_t d = rem % 3 - 1;
        rem /= 3;
        index_t j = cx[k] + d;
        if (j < 0 || j >= g.cells[k]) {
          if (!g.periodic[k]) {
            inside = false;
            break;
          }
          shift[k] = (j < 0 ? -1.0 : 1.0) * g.h * static_cast<double>(g.cells[k]);
          j = g.wrap_cell(k, j);
        }
        c2 += j * g.cs[k];
      }
      if (!inside || c2 == c) continue;
      const index_t r2 = cell_row(c2);
      if (r2 < 0) continue;
      double dx[D];
      for (int k = 0; k < D; ++k) dx[k] = X(r2, k) + shift[k] - X(r, k);
      const double dp = p_cell(c2) - p_cell(c);
      for (int k = 0; k < D; ++k) {
        b[k] += dx[k] * dp;
        for (int m = 0; m < D; ++m) A[k][m] += dx[k] * dx[m];
      }
    }
    // A grad = b; where the neighbours do not span every direction (a column one cell wide)
    // the cell keeps no gradient at all
    const bool spans = solve_dense(D, &A[0][0], b, 1e-12 * g.h * g.h);
    for (int k = 0; k < D; ++k) grad(r, k) = spans ? b[k] : 0.0;
  });
}

template <int D>
void slopes_to_nodes(const Grid<D>& g, View<const index_t> cell_slot, View<const double, 2> V,
                     View<const index_t> cell_row, View<const double> p_cell,
                     View<const double, 2> X, View<const double, 2> grad, View<double> p_node) {
  const bool linear = X.size() > 0;
  parallel_for(g.nnodes, [&](index_t i) {
    std::array<index_t, D> ix;
    g.node_coords(i, ix.data());
    double sum = 0.0, w = 0.0;
    node_cells_each<D>(g, ix, [&](index_t c, int a) {
      const index_t r = cell_row(c);
      if (r < 0) return;
      const index_t s = cell_slot(c);
      // the node as a corner of this cell (across a periodic end: the cell's own corner)
      std::array<index_t, D> cx;
      g.cell_coords(c, cx.data());
      double p = p_cell(c);
      for (int k = 0; k < D && linear; ++k) {
        const double xi = g.h * static_cast<double>(cx[k] + ((a >> k) & 1));
        p += grad(r, k) * (xi - X(r, k));
      }
      sum += V(s, a) * p;
      w += V(s, a);
    });
    p_node(i) = w > 0.0 ? sum / w : 0.0;
  });
}

template <int D>
void cell_to_nodes(const Grid<D>& g, View<const index_t> cell_slot, View<const double, 2> V,
                   View<const index_t> cell_row, View<const index_t> rows,
                   View<const double> p_cell, View<double, 2> X, View<double, 2> grad,
                   View<double> p_node) {
  cell_slopes<D>(g, cell_slot, V, cell_row, rows, p_cell, X, grad);
  slopes_to_nodes<D>(g, cell_slot, V, cell_row, p_cell, X, grad, p_node);
}

#define MPMFLOW_INSTANTIATE(D)                                                                     \
  template void cell_gradients<D>(const Grid<D>&, View<const index_t>, View<const double, 4>,      \
                                  View<const index_t>, View<double, 3>);                           \
  template void node_volumes<D>(const Grid<D>&, View<const index_t>, View<const double>, double,   \
                                View<double>);                                                     \
  template void assemble_cells<D>(const Grid<D>&, View<const index_t>, View<const index_t>,        \
                                  View<const double, 3>, View<const double, 3>,                    \
                                  View<const double>, View<index_t, 2>, View<double, 2>);          \
  template void cell_rhs<D>(const Grid<D>&, View<const index_t>, View<const double, 3>,            \
                            View<const double, 2>, double, View<double>);                          \
  template void darcy_matrix<D>(const Grid<D>&, View<const index_t>, View<const index_t>,          \
                                View<const double>, View<const double>, double, View<index_t, 2>,  \
                                View<double, 2>);                                                  \
  template void darcy_gravity<D>(const Grid<D>&, View<const index_t>, View<const index_t>,         \
                                 View<const double>, View<const double>, double, double,           \
                                 const std::array<double, D>&, View<double>);                      \
  template void darcy_apply<D>(const Grid<D>&, View<const index_t>, View<const index_t>,           \
                               View<const double>, View<const double>, double, View<const double>, \
                               View<double>);                                                      \
  template void darcy_magnitude<D>(const Grid<D>&, View<const index_t>, View<const index_t>,       \
                                   View<const double>, View<const double>, double, double,         \
                                   const std::array<double, D>&, View<const double>,               \
                                   View<double>);                                                  \
  template void add_cell_forces<D>(const Grid<D>&, View<const index_t>, View<const double, 3>,     \
                                   View<const double>, View<double, 2>);                           \
  template void correct_cells<D>(const Grid<D>&, View<const index_t>, View<const double, 3>,       \
                                 View<const double, 3>, View<const double>, View<const double>,    \
                                 View<const double, 2>, double, View<double, 2>);                  \
  template void cell_to_nodes<D>(const Grid<D>&, View<const index_t>, View<const double, 2>,       \
                                 View<const index_t>, View<const index_t>, View<const double>,     \
                                 View<double, 2>, View<double, 2>, View<double>);                  \
  template void cell_slopes<D>(const Grid<D>&, View<const index_t>, View<const double, 2>,         \
                               View<const index_t>, View<const index_t>, View<const double>,       \
                               View<double, 2>, View<double, 2>);                                  \
  template void slopes_to_nodes<D>(const Grid<D>&, View<const index_t>, View<const double, 2>,     \
                                   View<const index_t>, View<const double>, View<const double, 2>, \
                                   View<const double, 2>, View<double>);
MPMFLOW_INSTANTIATE(2)
MPMFLOW_INSTANTIATE(3)
#undef MPMFLOW_INSTANTIATE

}  // namespace mpmflow
