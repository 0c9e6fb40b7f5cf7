// Solids with a stress history on the particles (docs/method.md, "Solids"): the deviatoric
// stress s (Pa, traceless, symmetric) of an incompressible elasto-plastic material, whose
// pressure comes from the projection, so no bulk modulus enters the step.
//
// Each step, from the velocity gradient L = grad v of the corrected grid velocity at the
// particle (1/s):
//   trial:  s' = s + dt (2 G dev(D) + W s - s W),  D = (L + L^T)/2, W = (L - L^T)/2
//           (the Jaumann rate: the stress turns with the material's spin; dev removes the
//           trace over the D axes, so in 2D the stress is that of plane strain with the
//           out-of-plane deviator 0, which an incompressible plane-strain flow keeps);
//   return: where sqrt(J2) = sqrt(s':s'/2) exceeds the strength k, s = s' k / sqrt(J2)
//           (a radial return in the deviatoric plane: with zero dilatancy the plastic flow
//           keeps the volume, and the pressure is the projection's).
// Strength k (Pa), the largest sqrt(J2) the material bears:
//   ELASTIC:        none;
//   VON_MISES:      s_u + gradient max(0, datum - y) (y the particle's height along the last
//                   axis, m): Tresca's undrained strength s_u in plane strain, where sqrt(J2) =
//                   (sigma_1 - sigma_3)/2;
//   DRUCKER_PRAGER: max(0, p sin(phi) + c cos(phi)), and 0 where p < -t (the tension
//                   cut-off t: the material has parted): Mohr-Coulomb's in plane strain at
//                   zero dilatancy, where the out-of-plane stress is the mean of the in-plane
//                   ones, so sqrt(J2) = (sigma_1 - sigma_3)/2 and p = (sigma_1 + sigma_3)/2.
// The equivalent plastic strain grows by (sqrt(J2') - k) / (sqrt(3) G) on a return
// (sqrt(2/3 e_p:e_p) of the plastic strain increment e_p = (s' - s) / (2 G)).
//
// POROELASTIC, a saturated soil's skeleton (docs/method.md, "Saturated soil"): the stress
// carried is the effective stress sigma' (volumetric part included), linear elastic with the
// drained skeleton's Lame constants:
//   sigma' <- sigma' + dt (2 G D + lambda tr(D) I + W sigma' - sigma' W)
// (plane strain in 2D: the in-plane components), no yield. The pore pressure is the
// projection's, whose constraint is the mixture's volume balance with Darcy's flow of the
// pore water (cell_pressure.hpp: darcy_*), so the skeleton's volume changes only as the
// water drains.
#pragma once

#include <algorithm>
#include <cmath>

#include "view.hpp"

namespace mpmflow {

// model codes after the fluids' (rheology.hpp); parameters par, as mpmflow.materials packs
// them:
//   ELASTIC:        [shear_modulus]
//   VON_MISES:      [shear_modulus, undrained_strength, strength_gradient, strength_datum]
//   DRUCKER_PRAGER: [shear_modulus, sin(friction_angle), cohesion cos(friction_angle),
//                    tension_cutoff]
//   POROELASTIC:    [shear_modulus, lame (Pa: the drained skeleton's lambda), mobility
//                    (m^2/(Pa s): the hydraulic conductivity over the water's unit weight at
//                    standard gravity, k / (rho_w g_n)), water_density (kg/m^3)]
constexpr int ELASTIC = 4;
constexpr int VON_MISES = 5;
constexpr int DRUCKER_PRAGER = 6;
constexpr int POROELASTIC = 7;

MPMFLOW_HD inline bool is_solid(int model) { return model >= ELASTIC && model <= POROELASTIC; }

// a material that yields (a strength k below +inf)
MPMFLOW_HD inline bool is_plastic(int model) {
  return model == VON_MISES || model == DRUCKER_PRAGER;
}

// a saturated soil: its pore water flows through the skeleton (Darcy), with this mobility
// (m^2/(Pa s); 0: none, every other material)
MPMFLOW_HD inline double pore_mobility(int model, const double* par) {
  return model == POROELASTIC ? par[2] : 0.0;
}

// a saturated soil's skeleton: its lambda / G, the elastic solve's grad-div weight beside the
// shear's (its bulk stiffness lambda dt beside G dt; 0: none, every other material)
MPMFLOW_HD inline double grad_div_ratio(int model, const double* par) {
  return model == POROELASTIC ? par[1] / par[0] : 0.0;
}

// A saturated soil's free water (the reservoir above a seabed): its particles carry the
// water's density (mass / volume = water_density; the mixture's is above it, which the
// material's check holds), no skeleton and no stress.
MPMFLOW_HD inline bool free_water(int model, const double* par, double mass, double volume) {
  return model == POROELASTIC && mass <= par[3] * volume * (1.0 + 1e-9);
}

// The strength k (Pa) at pressure p (Pa) and height y (m); +inf: no yield.
MPMFLOW_HD inline double strength(int model, const double* par, double p, double y) {
  if (model == VON_MISES) return par[1] + par[2] * std::max(0.0, par[3] - y);
  if (model == DRUCKER_PRAGER) {
    if (p < -par[3]) return 0.0;
    return std::max(0.0, p * par[1] + par[2]);
  }
  return HUGE_VAL;
}

// The trial stress t (D x D, row-major) of one step of the stress s under velocity gradient
// L (D x D, L[k * D + j] = dv_k/dx_j) over dt (s): the elastic increment and the Jaumann spin
// (above), before any return; a solid's deviatoric t is kept traceless against rounding.
template <int D>
MPMFLOW_HD inline void trial_stress(int model, const double* par, const double* L, double dt,
                                    const double* s, double* t) {
  const double G = par[0];
  double d[D * D], w[D * D];
  // the strain rate's part that enters the stress: its deviator for an incompressible solid;
  // for a saturated soil's skeleton the whole of it with lambda tr(D) I (its effective stress
  // carries its volumetric part: 2 G (D + lambda / (2 G) tr(D) I))
  const bool poro = model == POROELASTIC;
  double trace = 0.0;
  for (int k = 0; k < D; ++k) trace += L[k * D + k];
  const double shift = poro ? -0.5 * par[1] / G * trace : trace / D;
  for (int k = 0; k < D; ++k)
    for (int j = 0; j < D; ++j) {
      d[k * D + j] = 0.5 * (L[k * D + j] + L[j * D + k]) - (k == j ? shift : 0.0);
      w[k * D + j] = 0.5 * (L[k * D + j] - L[j * D + k]);
    }
  for (int k = 0; k < D; ++k)
    for (int j = 0; j < D; ++j) {
      double spin = 0.0;
      for (int m = 0; m < D; ++m) spin += w[k * D + m] * s[m * D + j] - s[k * D + m] * w[m * D + j];
      t[k * D + j] = s[k * D + j] + dt * (2.0 * G * d[k * D + j] + spin);
    }
  if (poro) return;
  // the trace the products leave by rounding, removed so that s stays deviatoric
  double drift = 0.0;
  for (int k = 0; k < D; ++k) drift += t[k * D + k];
  for (int k = 0; k < D; ++k) t[k * D + k] -= drift / D;
}

// The radial return of a trial stress t at pressure p (Pa) and height y (m): sqrt(J2(t)) and
// the strength k (Pa; +inf: no yield, as a saturated soil's skeleton), and the factor that
// returns t onto the yield surface, k / sqrt(J2) where sqrt(J2) exceeds k (0 where k = 0),
// else 1.
struct Return {
  double q, k, factor;
};

template <int D>
MPMFLOW_HD inline Return radial_return(int model, const double* par, const double* t, double p,
                                       double y) {
  double j2 = 0.0;
  for (int i = 0; i < D * D; ++i) j2 += 0.5 * t[i] * t[i];
  const double q = std::sqrt(j2);
  const double k = strength(model, par, p, y);
  return {q, k, q > k ? (q > 0.0 ? k / q : 0.0) : 1.0};
}

// One step of the stress s (D x D, row-major, in place) under velocity gradient L over dt
// (s), at pressure p (Pa) and height y (m): the trial stress and its return. Returns the
// equivalent plastic strain increment: > 0 where the material yielded.
template <int D>
MPMFLOW_HD inline double update_stress(int model, const double* par, const double* L, double dt,
                                       double p, double y, double* s) {
  double t[D * D];
  trial_stress<D>(model, par, L, dt, s, t);
  const Return r = radial_return<D>(model, par, t, p, y);
  for (int i = 0; i < D * D; ++i) s[i] = t[i] * r.factor;
  return r.q > r.k ? (r.q - r.k) / (std::sqrt(3.0) * par[0]) : 0.0;
}

}  // namespace mpmflow
