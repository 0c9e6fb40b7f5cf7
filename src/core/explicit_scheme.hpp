// The explicit weakly compressible scheme (the comparator of Kularathna & Soga 2017, section
// 4), update stress last, written once for 2D and 3D. The material is water of bulk modulus
// K: p = K (1 - J), J = V / V0, once per cell from the particles in it (every particle of a
// cell takes its cell's J). A cell's pressure acts at its quadrature point: its centre when
// the cell is full, else its particles' centroid. The time loop runs inside
// ``explicit_steps`` (one explicit step is cheap and there are many).
//
// Scatters (particles to nodes, particles to cells) run serially in particle order, as the
// reference kernel does; cell-to-node sums are gathers per node over its cells in cell order;
// the rest runs in parallel. Results are therefore the same bits on any number of threads.
#pragma once

#include "grid.hpp"
#include "view.hpp"

namespace mpmflow {

// What ``explicit_steps`` reports.
struct ExplicitStats {
  index_t steps = 0;      // steps taken
  double time = 0.0;      // time advanced (s)
  double smallest = 0.0;  // smallest step taken (s; infinity if none)
  index_t moved = 0;      // particles put back inside the domain
  bool stopped = false;   // stopped because a particle was faster than max_speed (or NaN)
  double vmax = 0.0;      // largest particle speed at the end (m/s)
};

// Volumetric strain and pressure once per cell (in place). Per cell c: reference volume
// V0_c = sum m_p / density (m^3, cell_v0), current volume sum V_p (cell_j, then J_c), and the
// V0-weighted local coordinates of its particles (cell_xi, ncells x D). Then J_c = V_c / V0_c
// capped at 1 + tension / bulk, cell_vol = J_c V0_c (m^3), cell_p = bulk (1 - J_c) (Pa), and
// the quadrature point cell_xi: the centre if V0_c >= full h^D, else the particles' centroid.
// A cell with V0_c below sparse h^D: J_c = 1, no pressure, cell_vol = 0 (takes no part).
template <int D>
void cell_state(const Grid<D>& g, View<const double, 2> x, View<const double> mass,
                View<const double> volume, double density, double bulk, double tension, double full,
                double sparse, View<double> cell_j, View<double> cell_vol, View<double> cell_v0,
                View<double, 2> cell_xi, View<double> cell_p);

// Each particle takes its cell's J: volume = J_c m_p / density (m^3), and its pressure (Pa):
// with ``smoothing`` the interpolation of the node pressures node_p, each the cell_vol-weighted
// average of the pressures of the cells around the node (node_w: the weights); else its
// cell's pressure.
template <int D>
void particle_state(const Grid<D>& g, View<const double, 2> x, View<const double> mass,
                    View<double> volume, View<double> pressure, double density, bool smoothing,
                    View<const double> cell_j, View<const double> cell_vol,
                    View<const double> cell_p, View<double> node_w, View<double> node_p);

// The largest particle speed |v| (m/s) of v (n x D); NaN if any speed is NaN.
double max_speed(View<const double, 2> v);

// Explicit steps over ``span`` seconds (in place). With ``safety`` > 0 each step is
// re-evaluated from the current state: the span's remainder cut into equal steps of at most
// safety h / (|v|max + Q + sqrt(Q^2 + c^2)) (c = sqrt(bulk / density) the sound speed, Q the
// artificial viscosity's signal speed); with safety = 0, nsteps equal steps. Stops early when
// a particle is faster than ``max_speed`` (m/s) or NaN. Expects the cell state of the current
// particles (``cell_state``), keeps it up to date, and sets the particles' volume and pressure
// at the end (``particle_state``).
//
// One step: (1) particles to grid: mass and momentum, nodal velocity v_old; the artificial
// bulk viscosity q_c = rho_c (q_lin c h |div v| + q_quad h^2 (div v)^2) (Pa) of each
// compressing cell; (2) nodal force f_i = sum_c V_c (p_c + q_c) grad N_i(xi_c) (N), plus
// gravity (m/s^2, D entries); nodes lighter than mass_cut density h^D take gravity only;
// v_new after the step, wall contact (normal velocity zero where the velocity points into a
// wall, tangential too at a no-slip side, no_slip(2 k + (sign > 0)), 2 D flags x_min, x_max, ...;
// ``contact``: nnodes x D scratch); the new J of each cell from div v_new; (3) grid to particles:
// FLIP/PIC velocity (FLIP fraction flip_ms per millisecond), x += dt sum N v_new, put back inside
// [margin, upper - margin] if it crossed a wall; (4) the cells' J and pressure from the moved
// particles. full, sparse: fractions of a cell's volume (see ``cell_state``). Work arrays:
// node_mass (nnodes), node_mom, v_old, v_new (nnodes x D), cell_q (ncells), node_w, node_p
// (nnodes).
template <int D>
ExplicitStats explicit_steps(const Grid<D>& g, double span, index_t nsteps, double safety,
                             View<double, 2> x, View<double, 2> v, View<double> pressure,
                             View<const double> mass, View<double> volume, double density,
                             double bulk, View<const double> gravity, double flip_ms,
                             View<const bool> no_slip, bool smoothing, double full, double sparse,
                             double mass_cut, double q_lin, double q_quad, double tension,
                             double max_speed, View<const double> upper, double margin,
                             View<double> node_mass, View<double, 2> node_mom,
                             View<double, 2> v_old, View<double, 2> v_new, View<bool, 2> contact,
                             View<double> cell_j, View<double> cell_vol, View<double> cell_v0,
                             View<double, 2> cell_xi, View<double> cell_p, View<double> cell_q,
                             View<double> node_w, View<double> node_p);

}  // namespace mpmflow
