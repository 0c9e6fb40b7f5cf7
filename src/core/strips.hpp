// Strips of rows for scatters without races: a scatter whose targets reach one row up or
// down (particle-to-grid over slabs of cells, Galerkin products over slabs of nodes) cuts
// the rows into strips of at least two rows; strips two apart never write to the same
// place, so the even strips run in parallel, then the odd ones. The strips depend on the
// data only, and each strip is summed in row order, so results do not depend on the number
// of threads (kernels/parallel.py's ``strips``).
#pragma once

#include <algorithm>

#include "parallel.hpp"
#include "view.hpp"

namespace mpmflow {

// Scatters cut their rows into at most this many strips (particle-to-grid: 2 STRIPS; the
// multigrid's Galerkin products: STRIPS).
constexpr index_t STRIPS = 16;

// Cut rows 0 to nrows - 1 into at most nstrips strips of at least min_rows rows each,
// holding about equal amounts of work: strip t is rows bounds[t] to bounds[t + 1] - 1.
// row_cum(r) is the work in rows 0 to r - 1 (r = 0 to nrows, non-decreasing); bounds needs
// nstrips + 1 entries. Returns the number of strips (fewer when there are fewer rows; at
// least 1).
template <class F>
index_t strips(index_t nrows, F&& row_cum, index_t nstrips, index_t min_rows, index_t* bounds) {
  const index_t k = std::max<index_t>(1, std::min(nstrips, nrows / min_rows));
  const index_t total = row_cum(nrows);
  bounds[0] = 0;
  for (index_t t = 1; t < k; ++t) {
    const index_t target = total * t / k;
    index_t row = bounds[t - 1] + min_rows;
    const index_t last = nrows - min_rows * (k - t);  // leave room for the strips to come
    while (row < last && row_cum(row) < target) ++row;
    bounds[t] = row;
  }
  bounds[k] = nrows;
  return k;
}

// The same with the cumulative work as a vector of nrows + 1 entries.
inline index_t strips(View<const index_t> row_cum, index_t nstrips, index_t min_rows,
                      View<index_t> bounds) {
  MPMFLOW_BOUNDS(bounds.size() >= nstrips + 1);
  return strips(
      row_cum.size() - 1, [&](index_t r) { return row_cum(r); }, nstrips, min_rows, bounds.data());
}

// body(lo, hi) for the strips [bounds[u], bounds[u + 1]) (u = 0 to nstrips - 1): the even
// strips in parallel, then the odd ones, each strip taken by the next free thread (the
// strips hold equal work only as far as their two-row minimum allows: where the material
// fills a few rows, the first strips hold it all). ``work`` estimates the total work (for
// the serial cut-off of the loops).
template <class F>
void for_strips(const index_t* bounds, index_t nstrips, index_t work, F&& body) {
  for (index_t parity = 0; parity < 2; ++parity) {
    const index_t count = (nstrips - parity + 1) / 2;
    if (count <= 0) continue;
    for_each_task(
        count,
        [&](index_t t) {
          const index_t u = 2 * t + parity;
          body(bounds[u], bounds[u + 1]);
        },
        work);
  }
}

}  // namespace mpmflow
