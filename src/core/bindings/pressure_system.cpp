#include "../pressure_system.hpp"

#include "arrays.hpp"
#include "modules.hpp"

namespace mpmflow::bind {

void bind_pressure_system(nb::module_& m) {
  m.def(
      "assemble_matrix",
      [](std::vector<index_t> cells, Array<const index_t> cell_slot, Array<const double> K,
         Array<const index_t> node_row, Array<const double> node_f, bool subcell, double theta_min,
         Array<index_t> cols, Array<double> vals, Array<bool> anchored) {
        with_dim(cells.size(), [&](auto d) {
          constexpr int D = decltype(d)::value;
          assemble_matrix<D>(make_grid<D>(1.0, cells), view<const index_t>(cell_slot, "cell_slot"),
                             view<const double, 3>(K, "K"),
                             view<const index_t>(node_row, "node_row"),
                             view<const double>(node_f, "node_f"), subcell, theta_min,
                             view<index_t, 2>(cols, "cols"), view<double, 2>(vals, "vals"),
                             view<bool>(anchored, "anchored"));
        });
      },
      "The pressure matrix of eq. (14) in ELL form (rows of 3^D slots).");
  m.def(
      "assemble_rhs",
      [](std::vector<index_t> cells, double h, Array<const index_t> cell_slot,
         Array<const double> C, Array<const double> V, Array<const double> node_vol,
         Array<const index_t> row_nodes, Array<const double> vstar, Array<const bool> contact,
         bool wall_flux, double expansion, double rho_over_dt, Array<const index_t> static_slot,
         Array<const double> F, Array<const double> Wf, Array<const bool> ocontact,
         Array<double> rhs) {
        with_dim(cells.size(), [&](auto d) {
          constexpr int D = decltype(d)::value;
          assemble_rhs<D>(
              make_grid<D>(h, cells), view<const index_t>(cell_slot, "cell_slot"),
              view<const double, 4>(C, "C"), view<const double, 2>(V, "V"),
              view<const double>(node_vol, "node_vol"), view<const index_t>(row_nodes, "row_nodes"),
              view<const double, 2>(vstar, "vstar"), view<const bool, 2>(contact, "contact"),
              wall_flux, expansion, rho_over_dt, view<const index_t>(static_slot, "static_slot"),
              view<const double, 4>(F, "F"), view<const double, 4>(Wf, "Wf"),
              view<const bool>(ocontact, "ocontact"), View<const double, 2>(),
              view<double>(rhs, "rhs"));
        });
      },
      "The right-hand side of eq. (13) for every unknown.");
}

}  // namespace mpmflow::bind
