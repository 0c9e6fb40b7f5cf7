"""The analytic channel flows run at one mesh (``validation.channel_flows``'s cases): each
example run at a spacing and its measures against the theory (``channel_theory``)."""

import math

from ..simulation import Simulation
from .channel_theory import (
    bagnold,
    bingham,
    binned,
    depth,
    fit_plug,
    incline,
    inertial_number,
    l2,
    plug_width,
    poiseuille,
)
from .common import run_example
from .types import FloatArray, Measures

STARTUP = 0.1  # of T_visc: when the start-up profile is measured


def _run_record(sim: Simulation, h: float, H: float) -> Measures:
    """What every run's record starts with: its spacing and depth (m), end (s), wall time
    (s) and particle count."""
    return {
        "h": h,
        "H": H,
        "end": sim.time,
        "wall": sim.summary["wall_seconds"],
        "particles": sim.particles.count,
    }


def measure_poiseuille(
    h: float, end: float, dt: float | None = None, example: str = "poiseuille_film.toml"
) -> Measures:
    """Run the film at spacing ``h`` to ``end`` (s) with the step ``dt`` (s; None: the
    example's); the start-up and steady measures."""
    snaps: dict[str, tuple[float, FloatArray, FloatArray]] = {}
    state: dict[str, float] = {}

    def grab(sim: Simulation) -> None:
        if "T" not in state:
            m = sim.case.material
            nu = m.viscosity / m.density
            H = depth(sim.case)
            state.update(T=H * H / nu, nu=nu, H=H)
        if abs(sim.time - STARTUP * state["T"]) < 0.5 * sim.dt:
            snaps["startup"] = (
                sim.time,
                sim.particles.x[:, 1].copy(),
                sim.particles.v[:, 0].copy(),
            )

    # the example's output interval is 0.1 T_visc, so the start-up time is an output time
    over = [f"grid.spacing={h}", f"time.end={end}"] + ([f"time.dt={dt}"] if dt else [])
    sim = run_example(example, over, on_output=grab)
    theta, g = incline(sim.case)
    gs, H, nu = g * math.sin(theta), state["H"], state["nu"]
    r = {
        "h": h,
        "H": H,
        "nu": nu,
        "gs": gs,
        "T": state["T"],
        "dt": sim.dt,
        "end": sim.time,
        "wall": sim.summary["wall_seconds"],
        "particles": sim.particles.count,
    }
    if "startup" not in snaps:
        raise RuntimeError("the start-up time 0.1 T_visc is not an output time of the run")
    t0, y0, u0 = snaps["startup"]
    r["t_startup"] = t0
    r["startup_bins"] = binned(y0, u0, H, h, lambda yy: poiseuille(yy, H, nu, gs, t0))
    r["startup"] = l2(*r["startup_bins"][1:])
    y, u = sim.particles.x[:, 1], sim.particles.v[:, 0]
    r["steady_bins"] = binned(y, u, H, h, lambda yy: poiseuille(yy, H, nu, gs))
    r["steady"] = l2(*r["steady_bins"][1:])
    r["surface"] = r["steady_bins"][1][-1] / r["steady_bins"][2][-1] - 1.0
    return r


def measure_plug(h: float, end: float, example: str = "bingham_plug.toml") -> Measures:
    """Run the Bingham layer at spacing ``h`` to ``end`` (s); plug width and speed."""
    sim = run_example(example, [f"grid.spacing={h}", f"time.end={end}"])
    m = sim.case.material
    theta, g = incline(sim.case)
    gs, H = g * math.sin(theta), depth(sim.case)
    y, u = sim.particles.x[:, 1], sim.particles.v[:, 0]
    r = {
        **_run_record(sim, h, H),
        "rho": m.density,
        "K": m.consistency,
        "tau_y": m.yield_stress,
        "gs": gs,
        "cap": m.max_viscosity,
    }
    r["plug_theory"] = plug_width(H, m.density, m.yield_stress, gs)
    r["plug"] = fit_plug(y, u, H, h)
    r["plug_error"] = r["plug"] / r["plug_theory"] - 1.0
    r["bins"] = binned(
        y, u, H, h, lambda yy: bingham(yy, H, m.density, m.consistency, m.yield_stress, gs)
    )
    r["profile"] = l2(*r["bins"][1:])
    r["speed"], r["speed_theory"] = r["bins"][1][-1], r["bins"][2][-1]
    r["speed_error"] = r["speed"] / r["speed_theory"] - 1.0
    return r


def measure_layer(h: float, end: float, example: str = "mu_i_layer.toml") -> Measures:
    """Run the mu(I) layer at spacing ``h`` to ``end`` (s); surface velocity and profile."""
    sim = run_example(example, [f"grid.spacing={h}", f"time.end={end}"])
    m = sim.case.material
    theta, g = incline(sim.case)
    H = depth(sim.case)
    args = (
        H,
        theta,
        m.friction_static,
        m.friction_limit,
        m.inertial_number_ref,
        m.grain_diameter,
        m.density / m.grain_density,
        g,
    )
    y, u = sim.particles.x[:, 1], sim.particles.v[:, 0]
    r = {**_run_record(sim, h, H), "theta": theta, "args": args, "I": inertial_number(*args[1:5])}
    r["bins"] = binned(y, u, H, h, lambda yy: bagnold(yy, *args))
    r["profile"] = l2(*r["bins"][1:])
    r["surface"], r["surface_theory"] = r["bins"][1][-1], r["bins"][2][-1]
    r["surface_error"] = r["surface"] / r["surface_theory"] - 1.0
    return r
