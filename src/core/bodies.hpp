// Obstacles that move along a prescribed path (bodies in the flow, issue 44 item 1; the rigid
// tools of issue 43), 2D and 3D.
//
// A moving body is a rigid shape given by its signed distance phi_b (m, negative inside) on a
// lattice in its own frame (the caller samples the shape's exact distance there once; the
// lattice reaches far enough beyond the shape that the cells next to its surface read it), and
// a path: its frame's origin c(t) (m) and its rotation by angle(t) (rad) about a fixed axis
// (2D: the plane's normal; 3D: a unit vector), with their rates, tabulated and interpolated by
// cubic Hermite segments (position and velocity exact at the samples, both continuous). In
// the grid's frame phi(x, t) = phi_b(R(t)^T (x - c(t))), and the body's point at x moves at
// v(x, t) = c'(t) + angle'(t) axis x (x - c(t)).
//
// BodyTables keeps the obstacle tables the step reads (ObstacleTables: those of GridTables,
// with the obstacle nodes' velocities) for the fixed obstacles and the bodies at their pose at
// time t. place(t) rebuilds them within the box round the bodies' lattices (a node more each
// way), having restored the last place's box to the fixed tables, as boundaries/obstacles.py's
// build does once for fixed obstacles:
//   - phi = min(phi of the fixed obstacles, each body's) at the box's nodes; at a node on a
//     domain wall that the body's shape reaches, the body's phi is read one cell in
//     (obstacles.node_distance's shift, without its extrapolation along a slanted face: a
//     body's faces meeting a wall are taken as perpendicular to it within the first cell);
//   - a cell whose corners all have phi <= 0 is solid (slot -1); the cells touching the solid
//     and their face neighbours get their cut-cell integrals (cut_cells.hpp), in slots after
//     the fixed ones; a candidate with no fluid sub-cell is solid, one the surface cuts gets a
//     slot, the others are whole cells (slot 0);
//   - the obstacle nodes: those of the fixed tables outside the box, and the box's nodes
//     whose cut cells give int N_i n ds != 0 (its direction: the normal, into the solid),
//     no-slip as their nearest obstacle or body is.
// hold(t) sets the velocity of each node of the box nearest a body to the body's there at
// time t (nnodes x D, m/s; zero elsewhere): the step holds the node to it where it holds a fixed
// obstacle's node at rest. forces(p) sums the pressure's force and torque on each body over the
// cut cells nearest it.
#pragma once

#include <array>
#include <vector>

#include "grid.hpp"
#include "view.hpp"

namespace mpmflow {

// The obstacle tables the step reads (views: of the caller's fixed GridTables arrays, or of a
// BodyTables' storage while bodies move).
template <int D>
struct ObstacleTables {
  View<const double> phi, open;     // (nnodes) m; (ncells) fluid fraction
  View<const index_t> static_slot;  // (ncells) 0: whole cell, >= 1: cut, -1: solid
  View<const double, 3> K;          // (nstatic, 2^D, 2^D)
  View<const double, 4> C;          // (nstatic, 2^D, 2^D, D)
  View<const double, 2> V;          // (nstatic, 2^D)
  View<const double, 4> F;          // (nstatic, 2^D, 2^D, D)
  View<const double, 4> Wf;         // (nstatic, 2 D, 2^D, 2^D)
  View<const index_t> onode;        // (m) the obstacle nodes
  View<const double, 2> onormal;    // (m, D)
  View<const bool> ono_slip;        // (m)
  View<const double, 2> velocity;   // (nnodes, D) m/s; empty: every obstacle at rest
};

// A body's pose at a time: where its frame is and how it moves.
template <int D>
struct Pose {
  std::array<double, D> centre{}, velocity{};  // m, m/s
  std::array<std::array<double, D>, D> R{};    // body frame to grid frame
  std::array<double, 3> omega{};               // rad/s (2D: about z only)
  // the body's velocity (m/s) at grid point x
  void velocity_at(const double* x, double* out) const;
};

template <int D>
struct Body {
  View<const double> phi;            // lattice values, axis 0 fastest (m)
  std::array<index_t, D> counts{};   // lattice points per axis
  std::array<double, D> origin{};    // body frame (m)
  double spacing = 0.0;              // m
  std::array<double, D> lo{}, hi{};  // the shape's bounds in the body frame (m)
  std::array<double, 3> axis{0.0, 0.0, 1.0};
  View<const double> time;         // (n) s, increasing
  View<const double, 2> centre;    // (n, D) m
  View<const double, 2> velocity;  // (n, D) m/s
  View<const double> angle, rate;  // (n) rad, rad/s
  bool no_slip = false;
  // the pose at time t (held at the table's ends beyond them)
  Pose<D> pose(double t) const;
  // phi_b (m) at grid point x for the body at pose q; far (a large value) off the lattice
  double distance(const Pose<D>& q, const double* x) const;
};

template <int D>
class BodyTables {
 public:
  static constexpr int NC = 1 << D;
  static constexpr double FAR = 1e30;  // phi where no obstacle is near
  // fixed: the fixed obstacles' tables (phi empty: none); fixed_no_slip: per node, whether
  // its nearest fixed obstacle is no-slip (empty: none is); nsub: the cut cells' sub-cells
  // per axis. Reserves the storage (a step then allocates only when the bodies cut more
  // cells than any step before).
  void setup(const Grid<D>& g, const ObstacleTables<D>& fixed, View<const bool> fixed_no_slip,
             std::vector<Body<D>> bodies, index_t nsub);
  bool present() const { return !bodies_.empty(); }
  index_t count() const { return static_cast<index_t>(bodies_.size()); }
  const Body<D>& body(index_t b) const { return bodies_[b]; }
  void place(double t);
  void hold(double t);
  // the largest speed (m/s) of a body's point at time t (on its lattice)
  double max_speed(double t) const;
  // force (D) and torque (3) of the pressure p_node (Pa) on each body at its last place,
  // into force (count x D, N per m in 2D) and torque (count x 3)
  void forces(View<const double> p_node, View<double, 2> force, View<double, 2> torque);
  ObstacleTables<D> tables();

 private:
  void restore();
  Grid<D> g_;
  ObstacleTables<D> fixed_;
  View<const bool> fixed_no_slip_;
  std::vector<Body<D>> bodies_;
  std::vector<Pose<D>> poses_, held_;  // at the last place and the last hold
  index_t nsub_ = 8, nfixed_ = 1, nslots_ = 1, nonode_ = 0;
  std::array<index_t, D> box_lo_{}, box_hi_{};  // the last place's node box (inclusive)
  bool placed_ = false;
  Buffer<double> phi_, open_, K_, C_, V_, F_, Wf_, onormal_, velocity_, nvec_;
  Buffer<index_t> slot_, onode_, owner_, cand_, parts_, slot_owner_, slot_cell_;
  Buffer<bool> ono_slip_;
};

}  // namespace mpmflow
