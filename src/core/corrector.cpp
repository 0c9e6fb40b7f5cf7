#include "corrector.hpp"

#include <array>

#include "parallel.hpp"
#include "stencil.hpp"

namespace mpmflow {

template <int D>
void correct_velocity(const Grid<D>& g, View<const index_t> cell_slot, View<const double, 4> C,
                      View<const double, 2> V, View<const double> p_node,
                      View<const double, 2> vstar, double dt_over_rho, View<double, 2> v_new) {
  constexpr int NC = Grid<D>::NC;
  with_periodic(g, [&](auto periodic) {
    constexpr bool P = decltype(periodic)::value;
    for_each_chunk(g.nnodes, [&](index_t, index_t lo, index_t hi) {
      std::array<index_t, D> ix;
      g.node_coords(lo, ix.data());
      std::array<index_t, NC> slots, base;
      std::array<int, NC> local;
      for (index_t i = lo; i < hi; ++i) {
        double vol = 0.0;
        std::array<double, D> gp{};
        const int n = node_cells<D, P>(g, ix, cell_slot, slots, local, base);
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
  });
}

template void correct_velocity<2>(const Grid<2>&, View<const index_t>, View<const double, 4>,
                                  View<const double, 2>, View<const double>, View<const double, 2>,
                                  double, View<double, 2>);
template void correct_velocity<3>(const Grid<3>&, View<const index_t>, View<const double, 4>,
                                  View<const double, 2>, View<const double>, View<const double, 2>,
                                  double, View<double, 2>);

}  // namespace mpmflow
