#include "../corrector.hpp"

#include "arrays.hpp"
#include "modules.hpp"

namespace mpmflow::bind {

void bind_corrector(nb::module_& m) {
  m.def(
      "correct_velocity",
      [](std::vector<index_t> cells, Array<const index_t> cell_slot, Array<const double> C,
         Array<const double> V, Array<const double> p_node, Array<const double> vstar,
         double dt_over_rho, Array<double> v_new) {
        with_dim(cells.size(), [&](auto d) {
          constexpr int D = decltype(d)::value;
          correct_velocity<D>(make_grid<D>(1.0, cells), view<const index_t>(cell_slot, "cell_slot"),
                              view<const double, 4>(C, "C"), view<const double, 2>(V, "V"),
                              view<const double>(p_node, "p_node"),
                              view<const double, 2>(vstar, "vstar"), dt_over_rho,
                              view<double, 2>(v_new, "v_new"));
        });
      },
      nb::arg("cells"), nb::arg("cell_slot"), nb::arg("C"), nb::arg("V"), nb::arg("p_node"),
      nb::arg("vstar"), nb::arg("dt_over_rho"), nb::arg("v_new").noconvert(),
      "The corrector v_new = v* - dt/rho (G p) / V at every node.");
}

}  // namespace mpmflow::bind
