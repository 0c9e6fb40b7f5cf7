#include "complementarity.hpp"

namespace mpmflow {

void hold_at_zero(View<const index_t, 2> cols, View<const double, 2> vals0, View<const bool> zero,
                  View<double, 2> vals) {
  const index_t n = cols.extent(0), ns = cols.extent(1), centre = ns / 2;
  for (index_t r = 0; r < n; ++r)
    for (index_t s = 0; s < ns; ++s) {
      const index_t c = cols(r, s);
      const bool cut = s != centre && c >= 0 && (zero(r) || zero(c));
      vals(r, s) = cut ? 0.0 : vals0(r, s);
    }
}

index_t update_active_set(View<const index_t, 2> cols, View<const double, 2> vals0,
                          View<const double> x, View<const double> b, View<const bool> candidate,
                          View<const index_t> rows, View<const bool> owned, double x_tolerance,
                          double w_tolerance, View<const bool> zero, View<bool> next) {
  const index_t n = cols.extent(0), ns = cols.extent(1);
  const bool all = owned.size() == 0;
  index_t changed = 0;
  for (index_t r = 0; r < n; ++r) {
    next(r) = zero(r);
    if (!candidate(r) || !(all || owned(rows(r)))) continue;
    if (!zero(r)) {
      next(r) = x(r) < -x_tolerance;
    } else {
      double w = -b(r);
      for (index_t s = 0; s < ns; ++s)
        if (cols(r, s) >= 0) w += vals0(r, s) * x(cols(r, s));
      next(r) = w >= -w_tolerance;
    }
    changed += next(r) != zero(r) ? 1 : 0;
  }
  return changed;
}

}  // namespace mpmflow
