// A solid's pressure, one value per cell (Q1-P0), with its traction-free surface natural;
// 2D and 3D.
//
// The fluid's projection puts the pressure on the nodes (Q1-Q1), holds p = 0 at the nodes
// on the free surface and leaves their divergence rows out: the material within half a
// cell of the surface may change its volume freely, and the surface's pressure is 0 where
// a solid's is n.s.n. A fluid does not mind; a solid's surface carries its bending, and a
// cantilever came out five times too soft (docs/method.md, "Solids"). A static check of the
// spatial discretisation alone (Q1 displacements, the particles' quadrature, the deviatoric
// stiffness; docs/method.md) gives the cantilever's tip within 1.4% of beam theory with one
// incompressibility constraint per cell (Q1-P0, the B-bar element's), against 3.3-5.5% with
// a constraint per node including the surface's (Q1-Q1, natural surface) and 10-22% with
// that surface term lumped to the nodes.
//
// Here the pressure lives on the cells with material: p_c for each cell, its constraint
// int_cell div v dV = 0, its force on node i the weak f_i = p_c int_cell grad N_i dV (the
// surface term included: nothing is held at the surface, the traction -p n + s.n is left
// natural, as the deviatoric stress's is). With g_ci = int_cell grad N_i dV over the cell's
// material (the cell's integrals: the particles' in a partial cell), the projection is
// exact:
//   sum_c' (sum_i g_ci . P_i g_c'i / V_i) p_c' = -(rho / dt) sum_i g_ci . v*_i,
//   v_i = v*_i + (dt / rho) P_i sum_c g_ci p_c / V_i,
// V_i the node's volume (its share of the cells' volume integrals, the corrector's lumped
// mass over rho), P_i the projector onto the velocity components no wall or obstacle holds
// (a wall in contact holds its normal component, every component where it is no-slip). The
// cells sharing a node couple, so the matrix has the 3^D stencil on the cell grid (the
// volume correction's), symmetric positive semi-definite; no stabilisation term enters, so
// a static state is a fixed point of the step whatever dt. Q1-P0 is not inf-sup stable: a
// chequerboard of cell pressures can exert no force. The nodal pressure the particles read
// (their pressure, the yield criteria, the bodies' force) is the cells' values carried
// linearly to the nodes and averaged there (cell_to_nodes), which filters it.
#pragma once

#include <array>

#include "grid.hpp"
#include "view.hpp"

namespace mpmflow {

// The cells in the system (cell_slot >= 0) numbered in cell order into cell_row (-1: none)
// and rows (row -> cell); returns their count.
index_t number_cells(View<const index_t> cell_slot, View<index_t> cell_row, View<index_t> rows);

// G (rows x 2^D x D, m^(D-1)): g_ci = int_cell grad N_i dV = sum_b C[s, b, a_i, :] for each
// row's cell and its corner a.
template <int D>
void cell_gradients(const Grid<D>& g, View<const index_t> cell_slot, View<const double, 4> C,
                    View<const index_t> rows, View<double, 3> G);

// vol (nnodes, m^D): V_i = M_i / rho, the node's lumped mass (node_mass, kg) over the
// density (kg/m^3), at the nodes of the cells in the system (0 elsewhere and where M_i = 0).
// The projection's correction -dt / rho P_i sum_c g_ci p_c / V_i is then the pressure force
// over the mass the momentum has (the mass-weighted projection, which does no work). With
// each cell's own volumes instead (the Gauss cells' V = h^D / 2^D per corner, the
// particles' where a cell is partial) it was oblique wherever the particles sit unevenly in
// a full cell, as they do once a solid has moved (up to 90% off the node's mass at a
// cantilever's faces): the linearised step's bending period came out 0.07-0.15 s against
// 0.16 s, and the swinging beam 25% too stiff with 2 x 2 particles a cell, right with 4 x 4
// (docs/method.md, "Solids").
template <int D>
void node_volumes(const Grid<D>& g, View<const index_t> cell_slot, View<const double> node_mass,
                  double rho, View<double> vol);

// P (nnodes x D x D): the projector onto the components of a node's velocity that are not
// held: the identity, less the axis of a wall in contact (every axis on a no-slip wall),
// less an obstacle's normal where it is in contact (everything where it is no-slip).
// Arguments as apply_walls and apply_obstacles take them.
void hold_projector(View<const index_t> wall_node, View<const index_t> wall_axis,
                    View<const bool> wall_no_slip, View<const bool, 2> contact,
                    View<const index_t> onode, View<const double, 2> onormal,
                    View<const bool> ono_slip, View<const bool> ocontact, View<double, 3> P);

// The matrix above, row by row in ELL form on the cell grid (cols/vals: rows x 3^D, slot
// sum_k (d_k + 1) 3^k for the neighbour at offset d; column -1 where there is none). Its
// diagonal carries 1e-12 of itself more: a chequerboard's null space (or a sealed solid's
// constant) would leave the multigrid's coarsest Cholesky without a pivot; the shift holds
// such a mode near 0 and moves the rest by 1e-12 relative.
template <int D>
void assemble_cells(const Grid<D>& g, View<const index_t> cell_row, View<const index_t> rows,
                    View<const double, 3> G, View<const double, 3> P, View<const double> vol,
                    View<index_t, 2> cols, View<double, 2> vals);

// rhs_r = -rho_over_dt sum_i g_ci . v_i (Pa m^(D-2)) for each row's cell c; v: v* with what
// the walls and obstacles hold.
template <int D>
void cell_rhs(const Grid<D>& g, View<const index_t> rows, View<const double, 3> G,
              View<const double, 2> v, double rho_over_dt, View<double> rhs);

// A saturated soil's pore water flowing through its skeleton by Darcy's law (plasticity.hpp,
// POROELASTIC; docs/method.md, "Saturated soil"): the cell pressure is the pore pressure, and
// each cell's constraint is the mixture's volume balance,
//   int_cell div v dV + sum_faces q_cc' = 0,
//   q_cc' = mobility h^(D-1) ((p_c - p_c') / h + rho_w g . e_cc')  (m^D/s, out of c into c'),
// the two-point flux across each face (e_cc' the unit normal from c to c'), with the
// skeleton's velocity v. A face to a cell without material (not in the system, open) is
// drained: p = 0 at the face, half a cell away, so the flux has 2 p_c / h there; a face on a
// wall or to a cell an obstacle closes (open(c') == 0) lets nothing through. With the
// projection's rows multiplied by rho / dt, the flux's matrix joins the Poisson operator
// (darcy_matrix: coef = rho / dt x mobility, on the face neighbours' slots of the 3^D
// stencil) and its gravity part the right-hand side (darcy_gravity: rhs_r -= coef rho_w
// h^(D-1) sum_faces g . e_cc'); darcy_apply adds coef x (the flux's matrix) y to out, for
// the coupled solve's operator, and darcy_magnitude the sizes of the flows. The matrix is symmetric
// positive semi-definite, so the projection stays so; mobility = 0 adds nothing. Hydrostatic water
// in the pores (p_c - p_c' = rho_w g . (x_c' - x_c)) is a zero flux exactly. open: each cell's open
// fraction (empty: no obstacles).
template <int D>
void darcy_matrix(const Grid<D>& g, View<const index_t> cell_row, View<const index_t> rows,
                  View<const double> open, View<const double> water, double coef,
                  View<index_t, 2> cols, View<double, 2> vals);
template <int D>
void darcy_gravity(const Grid<D>& g, View<const index_t> cell_row, View<const index_t> rows,
                   View<const double> open, View<const double> water, double coef, double rho_w,
                   const std::array<double, D>& gravity, View<double> rhs);
template <int D>
void darcy_apply(const Grid<D>& g, View<const index_t> cell_row, View<const index_t> rows,
                 View<const double> open, View<const double> water, double coef,
                 View<const double> y, View<double> out);
// out_r += coef sum_faces |q_cc'| / mobility at the pressure y (gravity included): the size
// of each cell's pore flow, a scale for a solve's tolerance (its flows do not cancel)
template <int D>
void darcy_magnitude(const Grid<D>& g, View<const index_t> cell_row, View<const index_t> rows,
                     View<const double> open, View<const double> water, double coef, double rho_w,
                     const std::array<double, D>& gravity, View<const double> y, View<double> out);

// f_i += sum_c g_ci p_c (N; 2D N/m): the cells' pressure as the nodes' force (nnodes x D).
template <int D>
void add_cell_forces(const Grid<D>& g, View<const index_t> cell_row, View<const double, 3> G,
                     View<const double> p_cell, View<double, 2> f);

// v_new_i = v*_i + dt_over_rho P_i sum_c g_ci p_c / V_i at every node (v* where V_i = 0).
template <int D>
void correct_cells(const Grid<D>& g, View<const index_t> cell_row, View<const double, 3> G,
                   View<const double, 3> P, View<const double> vol, View<const double> p_cell,
                   View<const double, 2> vstar, double dt_over_rho, View<double, 2> v_new);

// The cells' pressure as a field the nodes and particles can read: each cell's value at its
// material's centroid x_c (sum_a V[s, a] x_a / sum_a V[s, a], exact for multilinear N) with
// the least-squares gradient of its neighbours' values (the 3^D cells round it in the
// system), p_node_i = sum_c V[s, a_i] (p_c + grad_c . (x_i - x_c)) / sum_c V[s, a_i] over
// the node's cells (0 where none). Exact for a linear pressure (a solid at rest under
// gravity keeps its hydrostatic pressure at the particles); a chequerboard averages out.
// X, grad: rows x D scratch (m, Pa/m). Empty X: the plain weighted mean of the cells' values
// (no gradient), which the walls' release reads: a node above a surface between nodes
// has a negative linear pressure, and its contact with a side wall would let go.
template <int D>
void cell_to_nodes(const Grid<D>& g, View<const index_t> cell_slot, View<const double, 2> V,
                   View<const index_t> cell_row, View<const index_t> rows,
                   View<const double> p_cell, View<double, 2> X, View<double, 2> grad,
                   View<double> p_node);

// cell_to_nodes in its two halves, for a rank, whose cells round its box need their owners'
// gradients (their neighbours lie past its grid) before the nodes read them: the cells'
// centroids X and gradients grad (empty X: nothing), then the nodes' values from them.
template <int D>
void cell_slopes(const Grid<D>& g, View<const index_t> cell_slot, View<const double, 2> V,
                 View<const index_t> cell_row, View<const index_t> rows, View<const double> p_cell,
                 View<double, 2> X, View<double, 2> grad);
template <int D>
void slopes_to_nodes(const Grid<D>& g, View<const index_t> cell_slot, View<const double, 2> V,
                     View<const index_t> cell_row, View<const double> p_cell,
                     View<const double, 2> X, View<const double, 2> grad, View<double> p_node);

}  // namespace mpmflow
