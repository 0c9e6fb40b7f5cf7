#include "binning.hpp"

#include "parallel.hpp"

namespace mpmflow {

template <int D>
void cell_index(const Grid<D>& g, View<const double, 2> x, View<index_t> cell) {
  parallel_for(x.extent(0), [&](index_t p) { cell(p) = g.cell_at(&x(p, 0)); });
}

void counting_sort(View<const index_t> cell, index_t ncells, View<index_t> start,
                   View<index_t> order) {
  for (index_t c = 0; c <= ncells; ++c) start(c) = 0;
  const index_t n = cell.size();
  for (index_t p = 0; p < n; ++p) start(cell(p) + 1) += 1;
  for (index_t c = 0; c < ncells; ++c) start(c + 1) += start(c);
  // fill pointers: start[c] moves up as cell c fills, then is shifted back
  for (index_t p = 0; p < n; ++p) order(start(cell(p))++) = p;
  for (index_t c = ncells; c > 0; --c) start(c) = start(c - 1);
  start(0) = 0;
}

void sort_with_fraction(View<const index_t> cell, index_t ncells, View<const double> volume,
                        double cell_volume, View<const double> open_, View<index_t> start,
                        View<index_t> order, View<double> theta) {
  for (index_t c = 0; c <= ncells; ++c) start(c) = 0;
  for (index_t c = 0; c < ncells; ++c) theta(c) = 0.0;
  const index_t n = cell.size();
  for (index_t p = 0; p < n; ++p) {
    const index_t c = cell(p);
    start(c + 1) += 1;
    theta(c) += volume(p);
  }
  for (index_t c = 0; c < ncells; ++c) start(c + 1) += start(c);
  // fill pointers: start[c] moves up as cell c fills, then is shifted back
  for (index_t p = 0; p < n; ++p) order(start(cell(p))++) = p;
  for (index_t c = ncells; c > 0; --c) start(c) = start(c - 1);
  start(0) = 0;
  const double inv = 1.0 / cell_volume;
  for (index_t c = 0; c < ncells; ++c) {
    theta(c) *= inv;
    if (0.0 < open_(c) && open_(c) < 1.0) theta(c) /= open_(c);
  }
}

void cell_volume_fraction(View<const index_t> order, View<const index_t> start,
                          View<const double> volume, double cell_volume, View<const double> open_,
                          View<double> theta) {
  const double inv = 1.0 / cell_volume;
  parallel_for(theta.size(), [&](index_t c) {
    double total = 0.0;
    for (index_t s = start(c); s < start(c + 1); ++s) total += volume(order(s));
    theta(c) = total * inv;
    if (0.0 < open_(c) && open_(c) < 1.0) theta(c) /= open_(c);
  });
}

template void cell_index<2>(const Grid<2>&, View<const double, 2>, View<index_t>);
template void cell_index<3>(const Grid<3>&, View<const double, 2>, View<index_t>);

}  // namespace mpmflow
