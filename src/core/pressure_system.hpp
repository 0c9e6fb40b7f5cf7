// The pressure Poisson system of eq. (13) on the node grid, 2D and 3D: the matrix rows in
// ELL form with the sub-cell (ghost-fluid) free surface, and the right-hand side with the
// wall and obstacle terms. Element integrals come stacked by slot, K[s], C[s], V[s]
// (quadrature.hpp), and cell_slot[c] says which slot cell c uses: -1 = left out of the
// system, 0 = the full-cell Gauss tensors, s > 0 = the cell's own tensors (cut by an
// obstacle, or from its material points).
//
// Free surface (subcell): the coupling of an unknown node i to a node g outside the unknowns
// uses the pressure extrapolated linearly along the edge i-g to p = 0 at the surface
// (ghost_pressure.hpp's ghost_factor); it changes only the diagonal, so the matrix stays
// symmetric. A coupling of the bilinear element is negative in a whole cell, and its
// extrapolation adds to the diagonal. In a cut cell whose fluid part is a sliver, two nodes
// on the same side of it couple positively; their extrapolation (factor 1 - 1/theta <= 0)
// takes from the diagonal, by at most the coupling itself (the factor held at -1 or above,
// theta >= 1/2; exact for a linear pressure there). Leaving such couplings out (p = 0 at g)
// broke the column at rest wherever the surface crosses a sliver: water beside a box whose
// side is 0.3 of a cell off a grid line moved at 2 mm/s within 1 s (docs/method.md,
// "Obstacles"). Without subcell nodes outside the unknowns have p = 0.
#pragma once

#include <array>

#include "grid.hpp"
#include "view.hpp"

namespace mpmflow {

// L of eq. (14) (m^(D-2)) row by row in ELL form: row r (the unknown at node i, node_row[i]
// = r) holds its coupling to the neighbour at offset d in slot sum_k (d_k + 1) 3^k of
// cols/vals (rows x 3^D; column -1 and value 0 where there is none); with rows numbered in
// node order the slots are in increasing column order. Couplings to nodes that are not
// unknowns go to the diagonal through the ghost extrapolation (subcell) or vanish.
// anchored[r]: row r couples to such a node (a system with no anchored row is singular).
template <int D>
void assemble_matrix(const Grid<D>& g, View<const index_t> cell_slot, View<const double, 3> K,
                     View<const index_t> node_row, View<const double> node_f, bool subcell,
                     double theta_min, View<index_t, 2> cols, View<double, 2> vals,
                     View<bool> anchored, View<const double> dep = View<const double>());

// Sum over the wetted wall faces through node i (coordinates ix) of int N_i (v* - u_w).n ds
// (m^3/s in 3D, m^2/s in 2D), counting only the nodes in contact (contact[j, k]: node j
// holds the material at its wall normal to axis k), u_w the wall's velocity there
// (held(j, k); held empty: walls at rest). In a cell an obstacle cuts
// (static_slot >= 1) only the fluid part of the face counts: Wf[s, 2 k + side, a, b] is its
// mass matrix.
template <int D>
double wall_integral(const Grid<D>& g, const std::array<index_t, D>& ix, index_t i,
                     View<const index_t> cell_slot, View<const index_t> static_slot,
                     View<const double, 4> Wf, View<const double, 2> vstar,
                     View<const bool, 2> contact, View<const double, 2> held);

// Sum over the node's cut cells in the system of int N_i ((v* - u).n) ds over the obstacle's
// face (F[s, a, b, k]: the face's integrals of N_a N_b n_k; u: the obstacle's velocity at the
// nodes, oheld, nnodes x D, empty: at rest), counting the obstacle nodes in contact (ocontact).
template <int D>
double obstacle_integral(const Grid<D>& g, const std::array<index_t, D>& ix,
                         View<const index_t> cell_slot, View<const index_t> static_slot,
                         View<const double, 4> F, View<const double, 2> vstar,
                         View<const bool> ocontact, View<const double, 2> oheld = {});

// Rows r0 to r1 - 1 of assemble_rhs (one parallel chunk's range).
template <int D>
void rhs_rows(const Grid<D>& g, index_t r0, index_t r1, View<const index_t> cell_slot,
              View<const double, 4> C, View<const double, 2> V, View<const double> node_vol,
              View<const index_t> row_nodes, View<const double, 2> vstar,
              View<const bool, 2> contact, bool wall_flux, double expansion, double rho_over_dt,
              View<const index_t> static_slot, View<const double, 4> F, View<const double, 4> Wf,
              View<const bool> ocontact, View<const double, 2> held, View<double> rhs,
              View<const double, 2> oheld = {});

// Right-hand side of eq. (13) (Pa m^(D-2)) for every unknown (row_nodes[r]: the node of
// row r):
//   rhs_i = -(rho/dt) sum_e C_e[a_i, b, k] v*_{b,k}                (divergence, eq. 15)
//           + (rho/dt) int_{wetted walls in contact} N_i (v* - u_w).n ds (if wall_flux;
//                                    u_w = held, the walls' velocity: an inlet's inflow)
//           + (rho/dt) int_{obstacle faces in contact} N_i (v* - u_o).n ds (if wall_flux,
//                   F has more than one slot; u_o = oheld, a moving obstacle's velocity)
//           + (rho/dt) expansion max(vol_i - V_i, 0)
// vol_i (node_vol, m^D): the material volume the particles give node i; V_i = sum_e
// V_e[a_i] the node's volume in the system; expansion (1/s) = beta/dt (0 = off). Rows in
// CHUNKS chunks in parallel.
template <int D>
void assemble_rhs(const Grid<D>& g, View<const index_t> cell_slot, View<const double, 4> C,
                  View<const double, 2> V, View<const double> node_vol,
                  View<const index_t> row_nodes, View<const double, 2> vstar,
                  View<const bool, 2> contact, bool wall_flux, double expansion, double rho_over_dt,
                  View<const index_t> static_slot, View<const double, 4> F,
                  View<const double, 4> Wf, View<const bool> ocontact, View<const double, 2> held,
                  View<double> rhs, View<const double, 2> oheld = {});

}  // namespace mpmflow
