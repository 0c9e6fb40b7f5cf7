#pragma once

#include <stdexcept>
#include <type_traits>

#include "grid.hpp"

namespace mpmflow {

template <class F>
decltype(auto) with_dim(std::size_t ndim, F&& f) {
  if (ndim == 2) return f(std::integral_constant<int, 2>{});
  if (ndim == 3) return f(std::integral_constant<int, 3>{});
  throw std::invalid_argument("the grid has 2 or 3 axes");
}

template <int D>
Grid<D> make_grid(double h, const std::vector<index_t>& cells) {
  std::array<index_t, D> c{};
  for (int k = 0; k < D; ++k) c[k] = cells[static_cast<std::size_t>(k)];
  return Grid<D>(h, c);
}

// The grid periodic along the axes where periodic[k] (empty: none). A periodic axis needs
// an even number of cells, at least 4 (grid.hpp); anything else is refused.
template <int D>
Grid<D> make_grid(double h, const std::vector<index_t>& cells, const std::vector<bool>& periodic) {
  const Grid<D> g = make_grid<D>(h, cells);
  if (periodic.empty()) return g;
  if (periodic.size() != static_cast<std::size_t>(D))
    throw std::invalid_argument("periodic: one flag per axis");
  std::array<bool, D> p{};
  for (int k = 0; k < D; ++k) {
    p[k] = periodic[static_cast<std::size_t>(k)];
    if (p[k] && (g.cells[k] < 4 || g.cells[k] % 2 != 0))
      throw std::invalid_argument("a periodic axis needs an even number of cells, at least 4");
  }
  return g.with_periodic(p);
}

}  // namespace mpmflow
