#include "corrector.hpp"

#include <array>

#include "parallel.hpp"

namespace mpmflow {

namespace {

// The cells around the node with coordinates ix that take part in the system (in the order
// of their bits b: cell ix - 1 + b): their slot in the element integrals, the node's corner
// in each, and each cell's first node. Returns how many (at most 2^D).
template <int D>
int node_cells(const Grid<D>& g, const std::array<index_t, D>& ix, View<const index_t> cell_slot,
               std::array<index_t, Grid<D>::NC>& slots, std::array<int, Grid<D>::NC>& local,
               std::array<index_t, Grid<D>::NC>& base) {
  int n = 0;
  for (int b = 0; b < Grid<D>::NC; ++b) {
    index_t c = 0, first = 0;
    int a = 0;
    bool inside = true;
    for (int k = 0; k < D; ++k) {
      const int bit = (b >> k) & 1;
      const index_t j = ix[k] - 1 + bit;
      if (j < 0 || j >= g.cells[k]) {
        inside = false;
        break;
      }
      c += j * g.cs[k];
      first += j * g.ns[k];
      if (bit == 0) a += 1 << k;
    }
    if (!inside) continue;
    const index_t s = cell_slot(c);
    if (s < 0) continue;
    slots[n] = s;
    local[n] = a;
    base[n] = first;
    ++n;
  }
  return n;
}

}  // namespace

template <int D>
void correct_velocity(const Grid<D>& g, View<const index_t> cell_slot, View<const double, 4> C,
                      View<const double, 2> V, View<const double> p_node,
                      View<const double, 2> vstar, double dt_over_rho, View<double, 2> v_new) {
  constexpr int NC = Grid<D>::NC;
  for_each_chunk(g.nnodes, [&](index_t, index_t lo, index_t hi) {
    std::array<index_t, D> ix;
    g.node_coords(lo, ix.data());
    std::array<index_t, NC> slots, base;
    std::array<int, NC> local;
    for (index_t i = lo; i < hi; ++i) {
      double vol = 0.0;
      std::array<double, D> gp{};
      const int n = node_cells<D>(g, ix, cell_slot, slots, local, base);
      for (int m = 0; m < n; ++m) {
        const index_t s = slots[m];
        const int a = local[m];
        vol += V(s, a);
        for (int b = 0; b < NC; ++b) {
          const double pj = p_node(base[m] + g.corner[b]);
          for (int k = 0; k < D; ++k) gp[k] += C(s, a, b, k) * pj;
        }
      }
      for (int k = 0; k < D; ++k) {
        if (vol > 0.0)
          v_new(i, k) = vstar(i, k) - dt_over_rho * gp[k] / vol;
        else
          v_new(i, k) = vstar(i, k);
      }
      for (int k = 0; k < D; ++k) {  // the next node, axis 0 fastest
        if (++ix[k] <= g.cells[k]) break;
        ix[k] = 0;
      }
    }
  });
}

template void correct_velocity<2>(const Grid<2>&, View<const index_t>, View<const double, 4>,
                                  View<const double, 2>, View<const double>, View<const double, 2>,
                                  double, View<double, 2>);
template void correct_velocity<3>(const Grid<3>&, View<const index_t>, View<const double, 4>,
                                  View<const double, 2>, View<const double>, View<const double, 2>,
                                  double, View<double, 2>);

}  // namespace mpmflow
