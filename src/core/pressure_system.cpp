#include "pressure_system.hpp"

#include <algorithm>

#include "ghost_pressure.hpp"
#include "parallel.hpp"
#include "stencil.hpp"

namespace mpmflow {

template <int D>
void assemble_matrix(const Grid<D>& g, View<const index_t> cell_slot, View<const double, 3> K,
                     View<const index_t> node_row, View<const double> node_f, bool subcell,
                     double theta_min, View<index_t, 2> cols, View<double, 2> vals,
                     View<bool> anchored, View<const double> dep) {
  constexpr int NC = 1 << D;
  constexpr int NS = stencil_size(D);
  constexpr int centre = NS / 2;
  const StencilTables<D> t = tables<D>(g);
  with_periodic(g, [&](auto periodic) {
    constexpr bool P = decltype(periodic)::value;
    for_slabs<D>(g, 1, [&](index_t i, const std::array<index_t, D>& ix) {
      const index_t r = node_row(i);
      if (r < 0 || g.is_image(ix.data())) return;  // an image's row is its master's
      std::array<double, NS> S;
      std::array<index_t, NC> slots, base;
      std::array<int, NC> local;
      node_stencil<D, P>(g, ix, cell_slot, K, t, S, slots, local, base);
      bool anch = false;
      for (int s = 0; s < NS; ++s) {
        const double sv = S[s];
        if (s == centre || sv == 0.0) continue;
        const index_t j = neighbour_node<D, P>(g, i, ix, s, t);
        if (node_row(j) < 0) {
          anch = true;
          if (subcell) {
            const double factor = dep.size() > 0 && dep(j) >= 0.0
                                      ? shallow_factor(dep(j))
                                      : ghost_factor(node_f(i), node_f(j), theta_min);
            S[centre] += sv * (sv < 0.0 ? factor : std::max(factor, -1.0));
          }
          S[s] = 0.0;
        }
      }
      anchored(r) = anch;
      for (int s = 0; s < NS; ++s) {
        const double sv = S[s];
        if (sv == 0.0) {
          cols(r, s) = -1;
          vals(r, s) = 0.0;
        } else {
          cols(r, s) = node_row(neighbour_node<D, P>(g, i, ix, s, t));
          vals(r, s) = sv;
        }
      }
    });
  });
}

template <int D>
double wall_integral(const Grid<D>& g, const std::array<index_t, D>& ix, index_t i,
                     View<const index_t> cell_slot, View<const index_t> static_slot,
                     View<const double, 4> Wf, View<const double, 2> vstar,
                     View<const bool, 2> contact, View<const double, 2> held) {
  constexpr int NC = 1 << D;
  const bool moving = held.size() > 0;
  // the normal velocity through the wall relative to the wall's own
  const auto through = [&](index_t j, int k) {
    return moving ? vstar(j, k) - held(j, k) : vstar(j, k);
  };
  const double hd = D == 2 ? g.h : g.h * g.h;  // h^(D-1)
  double total = 0.0;
  for (int k = 0; k < D; ++k)
    for (int side = 0; side < 2; ++side) {
      if (g.periodic[k]) break;  // no wall across a periodic axis
      const index_t wall = side == 0 ? 0 : g.cells[k];
      if (ix[k] != wall) continue;
      const double sign = side == 0 ? -1.0 : 1.0;
      const int on = side == 0 ? 0 : 1;  // corner bit along k of the nodes on this wall
      for (int b = 0; b < NC; ++b) {
        if (((b >> k) & 1) == on) continue;  // not a cell on this wall
        const NodeCell nc = node_cell<D>(g, ix, b);
        if (nc.c < 0 || cell_slot(nc.c) < 0) continue;
        const index_t ss = static_slot(nc.c);
        if (ss >= 1) {
          double face = 0.0;
          for (int corner = 0; corner < NC; ++corner) {
            const index_t jn = nc.first + g.corner[corner];
            if (contact(jn, k)) face += Wf(ss, 2 * k + side, nc.a, corner) * sign * through(jn, k);
          }
          total += face;
          continue;
        }
        double face = 0.0;
        for (int corner = 0; corner < NC; ++corner) {
          if (((corner >> k) & 1) != on) continue;
          index_t jn = nc.first;
          double denom = 1.0;
          for (int m = 0; m < D; ++m) {
            if ((corner >> m) & 1) jn += g.ns[m];
            if (m != k) denom *= ((corner >> m) & 1) == ((nc.a >> m) & 1) ? 3.0 : 6.0;
          }
          const double vn = contact(jn, k) ? sign * through(jn, k) : 0.0;
          face += vn / denom;
        }
        total += hd * face;
      }
    }
  return total;
}

template <int D>
double obstacle_integral(const Grid<D>& g, const std::array<index_t, D>& ix,
                         View<const index_t> cell_slot, View<const index_t> static_slot,
                         View<const double, 4> F, View<const double, 2> vstar,
                         View<const bool> ocontact, View<const double, 2> oheld) {
  constexpr int NC = 1 << D;
  const bool moving = oheld.size() > 0;
  double total = 0.0;
  for (int b = 0; b < NC; ++b) {
    const NodeCell nc = node_cell<D>(g, ix, b);
    if (nc.c < 0 || cell_slot(nc.c) < 0 || static_slot(nc.c) < 1) continue;
    const index_t s = static_slot(nc.c);
    for (int corner = 0; corner < NC; ++corner) {
      const index_t jn = nc.first + g.corner[corner];
      if (ocontact(jn))
        for (int k = 0; k < D; ++k)
          total += F(s, nc.a, corner, k) * (vstar(jn, k) - (moving ? oheld(jn, k) : 0.0));
    }
  }
  return total;
}

template <int D>
void rhs_rows(const Grid<D>& g, index_t r0, index_t r1, View<const index_t> cell_slot,
              View<const double, 4> C, View<const double, 2> V, View<const double> node_vol,
              View<const index_t> row_nodes, View<const double, 2> vstar,
              View<const bool, 2> contact, bool wall_flux, double expansion, double rho_over_dt,
              View<const index_t> static_slot, View<const double, 4> F, View<const double, 4> Wf,
              View<const bool> ocontact, View<const double, 2> held, View<double> rhs,
              View<const double, 2> oheld) {
  constexpr int NC = 1 << D;
  std::array<index_t, D> ix;
  std::array<index_t, NC> slots, base;
  std::array<int, NC> local;
  with_periodic(g, [&](auto periodic) {
    constexpr bool P = decltype(periodic)::value;
    for (index_t r = r0; r < r1; ++r) {
      const index_t i = row_nodes(r);
      coords<D>(g, i, ix);
      double b = 0.0, vol = 0.0;
      const int n = node_cells<D, P>(g, ix, cell_slot, slots, local, base);
      for (int m = 0; m < n; ++m) {
        const index_t s = slots[m];
        const int a = local[m];
        vol += V(s, a);
        for (int bb = 0; bb < NC; ++bb) {
          const index_t j = base[m] + g.corner[bb];
          double acc = 0.0;
          for (int k = 0; k < D; ++k) acc += C(s, a, bb, k) * vstar(j, k);
          b -= acc;
        }
      }
      const double excess = node_vol(i) - vol;
      if (expansion > 0.0 && excess > 0.0) b += expansion * excess;
      if (wall_flux) {
        b += wall_integral<D>(g, ix, i, cell_slot, static_slot, Wf, vstar, contact, held);
        if (F.extent(0) > 1)
          b += obstacle_integral<D>(g, ix, cell_slot, static_slot, F, vstar, ocontact, oheld);
      }
      rhs(r) = rho_over_dt * b;
    }
  });
}

template <int D>
void assemble_rhs(const Grid<D>& g, View<const index_t> cell_slot, View<const double, 4> C,
                  View<const double, 2> V, View<const double> node_vol,
                  View<const index_t> row_nodes, View<const double, 2> vstar,
                  View<const bool, 2> contact, bool wall_flux, double expansion, double rho_over_dt,
                  View<const index_t> static_slot, View<const double, 4> F,
                  View<const double, 4> Wf, View<const bool> ocontact, View<const double, 2> held,
                  View<double> rhs, View<const double, 2> oheld) {
  for_each_chunk(row_nodes.size(), [&](index_t, index_t lo, index_t hi) {
    rhs_rows<D>(g, lo, hi, cell_slot, C, V, node_vol, row_nodes, vstar, contact, wall_flux,
                expansion, rho_over_dt, static_slot, F, Wf, ocontact, held, rhs, oheld);
  });
}

#define MPMFLOW_INSTANTIATE(D)                                                                     \
  template void assemble_matrix<D>(const Grid<D>&, View<const index_t>, View<const double, 3>,     \
                                   View<const index_t>, View<const double>, bool, double,          \
                                   View<index_t, 2>, View<double, 2>, View<bool>,                  \
                                   View<const double>);                                            \
  template double wall_integral<D>(const Grid<D>&, const std::array<index_t, D>&, index_t,         \
                                   View<const index_t>, View<const index_t>,                       \
                                   View<const double, 4>, View<const double, 2>,                   \
                                   View<const bool, 2>, View<const double, 2>);                    \
  template double obstacle_integral<D>(                                                            \
      const Grid<D>&, const std::array<index_t, D>&, View<const index_t>, View<const index_t>,     \
      View<const double, 4>, View<const double, 2>, View<const bool>, View<const double, 2>);      \
  template void rhs_rows<D>(const Grid<D>&, index_t, index_t, View<const index_t>,                 \
                            View<const double, 4>, View<const double, 2>, View<const double>,      \
                            View<const index_t>, View<const double, 2>, View<const bool, 2>, bool, \
                            double, double, View<const index_t>, View<const double, 4>,            \
                            View<const double, 4>, View<const bool>, View<const double, 2>,        \
                            View<double>, View<const double, 2>);                                  \
  template void assemble_rhs<D>(                                                                   \
      const Grid<D>&, View<const index_t>, View<const double, 4>, View<const double, 2>,           \
      View<const double>, View<const index_t>, View<const double, 2>, View<const bool, 2>, bool,   \
      double, double, View<const index_t>, View<const double, 4>, View<const double, 4>,           \
      View<const bool>, View<const double, 2>, View<double>, View<const double, 2>);
MPMFLOW_INSTANTIATE(2)
MPMFLOW_INSTANTIATE(3)
#undef MPMFLOW_INSTANTIATE

}  // namespace mpmflow
