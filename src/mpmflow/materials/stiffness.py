"""How stiff a viscous material is for the time step: the split number S = eta dt / (rho H^2).

The projection step solves the viscous stress and then the pressure, one after the other
(docs/method.md, "Viscous materials"). The split costs a velocity of order |g| dt that no
viscosity removes: a block of Newtonian liquid at rest on a floor creeps at up to about
0.6 |g| dt (measured: 5.8 mm/s at dt = 1 ms, the same at 1e5, 1e8 and 1e12 Pa s), while
it should creep at the Stokes speed rho |g| H^2 / eta (H: the material's depth along
gravity). Their ratio is the split number S = eta dt / (rho H^2): the creep speeds of a run
are off by about 1.5 S (measured on a 0.1 m block at S = 0.06, 0.25 and 1: 8%, 36%, 120%).

- A Newtonian material with S above ``REFUSE`` is refused before the run: its answer would
  be the split's error; the message says which time step or viscosity brings S below it.
- Above ``TELL`` the run goes on with a notice of the expected error.
- A regularised model (Herschel-Bulkley, mu(I)) is told the same of its cap
  ``material.max_viscosity``: where it is unyielded it creeps at a speed the time step
  sets, not at |tau| / max_viscosity. Its yielded flow is not concerned.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from ..particles import Particles

if TYPE_CHECKING:  # the case's schema lists the materials (case.sections imports materials)
    from ..case import Case
    from ..case.sections import Material

CONDITION = 1e10  # eta dt / (rho h^2) above which the viscous solve has no digits left
REFUSE = 1.0  # S above which a Newtonian material's motion is mostly the split's error
TELL = 0.03  # S above which the expected error (about 1.5 S) is told: 5% and more
ERROR_PER_S = 1.5  # relative error of the creep speed per unit of S (measured, see above)
SPLIT_SPEED = 0.6  # the split's creep speed, in units of |g| dt (measured, see above)


def depth(particles: Particles, gravity: ArrayLike, comm: Any = None) -> float:
    """The material's extent (m) along gravity: the particles' spread along g plus one
    particle's size (their volume's D-th root). ``comm``: the MPI ranks whose parts the
    particles are (``parallel.comm``), None for the whole run."""
    g = np.asarray(gravity, dtype=float)
    norm = float(np.linalg.norm(g))
    along = particles.x @ (g / norm) if norm else np.zeros(particles.count)
    # (the largest along g, the largest against it, the volume, the count) of each part
    mine = (
        float(along.max()) if along.size else -np.inf,
        float(-along.min()) if along.size else -np.inf,
        float(particles.volume.sum()),
        particles.count,
    )
    every = [mine] if comm is None or comm.size == 1 else comm.allgather(mine)
    n = sum(e[3] for e in every)
    if norm == 0.0 or n == 0:
        return 0.0
    spread = float(max(e[0] for e in every) + max(e[1] for e in every))
    # (float ** float is typed Any: a negative base would give a complex; volumes are > 0)
    size: float = (sum(e[2] for e in every) / n) ** (1.0 / particles.x.shape[1])
    return spread + size


def stiffest(m: Material) -> tuple[float, str | None]:
    """(eta, key): the largest viscosity the model takes (Pa s) and the key that sets it;
    (0, None) for inviscid water."""
    if m.model == "newtonian":
        return float(m.viscosity), "material.viscosity"
    if m.model in ("herschel_bulkley", "mu_i"):
        return float(m.max_viscosity), "material.max_viscosity"
    return 0.0, None


def check(case: Case, particles: Particles, dt: float, comm: Any = None) -> list[str]:
    """The notices of a viscous case (list of strings); raises ValueError with the message
    for a Newtonian material too stiff for time step ``dt`` (s). ``particles``: the
    particles at the start (over MPI ranks this rank's part, ``comm`` the ranks)."""
    m = case.material
    eta, key = stiffest(m)
    h = case.grid.spacing
    if key is not None and eta * dt / (m.density * h * h) > CONDITION:
        raise ValueError(
            f"{key} = {eta:g} Pa s with material.density = {m.density:g} kg/m^3, time step "
            f"{dt:g} s and grid.spacing = {h:g} m makes the viscous system's stiffness "
            f"eta dt / (rho h^2) = {eta * dt / (m.density * h * h):.3g}, beyond "
            f"{CONDITION:g}, where its solve in double precision has no digits left; lower "
            f"{key} (1e5 Pa s is a usual cap for yield-stress and granular materials)"
        )
    g = float(np.linalg.norm(case.physics.gravity))
    H = depth(particles, case.physics.gravity, comm)
    if key is None or g == 0.0 or H == 0.0:
        return []
    S = eta * dt / (m.density * H * H)
    if S <= TELL:
        return []
    split = SPLIT_SPEED * g * dt
    stokes = m.density * g * H * H / eta
    dt_ok = REFUSE * m.density * H * H / eta
    eta_ok = REFUSE * m.density * H * H / dt
    numbers = (
        f"{key} = {eta:g} Pa s at time step {dt:g} s on a material {H:.4g} m deep: "
        f"split number S = eta dt / (rho H^2) = {S:.3g}"
    )
    if m.model == "newtonian" and S > REFUSE:
        raise ValueError(
            f"{numbers}. The viscous and pressure steps are solved one after the other, and "
            f"the split moves the material at up to about {split:.2g} m/s "
            f"({SPLIT_SPEED:g} |g| dt) whatever its viscosity, while it should creep at "
            f"about rho g H^2 / eta = {stokes:.2g} m/s: the answer would be the split's "
            f"error. Bring S below {REFUSE:g}: time.dt below {dt_ok:.3g} s, or "
            f"material.viscosity below {eta_ok:.3g} Pa s (creep speeds are then within "
            f"about {ERROR_PER_S:g} S); a body that should not move at all is an obstacle "
            '([[obstacles]]). See docs/method.md, "Viscous materials".'
        )
    if m.model == "newtonian":
        return [
            f"{numbers}: its creep speeds are off by about {ERROR_PER_S * S:.0%} (the "
            "split of the viscous and pressure steps, docs/method.md); a smaller "
            f"time.dt lowers it in proportion"
        ]
    if S <= REFUSE:
        return []
    return [
        f"{numbers}: where the material is unyielded it creeps at up to about "
        f"{split:.2g} m/s ({SPLIT_SPEED:g} |g| dt, the split of the viscous and pressure "
        f"steps) rather than at |tau| / max_viscosity (about {stokes:.2g} m/s); a "
        f"deposit stops to within that speed. time.dt below {dt_ok:.3g} s brings it to "
        'the cap\'s creep (docs/method.md, "Viscous materials")'
    ]
