#include "../transfer.hpp"

#include <nanobind/stl/optional.h>
#include <nanobind/stl/tuple.h>

#include <optional>

#include "../strips.hpp"
#include "arrays.hpp"
#include "modules.hpp"

namespace mpmflow::bind {

void bind_transfer(nb::module_& m) {
  m.def("flip_per_step", &flip_per_step, nb::arg("flip_rate"), nb::arg("dt"),
        "The FLIP fraction of one step of dt (s): flip_rate^(dt / 1 ms).");
  m.def(
      "particles_to_grid",
      [](Array<const double> x, Array<const double> v, Array<const double> mass,
         Array<const double> volume, Array<const index_t> order, Array<const index_t> start,
         double h, std::vector<index_t> cells, Array<const double> gravity, double dt,
         Array<double> node_mass, Array<double> node_mom, Array<double> node_vol,
         Array<double> v_old, Array<double> v_star, Array<double> cell_vol,
         std::optional<Array<const double>> affine) {
        with_dim(cells.size(), [&](auto d) {
          constexpr int D = decltype(d)::value;
          View<const double, 3> C;
          if (affine) {
            C = view<const double, 3>(*affine, "affine");
            if (C.extent(0) != static_cast<index_t>(x.shape(0)) || C.extent(1) != D ||
                C.extent(2) != D)
              throw std::invalid_argument("affine: one D x D matrix per particle");
          }
          particles_to_grid<D>(
              make_grid<D>(h, cells), view<const double, 2>(x, "x"), view<const double, 2>(v, "v"),
              view<const double>(mass, "mass"), view<const double>(volume, "volume"),
              view<const index_t>(order, "order"), view<const index_t>(start, "start"),
              view<const double>(gravity, "gravity"), dt, view<double>(node_mass, "node_mass"),
              view<double, 2>(node_mom, "node_mom"), view<double>(node_vol, "node_vol"),
              view<double, 2>(v_old, "v_old"), view<double, 2>(v_star, "v_star"),
              view<double>(cell_vol, "cell_vol"), C);
        });
      },
      nb::arg("x"), nb::arg("v"), nb::arg("mass"), nb::arg("volume"), nb::arg("order"),
      nb::arg("start"), nb::arg("h"), nb::arg("cells"), nb::arg("gravity"), nb::arg("dt"),
      nb::arg("node_mass").noconvert(), nb::arg("node_mom").noconvert(),
      nb::arg("node_vol").noconvert(), nb::arg("v_old").noconvert(), nb::arg("v_star").noconvert(),
      nb::arg("cell_vol").noconvert(), nb::arg("affine").none() = nb::none(),
      "Particle-to-grid: nodal mass, momentum, volume, velocity and predictor (and the "
      "volume on the cell centres if cell_vol is not empty); affine (n x D x D): APIC's "
      "matrices, None: FLIP/PIC.");
  m.def(
      "grid_to_particles",
      [](Array<double> x, Array<double> v, Array<double> pressure, double h,
         std::vector<index_t> cells, Array<const double> v_old, Array<const double> v_new,
         Array<const double> p_node, double dt, double flip, Array<const double> upper,
         double margin, std::vector<Array<const double>> faces,
         std::optional<Array<double>> affine) {
        return with_dim(cells.size(), [&](auto d) {
          constexpr int D = decltype(d)::value;
          View<double, 3> C;
          if (affine) {
            C = view<double, 3>(*affine, "affine");
            if (C.extent(0) != static_cast<index_t>(x.shape(0)) || C.extent(1) != D ||
                C.extent(2) != D)
              throw std::invalid_argument("affine: one D x D matrix per particle");
          }
          if (faces.size() != static_cast<std::size_t>(D))
            throw std::invalid_argument("faces: one array per axis");
          std::array<View<const double>, D> f;
          for (int k = 0; k < D; ++k) {
            f[k] = view<const double>(faces[k], "faces");
            index_t n = 1;  // the faces normal to axis k
            for (int j = 0; j < D; ++j) n *= cells[j] + (j == k ? 1 : 0);
            if (faces[0].size() > 0 && f[k].size() != n)
              throw std::invalid_argument("faces: the faces normal to each axis, or empty");
          }
          const std::array<double, D> lower{};  // the grid's box: its lower corner at 0
          return grid_to_particles<D>(
              make_grid<D>(h, cells), view<double, 2>(x, "x"), view<double, 2>(v, "v"),
              view<double>(pressure, "pressure"), view<const double, 2>(v_old, "v_old"),
              view<const double, 2>(v_new, "v_new"), view<const double>(p_node, "p_node"), dt, flip,
              View<const double>(lower.data(), {D}), view<const double>(upper, "upper"), margin, f,
              C);
        });
      },
      nb::arg("x").noconvert(), nb::arg("v").noconvert(), nb::arg("pressure").noconvert(),
      nb::arg("h"), nb::arg("cells"), nb::arg("v_old"), nb::arg("v_new"), nb::arg("p_node"),
      nb::arg("dt"), nb::arg("flip"), nb::arg("upper"), nb::arg("margin"), nb::arg("faces"),
      nb::arg("affine").noconvert().none() = nb::none(),
      "Grid-to-particle (FLIP/PIC, or APIC with affine (n x D x D) given; positions, "
      "pressure, wall put-back); returns how many particles were put back inside.");
  m.def(
      "scatter_mass_pressure",
      [](Array<const double> x, Array<const double> mass, Array<const double> pressure,
         Array<const index_t> order, Array<const index_t> start, double h,
         std::vector<index_t> cells, Array<double> work_m, Array<double> work_mp) {
        with_dim(cells.size(), [&](auto d) {
          constexpr int D = decltype(d)::value;
          scatter_mass_pressure<D>(
              make_grid<D>(h, cells), view<const double, 2>(x, "x"),
              view<const double>(mass, "mass"), view<const double>(pressure, "pressure"),
              view<const index_t>(order, "order"), view<const index_t>(start, "start"),
              view<double>(work_m, "work_m"), view<double>(work_mp, "work_mp"));
        });
      },
      nb::arg("x"), nb::arg("mass"), nb::arg("pressure"), nb::arg("order"), nb::arg("start"),
      nb::arg("h"), nb::arg("cells"), nb::arg("work_m").noconvert(), nb::arg("work_mp").noconvert(),
      "The nodal sums of m_p and m_p p_p (kg, kg Pa) of pressure_noise's smoothing, the "
      "particles grouped by cell (counting_sort's order and start).");
  m.def(
      "pressure_deviation",
      [](Array<const double> x, Array<const double> pressure, double h, std::vector<index_t> cells,
         Array<const double> work_m, Array<const double> work_mp) {
        return with_dim(cells.size(), [&](auto d) {
          constexpr int D = decltype(d)::value;
          return pressure_deviation<D>(make_grid<D>(h, cells), view<const double, 2>(x, "x"),
                                       view<const double>(pressure, "pressure"),
                                       view<const double>(work_m, "work_m"),
                                       view<const double>(work_mp, "work_mp"));
        });
      },
      nb::arg("x"), nb::arg("pressure"), nb::arg("h"), nb::arg("cells"), nb::arg("work_m"),
      nb::arg("work_mp"),
      "The sum over the particles of (p_p - smoothed p)^2 (Pa^2) from the nodal sums.");
  m.def(
      "strips",
      [](Array<const index_t> row_cum, index_t nstrips, index_t min_rows, Array<index_t> bounds) {
        if (row_cum.size() < 1) throw std::invalid_argument("row_cum: at least one entry");
        if (static_cast<index_t>(bounds.size()) < nstrips + 1)
          throw std::invalid_argument("bounds: nstrips + 1 entries");
        return strips(view<const index_t>(row_cum, "row_cum"), nstrips, min_rows,
                      view<index_t>(bounds, "bounds"));
      },
      nb::arg("row_cum"), nb::arg("nstrips"), nb::arg("min_rows"), nb::arg("bounds").noconvert(),
      "Cut rows into at most nstrips strips of at least min_rows rows of about equal work; "
      "returns their number.");
}

}  // namespace mpmflow::bind
