// The grid's side of solids with a stress history (plasticity.hpp; docs/method.md,
// "Solids"), 2D and 3D: the particles' deviatoric stress as nodal forces in the predictor
// (the paper's eq. 4, explicitly), and the stress's update from the corrected velocity.
#pragma once

#include "grid.hpp"
#include "view.hpp"

namespace mpmflow {

// f (nn x D, N; 2D N/m): f_i = -sum_p V_p s_p grad N_i(x_p), the nodes' force of the particles'
// deviatoric stress s_p (n x D x D, Pa), summed as internal_forces sums it (below).
template <int D>
void stress_forces(const Grid<D>& g, View<const double, 2> x, View<const double> volume,
                   View<const double, 3> stress, View<const index_t> order,
                   View<const index_t> start, View<double, 2> f);

// The predictor's internal force of the particles' deviatoric stress s_p (n x D x D, Pa):
// f_i = -sum_p V_p s_p grad N_i(x_p) (N), added to the predictor as the nodes' acceleration:
// v_star_i += dt f_i / M_i where M_i > 0. It is applied at the nodes as it is, the same force
// the stress update's strain rate does work against: passed to the particles and back first
// (dv = M^-1 M_c a, the particles' consistent mass), it was a smoothing that took the
// bending out of a cantilever's outer fibres, and with the projection's node volumes
// (cell_pressure.hpp: node_volumes) it made the swing 15-40% too soft (docs/method.md,
// "Solids"). At a node a solid has just reached, M_i is a sliver of a particle's mass and
// f_i / M_i large; the particles' velocities and positions read that node through N_i,
// which vanishes there, so what they take from it stays bounded (the stress reads its
// gradient: measured, a cantilever crossing rows of nodes for 8 periods at h = H / 8 and
// 3 in 3D, at time.dt = "auto"). The particles come binned by cell (order, start: binning.hpp) and
// are summed in strips of cell slabs as particles_to_grid sums them (strips.hpp), so results do not
// depend on the thread count. acc: scratch of nn x D.
template <int D>
void internal_forces(const Grid<D>& g, View<const double, 2> x, View<const double> volume,
                     View<const double, 3> stress, View<const index_t> order,
                     View<const index_t> start, View<const double> node_mass, double dt,
                     View<double, 2> acc, View<double, 2> v_star);

// Each cell's share (by mass) of its particles that yielded in the last step (0 to 1; 0 in
// cells without particles): the implicit elastic predictor leaves a yielded cell's elastic
// stiffness out (src/core/step.cpp, viscous_start), since a perfectly plastic material's
// stress does not grow along its flow. Particles binned (binning.hpp).
template <int D>
void yielded_share(const Grid<D>& g, View<const double> mass, View<const double> yielding,
                   View<const index_t> order, View<const index_t> start, View<double> share);

// A saturated soil's cells: each one's share (by mass) of free water (plasticity.hpp,
// free_water; 0 to 1, 0 in cells without particles). The elastic solve takes the skeleton's
// share of a cell's stiffness, and a cell with at least half of it free water is the free
// water's in the pore flow (cell_pressure.hpp, darcy_*). Particles binned.
template <int D>
void water_share(const Grid<D>& g, View<const double> mass, View<const double> volume,
                 double water_density, View<const index_t> order, View<const index_t> start,
                 View<double> share);

// The stress of the first n particles (n = x.extent(0)) over a step dt (s): the velocity
// gradient of v_grid (nn x D, m/s: the corrected grid velocity) and the pressure p_node (Pa)
// interpolated at x_p (the positions at the step's start), then update_stress (plasticity.hpp)
// with the material model and its parameters par. plastic_strain (n) accumulates the equivalent
// plastic strain; yielding (n) is set to 1 where the particle yielded in this step, else 0.
// Particles of mass 0 (retired through an outlet) are skipped, and a saturated soil's free
// water (plasticity.hpp: free_water; volume, m^3) keeps no stress. Returns how many yielded.
template <int D>
index_t update_stresses(const Grid<D>& g, View<const double, 2> x, View<const double> mass,
                        View<const double> volume, View<const double, 2> v_grid,
                        View<const double> p_node, double dt, int model, View<const double> par,
                        View<double, 3> stress, View<double> plastic_strain, View<double> yielding);

}  // namespace mpmflow
