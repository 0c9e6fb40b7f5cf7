// The grid's side of solids with a stress history (plasticity.hpp; docs/method.md,
// "Solids"), 2D and 3D: the particles' deviatoric stress as nodal forces in the predictor
// (the paper's eq. 4, explicitly), and the stress's update from the corrected velocity.
#pragma once

#include "grid.hpp"
#include "transfer.hpp"
#include "view.hpp"

namespace mpmflow {

// The predictor's internal force of the particles' deviatoric stress s_p (n x D x D, Pa):
// f_i = -sum_p V_p s_p grad N_i(x_p) (N), as the nodes' acceleration a_i = f_i / M_i, then
// passed to the particles and back (a_p = sum_i N_i(x_p) a_i; dv_i = sum_p N_i m_p a_p /
// M_i) and added to the predictor: v_star_i += dt dv_i where M_i > 0. The round trip is the
// predictor's side of the modified update-stress-last scheme (velocity_to_grid): with
// multilinear N the gradient of N_i does not vanish where N_i does, so at a node a solid has
// just reached f_i / M_i is unbounded; the projection spread that node's velocity to its
// full neighbours through the pressure and a cantilever blew up as its lower face crossed a
// row of nodes. Mapped through the particles, the acceleration is an average of bounded
// ones. The particles come binned by cell (order, start: binning.hpp) and are summed in
// strips of cell slabs as particles_to_grid sums them (strips.hpp), so results do not depend
// on the thread count. acc, dv: scratch of nn x D.
template <int D>
void internal_forces(const Grid<D>& g, View<const double, 2> x, View<const double> mass,
                     View<const double> volume, View<const double, 3> stress,
                     View<const index_t> order, View<const index_t> start,
                     View<const double> node_mass, double dt, View<double, 2> acc,
                     View<double, 2> dv, View<double, 2> v_star);

// Each cell's share (by mass) of its particles that yielded in the last step (0 to 1; 0 in
// cells without particles): the implicit elastic predictor leaves a yielded cell's elastic
// stiffness out (src/core/step.cpp, viscous_start), since a perfectly plastic material's
// stress does not grow along its flow. Particles binned (binning.hpp).
template <int D>
void yielded_share(const Grid<D>& g, View<const double> mass, View<const double> yielding,
                   View<const index_t> order, View<const index_t> start, View<double> share);

// The grid velocity a solid's stress update reads (the modified update-stress-last scheme,
// Sulsky et al. 1995 and Nairn 2003): the particles' new velocities (g2p.new_velocity, at
// their positions at the step's start) mapped back to the nodes, out_i = sum_p N_i m_p v_p /
// M_i (m/s; 0 where M_i = 0). The corrected grid velocity itself is not used: at a node that
// a particle has just reached, the node's mass is a sliver of the particle's and the force
// over it a whole one, so its velocity is far off, and a strain rate read from it grows
// without bound as the solid crosses cells (a cantilever at h = H / 8 blew up in 1,000
// steps). Particles binned as for particles_to_grid; summed in the same strips.
template <int D>
void velocity_to_grid(const GridToParticle<D>& g2p, View<const double> mass,
                      View<const index_t> order, View<const index_t> start,
                      View<const double> node_mass, View<double, 2> out);

// The stress of the first n particles (n = x.extent(0)) over a step dt (s): the velocity
// gradient of v_grid (nn x D, m/s: velocity_to_grid's) and the pressure p_node (Pa) interpolated at
// x_p (the positions at the step's start), then update_stress (plasticity.hpp) with the material
// model and its parameters par. plastic_strain (n) accumulates the equivalent plastic
// strain; yielding (n) is set to 1 where the particle yielded in this step, else 0.
// Particles of mass 0 (retired through an outlet) are skipped. Returns how many yielded.
template <int D>
index_t update_stresses(const Grid<D>& g, View<const double, 2> x, View<const double> mass,
                        View<const double, 2> v_grid, View<const double> p_node, double dt,
                        int model, View<const double> par, View<double, 3> stress,
                        View<double> plastic_strain, View<double> yielding);

}  // namespace mpmflow
