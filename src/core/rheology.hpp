// The materials' effective viscosity (mpmflow.materials holds their settings and checks;
// docs/method.md, "Viscous materials").
//
// Every model is a viscosity eta(rate, p) (Pa s) of the strain-rate magnitude
// rate = sqrt(2 D:D) (1/s; D the strain-rate tensor, so rate = du/dy in simple shear) and the
// pressure p (Pa), so one implicit solve serves them all. The yield-stress and granular models
// are regularised by a cap: eta <= max_viscosity (the bi-viscous regularisation).
#pragma once

#include <algorithm>
#include <cmath>

#include "view.hpp"

namespace mpmflow {

// model codes; parameters par, in the order mpmflow.materials packs them:
//   NEWTONIAN:        [viscosity]
//   HERSCHEL_BULKLEY: [consistency, yield_stress, flow_index, max_viscosity]
//   MU_I:             [mu_s, mu_2, I0, grain_diameter, grain_density, max_viscosity]
constexpr int WATER = 0;
constexpr int NEWTONIAN = 1;
constexpr int HERSCHEL_BULKLEY = 2;
constexpr int MU_I = 3;

// The cap of a regularised model (Pa s; +inf for the others).
inline double viscosity_cap(int model, View<const double> par) {
  if (model == HERSCHEL_BULKLEY) return par[3];
  if (model == MU_I) return par[5];
  return HUGE_VAL;
}

// The effective viscosity (Pa s) of ``model`` at strain rate ``rate`` (1/s) and pressure
// ``p`` (Pa; a negative pressure counts as 0: a granular material has no strength without
// confinement). WATER (inviscid) and unknown codes: 0.
inline double viscosity(int model, View<const double> par, double rate, double p) {
  if (model == NEWTONIAN) return par[0];
  if (model == HERSCHEL_BULKLEY) {
    const double cap = par[3];
    if (!(rate > 0.0)) return cap;
    return std::min(cap, par[0] * std::pow(rate, par[2] - 1.0) + par[1] / rate);
  }
  if (model == MU_I) {
    const double cap = par[5];
    p = std::max(p, 0.0);
    if (p == 0.0) return 0.0;
    if (!(rate > 0.0)) return cap;
    const double inertial = rate * par[3] / std::sqrt(p / par[4]);
    const double mu = par[0] + (par[1] - par[0]) * inertial / (par[2] + inertial);
    return std::min(cap, mu * p / rate);
  }
  return 0.0;
}

}  // namespace mpmflow
