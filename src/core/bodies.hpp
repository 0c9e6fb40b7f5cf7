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
//     no-slip as their nearest obstacle or body is;
//   - with nsub = 0 (a solid's tools) no cell is cut, and the box's obstacle nodes are the
//     staircase's (REACH, staircase_node).
// A solid's force on its tools is the held nodes' reactions (reactions()), not forces().
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

template <int D>
class Exchange;  // exchange.hpp

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
  double angle = 0.0;                          // rad about the path's axis (free: unused)
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
  // A free body instead of a path: moved by gravity and the pressure on it (bodies.cpp).
  // Its mass (kg; 2D kg/m), inertia about its pivot (its centroid) in its own frame (kg m^2;
  // 2D the zz entry, kg m), the degrees of freedom held at their start (translations along
  // the axes, then rotations about them; 2D: about z only), and its state: the pivot's
  // position and velocity, its orientation (a unit quaternion w, x, y, z; 2D about z) and
  // angular velocity (rad/s); *_star: the step's velocities before the pressure acts.
  bool free = false;
  double mass = 0.0;
  std::array<std::array<double, 3>, 3> inertia{};
  std::array<bool, 6> locked{};
  double friction = 0.0;  // the Coulomb coefficient of its contacts (contact())
  std::array<double, D> centre_now{}, velocity_now{}, velocity_star{};
  std::array<double, 4> quat{1.0, 0.0, 0.0, 0.0};
  std::array<double, 3> omega_now{}, omega_star{};
  // its centroid from its pivot in its own frame (m): 0 but for a hinge (a pivot elsewhere,
  // every translation held), about which gravity then turns it
  std::array<double, D> offset{};
  // points on a free body's surface in its own frame (m x D, m; empty: no contact), which
  // the contact with the domain's walls and the fixed obstacles checks (BodyTables::contact)
  View<const double, 2> surface;
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
  // The staircase (nsub 0, a solid's tools) holds the nodes in the body or on its surface
  // and, ahead of a face that advances into the material, the nodes closer than REACH cells
  // along the body's motion there (phi < REACH h times the cosine between the motion and
  // the face's outward normal): the row of nodes just ahead of the face moves with it, and
  // the material between is carried along. Holding only the nodes in the body (phi <= 0),
  // the particles its face overtook between rows of nodes bunched into a sliver in front of
  // it that chattered: a footing's pressure fell from 5.1 to 3.9 s_u, by +-5 s_u from one
  // step to the next, while its face crossed the last third of a cell. Holding the nodes
  // within a cell beside its faces too widened the body by up to a cell each side: a strip
  // footing at B / 15, its edge midway between two nodes, bore 1.156 times Prandtl's load,
  // 1.037 this way (docs/method.md, "Solids").
  static constexpr double REACH = 1.0;
  // A node whose distance to a body is within ON_SURFACE cells of 0 is on its surface (phi
  // = 0). A body's distance at a node comes from its pose and its lattice with rounding, so
  // a face or corner on a plane of nodes reads +-1e-15 m there, and its sign decided whether
  // the cells beside it were solid or cut (by a sliver): a free box with its corners on
  // nodes, sinking in a tank symmetric about its axis, turned at 0.05 rad/s after 40 steps
  // (one corner's node read in, the other's out), and a pose 1e-13 m off, or the ranks'
  // sums taken in another order, turned it otherwise. The bound is above the drift of a pose
  // that the solves' tolerance leaves (that box, landed on a block with its faces on nodes,
  // had drifted by 1e-11 m after 180 steps, and a bound of 1e-9 cells split two runs there),
  // and below anything a cut cell resolves (tests/parallel/test_split_bodies.py).
  static constexpr double ON_SURFACE = 1e-6;
  // fixed: the fixed obstacles' tables (phi empty: none); fixed_no_slip: per node, whether
  // its nearest fixed obstacle is no-slip (empty: none is); nsub: the cut cells' sub-cells
  // per axis, or 0 for the staircase (a solid's tools, below). Reserves the storage (a step then
  // allocates only when the bodies cut more cells than any step before).
  void setup(const Grid<D>& g, const ObstacleTables<D>& fixed, View<const bool> fixed_no_slip,
             std::vector<Body<D>> bodies, index_t nsub);
  // A rank's grid (a box of the domain and its ghost layer): its first node's index in the
  // domain's grid (origin) and the domain's cells per axis (by default the grid is the
  // domain's). The bodies' paths stay in the domain's frame and every node a body reads sits
  // at (i + origin) h, so that a rank computes a node's distance, velocity and arm with the
  // same operations as one process (bit for bit: a face on a sub-cell point would otherwise
  // fall on different sides of it); a body's distance is read one cell in at the domain's
  // walls only. (The free bodies' contacts, refused on ranks, read the grid's own frame.)
  void set_domain(const std::array<index_t, D>& origin, const std::array<index_t, D>& cells);
  bool present() const { return !bodies_.empty(); }
  index_t count() const { return static_cast<index_t>(bodies_.size()); }
  const Body<D>& body(index_t b) const { return bodies_[b]; }
  void place(double t);
  void hold(double t);
  // the largest speed (m/s) of a body's point at time t (on its lattice)
  double max_speed(double t) const;
  // force (D) and torque (3) of the pressure p_node (Pa) on each body at its last place,
  // into force (count x D, N per m in 2D) and torque (count x 3)
  // (owned: the cells a rank owns, whose cut cells it sums; empty: every cell)
  void forces(View<const double> p_node, View<double, 2> force, View<double, 2> torque,
              View<const bool> owned = {});
  // A solid's tools: the material's force (D) and torque (3, about the frame's origin) on
  // each body, from r (nnodes x D, N; 2D N/m), the force each node needs beyond its
  // stress and weight to move as it does (State::to_particles): minus the sum of r over the
  // obstacle nodes in contact nearest the body (its normal component where it slips).
  // (owned: the nodes a rank owns, whose reactions it sums; empty: every node)
  void reactions(View<const double, 2> r, View<const bool> ocontact, View<double, 2> force,
                 View<double, 2> torque, View<const bool> owned = {});
  ObstacleTables<D> tables();

  // Free bodies (bodies.cpp). Their unheld degrees of freedom, numbered body by body
  // (translations, then rotations).
  index_t free_dofs() const { return static_cast<index_t>(dofs_.size()); }
  // the step's velocities before the pressure: gravity g (m/s^2) over dt added to the
  // translations, the rotations' own change (omega x I omega) to the angular velocities
  void predict(double dt, const std::array<double, D>& g);
  // back to the predicted velocities (before each right-hand side of the pressure step)
  void reset_velocity();
  // The coupling of the pressure step's unknowns (node_row; cell_slot: the cells in the
  // system) to the free degrees of freedom q: J (dofs x rows, m^(D-1) per unit of q) the
  // face flux int N_i u(q).n ds over the obstacle nodes in contact (ocontact) that the body
  // holds, and K (dofs x rows, m^(D-1) per Pa) the generalized force of the pressure at the
  // rows on the body (force, torque about the pivot).
  void coupling(View<const index_t> cell_slot, View<const index_t> node_row,
                View<const bool> ocontact, View<double, 2> J, View<double, 2> K);
  // the mass matrix of the free degrees of freedom (dofs x dofs; the inertia in the grid's
  // frame)
  void mass_matrix(View<double, 2> M) const;
  // the velocities after the pressure: q = q* + M^-1 impulse (impulse: dofs, N s; 2D N s/m)
  void apply_impulse(View<const double> impulse);
  // the free bodies' contacts where they are (at t - dt), then their poses moved over dt at
  // the velocities the contacts leave (t: the time at the end of the move, s)
  // ``exchange``: the ranks' (a fixed obstacle's surface is read by the rank that owns the
  // point's cell, and summed over the ranks, so every rank takes the same contacts); null on
  // one process.
  void integrate(double dt, double t, Exchange<D>* exchange = nullptr);
  // Contact of the free bodies with the domain's walls (those not periodic), the fixed
  // obstacles and each other (t: the time of the bodies' poses, s; dt: the step's, s): rigid
  // and inelastic, with Coulomb's friction (Body::friction; 0: frictionless). Every surface
  // point on or beyond a wall, on or inside an obstacle (the fixed phi <= 0, its normal grad
  // phi) or another body (its distance, normal its gradient) is a contact; the body is moved
  // back out along the deepest one's normal by its depth, and the contacts' velocities into
  // what they touch (relative to a body's velocity there) are removed by impulses there
  // (through its mass and inertia; a held degree of freedom takes none), each impulse >= 0,
  // and the sliding at each is stopped by a tangential impulse up to mu times its normal one
  // (projected Gauss-Seidel: contact by contact, in sweeps until they agree). A point within
  // half a cell of a surface is a contact ahead: its velocity may close the gap over the
  // step, not more (a speculative contact). Another free body takes the opposite impulses; a
  // body on a path is not moved by them. Returns the contacts.
  index_t contact(double t, double dt, Exchange<D>* exchange = nullptr);
  // each body's pose and velocity at time t (bodies x 13: pivot (3), velocity (3), angular
  // velocity (3), orientation quaternion (4); 2D: z entries 0, rotation about z)
  void state(double t, View<double, 2> out) const;
  // a free body's state back from state()'s rows (a checkpoint); path bodies unchanged
  void set_state(View<const double, 2> in);

 private:
  std::vector<std::array<index_t, 2>> dofs_;    // (body, kind: 0..D-1 translation, D.. rotation)
  std::vector<std::array<index_t, 6>> dof_of_;  // per body and kind: its dof (-1: held)
  Buffer<double> small_, rhs_small_;            // the dense solves of the free dofs
  // contact(): per contact, point (3), normal (3), normal impulse, the other body (-1:
  // none), friction impulse (3), the gap ahead (m; 0: touching)
  static constexpr index_t CONTACT = 12;
  // a distance's gradient at least this long marks a flat part of a body's surface (contact)
  static constexpr double FLAT = 0.999;
  Buffer<double> contacts_;
  // contact(): per surface point of one body, the fixed obstacles' phi (m) and its gradient
  // (D) there, and 1 where a rank read them (its owner), else 0
  Buffer<double> fixed_at_;
  std::vector<Pose<D>> contact_poses_;  // contact(): each body where it is
  std::vector<std::array<std::array<double, 3>, 3>> inverse_inertia_;  // contact(): free ones'
  // the inverse of a free body's inertia in the grid's frame over its free rotations (2D:
  // about z; held rotations' rows and columns 0)
  std::array<std::array<double, 3>, 3> inverse_inertia(const Body<D>& b) const;
  void restore();
  // the staircase (nsub 0): whether node ix (index i) of the box holds the material (a
  // corner of a cell that is not solid, in the body or ahead of its advancing face: REACH),
  // and its normal into the solid (-grad phi, D)
  bool staircase_node(const std::array<index_t, D>& ix, index_t i, double* normal);
  // the cell of which node ix is corner a (-1: outside the grid)
  index_t corner_cell(const std::array<index_t, D>& ix, int a) const;
  // f(ix) for each node ix of the last place's box, its upper ends shrunk by shrink (1: the
  // first node of each of the box's cells), axis 0 fastest
  template <class F>
  void for_box(index_t shrink, F&& f) const {
    for (int k = 0; k < D; ++k)
      if (box_hi_[k] - shrink < box_lo_[k]) return;
    std::array<index_t, D> ix = box_lo_;
    while (true) {
      f(ix);
      int k = 0;
      for (; k < D; ++k) {
        if (++ix[k] <= box_hi_[k] - shrink) break;
        ix[k] = box_lo_[k];
      }
      if (k == D) return;
    }
  }
  Grid<D> g_;
  std::array<index_t, D> origin_{}, domain_{};  // set_domain
  // the coordinate k (m, the domain's frame) of grid point index ik (a node's, or a cell's
  // corner: cx + 0 or 1)
  double at(index_t ik, int k) const { return static_cast<double>(ik + origin_[k]) * g_.h; }
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
