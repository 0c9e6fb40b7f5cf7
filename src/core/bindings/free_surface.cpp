#include "../free_surface.hpp"

#include "arrays.hpp"
#include "modules.hpp"

namespace mpmflow::bind {

void bind_free_surface(nb::module_& m) {
  m.def(
      "nodal_fraction",
      [](std::vector<index_t> cells, Array<const double> theta, Array<const double> open_,
         Array<double> node_f) {
        with_dim(cells.size(), [&](auto d) {
          constexpr int D = decltype(d)::value;
          nodal_fraction<D>(make_grid<D>(1.0, cells), view<const double>(theta, "theta"),
                            view<const double>(open_, "open_"), view<double>(node_f, "node_f"));
        });
      },
      "Nodal volume fraction from the cells' theta and fluid fraction.");
  m.def(
      "enclosed_cells",
      [](std::vector<index_t> cells, Array<const double> node_f, Array<bool> enclosed) {
        with_dim(cells.size(), [&](auto d) {
          constexpr int D = decltype(d)::value;
          enclosed_cells<D>(make_grid<D>(1.0, cells), view<const double>(node_f, "node_f"),
                            view<bool>(enclosed, "enclosed"));
        });
      },
      "Cells all of whose nodes have a volume fraction above 1/2.");
  m.def(
      "classify_nodes",
      [](std::vector<index_t> cells, Array<const index_t> cell_slot,
         Array<const index_t> static_slot, Array<const double> node_f, bool subcell,
         Array<index_t> node_row) {
        return with_dim(cells.size(), [&](auto d) {
          constexpr int D = decltype(d)::value;
          return classify_nodes<D>(
              make_grid<D>(1.0, cells), view<const index_t>(cell_slot, "cell_slot"),
              view<const index_t>(static_slot, "static_slot"), view<const double>(node_f, "node_f"),
              subcell, view<index_t>(node_row, "node_row"));
        });
      },
      "Number the pressure unknowns into node_row; returns their count.");
  m.def(
      "number", [](Array<index_t> row) { return number(view<index_t>(row, "row")); },
      "Number the entries >= 0 in order; returns how many.");
}

}  // namespace mpmflow::bind
