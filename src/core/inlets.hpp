// Velocity inlets, 2D and 3D: water that enters the domain through part of a side at a given
// speed ([[inlets]] of a case; boundaries/inlets.py builds the tables). Two halves:
//
// - on the grid, an inlet's nodes are bonded no-slip wall pairs (walls.hpp) held to the
//   inflow's velocity (GridTables::wall_velocity: the held values), so that the pressure
//   step sees the flux the inlet brings (pressure_system.hpp's wall term) and the corrector
//   leaves it;
// - on the particles, each row of an inlet's lattice across the opening emits a particle
//   each time the inflow there has travelled one particle spacing since the last one (a
//   uniform inflow emits whole layers). The
//   particles come from a pool of dormant ones (mass and volume 0, which every phase skips or
//   counts as nothing) that the caller appends to the particle arrays before a chunk and
//   trims after it: the arrays' sizes are the caller's, and a step allocates nothing.
//
// The layers continue the lattice of an upstream reservoir moving at the inflow's speed: a
// layer is emitted when its centre crosses the side, at the distance its centre has then
// travelled inside (travel, 0 to one spacing), so that its volume, centred on it, reaches
// outside the side by as much as the gap behind it is empty and the cells along the side
// hold their share of water on average. The volume that enters is speed x (the opening's
// area) x time, to one layer. travel starting at half a spacing (the caller's choice)
// continues the lattice (k + 1/2) spacing of bodies seeded against the side.
#pragma once

#include "view.hpp"

namespace mpmflow {

template <int D>
struct Inlets {
  View<const index_t> axis;      // per inlet: the axis normal to its side
  View<const double> direction;  // +1: the side at the axis's lower end (flow towards +axis)
  View<const index_t> first;     // inlets + 1 entries: inlet q's layer rows [first(q), first(q+1))
  View<const double, 2> layer;   // rows x D (m): a layer's positions, at the side along axis
  View<const double> speed;      // per row (m/s, >= 0): the inflow's speed there (a profile)
  View<const double> spacing;    // per inlet (m): its particles' lattice spacing
  View<const double> mass, volume;  // per inlet (kg, m^3): each emitted particle's
  index_t count() const { return direction.size(); }
  index_t rows() const { return layer.extent(0); }
};

// The dormant particles a chunk may emit: [next, end) of the particle arrays.
struct InletPool {
  index_t next = 0, end = 0;
};

// The particles the inlets emit in a step of dt (s), row by row of their layers (each row
// moves at its own speed: a profiled inflow). travel(r) (m) says where row r's next
// particle is: its centre lies travel - spacing inside the side (negative: still outside).
// It grows by speed(r) dt; each time it reaches a spacing, a particle is emitted from the
// pool where its centre now is and travel falls by a spacing. An emitted particle gets its
// position, the velocity speed(r) along the axis, its mass and volume, pressure 0 and, with
// APIC (affine not empty), the affine matrix 0. Returns the particles emitted. Throws
// std::logic_error when the pool runs out (the caller sizes it for the chunk's time).
template <int D>
index_t emit_layers(const Inlets<D>& in, double dt, View<double> travel, InletPool& pool,
                    View<double, 2> x, View<double, 2> v, View<double> mass, View<double> volume,
                    View<double> pressure, View<double, 3> affine);

}  // namespace mpmflow
