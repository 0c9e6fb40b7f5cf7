// The corrector of the projection, eq. (16) with the row-sum lumped volume matrix (eq. 17),
// 2D and 3D (kernels/corrector.py): v_i = v*_i - dt/rho (G p)_i / V_i with
// (G p)_i = sum_e C_e[a_i, b, :] p_b and V_i = sum_e V_e[a_i] over the node's cells in the
// system.
#pragma once

#include "grid.hpp"
#include "view.hpp"

namespace mpmflow {

// v_new = v_star - dt_over_rho (G p) / V at every node (m/s); nodes outside every cell of
// the system keep v_star (they carry splashes only). cell_slot: each cell's slot in the
// element integrals (-1: not in the system); C: (slots, 2^D, 2^D, D) divergence integrals
// (m^D-1), V: (slots, 2^D) corner volumes (m^D); p_node: nodal pressure (Pa); dt_over_rho
// (s m^3/kg).
template <int D>
void correct_velocity(const Grid<D>& g, View<const index_t> cell_slot, View<const double, 4> C,
                      View<const double, 2> V, View<const double> p_node,
                      View<const double, 2> vstar, double dt_over_rho, View<double, 2> v_new);

}  // namespace mpmflow
