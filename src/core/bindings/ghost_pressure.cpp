#include "../ghost_pressure.hpp"

#include "arrays.hpp"
#include "modules.hpp"

namespace mpmflow::bind {

void bind_ghost_pressure(nb::module_& m) {
  m.def("ghost_factor", &ghost_factor, nb::arg("f_i"), nb::arg("f_g"), nb::arg("theta_min"),
        "(1 - 1/theta): the ghost extrapolation factor p_g / p_i.");
  m.def(
      "ghost_values",
      [](std::vector<index_t> cells, Array<const index_t> cell_slot, Array<const double> K,
         Array<const index_t> node_row, Array<const double> node_f, double theta_min,
         Array<double> p_node) {
        with_dim(cells.size(), [&](auto d) {
          constexpr int D = decltype(d)::value;
          ghost_values<D>(make_grid<D>(1.0, cells), view<const index_t>(cell_slot, "cell_slot"),
                          view<const double, 3>(K, "K"), view<const index_t>(node_row, "node_row"),
                          view<const double>(node_f, "node_f"), theta_min,
                          view<double>(p_node, "p_node"));
        });
      },
      "The pressure at the nodes of the system that are not unknowns (in place).");
}

}  // namespace mpmflow::bind
