"""The particles of a validated case: each body filled from the global lattice
(``geometry.lattice``), clear of the obstacles, with its velocity and, where asked, its
hydrostatic pressure; and the check that no cell starts over-packed."""

from collections.abc import Iterable, Iterator, Sequence
from typing import Any

import numpy as np

from ..cells import bin_particles
from ..errors import CaseError
from ..grid import Grid
from ..particles import Particles, subset
from .bodies import cosine_top, is_box, seed_region, seeded
from .lattice import lattice_chunks, lattice_in_box
from .shapes import Shape


def build_particles(case: Any, grid: Grid) -> Particles:
    """The particles of every body of the case on this grid (``Particles``)."""
    obstacles = obstacle_shapes(case)
    parts = [p for k in range(len(case.bodies)) for p in body_pieces(case, grid, k, obstacles)]
    particles = Particles.concatenate(parts)
    check_packing(case, grid, particles, [p.count for p in parts])
    return particles


def obstacle_shapes(case: Any) -> list[Shape]:
    return [case.obstacle_shape(k) for k in range(len(case.obstacles))]


def body_pieces(
    case: Any, grid: Grid, k: int, obstacles: Sequence[Shape], chunk: int | None = None
) -> Iterator[Particles]:
    """The particles of body ``k`` in their order in the run: one piece (``chunk`` None),
    or pieces from about ``chunk`` lattice points each (``lattice.lattice_chunks``: a pass
    over a case that no process holds whole, ``parallel.seeding``). A box's particles fill
    [min, max) (below a cosine top), any other shape's its bounding box's lattice points it
    contains; clear of the obstacles; with the body's velocity and, where asked, its
    hydrostatic pressure."""
    body = case.bodies[k]
    spacing = grid.spacing / body.particles_per_cell
    # a saturated soil's free water (bodies.N.free_water): the water's density
    rho = case.material.water_density if body.free_water else case.material.density
    down = np.asarray(case.physics.gravity, dtype=float)
    shape = None if is_box(body) else case.body_shape(k)
    lo, hi = seed_region(body, shape, spacing)
    if chunk is None:
        points: Iterable[np.ndarray] = [lattice_in_box(lo, hi, spacing)]
    else:
        points = lattice_chunks(lo, hi, spacing, chunk)
    hydrostatic = body.initial_pressure == "hydrostatic"
    for x in points:
        if shape is not None:
            part = seed_points(
                x[seeded(body, shape, x, spacing, obstacles)], spacing, rho, body.velocity
            )
            if hydrostatic:
                g = np.linalg.norm(down)
                up = -down / g if g > 0 else np.zeros_like(down)
                top = shape.support(up)
                part.pressure[:] = rho * g * (top - part.x @ up)
            yield part
            continue
        part = seed_points(x, spacing, rho, body.velocity)
        amplitude = body.surface_amplitude
        if amplitude != 0.0:  # a cosine top: the particles below the surface
            part = subset(part, part.x[:, 1] < cosine_top(body, part.x[:, 0]))
        if obstacles:
            part = subset(part, seeded(body, None, part.x, spacing, obstacles))
        if hydrostatic:
            if amplitude == 0.0:
                corners = np.array(np.meshgrid(*zip(body.min, body.max))).reshape(len(down), -1).T
                top = corners[np.argmax(corners @ -down)]
                part.pressure[:] = rho * ((top - part.x) @ -down)
            else:
                depth = cosine_top(body, part.x[:, 0]) - part.x[:, 1]
                part.pressure[:] = rho * np.linalg.norm(down) * depth
        yield part


def seed_points(
    x: np.ndarray, spacing: float, density: float, velocity: Sequence[float]
) -> Particles:
    """Particles at the lattice points x (n x D); each carries the volume spacing**dim (m^3,
    m^2 in 2D) and mass density * volume (kg)."""
    n, dim = x.shape
    vol = np.full(n, spacing**dim)
    return Particles(
        x=x,
        v=np.tile(np.asarray(velocity, dtype=float), (n, 1)),
        pressure=np.zeros(n),
        mass=vol * density,
        volume=vol,
    )


def check_packing(case: Any, grid: Grid, particles: Particles, counts: Sequence[int]) -> None:
    """Refuse a start with more particles in a cell than the bodies there ask for, or with
    more particle volume than the cell holds (CaseError). Bodies that overlap are refused by
    the case's validation; this catches what remains: bodies with different
    particles_per_cell meeting inside a cell, where their lattices overlap."""
    if particles.count == 0:
        return
    bins = bin_particles(grid, particles)
    dim = grid.dim
    asked = np.zeros(grid.ncells, dtype=np.int64)  # the largest ppc^dim of the bodies there
    body = np.repeat(np.arange(len(counts)), counts)
    ppc = np.array([b.particles_per_cell**dim for b in case.bodies], dtype=np.int64)
    np.maximum.at(asked, bins.cell, ppc[body])
    count = bins.counts()
    over = (count > asked) | (bins.theta > 1.0 + 1e-9)
    if not over.any():
        return
    c = int(np.argmax(np.where(over, bins.theta, -1.0)))
    here = bins.order[bins.start[c] : bins.start[c + 1]]
    names = sorted(set(body[here].tolist()))
    centre, r = [], c
    for n in grid.cells:
        centre.append((r % n + 0.5) * grid.spacing)
        r //= n
    listed = " and ".join(
        f"bodies.{k} (particles_per_cell = {case.bodies[k].particles_per_cell})" for k in names
    )
    raise CaseError(
        f"The cell at ({', '.join(f'{v:.6g}' for v in centre)}) m would start with {int(count[c])} "
        f"particles filling {bins.theta[c]:.3g} of its volume, more than one body packs into a "
        f"cell ({int(asked[c])} particles, filling it once): {listed} meet inside this cell "
        "and their particle lattices overlap there. Give bodies that touch the same "
        "particles_per_cell, or let them meet on a grid line (a multiple of grid.spacing = "
        f"{grid.spacing:g} m)."
    )


def seed_box(
    lo: Sequence[float],
    hi: Sequence[float],
    spacing: float,
    density: float,
    velocity: Sequence[float],
) -> Particles:
    """Particles filling a box; each carries the volume spacing**dim and mass density*volume."""
    return seed_points(lattice_in_box(lo, hi, spacing), spacing, density, velocity)
