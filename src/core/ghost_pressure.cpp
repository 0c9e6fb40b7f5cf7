#include "ghost_pressure.hpp"

#include <algorithm>
#include <cmath>

#include "stencil.hpp"

namespace mpmflow {

namespace {
// The coupling-weighted mean over the neighbours j of node i (stencil S, couplings S < 0)
// that weight(j) admits (a finite value), of weight(j) p_node(j); 0 where none does.
template <int D, int NS, class Weight>
double coupling_mean(const Grid<D>& g, index_t i, const std::array<index_t, D>& ix,
                     const StencilTables<D>& t, const std::array<double, NS>& S,
                     View<const double> p_node, Weight weight) {
  constexpr int centre = NS / 2;
  double num = 0.0, den = 0.0;
  for (int s = 0; s < NS; ++s) {
    const double sv = S[s];
    if (s == centre || sv >= 0.0) continue;
    const index_t j = neighbour_node<D>(g, i, ix, s, t);
    const double w = weight(j);
    if (!std::isfinite(w)) continue;
    num -= sv * w * p_node(j);
    den -= sv;
  }
  return den > 0.0 ? num / den : 0.0;
}
}  // namespace

template <int D>
void demote_shallow(const Grid<D>& g, View<const index_t> cell_slot, View<const double, 3> K,
                    View<const index_t> node_row, View<const double> node_f, double theta_c,
                    View<double> dep) {
  constexpr int NC = 1 << D;
  constexpr int NS = stencil_size(D);
  constexpr int centre = NS / 2;
  const StencilTables<D> t = tables<D>(g);
  for_slabs<D>(g, 1, [&](index_t i, const std::array<index_t, D>& ix) {
    dep(i) = -1.0;
    if (node_row(i) < 0) return;
    std::array<double, NS> S;
    std::array<index_t, NC> slots, base;
    std::array<int, NC> local;
    if (node_stencil<D>(g, ix, cell_slot, K, t, S, slots, local, base) == 0) return;
    const double fi = node_f(i);
    double nearest = 1.0;
    for (int s = 0; s < NS; ++s) {
      if (s == centre || S[s] >= 0.0) continue;
      const index_t j = neighbour_node<D>(g, i, ix, s, t);
      if (node_row(j) >= 0 || fi - node_f(j) <= 0.0) continue;
      nearest = std::min(nearest, (fi - 0.5) / (fi - node_f(j)));
    }
    if (nearest < theta_c) dep(i) = std::max(nearest, 0.0);
  });
}

template <int D>
void shallow_values(const Grid<D>& g, View<const index_t> cell_slot, View<const double, 3> K,
                    View<const index_t> node_row, View<const double> dep, View<double> p_node) {
  constexpr int NC = 1 << D;
  constexpr int NS = stencil_size(D);
  const StencilTables<D> t = tables<D>(g);
  for_slabs<D>(g, 1, [&](index_t i, const std::array<index_t, D>& ix) {
    if (dep(i) < 0.0) return;
    std::array<double, NS> S;
    std::array<index_t, NC> slots, base;
    std::array<int, NC> local;
    if (node_stencil<D>(g, ix, cell_slot, K, t, S, slots, local, base) == 0) {
      p_node(i) = 0.0;
      return;
    }
    const double mean = coupling_mean<D, NS>(
        g, i, ix, t, S, p_node, [&](index_t j) { return node_row(j) >= 0 ? 1.0 : NAN; });
    p_node(i) = shallow_factor(dep(i)) * mean;
  });
}

template <int D>
void ghost_values(const Grid<D>& g, View<const index_t> cell_slot, View<const double, 3> K,
                  View<const index_t> node_row, View<const double> node_f, double theta_min,
                  View<double> p_node, View<const double> dep) {
  constexpr int NC = 1 << D;
  constexpr int NS = stencil_size(D);
  const StencilTables<D> t = tables<D>(g);
  const bool with_dep = dep.size() > 0;
  for_slabs<D>(g, 1, [&](index_t i, const std::array<index_t, D>& ix) {
    if (node_row(i) >= 0) return;
    if (with_dep && dep(i) >= 0.0) return;
    std::array<double, NS> S;
    std::array<index_t, NC> slots, base;
    std::array<int, NC> local;
    // no material around the node: none of its cells is in the system (a cell in the
    // system holds particles or is enclosed by f > 1/2 nodes)
    if (node_f(i) == 0.0 || node_stencil<D>(g, ix, cell_slot, K, t, S, slots, local, base) == 0) {
      p_node(i) = 0.0;
      return;
    }
    p_node(i) = coupling_mean<D, NS>(g, i, ix, t, S, p_node, [&](index_t j) {
      const bool source = node_row(j) >= 0 || (with_dep && dep(j) >= 0.0);
      return source ? ghost_factor(node_f(j), node_f(i), theta_min) : NAN;
    });
  });
}

template void demote_shallow<2>(const Grid<2>&, View<const index_t>, View<const double, 3>,
                                View<const index_t>, View<const double>, double, View<double>);
template void demote_shallow<3>(const Grid<3>&, View<const index_t>, View<const double, 3>,
                                View<const index_t>, View<const double>, double, View<double>);
template void shallow_values<2>(const Grid<2>&, View<const index_t>, View<const double, 3>,
                                View<const index_t>, View<const double>, View<double>);
template void shallow_values<3>(const Grid<3>&, View<const index_t>, View<const double, 3>,
                                View<const index_t>, View<const double>, View<double>);
template void ghost_values<2>(const Grid<2>&, View<const index_t>, View<const double, 3>,
                              View<const index_t>, View<const double>, double, View<double>,
                              View<const double>);
template void ghost_values<3>(const Grid<3>&, View<const index_t>, View<const double, 3>,
                              View<const index_t>, View<const double>, double, View<double>,
                              View<const double>);

}  // namespace mpmflow
