#include "free_surface.hpp"

#include <algorithm>

#include "parallel.hpp"
#include "periodic.hpp"
#include "stencil.hpp"

namespace mpmflow {

template <int D>
void nodal_fraction(const Grid<D>& g, View<const double> theta, View<const double> open_,
                    View<double> node_f, bool swept, double sparse) {
  const auto offset = cell_offsets<D>(g);
  for_slabs<D>(g, 1, [&](index_t i, const std::array<index_t, D>& ix) {
    double fsum = 0.0, ncell = 0.0;
    bool walled = false, filled = true;
    const index_t first = interior_first_cell<D>(g, ix);
    for (int b = 0; b < (1 << D); ++b) {
      const index_t c = first >= 0 ? first + offset[b] : cell_of_node<D>(g, ix, b);
      if (c < 0) continue;
      walled = walled || open_(c) < 1.0;
      if (open_(c) > 0.0) {
        fsum += open_(c) * std::min(theta(c), 1.0);
        ncell += open_(c);
        filled = filled && theta(c) > 0.0 && theta(c) >= sparse;
      }
    }
    node_f(i) = ncell > 0.0 ? (swept && walled && filled ? 1.0 : fsum / ncell) : 0.0;
  });
}

template <int D>
void enclosed_cells(const Grid<D>& g, View<const double> node_f, View<bool> enclosed) {
  for_slabs<D>(g, 0, [&](index_t c, const std::array<index_t, D>& cx) {
    index_t first = 0;
    for (int k = 0; k < D; ++k) first += cx[k] * g.ns[k];
    bool inside = true;
    for (int a = 0; a < (1 << D); ++a)
      if (!(node_f(first + g.corner[a]) > 0.5)) {
        inside = false;
        break;
      }
    enclosed(c) = inside;
  });
}

namespace {
// Number the unknowns of node_row (>= 0, images marked -1) in node order, then give each
// image its master's row; returns their count.
template <int D>
index_t number_masters(const Grid<D>& g, View<index_t> node_row) {
  const index_t n = number(node_row);
  copy_images<D, index_t>(g, node_row.data(), 1);
  return n;
}
}  // namespace

template <int D>
index_t classify_nodes(const Grid<D>& g, View<const index_t> cell_slot,
                       View<const index_t> static_slot, View<const double> node_f, bool subcell,
                       View<index_t> node_row, bool any) {
  const auto offset = cell_offsets<D>(g);
  for_slabs<D>(g, 1, [&](index_t i, const std::array<index_t, D>& ix) {
    bool unknown = !(subcell && node_f(i) <= 0.5);
    bool fluid = false;  // some cell of the node lies outside every solid
    bool some = false;   // some such cell takes part
    const index_t first = interior_first_cell<D>(g, ix);
    for (int b = 0; b < (1 << D); ++b) {
      const index_t c = first >= 0 ? first + offset[b] : cell_of_node<D>(g, ix, b);
      if (c >= 0 && static_slot(c) >= 0) {
        fluid = true;
        if (cell_slot(c) < 0)
          unknown = false;
        else
          some = true;
      }
    }
    if (any) unknown = some;
    node_row(i) = unknown && fluid && !g.is_image(ix.data()) ? 0 : -1;
  });
  return number_masters<D>(g, node_row);
}

template <int D>
index_t renumber_nodes(const Grid<D>& g, View<index_t> node_row) {
  for_slabs<D>(g, 1, [&](index_t i, const std::array<index_t, D>& ix) {
    node_row(i) = node_row(i) >= 0 && !g.is_image(ix.data()) ? 0 : -1;
  });
  return number_masters<D>(g, node_row);
}

index_t number(View<index_t> row) {
  const index_t n = row.size();
  const index_t nchunks = std::min(CHUNKS, std::max<index_t>(n, 1));
  index_t count[CHUNKS + 1];
  for_each_chunk(n, [&](index_t t, index_t lo, index_t hi) {
    index_t m = 0;
    for (index_t i = lo; i < hi; ++i) m += row(i) >= 0;
    count[t] = m;
  });
  const index_t total = exclusive_scan<index_t>(View<const index_t>(count, {nchunks}),
                                                View<index_t>(count, {nchunks + 1}));
  for_each_chunk(n, [&](index_t t, index_t lo, index_t hi) {
    index_t m = count[t];
    for (index_t i = lo; i < hi; ++i)
      if (row(i) >= 0) row(i) = m++;
  });
  return total;
}

template void nodal_fraction<2>(const Grid<2>&, View<const double>, View<const double>,
                                View<double>, bool, double);
template void nodal_fraction<3>(const Grid<3>&, View<const double>, View<const double>,
                                View<double>, bool, double);
template void enclosed_cells<2>(const Grid<2>&, View<const double>, View<bool>);
template void enclosed_cells<3>(const Grid<3>&, View<const double>, View<bool>);
template index_t classify_nodes<2>(const Grid<2>&, View<const index_t>, View<const index_t>,
                                   View<const double>, bool, View<index_t>, bool);
template index_t classify_nodes<3>(const Grid<3>&, View<const index_t>, View<const index_t>,
                                   View<const double>, bool, View<index_t>, bool);
template index_t renumber_nodes<2>(const Grid<2>&, View<index_t>);
template index_t renumber_nodes<3>(const Grid<3>&, View<index_t>);

}  // namespace mpmflow
