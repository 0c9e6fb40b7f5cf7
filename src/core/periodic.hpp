// Periodic axes: keeping the image nodes (the last plane along a periodic axis) equal to
// their masters (the first plane). grid.hpp says how a periodic grid wraps; these are the
// two operations the step applies to its node arrays:
//   fold_images: after a scatter (particles to grid), the two planes hold the two halves of
//     one node's sum: the master gets the whole, the image a copy of it;
//   copy_images: after values are computed at the masters only (a solve's unknowns), the
//     images get a copy.
// Axes are taken one after the other, so the corners of two or three periodic axes (up to
// 2^D copies of one node) end with the sum of all of them.
#pragma once

#include "grid.hpp"
#include "view.hpp"

namespace mpmflow {

// body(master, image) for every node of the first plane along axis k and its image.
template <int D, class F>
inline void for_image_pairs(const Grid<D>& g, int k, F&& body) {
  const index_t below = g.ns[k];                      // nodes per line below axis k
  const index_t plane = g.nnodes / (g.cells[k] + 1);  // nodes of a plane normal to k
  const index_t jump = g.cells[k] * g.ns[k];
  for (index_t t = 0; t < plane; ++t) {
    const index_t i = t % below + (t / below) * below * (g.cells[k] + 1);
    body(i, i + jump);
  }
}

// a: m values per node (nnodes x m, row-major).
template <int D>
void fold_images(const Grid<D>& g, double* a, index_t m) {
  for (int k = 0; k < D; ++k) {
    if (!g.periodic[k]) continue;
    for_image_pairs<D>(g, k, [&](index_t i, index_t j) {
      for (index_t c = 0; c < m; ++c) {
        a[i * m + c] += a[j * m + c];
        a[j * m + c] = a[i * m + c];
      }
    });
  }
}

template <int D, class T>
void copy_images(const Grid<D>& g, T* a, index_t m) {
  for (int k = 0; k < D; ++k) {
    if (!g.periodic[k]) continue;
    for_image_pairs<D>(g, k, [&](index_t i, index_t j) {
      for (index_t c = 0; c < m; ++c) a[j * m + c] = a[i * m + c];
    });
  }
}

template <int D>
void fold_images(const Grid<D>& g, View<double> a) {
  fold_images<D>(g, a.data(), 1);
}
template <int D>
void fold_images(const Grid<D>& g, View<double, 2> a) {
  fold_images<D>(g, a.data(), a.extent(1));
}
template <int D, class T>
void copy_images(const Grid<D>& g, View<T> a) {
  copy_images<D, T>(g, a.data(), 1);
}
template <int D, class T>
void copy_images(const Grid<D>& g, View<T, 2> a) {
  copy_images<D, T>(g, a.data(), a.extent(1));
}

}  // namespace mpmflow
