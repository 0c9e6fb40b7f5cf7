// Where the material is, by node: the nodal volume fraction, the cells enclosed by the
// material, and the pressure unknowns (2D and 3D; kernels/surface.py describes the node and
// sub-cell free-surface treatments).
//
// A node's cells are the 2^D cells it is a corner of: cell b (0 <= b < 2^D) has index
// i_k - 1 + ((b >> k) & 1) along axis k. Loops over nodes deal slabs round the parallel
// chunks (stencil.hpp's for_slabs); each result depends on neighbours only.
#pragma once

#include <array>

#include "grid.hpp"
#include "view.hpp"

namespace mpmflow {

// Flat index of cell b of the node with coordinates ix (-1 when outside the grid; wrapped
// round periodic axes).
template <int D>
inline index_t cell_of_node(const Grid<D>& g, const std::array<index_t, D>& ix, int b) {
  index_t c = 0;
  for (int k = 0; k < D; ++k) {
    const index_t j = g.wrap_cell(k, ix[k] - 1 + ((b >> k) & 1));
    if (j < 0) return -1;
    c += j * g.cs[k];
  }
  return c;
}

// The flat offset of a node's cell b from its cell 0 (the one below it along every axis).
template <int D>
inline std::array<index_t, (1 << D)> cell_offsets(const Grid<D>& g) {
  std::array<index_t, (1 << D)> off{};
  for (int b = 0; b < (1 << D); ++b)
    for (int k = 0; k < D; ++k) off[b] += ((b >> k) & 1) * g.cs[k];
  return off;
}

// The node's cell 0 when all 2^D cells of the node lie in the grid (then cell b is this
// plus cell_offsets[b], as cell_of_node gives it), else -1.
template <int D>
inline index_t interior_first_cell(const Grid<D>& g, const std::array<index_t, D>& ix) {
  index_t c = 0;
  for (int k = 0; k < D; ++k) {
    if (ix[k] < 1 || ix[k] >= g.cells[k]) return -1;
    c += (ix[k] - 1) * g.cs[k];
  }
  return c;
}

// Nodal volume fraction node_f (nnodes, dimensionless): the mean of the node's in-domain
// cells' theta, each clipped to 1, weighted by the cells' fluid fraction open_ (a cell
// inside a solid does not count); 0 for a node with no such cell. With swept (a run whose
// obstacles move), a node beside an obstacle (one of its cells cut or solid) all of whose
// open cells hold material (theta > 0 and >= sparse) has node_f = 1: it lies inside the
// material, the obstacle is not air. A face that sweeps through the particles leaves the
// cells beside it half full one step and full the next (a strained lattice's rows crossing
// a cell boundary, or lagging a receding face); without the rule the node between them
// turned into free surface (p = 0) for a step, and a box descending at 1 cm/s felt force
// spikes of 70% of its buoyancy.
template <int D>
void nodal_fraction(const Grid<D>& g, View<const double> theta, View<const double> open_,
                    View<double> node_f, bool swept = false, double sparse = 0.0);

// enclosed[c]: all 2^D nodes of cell c lie inside the material (node_f > 1/2).
template <int D>
void enclosed_cells(const Grid<D>& g, View<const double> node_f, View<bool> enclosed);

// Number the pressure unknowns into node_row (row of each node, -1 = none); returns their
// count. A node is an unknown when all its in-domain cells outside solids (static_slot >= 0)
// take part in the system (cell_slot >= 0), there is at least one such cell and, with
// subcell, node_f > 1/2; with any (a solid's cell pressure, whose nodes mark where the
// material is), when any of those cells takes part. Unknowns are numbered in node order; an
// image node (periodic axes) shares its master's row.
template <int D>
index_t classify_nodes(const Grid<D>& g, View<const index_t> cell_slot,
                       View<const index_t> static_slot, View<const double> node_f, bool subcell,
                       View<index_t> node_row, bool any = false);

// Number again the unknowns of node_row (entries >= 0: an unknown, -1: not; e.g. after a
// caller took some out) as classify_nodes numbers them: in node order, an image node
// (periodic axes) sharing its master's row (the master's entry decides); returns their count.
template <int D>
index_t renumber_nodes(const Grid<D>& g, View<index_t> node_row);

// Number the entries >= 0 of row in order (0, 1, ...); returns how many. A chunked count and
// scan, so it runs in parallel with the serial result.
index_t number(View<index_t> row);

}  // namespace mpmflow
