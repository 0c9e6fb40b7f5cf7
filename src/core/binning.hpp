// Particles to cells: the cell of every particle, the particles grouped by cell (a stable
// counting sort), and the cells' volume fractions theta (eqs. 8-9 of the paper).
#pragma once

#include "grid.hpp"
#include "view.hpp"

namespace mpmflow {

// Flat cell index of every particle (x: n x D). Particles on the upper domain edge go to
// the last cell, beyond the grid to the nearest cell.
template <int D>
void cell_index(const Grid<D>& g, View<const double, 2> x, View<index_t> cell);

// Group particles by cell: the particles of cell c are order[start[c]:start[c + 1]]
// (start: ncells + 1 entries), in their original order.
void counting_sort(View<const index_t> cell, index_t ncells, View<index_t> start,
                   View<index_t> order);

// counting_sort and cell_volume_fraction in one: the volumes are summed into theta in the
// counting pass (particle order within each cell, from 0: the same sums), so the particles
// are read in their own order only.
void sort_with_fraction(View<const index_t> cell, index_t ncells, View<const double> volume,
                        double cell_volume, View<const double> open_, View<index_t> start,
                        View<index_t> order, View<double> theta);

// theta_e = sum of the particle volumes in cell e / cell volume, over the fluid part of a
// cell an obstacle cuts (open_: the fluid fraction).
void cell_volume_fraction(View<const index_t> order, View<const index_t> start,
                          View<const double> volume, double cell_volume, View<const double> open_,
                          View<double> theta);

}  // namespace mpmflow
