// One step of the projection scheme (Kularathna & Soga 2017; docs/method.md, steps 1-8),
// 2D and 3D. The step is a sequence of named phases, each one or a few parallel loops:
//
//   predict: scatter (bin_particles -> particles_to_grid -> nodal_fraction)
//            -> classify (enclosed_cells -> cell_integrals -> classify_nodes)
//     -> viscous_predictor (viscous materials; a solid's elastic increment, eta = G dt)
//     -> pressure_solve (contact walls, assembly, solve, release, ghost values)
//     -> finish: correct (correct_velocity and the walls) -> volume_correction (every few
//        steps: volume_system -> solve -> volume_apply) -> to_particles (grid_to_particles
//        -> push out of obstacles)
//
// One loop takes the steps for every configuration (advance: fixed steps, advance_span:
// adaptive ones, both through step_once): one process, or a rank of a domain split over MPI
// (issue 42, docs/design/mpi.md, section 2). A rank's State is given an Exchange
// (exchange.hpp), which the phases call where a step meets the other ranks (the halo, the
// owners' values at the nodes round its box, the owners' say on the unknowns, reductions,
// migration), and solvers that solve its systems across the ranks (LinearSolver,
// ViscousSolver, use_solvers). A pressure solver from Python (amg, direct) plugs in the
// same way. The phases stay public for checks and for callers that run a step in parts.
//
// A State<D> owns everything the step needs beyond the particles: the grid's fixed tables
// (walls, obstacles' cut cells), the work arrays (sized once to the grid, grown to the
// particle count or to a step's system when a run needs more; never allocated in a step
// otherwise) and the multigrid hierarchies. Failures (a solve that does not converge, a
// pressure system without a free surface) stop the chunk of steps with a status in the
// Report; Python turns them into messages.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <vector>

#include "bodies.hpp"
#include "exchange.hpp"
#include "grid.hpp"
#include "inlets.hpp"
#include "multigrid.hpp"
#include "sponges.hpp"
#include "view.hpp"

namespace mpmflow {

enum Status : int {
  OK = 0,
  SINGULAR = 1,
  PRESSURE_NOT_CONVERGED = 2,
  VOLUME_NOT_CONVERGED = 3,
  VISCOUS_NOT_CONVERGED = 4,
  INTERRUPTED = 5,  // the caller's check between steps asked to stop (a signal)
  // the coupled step's plastic iterations (State::plastic_solve) did not settle
  PLASTIC_NOT_CONVERGED = 6
};
enum SurfaceQuadrature : int { GAUSS = 0, DIVERGENCE = 1, CONSISTENT = 2 };

// What a chunk of steps did (sums over its steps unless said).
struct Report {
  index_t unknowns = 0;  // the largest number of pressure unknowns in a step
  index_t solves = 0;
  index_t iterations = 0;
  index_t max_iterations = 0;  // the most iterations in one step
  double residual = 0.0;       // the worst relative residual
  index_t released = 0;
  index_t moved = 0;
  int status = OK;
  index_t step = 0;  // the step (0-based, within the chunk) that failed or is running
  index_t fail_iterations = 0;
  double fail_residual = 0.0;
  index_t fail_node = 0;  // node (pressure, viscous) or cell (volume correction)
  index_t fail_size = 0;  // unknowns of the failed system
  index_t volume_iterations = 0;
  index_t last_unknowns = 0;  // the unknowns of the last step
  index_t viscous_iterations = 0;
  index_t steps = 0;    // the steps taken
  double dt_min = 0.0;  // the shortest and longest step taken (s)
  double dt_max = 0.0;
  index_t capped = 0;   // cells whose viscosity was held at the model's cap (per step)
  index_t clamped = 0;  // faces whose volume-correction displacement was clamped
  index_t pockets = 0;  // pressure pockets sealed from the free surface, held at 0 at their top
  // steps whose walls' contact had not settled after MAX_CONTACT_ROUNDS rounds
  // (complementarity.hpp): the last round's pressure stood
  index_t unsettled = 0;
  // the coupled step's plastic iterations (State::plastic_solve), each one more coupled solve
  index_t plastic_iterations = 0;
};

// The phases of a step, as timed by State (seconds summed over the steps of a run).
enum Phase : int {
  PHASE_BINNING = 0,
  PHASE_P2G,
  PHASE_FREE_SURFACE,
  PHASE_INTEGRALS,
  PHASE_VISCOUS,
  PHASE_PRESSURE,
  PHASE_CORRECTOR,
  PHASE_VOLUME,
  PHASE_G2P,
  NPHASES
};

// The step's settings (constant over a chunk of steps).
template <int D>
struct Options {
  double dt = 1e-3;
  std::array<double, D> gravity{};
  double rho = 1000.0;
  double flip = 1.0;  // the FLIP fraction of one step
  double full = 0.9;
  double sparse = 0.0;
  bool partial_particles = false;
  // a solid's pressure: one value per cell, its surface natural (cell_pressure.hpp); the
  // cells' integrals are then the particles' in a partial cell, as with partial_particles
  bool cell_pressure = false;
  // with cell_pressure and a solid's elastic solve: the elastic solve and the projection
  // solved as one system (coupled_solve), for steps past the shear wave's crossing of a cell,
  // where the split of the two grows a bending beam (docs/method.md, "Solids")
  bool coupled = false;
  int surface = GAUSS;
  bool subcell = true;
  bool wall_flux = true;
  // pressure_matrix holds each sealed pocket at 0 at its top (pockets.hpp); false: it leaves
  // them (pockets() = 0), for a caller that owns only part of the domain and decides the
  // pockets across its parts itself
  bool pockets = true;
  double theta_min = 0.0;
  // sub-cell surface: an unknown nearer the surface than this fraction of an edge is taken
  // out of the unknowns and interpolated (ghost_pressure.hpp's demote_shallow) at steps
  // dt < shallow_max_dt (s; the adaptive step decides each step); shallow = 0: never
  double shallow = 0.0;
  double shallow_max_dt = 0.0;
  double expansion = 0.0;
  double tol = 1e-8;
  index_t max_iterations = 500;
  int sweeps = 1;
  double volume_rate = 0.0;
  index_t volume_every = 0;  // the volume correction runs on steps numbered a multiple of it
  double volume_tol = 1e-6;
  index_t volume_max_iterations = 200;
  double volume_dmax = 0.1;
  bool viscous = false;
  int model = 0;
  std::array<double, 8> model_params{};
  // the adaptive step (advance_span): dt = min(dt_max, courant h / max |v_p|), the FLIP
  // fraction per FLIP_TIME of flow, the volume correction every volume_interval of flow
  double courant = 1.0;
  double dt_max = 1e-2;
  double flip_rate = 1.0;
  double volume_interval = 2e-3;
};

// The grid's fixed tables (views of arrays the caller keeps alive for the State's life).
// Walls: the wall nodes with the axis and side of their wall and its condition (no-slip
// flag per pair). Obstacles (empty phi: none):
// phi at the nodes, each cell's fluid fraction and static slot (0: whole cell, s >= 1: a
// cut cell's, -1: solid), the static element integrals by slot, the cut cells' face terms,
// the obstacle nodes with their normals and no-slip flags; the outlet sides (they have no
// wall pairs). viscous_T: the full cell's
// gradient products (viscous materials; empty otherwise).
template <int D>
struct GridTables {
  View<const index_t> wall_node, wall_axis;
  View<const double> wall_sign;
  View<const bool> wall_no_slip;
  View<const bool> wall_bonded;  // per pair, held in tension too (empty: none; walls.hpp)
  View<const double> phi, open;
  View<const index_t> static_slot;
  View<const double, 3> K_static;   // (nstatic, 2^D, 2^D)
  View<const double, 4> C_static;   // (nstatic, 2^D, 2^D, D)
  View<const double, 2> V_static;   // (nstatic, 2^D)
  View<const double, 4> F_static;   // (nstatic, 2^D, 2^D, D)
  View<const double, 4> Wf_static;  // (nstatic, 2 D, 2^D, 2^D)
  View<const index_t> onode;
  View<const double, 2> onormal;  // (m, D)
  View<const bool> ono_slip;
  View<const double, 4> viscous_T;
  // outlets: one flag per side (x_min, x_max, y_min, ...; empty: none), the sides the
  // material leaves through (grid_to_particles retires what crosses them)
  View<const bool> outlet;
  // the velocity each wall node is held to where its wall holds the material (nnodes x D,
  // m/s; empty: every wall at rest): an inlet's inflow at its nodes (inlets.hpp)
  View<const double, 2> wall_velocity;
  // the inlets' layers of particles (none: inlets.count() == 0)
  Inlets<D> inlets;
  // damping zones: each node's rate (1/s; empty: none; sponges.hpp)
  View<const double> damping;
  // surface loads: each node's share of the tractions on the loaded faces (nnodes x D, N;
  // 2D N/m; empty: none), added to the predictor as v*_i += dt f_i / M_i where M_i > 0
  View<const double, 2> load;
};

// The step's schedule, written once for every loop that takes steps (State::advance and
// advance_span here, and the MPI ranks' loop, parallel/scheme.py, through the bindings).
//
// The adaptive step's size (time.dt = "auto", s): min(dt_max, courant h / |v|max) (vmax2:
// the largest squared particle speed; dt_max when nothing moves), then fitted to the rest of
// the span: all of it when it fits (to rounding), half of it when a second step would leave
// a sliver.
inline double adaptive_dt(double vmax2, double courant, double h, double dt_max, double rest) {
  double dt = dt_max;
  if (vmax2 > 0.0) dt = std::min(dt, courant * h / std::sqrt(vmax2));
  if (dt >= rest * (1.0 - 1e-9))
    dt = rest;
  else if (2.0 * dt > rest)
    dt = 0.5 * rest;
  return dt;
}
// The volume correction's cadence: fixed steps, on the steps numbered (from 1, from the
// start of the run) a multiple of every (0: never); adaptive steps, once the flow time
// since the last correction (since, s, advanced here by dt) reaches the interval (then
// since restarts from 0; rate 0: never).
inline bool volume_due_fixed(index_t number, index_t every) {
  return every > 0 && number % every == 0;
}
inline bool volume_due_adaptive(double& since, double dt, double rate, double interval) {
  if (!(rate > 0.0)) return false;
  since += dt;
  if (since < interval * (1.0 - 1e-9)) return false;
  since = 0.0;
  return true;
}

// A solver the step calls instead of its own multigrid for one of its ELL systems, the
// pressure's or the volume correction's (bindings/step.cpp: one from Python, amg, direct
// or PETSc's, solver.linear_solver; a rank's, over the ranks): set up for the step's
// matrix (row r on node or cell rows(r)), then solve for each right-hand side (the wall
// release asks for several), x the initial guess in and the solution out (on a rank, at
// every local row: the owners' values at the rows it does not own), returning the
// iterations and the true relative residual ||rhs - A x|| / ||rhs||. The step decides what
// a residual above the tolerance means (PRESSURE_NOT_CONVERGED, VOLUME_NOT_CONVERGED), as
// for its multigrid; an exception (a setup that fails) stops the chunk and reaches the
// caller. On a rank both calls are collective: they come on every rank, rows or none.
class LinearSolver {
 public:
  virtual ~LinearSolver() = default;
  virtual void setup(View<const index_t, 2> cols, View<const double, 2> vals,
                     View<const index_t> rows) = 0;
  virtual SolveResult solve(View<const double> rhs, View<double> x) = 0;
};

// The viscous predictor's solver instead of the step's own (a rank's, over the ranks): the
// system of the last viscous_system (viscous_rows, viscous_off, viscous_cols, viscous_vals,
// viscous_rhs), x its start in (viscous_x) and its solution out at every local unknown.
// Collective on a rank.
class ViscousSolver {
 public:
  virtual ~ViscousSolver() = default;
  virtual SolveResult solve(View<double> x) = 0;
};

template <int D>
class State {
 public:
  static constexpr int NC = 1 << D;
  static constexpr int NS = stencil_size(D);

  // lower, upper: the corners of the domain (m, in the grid's coordinates) that
  // grid_to_particles puts particles back inside (put_inside): the grid's own box [0, cells h]
  // for a State on the whole domain; a State on a sub-box of a larger domain (a rank's)
  // gives the global domain's corners, so that it puts particles back inside that domain,
  // not inside its own box.
  State(const Grid<D>& grid, double cell_volume, const std::array<double, D>& lower,
        const std::array<double, D>& upper, double margin, const GridTables<D>& tables,
        bool volume_correction, bool viscous);

  // nsteps steps of options.dt; first: the number of the first step (1-based, from the start
  // of the run). Stops at the first failure; returns the steps done.
  // between(): called after every step, false stops the chunk (status INTERRUPTED).
  using Between = std::function<bool()>;
  index_t advance(const Particles<D>& P, const Options<D>& O, index_t first, index_t nsteps,
                  Report& report, const Between& between = nullptr);

  // Steps of adaptive size (time.dt = "auto") over the time span (s): each step's size
  // from the Courant number on the particles' speeds at its start, within O.dt_max; the
  // last two steps are shortened to land on the end of the span exactly (no sliver: when
  // less than two steps remain, the rest is cut in two equal halves). Stops after
  // max_steps or at the first failure; returns the time covered (report.steps: the steps).
  double advance_span(const Particles<D>& P, const Options<D>& O, double span, index_t max_steps,
                      Report& report, const Between& between = nullptr);
  // the flow time since the last volume correction (adaptive steps; kept in checkpoints)
  double since_volume() const { return since_volume_; }
  void set_since_volume(double t) { since_volume_ = t; }
  // The inlets' pool for the next chunk: the dormant particles [first, end) of the particle
  // arrays it is given (inlets.hpp); inlet_next(): the first not emitted yet.
  void set_inlet_pool(index_t first, index_t end) { pool_ = InletPool{first, end}; }
  index_t inlet_next() const { return pool_.next; }
  // where each inlet row's next particle is (m, inlets.hpp; kept in checkpoints)
  View<double> inlet_travel() { return View<double>(travel_.data(), {T_.inlets.rows()}); }

  // Obstacles that move along a prescribed path (bodies.hpp): they join the fixed ones of
  // the tables; fixed_no_slip, per node, whether its nearest fixed obstacle is no-slip
  // (empty: none is); nsub, the cut cells' sub-cells per axis. Places them at time().
  void set_bodies(std::vector<Body<D>> bodies, View<const bool> fixed_no_slip, index_t nsub);
  // The flow time (s), which every step advances by its dt; setting it places the bodies.
  // A rigid, frictionless, impermeable plate on the walls of one side of the domain (axis;
  // side -1: its lower side, +1: its upper), pressed on the material with a total force
  // (N; 2D N/m; along the axis, positive along it: the plate's force on the material): its
  // walls' pairs hold the material in tension too (bonded) at the normal velocity of the
  // plate, the one velocity at which the material's reaction on them meets the force
  // (plate_solve). A saturated soil's coupled step only (Mandel's problem). Allocates.
  void set_plate(int axis, int side, double force);
  // the plate's velocity along its axis (m/s; settable, as a checkpoint restores it)
  double plate_velocity() const { return plate_.velocity; }
  void set_plate_velocity(double v);
  void set_time(double t);
  double time() const { return time_; }
  // the pressure's force (N, 2D: N/m) and torque (N m; 2D: N m/m, about z) on each body in
  // the last step (bodies x D, bodies x 3), about its frame's origin
  View<double, 2> body_force() { return body_force_.template view<2>({bodies_.count(), D}); }
  View<double, 2> body_torque() { return body_torque_.template view<2>({bodies_.count(), 3}); }
  index_t body_count() const { return bodies_.count(); }
  // each body's pose and velocity (bodies x 13, BodyTables::state); set_body_state: a free
  // body's back from such rows (a checkpoint)
  View<double, 2> body_state() {
    auto out = body_state_.template sized<2>({bodies_.count(), 13});
    bodies_.state(time_, out);
    return out;
  }
  void set_body_state(View<const double, 2> in) {
    bodies_.set_state(in);
    set_time(time_);
  }

  // The systems' solvers (not owned; they must outlive their use): the pressure's, the
  // volume correction's and the viscous predictor's; nullptr (the default): the step's own.
  void use_solvers(LinearSolver* pressure, LinearSolver* volume = nullptr,
                   ViscousSolver* viscous = nullptr) {
    solver_ = pressure;
    volume_solver_ = volume;
    viscous_solver_ = viscous;
  }
  // Where the step meets the other ranks (not owned); nullptr: one process alone.
  void use_exchange(Exchange<D>* exchange) { exchange_ = exchange ? exchange : &alone_; }

  // The phases, for a caller that owns a part of the domain (MPI) and for checks.
  // predict = scatter, then classify; returns the pressure unknowns.
  index_t predict(const Particles<D>& P, const Options<D>& O, bool correct);
  // The sub-cell surface's shallow nodes (O.shallow; ghost_pressure.hpp's demote_shallow)
  // taken out of node_row, the owners' decision on ranks; true when there is one (the caller
  // numbers the rows again). Part of classify on one process, of predict on ranks (after
  // the owners' unknowns).
  bool shallow_nodes(const Options<D>& O);
  // The particles to the grid: binning (theta), node mass, volume, v_old and v* (and the
  // cells' volume for the volume correction when correct), v* extended into the obstacles,
  // the nodal fraction node_f.
  void scatter(const Particles<D>& P, const Options<D>& O, bool correct);
  // The cells and nodes of the pressure system from scatter's arrays (which a caller may
  // change in between, e.g. node_f and v* on a ghost ring): the enclosed cells (subcell;
  // none otherwise), the cells' element integrals, the unknowns (node_row, rows). P: the
  // particles scatter binned (std::invalid_argument otherwise). Returns the unknowns.
  index_t classify(const Particles<D>& P, const Options<D>& O);
  // Rows and their count again from node_row (>= 0: an unknown, -1: not) after a caller
  // changed which nodes are unknowns, numbered as classify numbers them (in node order; an
  // image node of a periodic axis shares its master's row, the master's entry deciding).
  // Right after classify it changes nothing. Returns the unknowns.
  index_t renumber();
  // The pressure step after predict: assembly, the solve (the solver of use_solvers, or the
  // multigrid) for each right-hand side the wall release asks for, the ghost values.
  // Returns a Status (OK, SINGULAR, PRESSURE_NOT_CONVERGED).
  int pressure_solve(const Options<D>& O, Report& report);
  bool pressure_matrix(const Options<D>& O);  // assemble; false: singular (no free surface)
  // O.cell_pressure's pressure step in place of the nodes' (cell_pressure.hpp)
  int cell_pressure_solve(const Options<D>& O, Report& report);
  // O.coupled: after cell_pressure_solve (the split step: the contacts, a first pressure
  // and the Poisson operator's multigrid), the cells' pressure p at which the elastic
  // solve's velocity x(p) = (M / dt + K)^-1 M / dt (v* - dt / rho V^-1 P G^T p) is itself
  // divergence-free: flexible conjugate gradients on the Schur complement (rho / dt) C (M /
  // dt + K)^-1 P G^T, preconditioned by the Poisson operator's inverse plus G dt^2 / (rho
  // V_c) (Cahouet and Chabard 1988), each iteration one elastic and one Poisson solve. The
  // corrected velocity is then x(p), and the stress (to_particles) follows it: the
  // incompressible backward-Euler step, stable at any dt. The walls and tools hold what the
  // split step's contacts hold, at their velocities.
  // loosen: its tolerance times this (plastic_solve's iterates far from their fixed point)
  int coupled_solve(const Options<D>& O, Report& report, double loosen = 1.0);
  // the relative residual of the Poisson solve in coupled_solve's preconditioner
  static constexpr double PRECONDITIONER_TOL = 1e-2;
  // O.coupled with a plastic material (plasticity.hpp, is_plastic): after the coupled solve,
  // Picard iterations on the particles' return factors (solid.hpp, return_factors), each a
  // coupled solve with the old stress's force and the cells' elastic weights scaled by them,
  // until no particle's stress moves by more than PLASTIC_TOL of the largest: the step's
  // stress is then the radial return of the velocity it gives (docs/method.md, "Solids").
  // Each solve to PLASTIC_LOOSEN of the last move where that is above its own tolerance.
  // PLASTIC_NOT_CONVERGED after PLASTIC_ITERATIONS.
  int plastic_solve(const Particles<D>& P, const Options<D>& O, Report& report);
  static constexpr double PLASTIC_TOL = 1e-3;
  static constexpr double PLASTIC_LOOSEN = 1e-2;
  static constexpr index_t PLASTIC_ITERATIONS = 100;
  // the elastic solve's velocity (nn x D) from the base velocity in v_c_ (the viscous
  // system assembled from it, solved, the fixed components as given); false: not converged
  bool elastic_velocity(const Options<D>& O, Report& report, View<double, 2> out);
  // the viscous system of the last viscous_system (n unknowns) solved into vx_, counted in
  // the report; false: it did not converge (the report names the worst row's node)
  bool viscous_solve(const Options<D>& O, Report& report, index_t n);
  void cell_hold();  // the projector onto the components walls and obstacles do not hold
  // one solve of the pressure matrix (cols, vals over rows: nodes, or cells), counted in the
  // report; false: it did not converge (the report names the worst row's node)
  bool counted_solve(const Options<D>& O, Report& report, View<const index_t, 2> cols,
                     View<const double, 2> vals, View<const index_t> rows, View<const double> b,
                     View<double> y, View<double> scratch, index_t& iterations, bool cells,
                     double tol = 0.0);  // tol: the relative residual (0: O.tol)
  void pressure_rhs(const Options<D>& O);
  void extend_pressure(const Options<D>& O);
  void warm_start();  // the last pressure at this step's unknowns into x0, p_node cleared
  // the sealed pockets of the last pressure_matrix (pockets.hpp), each held at 0 at its top
  index_t pockets() const { return npockets_; }
  // viscous_predictor = viscous_start, viscous_system, the solve (when it has unknowns),
  // viscous_apply: in parts for a caller that solves the system itself (MPI:
  // docs/design/mpi.md). O.viscous false: none of them does anything.
  int viscous_predictor(const Options<D>& O, Report& report);
  // viscous_start: the walls' starting contact, the cells' viscosity (eta; report.capped
  // counts the local cells held at the cap) and the velocity the solve starts from
  // (viscous_base, nn x D: v* corrected by the last pressure; a caller that holds only part
  // of the grid overwrites it at the nodes whose corrector reaches past its cells).
  void viscous_start(const Options<D>& O, Report& report);
  // viscous_system: the unknowns (viscous_rows: nn x D, -1 where held or massless;
  // viscous_off: D + 1, the first row of each component) and the system (viscous_cols,
  // viscous_vals: D x n x 3^D, columns numbered within their component; viscous_rhs;
  // viscous_x: the start at each row) from viscous_base. Returns n.
  index_t viscous_system(const Options<D>& O);
  // viscous_apply: x (n values of the last viscous_system, m/s; std::invalid_argument
  // otherwise) into v_star, the held nodes set to their held values; nothing when that system
  // had no unknowns.
  void viscous_apply(View<const double> x);
  // finish = correct, volume_correction (when correct), to_particles.
  int finish(const Particles<D>& P, const Options<D>& O, bool correct, Report& report);
  // v_new: the corrected velocity (eq. 16) with the walls' and obstacles' conditions.
  void correct(const Options<D>& O);
  // The volume correction in parts, for a caller that solves its cell-centred system itself
  // (MPI: docs/design/mpi.md, section 2): volume_correction = volume_system, the solve (when
  // the system has rows and is anchored), volume_apply. Both throw std::logic_error on a State
  // built without the volume correction.
  // volume_system: the cells' density from cell_vol (a scatter with correct), the system on
  // the cells holding material (volume_rows, volume_cols, volume_vals, volume_rhs, cell_row,
  // volume_air, volume_anchored) and, when O.pockets and the system is anchored, its sealed
  // pockets made solvable (pockets.hpp); O.pockets false leaves them, for a caller that owns
  // part of the domain and decides them across its parts. Returns the rows.
  index_t volume_system(const Options<D>& O);
  // volume_apply: q, one value per row of the last volume_system (std::invalid_argument
  // otherwise), into volume_q (0 off the rows) and the faces' displacements that
  // to_particles(displaced) adds. When that system had no rows or was not anchored (it touched
  // no empty cell: its volume cannot change) the faces are zero, q and volume_q untouched.
  // Returns the faces clamped at O.volume_dmax cells.
  index_t volume_apply(const Options<D>& O, View<const double> q);
  // Grid to particles (with the last volume correction's face displacements when displaced),
  // push-out of obstacles, the periodic wrap, for the first `owned` of the particles scatter
  // was given (a rank's own; -1: all); returns the particles put back inside. A solid's
  // stress update (solid.hpp) runs on them; its tools' reactions read every particle's
  // stress round their nodes through scatter's binning (std::logic_error when P is not what
  // scatter binned), a rank's halo with its owners' new stress (Exchange::refresh_halo).
  index_t to_particles(const Particles<D>& P, const Options<D>& O, bool displaced,
                       index_t owned = -1);

  // the arrays Python reads (views of the state's own storage)
  View<double> p_node() { return p_node_.view(grid_.nnodes); }
  // a solid's pressure per cell (Options::cell_pressure; 0 elsewhere), Pa
  View<double> p_cell() { return p_cell_.view(grid_.ncells); }
  View<double, 2> v_new() { return v_new_.template view<2>({grid_.nnodes, D}); }
  View<bool, 2> contact() { return contact_.template view<2>({grid_.nnodes, D}); }
  View<double> eta() { return eta_.view(viscous_on_ ? grid_.ncells : 0); }
  View<bool> ocontact() { return ocontact_.view(grid_.nnodes); }
  View<double> volume_q() { return q_.view(volume_on_ ? grid_.ncells : 0); }
  View<const index_t> rows() { return rows_.view(nrows_); }
  // scatter's and classify's arrays, read and written by a caller between the phases
  View<double> node_mass() { return node_mass_.view(grid_.nnodes); }
  View<double> node_vol() { return node_vol_.view(grid_.nnodes); }
  View<double, 2> v_old() { return v_old_.template view<2>({grid_.nnodes, D}); }
  View<double, 2> v_star() { return v_star_.template view<2>({grid_.nnodes, D}); }
  View<double> node_f() { return node_f_.view(grid_.nnodes); }
  View<index_t> node_row() { return node_row_.view(grid_.nnodes); }
  View<double> theta() { return theta_.view(grid_.ncells); }
  View<double> cell_vol() { return cell_vol_.view(volume_on_ ? grid_.ncells : 0); }
  // the rows next to a free surface, as the last pressure_matrix found them
  View<bool> anchored() { return anchored_.view(nrows_); }
  View<const index_t, 2> matrix_cols() { return cols_.template view<2>({nrows_, NS}); }
  View<const double, 2> matrix_vals() { return vals_.template view<2>({nrows_, NS}); }
  View<double> rhs() { return rhs_.view(nrows_); }
  View<double> x0() { return x_.view(nrows_); }
  // the last volume_system's cell-centred system (empty before one, and without the volume
  // correction): the cell of each row, the ELL matrix (n x 3^D, -1: no column), the
  // right-hand side, the rows that touch an empty cell (their values sum to more than 0.5:
  // unit couplings) and whether any does (anchored); each cell's row (-1: none)
  View<const index_t> volume_rows() { return vol_rows_.view(vol_n_); }
  View<const index_t, 2> volume_cols() { return vol_cols_.template view<2>({vol_n_, NS}); }
  View<const double, 2> volume_vals() { return vol_vals_.template view<2>({vol_n_, NS}); }
  View<double> volume_rhs() { return vol_rhs_.view(vol_n_); }
  View<const bool> volume_air() { return vol_air_.view(vol_n_); }
  View<const index_t, 2> viscous_rows() { return vrow_.template view<2>({vis_nn(), D}); }
  View<const index_t> viscous_off() { return voff_.view(viscous_on_ ? D + 1 : 0); }
  View<const index_t, 3> viscous_cols() { return vcols_.template view<3>({D, vis_n_, NS}); }
  View<const double, 3> viscous_vals() { return vvals_.template view<3>({D, vis_n_, NS}); }
  View<const double> viscous_rhs() { return vrhs_.view(vis_n_); }
  View<double> viscous_x() { return vx_.view(vis_n_); }
  View<double, 2> viscous_base() { return v_c_.template view<2>({vis_nn(), D}); }
  bool volume_anchored() const { return vol_anchored_; }
  // a caller that owns part of the domain (MPI) says whether the whole system touches an
  // empty cell: volume_apply zeroes the faces of a system that does not
  void set_volume_anchored(bool anchored) { vol_anchored_ = anchored; }
  View<const index_t> cell_row() { return cell_row_.view(volume_on_ ? grid_.ncells : 0); }
  const Grid<D>& grid() const { return grid_; }
  // wall-clock seconds spent in each phase (Phase) since construction
  const std::array<double, NPHASES>& phase_seconds() const { return phase_seconds_; }

 private:
  int volume_correction(const Options<D>& O, Report& report);
  void bin_particles(const Particles<D>& P);
  void cell_integrals(const Particles<D>& P, const Options<D>& O);
  void classify_nodes(const Options<D>& O);
  void fill_rows();  // rows_ from node_row_ and nrows_
  void anchor_pockets(const Options<D>& O);

  int step_once(const Particles<D>& P, const Options<D>& O, bool correct, Report& report);
  std::array<double, NPHASES> phase_seconds_{};
  double since_volume_ = 0.0;
  std::vector<double> travel_;  // per inlet row (inlet_travel)
  InletPool pool_;
  Grid<D> grid_;
  double cell_volume_;
  std::array<double, D> lower_, upper_;
  double margin_;
  GridTables<D> T_;
  bool volume_on_, viscous_on_;
  bool obstacles_;
  // the obstacle tables the step reads: the fixed ones of T_, or with moving bodies their
  // tables at the bodies' present pose (bodies.hpp)
  ObstacleTables<D> ob_;
  BodyTables<D> bodies_;
  double time_ = 0.0;                        // s: the flow time (moves the bodies)
  Buffer<double> body_force_, body_torque_;  // the last step's pressure force on each body
  Buffer<double> body_state_;                // body_state's rows
  // couple_bodies' arrays
  Buffer<double> body_J_, body_K_, body_Y_, body_S_, body_z_, body_KY_;
  template <class Solve>
  bool couple_bodies(const Options<D>& O, Solve& solve);
  index_t nrows_ = 0;
  index_t binned_ = -1;  // the particles of the last scatter (-1: none yet)
  index_t nsurface_ = 0, npartial_ = 0;

  // work arrays (Buffers: grown, never shrunk)
  Buffer<index_t> cell_, start_, order_;
  // the shallow nodes' surface fraction (-1: not one; ghost_pressure.hpp's demote_shallow)
  Buffer<double> dep_t_;
  bool shallow_ = false;
  View<const double> shallow(index_t nn) {
    return shallow_ ? View<const double>(dep_t_.view(nn)) : View<const double>();
  }
  Buffer<double> theta_, node_mass_, node_mom_, node_vol_, v_old_, v_star_, v_c_, v_new_, node_f_;
  Buffer<bool> enclosed_;
  Buffer<index_t> slot_, surface_slot_, node_row_, rows_, partial_, listed_;
  // sealed pockets of the pressure system (pockets.hpp): each row's pocket, the held rows
  Buffer<index_t> component_, pocket_order_, pockets_;
  Buffer<double> pocket_mean_;
  index_t npockets_ = 0;
  Buffer<bool> contact_, ocontact_, anchored_;
  // the contact's complementarity (pressure_solve): the rows it constrains, those held at
  // p = 0 and the next round's, the right-hand side, the matrix before holding, the held
  // rows as node values (a rank's exchange)
  Buffer<bool> candidate_, zero_, next_;
  Buffer<double> b_, vals0_, zero_node_;
  Buffer<double> p_node_;
  // the cell pressure's rows, gradients (rows x 2^D x D), hold projectors (nn x D x D), node
  // volumes and pressure (cell_pressure.hpp); grown at a solid's first step
  Buffer<index_t> pc_row_, pc_rows_;
  Buffer<double> pc_G_, pc_P_, pc_vol_, pc_X_, pc_grad_, pc_mean_, p_cell_;
  Buffer<double> pc_cell_grad_;  // a rank's cells' pressure gradients (its ghost layer's filled)
  // the coupled solve's (O.coupled): v* before the elastic solve, the elastic velocity and
  // its part along the search direction (nn x D), the CG's cell vectors (rows x 6), a
  // pressure by cell (nc)
  Buffer<double> cp_v0_, cp_x_, cp_dx_, cp_cells_, cp_field_;
  index_t npc_ = 0;
  Buffer<double> K_, C_, V_, Cs_, Vs_, Vcells_;  // the step's element integrals
  Buffer<index_t> cols_;
  Buffer<double> vals_, rhs_, x_, scratch_;
  Multigrid<D> pressure_mg_;
  // a saturated soil's coupled solve: the preconditioner's second part, the skeleton's
  // stiffness and the pore flow as one operator on the cells (coupled_solve)
  Multigrid<D> pore_mg_;
  Buffer<index_t> pore_cols_;
  Buffer<double> pore_vals_, pore_z_;
  LinearSolver* solver_ = nullptr;
  LinearSolver* volume_solver_ = nullptr;
  ViscousSolver* viscous_solver_ = nullptr;
  Exchange<D> alone_;
  Exchange<D>* exchange_ = &alone_;
  // the rows at nodes this part owns (all: nrows_), the owned nodes' wall contacts
  index_t owned_rows();
  index_t owned_cell_rows();  // a solid's cell-pressure rows a rank owns
  index_t owned_contacts();
  // The walls' and obstacles' releases release() makes (it returns their count): on a rank
  // those at the nodes it owns, summed over the ranks (every rank then solves again or not)
  template <class Release>
  index_t releases(Release&& release);
  // volume correction
  Buffer<double> cell_vol_, density_, vol_vals_, vol_rhs_, q_, qx_, faces_[D];
  Buffer<index_t> cell_row_, vol_cols_, vol_rows_;
  Buffer<bool> vol_air_;
  index_t vol_n_ = 0;                                   // the last volume_system's rows
  bool vol_anchored_ = false;                           // and whether one touches an empty cell
  Buffer<index_t> vol_part_, vol_order_, vol_anchors_;  // its sealed pockets
  Buffer<double> vol_mean_;
  Multigrid<D> volume_mg_;
  // viscous predictor
  Buffer<double> eta_, eta_weight_, vu_, v_rate_, vvals_, vrhs_, vx_, vwork_;
  Buffer<index_t> vrow_, voff_, vcols_, vnode_;
  index_t vis_n_ = 0;  // the last viscous_system's unknowns
  index_t vis_nn() const { return viscous_on_ ? grid_.nnodes : 0; }
  Buffer<double> v_save_;  // scratch (MPMFLOW_PICARD): v* before the viscous step
  Buffer<double> force_;   // a solid's internal forces (solid.hpp; sized on its first step)
  // a solid's cells' share of particles that yielded in the last step (solid.hpp)
  Buffer<double> cell_yield_;
  Buffer<double> cell_water_;  // a saturated soil's: each cell's share of free water
  // plastic_solve's: the particles' return factors, the cells' mean of them, the cells' whole
  // elastic weight, v* before the elastic increment with the whole old stress's force, the
  // scaled stress's force
  Buffer<double> ps_factor_, ps_mean_, ps_weight_, ps_v0_, ps_f_;
  struct Plate {
    bool on = false;
    int axis = 0;
    double force = 0.0, velocity = 0.0;
    std::vector<index_t> pairs;  // its walls' pairs
  };
  Plate plate_;
  // the walls' held velocities and bonds with the plate's (the tables' own where none)
  Buffer<double> plate_held_;
  Buffer<bool> plate_bonded_;
  Buffer<double> pl_p_, pl_v_, pl_n_, pl_f_;  // plate_solve's first solution; pressure forces
  void hold_plate(double velocity);
  double plate_reaction(const Options<D>& O);
  int plate_solve(const Options<D>& O, Report& report);
  // the cells' shares of free water of a saturated soil's last scatter (empty: none)
  View<const double> water_cells(const Options<D>& O);
  // The multigrid's shape of the cell grid (nodes false: a point a cell) or of the node grid
  // (a point a node): the points along each axis, and each periodic axis's period (0: none)
  struct MgShape {
    std::array<index_t, D> dims{}, period{};
  };
  MgShape mg_shape(bool nodes) const;
  bool solid_scattered_ = false;  // the last scatter's particles carry a solid's stress
  bool held_still_ = false;       // viscous_system holds its held components at 0 (coupled_solve)
  bool rate_from_new_ = false;
  std::array<Multigrid<D>, D> viscous_mg_;
  // integrals of this step, as views into the buffers above
  struct Integrals {
    View<const index_t> slot, rhs_slot, cor_slot;
    View<const double, 3> K;
    View<const double, 4> rhs_C, cor_C;
    View<const double, 2> rhs_V, cor_V;
  } I_;
};

}  // namespace mpmflow
