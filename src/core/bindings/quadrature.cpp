#include "../quadrature.hpp"

#include "arrays.hpp"
#include "modules.hpp"

namespace mpmflow::bind {

void bind_quadrature(nb::module_& m) {
  m.def(
      "gauss_cell_tensors",
      [](double h, Array<double> K, Array<double> C, Array<double> V) {
        if (C.ndim() != 3) throw std::invalid_argument("C: expected 3 dimensions");
        with_dim(C.shape(2), [&](auto d) {
          constexpr int D = decltype(d)::value;
          std::array<index_t, D> one;
          one.fill(1);
          gauss_cell_tensors<D>(Grid<D>(h, one), view<double, 2>(K, "K"), view<double, 3>(C, "C"),
                                view<double>(V, "V"));
        });
      },
      "Element integrals K, C, V of a full cell of side h (2^D Gauss points).");
  m.def(
      "particle_cell_tensors",
      [](Array<const double> x, Array<const double> volume, Array<const index_t> order,
         Array<const index_t> start, Array<const index_t> cells_list, double h,
         std::vector<index_t> cells, Array<double> K, Array<double> C, Array<double> V) {
        with_dim(cells.size(), [&](auto d) {
          constexpr int D = decltype(d)::value;
          particle_cell_tensors<D>(
              make_grid<D>(h, cells), view<const double, 2>(x, "x"),
              view<const double>(volume, "volume"), view<const index_t>(order, "order"),
              view<const index_t>(start, "start"), view<const index_t>(cells_list, "cells_list"),
              view<double, 3>(K, "K"), view<double, 4>(C, "C"), view<double, 2>(V, "V"));
        });
      },
      "Element integrals of the listed cells with their material points (K may have no rows).");
}

}  // namespace mpmflow::bind
