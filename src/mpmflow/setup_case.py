"""Build the grid and the particles of a validated case."""

import numpy as np

from .cells import bin_particles
from .errors import CaseError
from .grid import Grid
from .particles import Particles, seed_box, subset


def build_grid(case):
    return Grid.covering(case.domain.size, case.grid.spacing)


def build_particles(case, grid):
    parts = []
    rho = case.material.density
    down = np.asarray(case.physics.gravity, dtype=float)
    for body in case.bodies:
        spacing = grid.spacing / body.particles_per_cell
        amplitude = body.surface_amplitude
        if amplitude == 0.0:
            part = seed_box(body.min, body.max, spacing, rho, body.velocity)
        else:
            part = seed_cosine_box(body.min, body.max, amplitude, spacing, rho, body.velocity)
        if body.initial_pressure == "hydrostatic":
            if amplitude == 0.0:
                corners = np.array(np.meshgrid(*zip(body.min, body.max))).reshape(len(down), -1).T
                top = corners[np.argmax(corners @ -down)]
                part.pressure[:] = rho * ((top - part.x) @ -down)
            else:
                depth = cosine_surface(body.min, body.max, amplitude, part.x[:, 0]) - part.x[:, 1]
                part.pressure[:] = rho * np.linalg.norm(down) * depth
        parts.append(part)
    particles = Particles.concatenate(parts)
    check_packing(case, grid, particles, [p.count for p in parts])
    return particles


def check_packing(case, grid, particles, counts):
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
    ppc = np.array([b.particles_per_cell ** dim for b in case.bodies], dtype=np.int64)
    np.maximum.at(asked, bins.cell, ppc[body])
    count = bins.counts()
    over = (count > asked) | (bins.theta > 1.0 + 1e-9)
    if not over.any():
        return
    c = int(np.argmax(np.where(over, bins.theta, -1.0)))
    here = bins.order[bins.start[c]:bins.start[c + 1]]
    names = sorted(set(body[here].tolist()))
    centre, r = [], c
    for n in grid.cells:
        centre.append((r % n + 0.5) * grid.spacing)
        r //= n
    listed = " and ".join(f"bodies.{k} (particles_per_cell = {case.bodies[k].particles_per_cell})"
                          for k in names)
    raise CaseError(
        f"The cell at ({', '.join(f'{v:.6g}' for v in centre)}) m would start with {int(count[c])} "
        f"particles filling {bins.theta[c]:.3g} of its volume, more than one body packs into a "
        f"cell ({int(asked[c])} particles, filling it once): {listed} meet inside this cell "
        "and their particle lattices overlap there. Give bodies that touch the same "
        "particles_per_cell, or let them meet on a grid line (a multiple of grid.spacing = "
        f"{grid.spacing:g} m).")


def cosine_surface(lo, hi, amplitude, x):
    """Height of the cosine top of a body: hi[1] + A cos(pi (x - lo[0]) / (hi[0] - lo[0])) (m)."""
    return hi[1] + amplitude * np.cos(np.pi * (x - lo[0]) / (hi[0] - lo[0]))


def seed_cosine_box(lo, hi, amplitude, spacing, density, velocity):
    """A box seeded up to hi[1] + |A|, keeping the particles below the cosine surface."""
    top = [hi[0], hi[1] + abs(amplitude)]
    part = seed_box(lo, top, spacing, density, velocity)
    keep = part.x[:, 1] < cosine_surface(lo, hi, amplitude, part.x[:, 0])
    return subset(part, keep)
