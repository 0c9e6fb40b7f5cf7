// A node's cells and its 3^D stencil of couplings, for 2D and 3D (grid.hpp's conventions).
//
// The pressure system couples each node to its neighbours at offsets in {-1, 0, 1}^D through
// the element integrals of the cells around it. These helpers gather them: which of the
// node's 2^D cells take part in the system, the node's corner in each, and the coupling to
// each neighbour summed over the cells, in slot sum_k (d_k + 1) 3^k (the centre is slot
// (3^D - 1) / 2). Cells and corners are visited in the order of their bits, as the Numba
// kernels (kernels/stencil.py) visit them, so sums have the same bits.
//
// Loops over nodes deal slabs of nodes (one index along the last axis) round the CHUNKS
// parallel chunks (for_slabs), so every chunk gets nodes wherever the material is.
#pragma once

#include <array>

#include "grid.hpp"
#include "parallel.hpp"
#include "view.hpp"

namespace mpmflow {

// slot[a][b]: the stencil slot of corner b seen from corner a of the same cell;
// offset[s]: the flat node offset of stencil slot s.
template <int D>
struct StencilTables {
  static constexpr int NC = 1 << D;
  static constexpr int NS = stencil_size(D);
  static constexpr int CENTRE = NS / 2;
  std::array<std::array<int, NC>, NC> slot{};
  std::array<index_t, NS> offset{};
};

// The stencil tables of grid g.
template <int D>
StencilTables<D> tables(const Grid<D>& g) {
  constexpr int NC = 1 << D;
  StencilTables<D> t;
  for (int a = 0; a < NC; ++a)
    for (int b = 0; b < NC; ++b) {
      int s = 0, p3 = 1;
      for (int k = 0; k < D; ++k) {
        s += (((b >> k) & 1) - ((a >> k) & 1) + 1) * p3;
        p3 *= 3;
      }
      t.slot[a][b] = s;
    }
  for (int s = 0; s < StencilTables<D>::NS; ++s) {
    index_t o = 0;
    int r = s;
    for (int k = 0; k < D; ++k) {
      o += (r % 3 - 1) * g.ns[k];
      r /= 3;
    }
    t.offset[s] = o;
  }
  return t;
}

// Cell b (0 <= b < 2^D) of a node: its flat index (-1 when outside the grid), its first
// node, and the node's corner in it. Along a periodic axis the cells wrap round: the first
// plane's node is the upper corner of the last cell (whose upper nodes are the images).
struct NodeCell {
  index_t c;
  index_t first;
  int a;
};

// Cell b of the node with coordinates ix. P = false: the grid has no periodic axis (the
// wrap is compiled out; with_periodic in grid.hpp picks).
template <int D, bool P = true>
inline NodeCell node_cell(const Grid<D>& g, const std::array<index_t, D>& ix, int b) {
  index_t c = 0, first = 0;
  int a = 0;
  for (int k = 0; k < D; ++k) {
    const int bit = (b >> k) & 1;
    index_t j = ix[k] - 1 + bit;
    if constexpr (P) {
      j = g.wrap_cell(k, j);
      if (j < 0) return {-1, 0, 0};
    } else if (j < 0 || j >= g.cells[k]) {
      return {-1, 0, 0};
    }
    c += j * g.cs[k];
    first += j * g.ns[k];
    if (bit == 0) a += 1 << k;
  }
  return {c, first, a};
}

// The neighbour of node i (coordinates ix) at stencil slot s (t.offset[s] away), wrapped
// round periodic axes; -1 beyond a wall.
template <int D, bool P = true>
inline index_t neighbour_node(const Grid<D>& g, index_t i, const std::array<index_t, D>& ix, int s,
                              const StencilTables<D>& t) {
  if (!P || !g.any_periodic) return i + t.offset[s];
  index_t j = 0;
  for (int k = 0; k < D; ++k) {
    const index_t c = g.wrap_node(k, ix[k] + s % 3 - 1);
    if (c < 0) return -1;
    j += c * g.ns[k];
    s /= 3;
  }
  return j;
}

// The cells around the node with coordinates ix that take part in the system
// (cell_slot[c] >= 0): their slot in the element integrals, the node's corner in each and
// each cell's first node. Returns how many (at most 2^D).
template <int D, bool P = true>
inline int node_cells(const Grid<D>& g, const std::array<index_t, D>& ix,
                      View<const index_t> cell_slot, std::array<index_t, (1 << D)>& slots,
                      std::array<int, (1 << D)>& local, std::array<index_t, (1 << D)>& base) {
  int n = 0;
  for (int b = 0; b < (1 << D); ++b) {
    const NodeCell nc = node_cell<D, P>(g, ix, b);
    if (nc.c < 0) continue;
    const index_t s = cell_slot(nc.c);
    if (s < 0) continue;
    slots[n] = s;
    local[n] = nc.a;
    base[n] = nc.first;
    ++n;
  }
  return n;
}

// Couplings sum_e K_e[a_i, b] of the node with coordinates ix to its 3^D neighbours, into
// S (by slot). Returns the number of its cells in the system.
template <int D, bool P = true>
inline int node_stencil(const Grid<D>& g, const std::array<index_t, D>& ix,
                        View<const index_t> cell_slot, View<const double, 3> K,
                        const StencilTables<D>& t, std::array<double, stencil_size(D)>& S,
                        std::array<index_t, (1 << D)>& slots, std::array<int, (1 << D)>& local,
                        std::array<index_t, (1 << D)>& base) {
  constexpr int NC = 1 << D;
  S.fill(0.0);
  const int n = node_cells<D, P>(g, ix, cell_slot, slots, local, base);
  for (int m = 0; m < n; ++m) {
    const int a = local[m];
    for (int b = 0; b < NC; ++b) S[t.slot[a][b]] += K(slots[m], a, b);
  }
  return n;
}

// Coordinates of the first node of a slab (its index along the last axis).
template <int D>
inline void first_of_slab(index_t slab, std::array<index_t, D>& ix) {
  for (int k = 0; k < D - 1; ++k) ix[k] = 0;
  ix[D - 1] = slab;
}

// Step ix to the next point of the slab (axis 0 fastest) on a grid of cells[k] + extra
// points along axis k (extra = 1: nodes, 0: cells).
template <int D>
inline void next_in_slab(const Grid<D>& g, std::array<index_t, D>& ix, int extra = 1) {
  for (int k = 0; k < D - 1; ++k) {
    ix[k] += 1;
    if (ix[k] < g.cells[k] + extra) return;
    ix[k] = 0;
  }
}

// The coordinates of node i into ix.
template <int D>
inline void coords(const Grid<D>& g, index_t i, std::array<index_t, D>& ix) {
  g.node_coords(i, ix.data());
}

// body(i, ix) for every node i (extra = 1) or cell i (extra = 0) of the grid, ix its
// coordinates: slabs along the last axis dealt round CHUNKS chunks in parallel.
template <int D, class F>
void for_slabs(const Grid<D>& g, int extra, F&& body) {
  index_t per = 1;
  for (int k = 0; k < D - 1; ++k) per *= g.cells[k] + extra;
  const index_t nslabs = g.cells[D - 1] + extra;
  for_each_chunk(
      CHUNKS,
      [&](index_t t, index_t, index_t) {
        std::array<index_t, D> ix;
        for (index_t slab = t; slab < nslabs; slab += CHUNKS) {
          first_of_slab<D>(slab, ix);
          for (index_t i = slab * per; i < (slab + 1) * per; ++i) {
            body(i, ix);
            next_in_slab<D>(g, ix, extra);
          }
        }
      },
      per * nslabs);
}

}  // namespace mpmflow
