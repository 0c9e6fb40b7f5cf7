"""The materials' effective viscosity as compiled code (``mpmflow.materials`` holds their
settings and checks; docs/method.md, "Viscous materials").

Every model is written as a viscosity eta(rate, p) (Pa s) of the strain-rate magnitude
rate = sqrt(2 D:D) (1/s; D the strain-rate tensor, so rate = du/dy in simple shear) and the
pressure p (Pa), so one implicit solve serves them all. The yield-stress and granular models
are regularised by a cap: eta <= max_viscosity (the bi-viscous regularisation; below the
yield the material creeps at rate tau / max_viscosity instead of standing still).
"""

import math

from numba import njit

WATER, NEWTONIAN, HERSCHEL_BULKLEY, MU_I = 0, 1, 2, 3
# parameters, in the order ``mpmflow.materials`` packs them:
#   NEWTONIAN:        [viscosity]
#   HERSCHEL_BULKLEY: [consistency, yield_stress, flow_index, max_viscosity]
#   MU_I:             [mu_s, mu_2, I0, grain_diameter, grain_density, max_viscosity]


@njit(cache=True)
def viscosity(model, par, rate, p):
    """The effective viscosity (Pa s) of ``model`` at strain rate ``rate`` (1/s) and
    pressure ``p`` (Pa; a negative pressure counts as 0: a granular material has no
    strength without confinement)."""
    if model == NEWTONIAN:
        return par[0]
    if model == HERSCHEL_BULKLEY:
        cap = par[3]
        if not rate > 0.0:
            return cap
        return min(cap, par[0] * rate ** (par[2] - 1.0) + par[1] / rate)
    if model == MU_I:
        cap = par[5]
        p = max(p, 0.0)
        if p == 0.0:
            return 0.0
        if not rate > 0.0:
            return cap
        inertial = rate * par[3] / math.sqrt(p / par[4])
        mu = par[0] + (par[1] - par[0]) * inertial / (par[2] + inertial)
        return min(cap, mu * p / rate)
    return 0.0
