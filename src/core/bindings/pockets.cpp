#include "../pockets.hpp"

#include "arrays.hpp"
#include "modules.hpp"

namespace mpmflow::bind {

void bind_pockets(nb::module_& m) {
  m.def(
      "reach",
      [](Array<const index_t> cols, Array<const bool> seed, Array<bool> reached,
         Array<index_t> order) {
        auto c = view<const index_t, 2>(cols, "cols");
        const index_t n = c.extent(0);
        if (static_cast<index_t>(seed.shape(0)) != n ||
            static_cast<index_t>(reached.shape(0)) != n ||
            static_cast<index_t>(order.shape(0)) != n)
          throw std::invalid_argument("reach: seed, reached and order need one entry per row");
        return reach(c, view<const bool>(seed, "seed"), view<bool>(reached, "reached"),
                     view<index_t>(order, "order"));
      },
      nb::arg("cols"), nb::arg("seed"), nb::arg("reached"), nb::arg("order"),
      "The rows reached from the seed rows over the couplings (in place); returns their count.");
}

}  // namespace mpmflow::bind
