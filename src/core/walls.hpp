// Velocity conditions at the domain walls and at obstacles, 2D and 3D: one-sided contact, a
// wall stops penetration only. The wall nodes come as (node, axis of the wall's normal,
// outward sign) triples from wall_pairs: the walls normal to axis 0 first, then axis 1, ...;
// along each, the nodes in node order with the lower wall before the upper; a node on an
// edge or a corner appears once for each of its walls. Each pair carries its wall's
// condition (no_slip: one flag per pair, domain.walls side by side). Obstacle nodes come as (node,
// unit normal into the solid, no-slip flag) entries (onode, onormal, no_slip), with one contact
// flag per node (ocontact). Velocities in m/s; the loops are serial (wall nodes are few,
// and a corner node appears under several walls).
#pragma once

#include "grid.hpp"
#include "view.hpp"

namespace mpmflow {

// The number of (node, wall) pairs of grid g: 2 sum_k nnodes / (cells[k] + 1).
template <int D>
index_t wall_pair_count(const Grid<D>& g);

// The (node, axis, sign) triples of every wall node and wall into node, axis, sign (each
// sized to at least wall_pair_count(g)); returns how many.
template <int D>
index_t wall_pairs(const Grid<D>& g, View<index_t> node, View<index_t> axis, View<double> sign);

// Velocity conditions at wall nodes (in place in v, nnodes x D). Where the wall holds the
// material (contact[i, k]) the normal velocity is the wall's: held(i, k) (m/s; held empty:
// every wall at rest; an inlet's nodes hold its inflow, inlets.hpp); elsewhere on the wall
// only a velocity into the wall is removed. A no-slip pair (no_slip(e)) also sets the
// tangential velocity to the wall's where its node is in contact (at an edge node of a
// no-slip and a slip wall the no-slip wall's hold wins).
void apply_walls(View<const index_t> node, View<const index_t> axis, View<const double> sign,
                 View<const bool> no_slip, View<double, 2> v, View<const bool, 2> contact,
                 View<const double, 2> held = {});

// The wall nodes that hold the material as the pressure step starts (in place):
// contact[i, k] is set where node i carries a pressure unknown (node_row >= 0) or v* presses
// into its wall normal to k, and always where the pair is bonded (bonded(e); empty: none, a
// clamped wall: domain.walls = "bonded"); every other entry is cleared.
void start_contact(View<const index_t> node, View<const index_t> axis, View<const double> sign,
                   View<const double, 2> vstar, View<const index_t> node_row, View<bool, 2> contact,
                   View<const bool> bonded = {});

// Release the wall nodes in contact whose pressure p_node (Pa) came out negative while v*
// leaves the wall (in place), except the bonded pairs (bonded(e); empty: none), which hold
// in tension too; returns how many (node, wall) pairs were released.
index_t release_contact(View<const index_t> node, View<const index_t> axis, View<const double> sign,
                        View<const double, 2> vstar, View<const index_t> node_row,
                        View<const double> p_node, View<bool, 2> contact,
                        View<const bool> bonded = {});

// The pressure unknowns the contact constrains to p >= 0 (complementarity.hpp), one flag
// per row into candidate (sized to the rows; node_row(i) the row of node i, -1: none): the
// unknowns of the wall nodes in contact as the pressure step starts (start_contact), but
// for the bonded pairs (bonded(e); empty: none), which hold in tension too, and of the
// obstacle nodes in contact (ocontact, start_obstacles).
void contact_rows(View<const index_t> node, View<const index_t> axis, View<const bool> bonded,
                  View<const bool, 2> contact, View<const index_t> onode, View<const bool> ocontact,
                  View<const index_t> node_row, View<bool> candidate);

// After the pressure step: the wall and obstacle nodes whose row the contact held at p = 0
// (zero(node_row(i))) let the water leave (contact and ocontact cleared there, in place;
// the bonded pairs keep theirs). Returns how many (node, wall) pairs and obstacle nodes.
index_t release_rows(View<const index_t> node, View<const index_t> axis, View<const bool> bonded,
                     View<const index_t> onode, View<const index_t> node_row, View<const bool> zero,
                     View<bool, 2> contact, View<bool> ocontact);

// v_i . n_e (m/s): the velocity of node i into the solid along obstacle entry e's normal.
inline double normal_velocity(View<const double, 2> v, index_t i, View<const double, 2> onormal,
                              index_t e) {
  double vn = 0.0;
  for (index_t k = 0; k < v.extent(1); ++k) vn += v(i, k) * onormal(e, k);
  return vn;
}
// (v_i - held_i) . n_e (m/s): the same relative to the obstacle's velocity there (held: nnodes
// x D; empty: every obstacle at rest).
inline double normal_velocity(View<const double, 2> v, View<const double, 2> held, index_t i,
                              View<const double, 2> onormal, index_t e) {
  double vn = normal_velocity(v, i, onormal, e);
  if (held.size() > 0)
    for (index_t k = 0; k < v.extent(1); ++k) vn -= held(i, k) * onormal(e, k);
  return vn;
}

// Velocity conditions at the obstacle nodes (in place), as apply_walls: the normal velocity
// is removed where the obstacle holds the material, elsewhere only a velocity into the
// solid; a no-slip obstacle zeroes the whole velocity where it holds. With phi (the signed
// distance at the nodes) only the nodes inside the solid or on its face (phi <= 0) are
// constrained: an obstacle node in the water (a corner of a cut cell on the fluid side of
// the face) keeps its velocity, since the face lies beyond it.
void apply_obstacles(View<const index_t> onode, View<const double, 2> onormal,
                     View<const bool> no_slip, View<double, 2> v, View<const bool> ocontact,
                     View<const double> phi = View<const double>(),
                     View<const double, 2> held = {});

// The obstacle nodes that hold the material as the pressure step starts (in place): a
// pressure unknown, or v* pressing into the solid (relative to its velocity held).
void start_obstacles(View<const index_t> onode, View<const double, 2> onormal,
                     View<const double, 2> vstar, View<const index_t> node_row, View<bool> ocontact,
                     View<const double, 2> held = {});

// Release the obstacle nodes in contact whose pressure came out negative while v* leaves
// the solid (in place); returns how many.
index_t release_obstacles(View<const index_t> onode, View<const double, 2> onormal,
                          View<const double, 2> vstar, View<const index_t> node_row,
                          View<const double> p_node, View<bool> ocontact,
                          View<const double, 2> held = {});

}  // namespace mpmflow
