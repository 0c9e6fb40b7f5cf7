#include "../cut_cells.hpp"

#include "arrays.hpp"
#include "modules.hpp"

namespace mpmflow::bind {

void bind_cut_cells(nb::module_& m) {
  m.attr("SLIVER") = SLIVER;
  m.def(
      "cut_cell_tensors",
      [](Array<const double> phi_node, double h, std::vector<index_t> cells,
         Array<const index_t> candidates, index_t nsub, Array<double> K, Array<double> C,
         Array<double> V, Array<double> F, Array<double> Wf, Array<index_t> solid_parts) {
        with_dim(cells.size(), [&](auto d) {
          constexpr int D = decltype(d)::value;
          cut_cell_tensors<D>(make_grid<D>(h, cells), view<const double>(phi_node, "phi_node"),
                              view<const index_t>(candidates, "candidates"), nsub,
                              view<double, 3>(K, "K"), view<double, 4>(C, "C"),
                              view<double, 2>(V, "V"), view<double, 4>(F, "F"),
                              view<double, 4>(Wf, "Wf"), view<index_t>(solid_parts, "solid_parts"));
        });
      },
      "Element integrals, obstacle face terms and wall face terms of the candidate cells.");
  m.def(
      "face_mass",
      [](double h, int dim, Array<double> Wf) {
        with_dim(static_cast<std::size_t>(dim), [&](auto d) {
          constexpr int D = decltype(d)::value;
          face_mass<D>(make_grid<D>(h, std::vector<index_t>(D, 1)), view<double, 3>(Wf, "Wf"));
        });
      },
      "Wf[f, a, b] = int N_a N_b over face f of a whole cell.");
  m.def(
      "push_out",
      [](Array<double> x, Array<double> v, Array<const double> phi_node, double h,
         std::vector<index_t> cells, double margin) {
        return with_dim(cells.size(), [&](auto d) {
          constexpr int D = decltype(d)::value;
          return push_out<D>(make_grid<D>(h, cells), view<double, 2>(x, "x"),
                             view<double, 2>(v, "v"), view<const double>(phi_node, "phi_node"),
                             margin);
        });
      },
      "Move particles inside an obstacle out to phi = margin; returns how many moved.");
  m.def(
      "sliver_fractions",
      [](std::vector<index_t> cells, Array<const double> open_, Array<double> theta) {
        with_dim(cells.size(), [&](auto d) {
          constexpr int D = decltype(d)::value;
          sliver_fractions<D>(make_grid<D>(1.0, cells), view<const double>(open_, "open_"),
                              view<double>(theta, "theta"));
        });
      },
      "Volume fractions of sliver cut cells taken from their neighbours (in place).");
  m.def(
      "extend_velocity",
      [](Array<const index_t> onode, std::vector<index_t> cells, Array<const double> node_mass,
         Array<double> v_old, Array<double> v_star) {
        with_dim(cells.size(), [&](auto d) {
          constexpr int D = decltype(d)::value;
          extend_velocity<D>(make_grid<D>(1.0, cells), view<const index_t>(onode, "onode"),
                             view<const double>(node_mass, "node_mass"),
                             view<double, 2>(v_old, "v_old"), view<double, 2>(v_star, "v_star"));
        });
      },
      "Velocities of massless obstacle nodes from their neighbours (in place).");
}

}  // namespace mpmflow::bind
