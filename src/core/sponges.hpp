// Damping zones (a numerical beach; [[sponges]] of a case, boundaries/sponges.py builds the
// rates): the water's velocity relaxed towards rest where the rate c (1/s, per node) is not
// zero, implicitly over the step, so that a wave running into the zone is damped out instead
// of reflected by the wall behind it. The predictor's velocity is v* = v + dt g (+ the viscous
// and a solid's forces): the zone damps all of it but gravity's increment,
//   v* <- dt g + (v* - dt g) / (1 + c dt),
// so that water at rest in the zone stays at rest (damping dt g too would lower the pressure
// gradient the projection then needs there below rho g: the zone's water would stand higher
// than the rest). The projection that follows keeps the flow divergence-free: the zone takes
// momentum, not volume. Nodes without mass are left alone.
#pragma once

#include <array>

#include "view.hpp"

namespace mpmflow {

template <int D>
void damp_velocity(View<const double> rate, View<const double> node_mass,
                   const std::array<double, D>& gravity, double dt, View<double, 2> v) {
  for (index_t i = 0; i < rate.size(); ++i) {
    if (!(rate(i) > 0.0) || !(node_mass(i) > 0.0)) continue;
    const double f = 1.0 / (1.0 + rate(i) * dt);
    for (int k = 0; k < D; ++k) v(i, k) = dt * gravity[k] + f * (v(i, k) - dt * gravity[k]);
  }
}

}  // namespace mpmflow
