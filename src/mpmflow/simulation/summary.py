"""The run's summary (summary.json): status, counts, timings and the resolved case."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from .._version import __version__
from ..case import resolved
from ..diagnostics import probes
from ..output.timeseries import units as timeseries_units
from ..stability import case_stable_time_step, sound_speed
from . import energy

if TYPE_CHECKING:
    from .loop import Simulation


def _explicit(sim: Simulation) -> dict[str, float]:
    if sim.case.solver.scheme != "explicit":
        return {}
    m = sim.case.material
    return {
        "sound_speed": sound_speed(m.bulk_modulus, m.density),
        "stable_time_step": case_stable_time_step(sim.case),
    }


def _adaptive(sim: Simulation) -> dict[str, dict[str, float | None]]:
    """time.dt = "auto" with the projection scheme: the steps' range."""
    scheme = sim.scheme
    if not getattr(scheme, "auto", False) or not hasattr(scheme, "dt_range"):
        return {}
    shortest, longest = scheme.dt_range
    return {
        "adaptive_steps": {
            "courant": sim.case.time.courant,
            "max_dt": sim.case.time.max_dt,
            "shortest": shortest if np.isfinite(shortest) else None,
            "longest": longest or None,
        }
    }


def _ranks(sim: Simulation) -> dict[str, Any]:
    """A run over MPI ranks: its load per rank (``parallel.scheme``)."""
    report = getattr(sim.scheme, "ranks_report", None)
    return {"mpi": report} if report else {}


def summary(sim: Simulation, status: str, message: str) -> dict[str, Any]:  # JSON
    """The summary dict of ``sim`` as it stands, with its ``status`` and ``message``."""
    c, case, grid = sim.counters, sim.case, sim.grid
    bins = sim._bins()
    mass = sim.particle_sum("mass")
    count = sim.particle_count()
    out = sim.scheme.outflow
    into = sim.scheme.inflow
    return {
        "status": status,
        "message": message,
        "mpmflow_version": __version__,
        "time": sim.time,
        "steps": sim.steps,
        "particles": count,
        "particles_lost": sim.count0 + into.count - count - out.count,
        "particles_moved_inside": c.moved_inside,
        "mass_initial": sim.mass0,
        "mass_final": mass,
        "mass_relative_change": (mass + out.mass - into.mass - sim.mass0) / sim.mass0,
        # through the outlets (domain.walls = "outlet") and the inlets ([[inlets]]):
        # particles, kg, m^3
        "outflow": {"particles": out.count, "mass": out.mass, "volume": out.volume},
        "inflow": {"particles": into.count, "mass": into.mass, "volume": into.volume},
        "max_particles_per_cell": sim.most_per_cell(bins),
        # the largest rise of KE + PE above its start, against the threshold (energy.py)
        "energy": energy.record(sim),
        "wall_seconds": sim.wall_seconds(),
        "restarted_from": sim.resumed_from.name if sim.resumed_from else None,
        "last_checkpoint": sim.last_checkpoint.name if sim.last_checkpoint else None,
        "scheme": case.solver.scheme,
        "dt": sim.dt,
        **_explicit(sim),
        **_adaptive(sim),
        **_ranks(sim),
        "grid": {
            "spacing": grid.spacing,
            "cells": list(grid.cells),
            "domain_used": [float(s) for s in grid.size],
        },
        "pressure_solver": {
            "solves": c.solves,
            "iterations": c.iterations,
            "max_iterations_per_step": c.max_iterations,
            "max_unknowns": c.max_unknowns,
            "worst_relative_residual": c.worst_residual,
            "wall_nodes_released": c.released,
        },
        "viscous_solver": (
            {
                "iterations": c.viscous_iterations,
                "model": case.material.model,
                # the coupled step's plastic iterations, each one more coupled solve
                "plastic_iterations": c.plastic_iterations,
            }
            if case.material.model != "water"
            else None
        ),
        "notices": sim.notices,
        "caps_and_fallbacks": sim.fallbacks.rows(),
        "threads": sim.threads.record() if sim.threads is not None else None,
        "memory_estimate_bytes": sim.memory.as_dict(),
        "probes": {
            p.name: {
                "quantity": p.quantity,
                "position": p.position,
                "unit": probes.UNITS[p.quantity],
                **(
                    {"window": probes.window(p, grid, case), "estimate": p.estimate}
                    if p.quantity == "pressure"
                    else {}
                ),
            }
            for p in case.probes
        },
        "units": dict(
            timeseries_units(grid.dim),
            mass="kg/m" if grid.dim == 2 else "kg",
            initial_energy="J/m" if grid.dim == 2 else "J",
            at_time="s",
            wall_seconds="s",
            domain_used="m",
            spacing="m",
            dt="s",
            sound_speed="m/s",
            stable_time_step="s",
            memory_estimate_bytes="B",
        ),
        "case": resolved(case),
    }
