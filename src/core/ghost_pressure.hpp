// The sub-cell free surface's ghost values (2D and 3D): the pressure extrapolated from the
// unknowns to the nodes just outside the material, p = 0 at the f = 1/2 surface.
//
// Along the edge from an unknown node i to a node g outside, theta = (f_i - 1/2)/(f_i - f_g)
// is the fractional distance from i to the surface and p_g = (1 - 1/theta) p_i the linear
// extrapolation to p = 0 there (the ghost-fluid method of Gibou et al. 2002).
#pragma once

#include "grid.hpp"
#include "view.hpp"

namespace mpmflow {

// (1 - 1/theta) (dimensionless): p_g = factor p_i, the linear extrapolation to p = 0 at
// f = 1/2 from nodal volume fractions f_i (unknown) and f_g (ghost); theta is kept at or
// above theta_min; 0 where the surface is not between them.
inline double ghost_factor(double f_i, double f_g, double theta_min) {
  if (f_i - f_g <= 0.0) return 0.0;
  double t = (f_i - 0.5) / (f_i - f_g);
  if (t >= 1.0) return 0.0;
  if (t < theta_min) t = theta_min;
  return 1.0 - 1.0 / t;
}

// t / (1 + t) (dimensionless): a shallow node's pressure over its unknown neighbours' (one
// edge further from the surface), the linear interpolation to p = 0 at the surface a
// fraction t of an edge beyond it (demote_shallow below).
inline double shallow_factor(double t) { return t / (1.0 + t); }

// Shallow unknowns: dep(i) = t, the fraction of the edge at which the surface crosses the
// nearest of the unknown i's edges to nodes outside (non-unknowns with less material,
// coupling S < 0), where t < theta_c; -1 at every other node. The caller takes the shallow
// nodes out of the unknowns: a shallow node's pressure is the linear interpolation between
// its unknown neighbours, one edge further in, and p = 0 at the surface, t / (1 + t) times
// their mean (exact for a linear field), which bounds every weight of the extension by
// 1/theta_c - 1 where the ghost extrapolation's reach 1/theta_min - 1.
template <int D>
void demote_shallow(const Grid<D>& g, View<const index_t> cell_slot, View<const double, 3> K,
                    View<const index_t> node_row, View<const double> node_f, double theta_c,
                    View<double> dep);

// Pressure (Pa) at the shallow nodes (dep >= 0, demote_shallow's), in place in p_node (the
// unknowns' values set): t / (1 + t) times the coupling-weighted (K: the Laplacian's element
// integrals by cell_slot) mean of their unknown neighbours', as the assembly weighs them.
template <int D>
void shallow_values(const Grid<D>& g, View<const index_t> cell_slot, View<const double, 3> K,
                    View<const index_t> node_row, View<const double> dep, View<double> p_node);

// Pressure (Pa) at the other nodes that are not unknowns (node_row < 0), in place in p_node
// (the unknowns' values set, and the shallow nodes' with dep): each takes the coupling-weighted
// mean of the extrapolations from its unknown (and shallow) neighbours, the same
// extrapolations the assembly used; 0 where it has none.
template <int D>
void ghost_values(const Grid<D>& g, View<const index_t> cell_slot, View<const double, 3> K,
                  View<const index_t> node_row, View<const double> node_f, double theta_min,
                  View<double> p_node, View<const double> dep = View<const double>());

}  // namespace mpmflow
