#include "../volume_correction.hpp"

#include <nanobind/stl/pair.h>

#include "arrays.hpp"
#include "modules.hpp"

namespace mpmflow::bind {

void bind_volume_correction(nb::module_& m) {
  m.attr("HALF_FULL") = HALF_FULL;
  m.def(
      "cell_volume",
      [](Array<const double> x, Array<const double> volume, double h, std::vector<index_t> cells,
         Array<double> out) {
        with_dim(cells.size(), [&](auto d) {
          constexpr int D = decltype(d)::value;
          cell_volume<D>(make_grid<D>(h, cells), view<const double, 2>(x, "x"),
                         view<const double>(volume, "volume"), view<double>(out, "out"));
        });
      },
      nb::arg("x"), nb::arg("volume"), nb::arg("h"), nb::arg("cells"), nb::arg("out").noconvert(),
      "The particles' volume on the cell centres (m^3).");
  m.def(
      "assemble_volume",
      [](std::vector<index_t> cells, Array<const double> theta, Array<const double> density,
         double wet, Array<const bool> contact, Array<const index_t> static_slot,
         Array<index_t> cell_row, Array<index_t> cols, Array<double> vals, Array<double> rhs,
         Array<index_t> rows) {
        return with_dim(cells.size(), [&](auto d) {
          constexpr int D = decltype(d)::value;
          const Grid<D> g = make_grid<D>(1.0, cells);
          if (cols.ndim() != 2 || static_cast<int>(cols.shape(1)) != Grid<D>::NS)
            throw std::invalid_argument("cols: 3^D slots per row");
          const VolumeSystem s = assemble<D>(
              g, view<const double>(theta, "theta"), view<const double>(density, "density"), wet,
              view<const bool, 2>(contact, "contact"),
              view<const index_t>(static_slot, "static_slot"), view<index_t>(cell_row, "cell_row"),
              view<index_t, 2>(cols, "cols"), view<double, 2>(vals, "vals"),
              view<double>(rhs, "rhs"), view<index_t>(rows, "rows"));
          return std::make_pair(s.n, s.anchored);
        });
      },
      nb::arg("cells"), nb::arg("theta"), nb::arg("density"), nb::arg("wet"), nb::arg("contact"),
      nb::arg("static_slot"), nb::arg("cell_row").noconvert(), nb::arg("cols").noconvert(),
      nb::arg("vals").noconvert(), nb::arg("rhs").noconvert(), nb::arg("rows").noconvert(),
      "The volume correction's Poisson system; returns (rows, whether any row touches air).");
  m.def(
      "face_displacements",
      [](std::vector<index_t> cells, Array<const index_t> cell_row,
         Array<const index_t> static_slot, Array<const double> q, double scale, double dmax,
         std::vector<nb::handle> faces) {
        with_dim(cells.size(), [&](auto d) {
          constexpr int D = decltype(d)::value;
          const Grid<D> g = make_grid<D>(1.0, cells);
          if (faces.size() != static_cast<std::size_t>(D))
            throw std::invalid_argument("faces: one array per axis");
          std::array<View<double>, D> f;
          for (int k = 0; k < D; ++k) {
            index_t n = 1;
            for (int j = 0; j < D; ++j) n *= g.cells[j] + (j == k ? 1 : 0);
            // written: no implicit conversion (a converted copy would take the writes)
            Array<double> a;
            try {
              a = nb::cast<Array<double>>(faces[k], false);
            } catch (const std::exception&) {
              throw std::invalid_argument("faces: C-contiguous float64 arrays");
            }
            if (static_cast<index_t>(a.size()) != n)
              throw std::invalid_argument("faces: the faces normal to each axis");
            f[k] = view<double>(a, "faces");
          }
          face_displacements<D>(g, view<const index_t>(cell_row, "cell_row"),
                                view<const index_t>(static_slot, "static_slot"),
                                view<const double>(q, "q"), scale, dmax, f);
        });
      },
      nb::arg("cells"), nb::arg("cell_row"), nb::arg("static_slot"), nb::arg("q"), nb::arg("scale"),
      nb::arg("dmax"), nb::arg("faces"),
      "The volume correction's displacement on the cell faces (m).");
}

}  // namespace mpmflow::bind
