// Cells cut by fixed obstacles, 2D and 3D (port of kernels/cutcells.py): their element
// integrals over the fluid part, the integrals over the obstacle's face that enter the
// pressure system, and the per-step corrections near obstacles.
//
// The obstacles are given by their signed distance phi (m, negative inside a solid) at the
// grid nodes, interpolated multilinearly inside each cell. Each cut cell is divided into
// nsub^D sub-cells; a sub-cell is fluid when phi at its centre is positive. On that
// staircase fluid region the integrals are exact with 2^D Gauss points per fluid sub-cell:
//   K[a, b] = int grad N_a . grad N_b (m^(D-2)),  C[a, b, k] = int N_a dN_b/dx_k (m^(D-1)),
//   V[a] = int N_a (m^D),
// the obstacle's face term by the divergence theorem on the staircase,
//   F[a, b, k] = int_{obstacle face in the cell} N_a N_b n_k ds (m^(D-1)), n into the solid,
// and Wf[f, a, b] = int_{fluid part of cell face f} N_a N_b ds (m^(D-1)) for the faces
// f = 2 k + side on the domain's boundary (the walls' term).
#pragma once

#include <array>

#include "grid.hpp"
#include "view.hpp"

namespace mpmflow {

// A cut cell with less fluid than this takes its volume fraction from beside it.
constexpr double SLIVER = 0.5;

// phi (m) interpolated multilinearly at local coordinates `local` (each in [0, 1]) of the
// cell whose first node is `first`.
template <int D>
double phi_at(const Grid<D>& g, View<const double> phi_node, const std::array<double, D>& local,
              index_t first);

// The integrals of the candidate cells (flat indices candidates[m]) into K[m] (m x 2^D x
// 2^D), C[m] (m x 2^D x 2^D x D), V[m] (m x 2^D), F[m] (m x 2^D x 2^D x D) and Wf[m]
// (m x 2D x 2^D x 2^D), with nsub sub-cells per axis; solid_parts[m]: the number of solid
// sub-cells plus the solid sub-faces seen across the cell's inner faces (0: not cut).
template <int D>
void cut_cell_tensors(const Grid<D>& g, View<const double> phi_node, View<const index_t> candidates,
                      index_t nsub, View<double, 3> K, View<double, 4> C, View<double, 2> V,
                      View<double, 4> F, View<double, 4> Wf, View<index_t> solid_parts);

// Wf[f, a, b] (2D x 2^D x 2^D) of a whole cell (every face fluid): int N_a N_b over face f
// (m^(D-1)).
template <int D>
void face_mass(const Grid<D>& g, View<double, 3> Wf);

// phi (m) at particle p (x: n x D, m), multilinear in its cell, and its gradient into grad
// (D entries, dimensionless).
template <int D>
double interpolate_phi(const Grid<D>& g, View<const double> phi_node, View<const double, 2> x,
                       index_t p, double* grad);

// Particles inside an obstacle (interpolated phi < margin, m) moved out along grad phi to
// phi = margin (up to 4 Newton steps, each at most 2 cells long; none where |grad phi| <
// 0.01, a flat cell that gives no direction), their velocity into the solid removed (x, v:
// n x D, in place); with held (nnodes x D, m/s: a moving obstacle's velocity at the nodes,
// bodies.hpp; empty: at rest) their velocity into it relative to held interpolated where
// they end. Returns how many were moved.
template <int D>
index_t push_out(const Grid<D>& g, View<double, 2> x, View<double, 2> v,
                 View<const double> phi_node, double margin, View<const double, 2> held = {});

// The volume fraction theta of a cut cell whose fluid part is a sliver (0 < open < SLIVER):
// the largest of its face neighbours' with open >= SLIVER (in place; unchanged without one).
// With swept (a run whose obstacles move), also that of an empty cut cell (theta 0) with no
// empty whole cell (air) beside it: the largest of its face neighbours' that hold material.
// A face sweeping through the particles leaves the cut cells ahead of it a fluid part
// thinner than a particle row plus the push-out margin, often empty; such a cell left out
// of the pressure system put p = 0 at the nodes behind the face for a step (a body
// descending at 1 cm/s felt a force spike of 70% of its buoyancy as it crossed a grid line).
template <int D>
void sliver_fractions(const Grid<D>& g, View<const double> open_, View<double> theta,
                      bool swept = false);

// The velocities (m/s, nnodes x D, in place) of the obstacle nodes onode that no particle
// reaches (node_mass 0): the mass-weighted mean of their stencil neighbours' with mass.
template <int D>
void extend_velocity(const Grid<D>& g, View<const index_t> onode, View<const double> node_mass,
                     View<double, 2> v_old, View<double, 2> v_star);

}  // namespace mpmflow
