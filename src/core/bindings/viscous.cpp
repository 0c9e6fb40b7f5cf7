#include "../viscous.hpp"

#include <nanobind/stl/pair.h>

#include <vector>

#include "../rheology.hpp"
#include "arrays.hpp"
#include "modules.hpp"

namespace mpmflow::bind {

void bind_viscous(nb::module_& m) {
  m.attr("WATER") = WATER;
  m.attr("NEWTONIAN") = NEWTONIAN;
  m.attr("HERSCHEL_BULKLEY") = HERSCHEL_BULKLEY;
  m.attr("MU_I") = MU_I;
  m.def(
      "viscosity",
      [](int model, Array<const double> par, double rate, double p) {
        return viscosity(model, view<const double>(par, "par"), rate, p);
      },
      "The effective viscosity (Pa s) of a rheology model at strain rate and pressure.");
  m.def(
      "gauss_gradients",
      [](std::vector<index_t> cells, double h, Array<double> T) {
        with_dim(cells.size(), [&](auto d) {
          constexpr int D = decltype(d)::value;
          gauss_gradients<D>(make_grid<D>(h, cells), view<double, 4>(T, "T"));
        });
      },
      "T[a, b, m, k] = int over a full cell of dN_a/dx_m dN_b/dx_k.");
  m.def(
      "cell_viscosity",
      [](std::vector<index_t> cells, double h, Array<const double> theta, Array<const double> open_,
         Array<const bool> enclosed, double full, Array<const double> v, Array<const double> p_node,
         int model, Array<const double> par, Array<double> eta, Array<double> weight) {
        with_dim(cells.size(), [&](auto d) {
          constexpr int D = decltype(d)::value;
          cell_viscosity<D>(make_grid<D>(h, cells), view<const double>(theta, "theta"),
                            view<const double>(open_, "open_"),
                            view<const bool>(enclosed, "enclosed"), full,
                            view<const double, 2>(v, "v"), view<const double>(p_node, "p_node"),
                            model, view<const double>(par, "par"), view<double>(eta, "eta"),
                            view<double>(weight, "weight"));
        });
      },
      "Each cell's viscosity and viscosity x fluid fraction.");
  m.def(
      "number_unknowns",
      [](Array<const double> node_mass, Array<const index_t> wall_node,
         Array<const index_t> wall_axis, Array<const bool> wall_no_slip, Array<const bool> contact,
         Array<const index_t> onode, Array<const bool> ocontact, Array<const bool> ono_slip,
         Array<const double> vstar, Array<double> u, Array<index_t> row, Array<index_t> off) {
        return with_dim(u.ndim() == 2 ? u.shape(1) : 0, [&](auto d) {
          constexpr int D = decltype(d)::value;
          return number_unknowns<D>(
              view<const double>(node_mass, "node_mass"), view<const index_t>(wall_node),
              view<const index_t>(wall_axis), view<const bool>(wall_no_slip, "wall_no_slip"),
              view<const bool, 2>(contact, "contact"), view<const index_t>(onode),
              view<const bool>(ocontact, "ocontact"), view<const bool>(ono_slip, "ono_slip"),
              view<const double, 2>(vstar, "vstar"), view<double, 2>(u, "u"),
              view<index_t, 2>(row, "row"), view<index_t>(off, "off"));
        });
      },
      "Number the viscous system's unknowns; returns their count.");
  m.def(
      "viscous_assemble",
      [](std::vector<index_t> cells, Array<const double> T, Array<const double> weight,
         Array<const double> node_mass, double dt, Array<const double> u, Array<const index_t> row,
         Array<const index_t> off, Array<index_t> cols, Array<double> vals, Array<double> rhs,
         Array<index_t> node) {
        with_dim(cells.size(), [&](auto d) {
          constexpr int D = decltype(d)::value;
          assemble<D>(make_grid<D>(1.0, cells), view<const double, 4>(T, "T"),
                      view<const double>(weight, "weight"),
                      view<const double>(node_mass, "node_mass"), dt, view<const double, 2>(u, "u"),
                      view<const index_t, 2>(row, "row"), view<const index_t>(off, "off"),
                      view<index_t, 3>(cols, "cols"), view<double, 3>(vals, "vals"),
                      view<double>(rhs, "rhs"), view<index_t>(node, "node"));
        });
      },
      "The viscous system's blocks, right-hand side and the node of each row.");
  m.def(
      "viscous_worst_row",
      [](Array<const index_t> cols, Array<const double> vals, Array<const index_t> off,
         Array<const double> x, Array<const double> rhs) {
        std::vector<double> r(rhs.size()), tmp(rhs.size());
        const index_t n = static_cast<index_t>(rhs.size());
        return worst_row(view<const index_t, 3>(cols, "cols"), view<const double, 3>(vals, "vals"),
                         view<const index_t>(off, "off"), view<const double>(x, "x"),
                         view<const double>(rhs, "rhs"), View<double>(r.data(), {n}),
                         View<double>(tmp.data(), {n}));
      },
      "The row of the largest |rhs - A x| of the viscous system.");
  m.def(
      "viscous_solve",
      [](Array<const index_t> cols, Array<const double> vals, Array<const index_t> node,
         Array<const index_t> off, std::vector<index_t> cells, Array<const double> rhs,
         Array<double> x, double tol, index_t maxiter, int sweeps) {
        return with_dim(cells.size(), [&](auto d) {
          constexpr int D = decltype(d)::value;
          const index_t n = static_cast<index_t>(rhs.size());
          std::array<Multigrid<D>, D> mg;
          std::vector<double> work(static_cast<std::size_t>(5 * n));
          const SolveResult res = solve<D>(
              make_grid<D>(1.0, cells), view<const index_t, 3>(cols, "cols"),
              view<const double, 3>(vals, "vals"), view<const index_t>(node, "node"),
              view<const index_t>(off, "off"), view<const double>(rhs, "rhs"), view<double>(x, "x"),
              tol, maxiter, sweeps, mg, View<double, 2>(work.data(), {5, n}));
          return std::make_pair(res.iterations, res.residual);
        });
      },
      "Block-preconditioned CG of the viscous system; returns (iterations, residual).");
}

}  // namespace mpmflow::bind
