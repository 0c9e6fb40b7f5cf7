// The implicit viscous predictor (docs/method.md, "Viscous materials"), 2D and 3D.
//
// Before the pressure step, the predicted velocity v* becomes the solution u of
//
//     M/dt (u - v*) = -K_visc u,   (K_visc u)_(i,k) = sum_e c_e int dN_i/dx_m (du_k/dx_m +
//     du_m/dx_k)
//
// the backward-Euler step of the full deviatoric stress tau = 2 eta D(u). M is the lumped
// nodal mass (kg), c_e = eta_e w_e with eta_e the cell's viscosity (Pa s, rheology.hpp) and
// w_e its fluid fraction; the element integrals are the full-cell Gauss tensors
// T[a, b, m, k] = int dN_a/dx_m dN_b/dx_k. The free surface is traction-free. Walls: the normal
// component of a wall node keeps v*; a no-slip wall or obstacle holds the tangential velocity
// at 0 where the material presses on it or rests.
//
// The system is symmetric positive definite, stored as D x D blocks in ELL form (cols, vals:
// D x n x 3^D; block (k, m) = rows of component k, columns of component m numbered within
// component m), and solved by conjugate gradients preconditioned with one multigrid V-cycle
// of each diagonal block. See src/mpmflow/kernels/viscous.py (the Numba original).
#pragma once

#include <array>

#include "grid.hpp"
#include "multigrid.hpp"
#include "view.hpp"

namespace mpmflow {

// T[a, b, m, k] = int over a full cell of dN_a/dx_m dN_b/dx_k (m^(D-2)), by 2^D Gauss points
// (exact for multilinear N). T: 2^D x 2^D x D x D.
template <int D>
void gauss_gradients(const Grid<D>& g, View<double, 4> T);

// Each cell's viscosity eta (Pa s) at the strain rate of the nodal velocity v (nn x D, m/s)
// at its centre and the mean of its corners' pressure p_node (Pa; negative counts as 0),
// and weight = eta x its fluid fraction (1 where theta >= full or enclosed, else theta)
// x open_ (the part an obstacle leaves open); both 0 in cells without material (theta <= 0
// and not enclosed). model, par: the rheology's code and parameters (rheology.hpp).
template <int D>
void cell_viscosity(const Grid<D>& g, View<const double> theta, View<const double> open_,
                    View<const bool> enclosed, double full, View<const double, 2> v,
                    View<const double> p_node, int model, View<const double> par, View<double> eta,
                    View<double> weight);

// The velocity whose strain rate sets the cells' viscosity (cell_viscosity): the nodal
// velocity v (nn x D, the particles' velocity on the grid) with the nodes the solve holds
// set to their held value: a no-slip wall pair's node (wall_no_slip(e)) where contact(i,
// axis) to its wall's velocity (held, nn x D; empty: 0; an inlet's inflow), a no-slip
// obstacle node where ocontact(i) to its velocity (oheld, nn x D; empty: 0; a moving body's,
// bodies.hpp) (the holds of number_unknowns). On the grid of the particles
// a wall node reads the mean velocity of the particles above it (a third of the first node's in a
// sheared layer), so the cell on the wall read about half its shear rate and a yield-stress
// material held there at twice its yield stress (docs/method.md, "Viscous materials").
template <int D>
void rate_velocity(View<const double, 2> v, View<const index_t> wall_node,
                   View<const index_t> wall_axis, View<const bool> wall_no_slip,
                   View<const bool, 2> contact, View<const index_t> onode,
                   View<const bool> ocontact, View<const bool> ono_slip, View<double, 2> out,
                   View<const double, 2> held = {}, View<const double, 2> oheld = {});

// The unknowns and held values of the system: u (nn x D) = vstar with the no-slip contacts
// set to their wall's velocity (held, nn x D; empty: 0, walls at rest; an inlet's inflow); row(i,
// k) the unknown's number (component by component, each in node order), -1 where held or massless;
// off (D + 1) the first row of each component. Walls: entries (wall_node, wall_axis, wall_no_slip),
// whose normal component is held (at vstar); a no-slip pair holds every component of its node at 0
// where contact(i, axis) (nn x D). Obstacles: entries onode, held (all components, at oheld: a
// moving body's velocity, nn x D; empty: 0) where no-slip (ono_slip) and ocontact(i) (nn). contact
// and ocontact are the pressure step's starting contact (start_contact, start_obstacles), so that
// the viscous solve holds exactly the nodes the corrector will. Returns the number of unknowns.
template <int D>
index_t number_unknowns(View<const double> node_mass, View<const index_t> wall_node,
                        View<const index_t> wall_axis, View<const bool> wall_no_slip,
                        View<const bool, 2> contact, View<const index_t> onode,
                        View<const bool> ocontact, View<const bool> ono_slip,
                        View<const double, 2> vstar, View<double, 2> u, View<index_t, 2> row,
                        View<index_t> off, const Grid<D>* grid = nullptr,
                        View<const double, 2> held = {}, View<const double, 2> oheld = {});

// The system for the unknowns of number_unknowns (n of them): cols(m, r, s), vals(m, r, s)
// (D x n x 3^D, kg/s) the couplings of row r to component m (columns numbered within
// component m, -1 empty), rhs (n, kg m/s^2) = M/dt u with the held values moved to it, and
// node(r) the node of row r. T from gauss_gradients, weight from cell_viscosity (Pa s), dt (s).
// grad_div: a compressible elastic skeleton's lambda / G (plasticity.hpp, POROELASTIC), whose
// stiffness weight x grad_div int div(u) div(w) joins the deviatoric one (0: none).
template <int D>
void assemble(const Grid<D>& g, View<const double, 4> T, View<const double> weight,
              View<const double> node_mass, double dt, View<const double, 2> u,
              View<const index_t, 2> row, View<const index_t> off, View<index_t, 3> cols,
              View<double, 3> vals, View<double> rhs, View<index_t> node, double grad_div = 0.0);

// The elastic (viscous) operator's force at node i along axis k for the nodal velocity x
// (nn x D): (K x)_(i,k), the row of assemble's system without its mass term, at any node
// (a held one's too: the force its hold takes). Arguments as assemble's.
template <int D>
double operator_force(const Grid<D>& g, View<const double, 4> T, View<const double> weight,
                      double grad_div, View<const double, 2> x, index_t i, int k);

// y = A x block by block (the Numba _apply); tmp: scratch of n values.
void apply_blocks(View<const index_t, 3> cols, View<const double, 3> vals, View<const index_t> off,
                  View<const double> x, View<double> y, View<double> tmp);

// The row of the largest |rhs - A x| (NaN counts as largest); r, tmp: scratch of n values.
index_t worst_row(View<const index_t, 3> cols, View<const double, 3> vals, View<const index_t> off,
                  View<const double> x, View<const double> rhs, View<double> r, View<double> tmp);

// Block-preconditioned CG from the initial guess in x (updated in place; m/s); stops when
// ||rhs - A x|| <= tol ||rhs|| or after maxiter iterations. Preconditioner: one V-cycle
// (sweeps Gauss-Seidel sweeps) of each component's diagonal block, whose hierarchy is set up
// here in mg[k] (the caller owns the objects, reused between steps). work: scratch of
// 5 x n values. Returns (iterations, true relative residual).
template <int D>
SolveResult solve(const Grid<D>& g, View<const index_t, 3> cols, View<const double, 3> vals,
                  View<const index_t> node, View<const index_t> off, View<const double> rhs,
                  View<double> x, double tol, index_t maxiter, int sweeps,
                  std::array<Multigrid<D>, D>& mg, View<double, 2> work);

}  // namespace mpmflow
