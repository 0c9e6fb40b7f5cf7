// The particles' totals at an output time (src/core/totals.hpp).
#include "../totals.hpp"

#include <nanobind/stl/tuple.h>

#include <stdexcept>
#include <tuple>

#include "arrays.hpp"
#include "modules.hpp"

namespace mpmflow::bind {

void bind_totals(nb::module_& m) {
  m.def(
      "particle_totals",
      [](Array<const double> x, Array<const double> v, Array<const double> mass,
         Array<const double> pressure, Array<const double> gravity) {
        auto vx = view<const double, 2>(x, "x");
        auto vv = view<const double, 2>(v, "v");
        auto vm = view<const double>(mass, "mass");
        auto vp = view<const double>(pressure, "pressure");
        auto vg = view<const double>(gravity, "gravity");
        const index_t n = vx.extent(0), D = vx.extent(1);
        if (vv.extent(0) != n || vv.extent(1) != D || vm.size() != n || vp.size() != n ||
            vg.size() != D)
          throw std::invalid_argument(
              "particle_totals: x and v (n x D), mass and pressure (n) and gravity (D) differ "
              "in size");
        const ParticleTotals t = with_dim(D, [&](auto d) {
          constexpr int DD = decltype(d)::value;
          return particle_totals<DD>(vx, vv, vm, vp, vg.data());
        });
        return std::make_tuple(t.kinetic, t.potential, t.max_speed2, t.max_pressure, t.fastest,
                               t.nonfinite, t.first_nonfinite);
      },
      nb::arg("x"), nb::arg("v"), nb::arg("mass"), nb::arg("pressure"), nb::arg("gravity"),
      "The particles' totals in one pass: (kinetic energy, potential energy, largest squared "
      "speed, largest pressure, fastest particle, how many are not finite, the first of "
      "those); non-finite particles left out of the energies and the fastest.");
}

}  // namespace mpmflow::bind
