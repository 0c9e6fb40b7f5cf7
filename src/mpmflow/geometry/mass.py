"""The mass each body is seeded with against the mass of its shape, rho V.

A body's particles stand on the global lattice (``lattice``): each carries the mass of one
lattice cell, rho s^D (s = grid.spacing / particles_per_cell), and a body keeps the lattice
points inside it. Its seeded mass is therefore rho V only when its boundary runs along the
lattice's cell faces (a box whose faces lie on multiples of s); otherwise each boundary
cell is kept whole or left out by its centre, and the mass differs by up to about one
layer of cells over the boundary: 2D boxes with a top at 0.104 or 0.106 m on a 0.01 m
lattice carry 20 or 22 kg/m instead of 20.8 or 21.2, discs a few cells across 12-33% too
much, a mesh sphere of 2 mm on a 5 mm lattice one particle of 30 times its mass.

* More than ``NOTICE`` (2%) from rho V: the run says so at its start, per body, with the
  fix (align a box's faces to the lattice, or more particles per cell or a finer grid).
* Outside a factor of ``REFUSE`` (2) from rho V: refused. Such a body spans about two
  particle spacings or fewer; its particles do not describe it, and the run would carry a
  body of another mass.

A body filled round obstacles (``around_obstacles``) is measured without them: the points
the obstacles take are meant to be left out, and the shape's volume does not know them."""

from typing import Any

from . import bodies

NOTICE = 0.02  # relative difference from rho V that a run's notices report
REFUSE = 2.0  # a seeded mass more than this factor from rho V is refused


def _unit(dim: int) -> str:
    return "kg/m" if dim == 2 else "kg"  # a 2D case's mass is per metre of depth


def _fix(case: Any, k: int, body: Any, s: float) -> str:
    """How to seed bodies.k closer to rho V."""
    more = (
        f"raise bodies.{k}.particles_per_cell (now {body.particles_per_cell}, at most 16) "
        "or refine grid.spacing"
    )
    if not bodies.is_box(body) or body.surface_amplitude:
        return (
            "its boundary cuts the lattice's cells, each kept whole or left out by its "
            f"centre; {more}: the difference shrinks with the spacing"
        )
    off = []
    for name, corner in (("min", body.min), ("max", body.max)):
        for axis, c in enumerate(corner):
            n = c / s
            if abs(n - round(n)) > 1e-6:
                lo, hi = int(n // 1) * s, (int(n // 1) + 1) * s
                off.append(f"{name}[{axis}] = {c:g} m lies between {lo:.6g} and {hi:.6g}")
    faces = "; ".join(off) if off else "its faces lie on the lattice's cell faces"
    return (
        f"its faces fall between the lattice's cell faces, the multiples of {s:.6g} m "
        f"({faces}): put them on multiples of {s:.6g} m (bodies.{k}.min/max), or {more}"
    )


def check(case: Any) -> list[str]:
    """The notices of the bodies whose seeded mass is more than NOTICE from rho V (list of
    strings); ValueError for one more than a factor REFUSE from it. ``case``: a validated
    case (its particle counts are those the memory estimate counted)."""
    h, rho = case.grid.spacing, case.material.density
    dim = len(case.domain.size)
    counts = case.particle_counts()
    notices = []
    for k, body in enumerate(case.bodies):
        shape = case.body_shape(k)
        count = counts[k]
        if body.around_obstacles and case.obstacles:
            count = bodies.particle_count(body, h, shape)  # the shape whole, as V is
        s = h / body.particles_per_cell
        volume = shape.volume()
        if not count > 0 or not volume > 0:
            continue  # a body left out: placement's messages
        seeded, asked = rho * count * s**dim, rho * volume
        ratio = seeded / asked
        unit = _unit(dim)
        what = (
            f"bodies.{k} (a {getattr(body, 'type', 'box')}) is seeded with {count:,.0f} "
            f"particle{'s' if count != 1 else ''} carrying {seeded:.4g} {unit}"
        )
        holds = (
            f"its shape holds rho V = {rho:g} kg/m^3 x {volume:.4g} m^{dim} = {asked:.4g} {unit}"
        )
        if not 1 / REFUSE <= ratio <= REFUSE:
            lo, hi = shape.bounds()
            extent = min(float(b - a) for a, b in zip(lo, hi))
            raise ValueError(
                f"{what}, {ratio:.3g} times the mass {holds}: the body is about the size of "
                f"its particles (it spans {extent:.4g} m at its narrowest; the particles' "
                f"spacing is grid.spacing / particles_per_cell = {h:g} / "
                f"{body.particles_per_cell} = {s:.4g} m), so they do not describe it. Make "
                f"it several particle spacings across, raise bodies.{k}.particles_per_cell "
                f"(at most 16) or refine grid.spacing, or remove bodies.{k}"
            )
        if abs(ratio - 1) > NOTICE:
            more_less = "more" if ratio > 1 else "less"
            notices.append(
                f"{what}, {abs(ratio - 1):.1%} {more_less} than {holds}: each particle "
                f"carries the mass of one lattice cell ({s:.4g} m a side), and "
                + _fix(case, k, body, s)
            )
    return notices
