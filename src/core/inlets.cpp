#include "inlets.hpp"

#include <stdexcept>
#include <string>

namespace mpmflow {

template <int D>
index_t emit_layers(const Inlets<D>& in, double dt, View<double> travel, InletPool& pool,
                    View<double, 2> x, View<double, 2> v, View<double> mass, View<double> volume,
                    View<double> pressure, View<double, 3> affine) {
  index_t emitted = 0;
  for (index_t q = 0; q < in.count(); ++q) {
    const index_t k = in.axis(q);
    const double dir = in.direction(q), s = in.spacing(q);
    for (index_t r = in.first(q); r < in.first(q + 1); ++r) {
      travel(r) += in.speed(r) * dt;
      while (travel(r) >= s) {
        travel(r) -= s;
        if (pool.next >= pool.end)
          throw std::logic_error("emit_layers: the inlets' pool of dormant particles ran out (" +
                                 std::to_string(pool.end) +
                                 " particles): the chunk was longer than its pool");
        const index_t p = pool.next++;
        for (int m = 0; m < D; ++m) {
          x(p, m) = in.layer(r, m);
          v(p, m) = 0.0;
          if (affine.size() > 0)
            for (int j = 0; j < D; ++j) affine(p, m, j) = 0.0;
        }
        x(p, k) += dir * travel(r);
        v(p, k) = dir * in.speed(r);
        mass(p) = in.mass(q);
        volume(p) = in.volume(q);
        pressure(p) = 0.0;
        ++emitted;
      }
    }
  }
  return emitted;
}

template index_t emit_layers<2>(const Inlets<2>&, double, View<double>, InletPool&, View<double, 2>,
                                View<double, 2>, View<double>, View<double>, View<double>,
                                View<double, 3>);
template index_t emit_layers<3>(const Inlets<3>&, double, View<double>, InletPool&, View<double, 2>,
                                View<double, 2>, View<double>, View<double>, View<double>,
                                View<double, 3>);

}  // namespace mpmflow
