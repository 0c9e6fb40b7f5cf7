#include "../binning.hpp"

#include "arrays.hpp"
#include "modules.hpp"

namespace mpmflow::bind {

void bind_binning(nb::module_& m) {
  m.def(
      "cell_index",
      [](Array<const double> x, double h, std::vector<index_t> cells, Array<index_t> out) {
        with_dim(cells.size(), [&](auto d) {
          constexpr int D = decltype(d)::value;
          cell_index<D>(make_grid<D>(h, cells), view<const double, 2>(x, "x"),
                        view<index_t>(out, "out"));
        });
      },
      "Flat cell index of every particle.");
  m.def("counting_sort", [](Array<const index_t> cell, index_t ncells, Array<index_t> start,
                            Array<index_t> order) {
    counting_sort(view<const index_t>(cell), ncells, view<index_t>(start), view<index_t>(order));
  });
  m.def("cell_volume_fraction",
        [](Array<const index_t> order, Array<const index_t> start, Array<const double> volume,
           double cell_volume, Array<const double> open_, Array<double> theta) {
          cell_volume_fraction(view<const index_t>(order), view<const index_t>(start),
                               view<const double>(volume), cell_volume, view<const double>(open_),
                               view<double>(theta));
        });
}

}  // namespace mpmflow::bind
