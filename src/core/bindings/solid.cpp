// The solids' constitutive update (src/core/plasticity.hpp) for checks: the model codes and
// one particle's stress step.
#include <nanobind/stl/pair.h>

#include <stdexcept>
#include <utility>
#include <vector>

#include "../plasticity.hpp"
#include "arrays.hpp"
#include "modules.hpp"

namespace mpmflow::bind {

void bind_solid(nb::module_& m) {
  m.attr("ELASTIC") = ELASTIC;
  m.attr("VON_MISES") = VON_MISES;
  m.attr("DRUCKER_PRAGER") = DRUCKER_PRAGER;
  m.attr("POROELASTIC") = POROELASTIC;
  m.def(
      "update_stress",
      [](int model, Array<const double> par, Array<const double> L, double dt, double p, double y,
         Array<double> s) {
        auto P = view<const double>(par, "par");
        auto vL = view<const double, 2>(L, "L");
        auto vs = view<double, 2>(s, "s");
        const index_t D = vL.extent(0);
        if (!(D == 2 || D == 3) || vL.extent(1) != D || vs.extent(0) != D || vs.extent(1) != D ||
            P.size() < 4)
          throw std::invalid_argument("update_stress: L and s are D x D (D = 2, 3), par >= 4");
        return D == 2 ? update_stress<2>(model, P.data(), vL.data(), dt, p, y, vs.data())
                      : update_stress<3>(model, P.data(), vL.data(), dt, p, y, vs.data());
      },
      nb::arg("model"), nb::arg("par"), nb::arg("L"), nb::arg("dt"), nb::arg("p"), nb::arg("y"),
      nb::arg("s").noconvert(),
      "One step of a solid's deviatoric stress s (D x D, Pa, in place) under the velocity "
      "gradient L (D x D, 1/s) over dt (s) at pressure p (Pa) and height y (m); returns the "
      "equivalent plastic strain increment (> 0: yielded).");
}

}  // namespace mpmflow::bind
