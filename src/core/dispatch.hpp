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

}  // namespace mpmflow
