// Sealed pockets of a symmetric system on the grid: parts of the pressure or volume-correction
// system connected to no anchored row (a row coupled to a held value: a free-surface node, an
// empty cell). Water trapped between an obstacle and the domain's walls forms such a part: its
// rows have only Neumann (wall, obstacle) boundaries, the part is singular, and its right-hand
// side need not sum to zero. The solves diverged on it (pressure: relative residual 50 after
// 200 iterations; volume correction: 4.5e5).
#pragma once

#include "view.hpp"

namespace mpmflow {

// Finds the parts of the system (cols, vals: n x ns in ELL form, -1 = no column, symmetric,
// centre slot the diagonal) with no row r where anchored(r) (a callable, as height), and makes each
// solvable: its right-hand side loses its mean over the part (the solvability condition of a
// Neumann problem: the trapped water keeps its volume), and its row with the largest height(r)
// (ties: the lowest r) is held at 0, its couplings removed (the matrix stays symmetric positive
// definite; with a consistent right-hand side the dropped equation holds by itself). The
// solution then is the Neumann solution with 0 at that row. Writes the held rows to
// anchors(0 ...) and
// each row's part to part (pocket number, or -1 outside pockets); order: n of scratch.
// Returns the number of pockets.
template <class Anchored, class Height>
index_t find_pockets(View<index_t, 2> cols, View<double, 2> vals, const Anchored& anchored,
                     const Height& height, View<index_t> part, View<index_t> order,
                     View<index_t> anchors) {
  const index_t n = cols.extent(0);
  const int ns = static_cast<int>(cols.extent(1));
  const int centre = ns / 2;
  for (index_t r = 0; r < n; ++r) part(r) = -2;  // -2: not reached yet
  index_t pockets = 0, end = 0;
  for (index_t seed = 0; seed < n; ++seed) {
    if (part(seed) != -2) continue;
    // breadth-first over the part of seed: its rows are order(begin ... end - 1)
    const index_t begin = end;
    part(seed) = -3;  // -3: in the part being searched
    order(end++) = seed;
    bool open = false;
    index_t top = seed;
    for (index_t q = begin; q < end; ++q) {
      const index_t r = order(q);
      open = open || anchored(r);
      const double hr = height(r), ht = height(top);
      if (hr > ht || (hr == ht && r < top)) top = r;
      for (int s = 0; s < ns; ++s) {
        const index_t j = cols(r, s);
        if (s == centre || j < 0 || part(j) != -2) continue;
        part(j) = -3;
        order(end++) = j;
      }
    }
    for (index_t q = begin; q < end; ++q) part(order(q)) = open ? -1 : pockets;
    if (open) continue;
    for (int s = 0; s < ns; ++s) {
      const index_t j = cols(top, s);
      if (s == centre || j < 0) continue;
      for (int t = 0; t < ns; ++t)
        if (cols(j, t) == top) {
          cols(j, t) = -1;
          vals(j, t) = 0.0;
        }
      cols(top, s) = -1;
      vals(top, s) = 0.0;
    }
    anchors(pockets++) = top;
  }
  return pockets;
}

// The rows a breadth-first walk over the system's couplings (cols: n x ns, -1 = none) reaches
// from the rows where seed(r) is true: reached(r) = 1, else 0; order: n of scratch. On a rank of
// a split run (src/mpmflow/parallel/pockets.py) it is the cheap test before the exact one: when
// every row a rank owns is reached from an owned row next to a free surface, no part of the
// whole system through that rank is sealed. Returns the rows reached.
inline index_t reach(View<const index_t, 2> cols, View<const bool> seed, View<bool> reached,
                     View<index_t> order) {
  const index_t n = cols.extent(0);
  const int ns = static_cast<int>(cols.extent(1));
  index_t end = 0;
  for (index_t r = 0; r < n; ++r) {
    reached(r) = seed(r);
    if (seed(r)) order(end++) = r;
  }
  for (index_t q = 0; q < end; ++q) {
    const index_t r = order(q);
    for (int s = 0; s < ns; ++s) {
      const index_t j = cols(r, s);
      if (j < 0 || reached(j)) continue;
      reached(j) = true;
      order(end++) = j;
    }
  }
  return end;
}

// The right-hand side of the pockets found by find_pockets: its mean over each pocket
// removed, 0 at the held rows. mean: npockets of scratch.
inline void apply_pockets(View<const index_t> part, View<const index_t> anchors, View<double> mean,
                          View<double> count, View<double> rhs) {
  const index_t m = anchors.size();
  if (m == 0) return;
  for (index_t k = 0; k < m; ++k) mean(k) = count(k) = 0.0;
  for (index_t r = 0; r < rhs.size(); ++r)
    if (part(r) >= 0) {
      mean(part(r)) += rhs(r);
      count(part(r)) += 1.0;
    }
  for (index_t r = 0; r < rhs.size(); ++r)
    if (part(r) >= 0) rhs(r) -= mean(part(r)) / count(part(r));
  for (index_t k = 0; k < m; ++k) rhs(anchors(k)) = 0.0;
}

}  // namespace mpmflow
