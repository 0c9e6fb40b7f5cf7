#include "totals.hpp"

#include <cmath>
#include <limits>

#include "parallel.hpp"

namespace mpmflow {

template <int D>
ParticleTotals particle_totals(View<const double, 2> x, View<const double, 2> v,
                               View<const double> mass, View<const double> pressure,
                               const double* gravity) {
  const index_t n = x.extent(0);
  std::array<double, D> g{};
  for (int k = 0; k < D; ++k) g[k] = gravity[k];
  auto body = [&](index_t lo, index_t hi) {
    ParticleTotals t;
    t.max_pressure = -std::numeric_limits<double>::infinity();
    for (index_t p = lo; p < hi; ++p) {
      double v2 = 0.0, gx = 0.0;
      bool finite = true;
      for (int k = 0; k < D; ++k) {
        finite = finite && std::isfinite(x(p, k)) && std::isfinite(v(p, k));
        v2 += v(p, k) * v(p, k);
        gx += g[k] * x(p, k);
      }
      if (pressure(p) > t.max_pressure) t.max_pressure = pressure(p);
      if (!finite) {
        if (t.nonfinite == 0) t.first_nonfinite = p;
        t.nonfinite += 1;
        continue;
      }
      t.kinetic += 0.5 * mass(p) * v2;
      t.potential -= mass(p) * gx;
      if (t.fastest < 0 || v2 > t.max_speed2) {
        t.max_speed2 = v2;
        t.fastest = p;
      }
    }
    return t;
  };
  auto combine = [](const ParticleTotals& a, const ParticleTotals& b) {
    ParticleTotals t = a;
    t.kinetic += b.kinetic;
    t.potential += b.potential;
    if (b.max_pressure > t.max_pressure) t.max_pressure = b.max_pressure;
    if (b.fastest >= 0 && (t.fastest < 0 || b.max_speed2 > t.max_speed2)) {
      t.max_speed2 = b.max_speed2;
      t.fastest = b.fastest;
    }
    if (b.nonfinite > 0 && t.nonfinite == 0) t.first_nonfinite = b.first_nonfinite;
    t.nonfinite += b.nonfinite;
    return t;
  };
  return reduce_chunks<ParticleTotals>(n, body, combine);
}

template ParticleTotals particle_totals<2>(View<const double, 2>, View<const double, 2>,
                                           View<const double>, View<const double>, const double*);
template ParticleTotals particle_totals<3>(View<const double, 2>, View<const double, 2>,
                                           View<const double>, View<const double>, const double*);

}  // namespace mpmflow
