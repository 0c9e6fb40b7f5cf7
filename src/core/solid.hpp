// The grid's side of solids with a stress history (plasticity.hpp; docs/method.md,
// "Solids"), 2D and 3D: the particles' deviatoric stress as nodal forces in the predictor
// (the paper's eq. 4, explicitly), and the stress's update from the corrected velocity.
#pragma once

#include "grid.hpp"
#include "view.hpp"

namespace mpmflow {

// f (nn x D, N; 2D N/m): f_i = -sum_p V_p s_p grad N_i(x_p), the nodes' force of the particles'
// deviatoric stress s_p (n x D x D, Pa), summed as internal_forces sums it (below); with
// scale (n; empty: 1), of the stresses scale_p s_p (the coupled step's secant: return_factors).
template <int D>
void stress_forces(const Grid<D>& g, View<const double, 2> x, View<const double> volume,
                   View<const double, 3> stress, View<const index_t> order,
                   View<const index_t> start, View<double, 2> f,
                   View<const double> scale = View<const double>());

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
                     View<double, 2> acc, View<double, 2> v_star,
                     View<const double> scale = View<const double>());

// Each cell's mean (by mass) of a value on its particles (0 in cells without particles):
// the share of particles that yielded in the last step, whose elastic stiffness the implicit
// elastic predictor leaves out (src/core/step.cpp, viscous_start), since a perfectly plastic
// material's stress does not grow along its flow; the coupled step's mean return factor
// (return_factors). Particles binned (binning.hpp).
template <int D>
void cell_mean(const Grid<D>& g, View<const double> mass, View<const double> value,
               View<const index_t> order, View<const index_t> start, View<double> mean);

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

// The coupled step's plastic secant (src/core/step.cpp, plastic_solve): for each of the
// first n particles (n = x.extent(0)), the factor of the radial return (plasticity.hpp,
// radial_return) of the trial stress that the velocity v_grid (nn x D, m/s) and the pressure
// p_node (Pa) would give its stress (n x D x D, Pa) over dt (s), as update_stresses would
// take it: 1 where it stays elastic, k / sqrt(J2) where it yields. The stress after the step
// is then factor (s + dt (2 G dev D + spin)). Particles of mass 0 take 1. factor holds the
// last iterate's on entry. Returns the largest change of a particle's stress this makes,
// |factor change| sqrt(J2(trial)), over the largest sqrt(J2) of the returned stresses (0
// where no particle is stressed): a particle near no strength (a frictional soil's surface,
// at p near 0) may swing its factor from 0 to 1 from one iterate to the next, and move its
// stress by nothing that matters.
template <int D>
double return_factors(const Grid<D>& g, View<const double, 2> x, View<const double> mass,
                      View<const double, 2> v_grid, View<const double> p_node, double dt, int model,
                      View<const double> par, View<const double, 3> stress, View<double> factor);

}  // namespace mpmflow
