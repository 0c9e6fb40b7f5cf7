// Element integrals of the pressure system (eqs. 14, 15, 17, 18) from quadrature points, for
// 2D and 3D (corners numbered as in grid.hpp). For one cell, over points with weights w (m^D):
//   K[a, b]    = sum w grad N_a . grad N_b   (Laplacian, eq. 14; m^(D-2))
//   C[a, b, k] = sum w N_a d/dx_k N_b        (divergence, eq. 15, and gradient, eq. 18; m^(D-1))
//   V[a]       = sum w N_a                   (row-sum lumped volume matrix, eq. 17; m^D)
// The points are the 2^D Gauss points of a full cell or the material points of a partial
// cell (the rules: kernels/quadrature.py and the step's cell_integrals).
#pragma once

#include "grid.hpp"
#include "view.hpp"

namespace mpmflow {

// Add one quadrature point at local coordinates local[0..D) (in [0, 1]) with weight w
// (m^D) to K (2^D x 2^D), C (2^D x 2^D x D) and V (2^D). K with no entries is left out.
template <int D>
void accumulate_point(const Grid<D>& g, const double* local, double w, View<double, 2> K,
                      View<double, 3> C, View<double> V);

// Element integrals of a full cell of side g.h with its 2^D Gauss points (exact for
// multilinear products); K, C, V are overwritten.
template <int D>
void gauss_cell_tensors(const Grid<D>& g, View<double, 2> K, View<double, 3> C, View<double> V);

// Element integrals of the listed cells with their material points as quadrature points
// (weights: the particle volumes, m^D): cells_list[m] is a flat cell index, its integrals go
// to K[m], C[m], V[m] (overwritten). K may have no rows: then only C and V. The particles of
// cell c are order[start[c]:start[c + 1]]. Cells in parallel, each writing its own slot.
template <int D>
void particle_cell_tensors(const Grid<D>& g, View<const double, 2> x, View<const double> volume,
                           View<const index_t> order, View<const index_t> start,
                           View<const index_t> cells_list, View<double, 3> K, View<double, 4> C,
                           View<double, 2> V);

}  // namespace mpmflow
