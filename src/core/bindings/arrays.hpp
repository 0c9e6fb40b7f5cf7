// NumPy arrays as views (no copy): the only place where nanobind types meet the kernels.
#pragma once

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/vector.h>

#include <array>

#include "../dispatch.hpp"
#include "../view.hpp"

namespace mpmflow::bind {

namespace nb = nanobind;

template <class T>
using Array = nb::ndarray<T, nb::c_contig, nb::device::cpu>;

// The array as a view of R dimensions; a clear error if its rank differs.
template <class T, int R = 1, class A>
View<T, R> view(const A& a, const char* name = "array") {
  if (static_cast<int>(a.ndim()) != R)
    throw std::invalid_argument(std::string(name) + ": expected " + std::to_string(R) +
                                " dimensions, got " + std::to_string(a.ndim()));
  std::array<index_t, R> s{};
  for (int k = 0; k < R; ++k) s[k] = static_cast<index_t>(a.shape(k));
  return View<T, R>(static_cast<T*>(const_cast<std::remove_const_t<T>*>(a.data())), s);
}

}  // namespace mpmflow::bind
