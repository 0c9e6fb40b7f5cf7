// The particles a step moves: views of the caller's arrays (NumPy's, or a rank's local set
// of its own particles and its neighbours' halo, exchange.hpp).
#pragma once

#include "view.hpp"

namespace mpmflow {

// n particles.
template <int D>
struct Particles {
  View<double, 2> x;    // n x D (m)
  View<double, 2> v;    // n x D (m/s)
  View<double> mass;    // kg; written only where an outlet retires a particle (0)
  View<double> volume;  // m^3; likewise
  View<double> pressure;
  // n x D x D (1/s): each particle's affine velocity matrix C_p with APIC transfers (empty:
  // FLIP/PIC, Options::flip)
  View<double, 3> affine{};
  // solids (plasticity.hpp; empty: a fluid): the deviatoric stress s_p (n x D x D, Pa), the
  // equivalent plastic strain and whether the particle yielded in the last step (n, 0 or 1)
  View<double, 3> stress{};
  View<double> plastic_strain{}, yielding{};
  index_t count() const { return x.extent(0); }

  // the first m particles (m <= count())
  Particles head(index_t m) const {
    MPMFLOW_BOUNDS(m >= 0 && m <= count());
    Particles P = *this;
    P.x = View<double, 2>(x.data(), {m, D});
    P.v = View<double, 2>(v.data(), {m, D});
    P.mass = View<double>(mass.data(), {m});
    P.volume = View<double>(volume.data(), {m});
    P.pressure = View<double>(pressure.data(), {m});
    if (affine.size() > 0) P.affine = View<double, 3>(affine.data(), {m, D, D});
    if (stress.size() > 0) {
      P.stress = View<double, 3>(stress.data(), {m, D, D});
      P.plastic_strain = View<double>(plastic_strain.data(), {m});
      P.yielding = View<double>(yielding.data(), {m});
    }
    return P;
  }
};

}  // namespace mpmflow
