// The particles' totals a run's outputs and its blow-up guard read at an output time, in one
// pass over the particles, 2D and 3D: kinetic and potential energy, the fastest particle, the
// largest pressure and the particles whose position or velocity is not finite.
#pragma once

#include "view.hpp"

namespace mpmflow {

struct ParticleTotals {
  double kinetic = 0.0;       // J (J/m in 2D): sum of m |v|^2 / 2
  double potential = 0.0;     // J (J/m in 2D): -sum of m g . x
  double max_speed2 = 0.0;    // (m/s)^2: the largest |v|^2 of the finite particles
  double max_pressure = 0.0;  // Pa: the largest pressure (-inf when there is no particle)
  index_t fastest = -1;       // the particle of max_speed2 (the first of equal ones; -1: none)
  index_t nonfinite = 0;      // particles with a non-finite position or velocity
  index_t first_nonfinite = -1;
};

// The totals of the particles (x, v: n x D, m and m/s; mass, kg; pressure, Pa) under gravity
// (D entries, m/s^2). Summed in fixed chunks (parallel.hpp: reduce_chunks), so the bits do
// not depend on the number of threads. A particle whose position or velocity is not finite
// is counted, and left out of the energies and the fastest.
template <int D>
ParticleTotals particle_totals(View<const double, 2> x, View<const double, 2> v,
                               View<const double> mass, View<const double> pressure,
                               const double* gravity);

}  // namespace mpmflow
