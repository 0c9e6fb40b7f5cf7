"""Hydrostatic column: pressure error at three grid spacings, spurious velocity, checkerboard.

Water at rest in a tank 0.1 m wide (examples/hydrostatic.toml), filled to 0.1975 m. The
particles fill whole layers of spacing/4, so the material's surface lies at the top of the
last layer below 0.1975 m: H = 0.195 m (0.02 m grid), 0.1975 m (0.01 m and 0.005 m grids),
a quarter or half a cell off the grid lines. The exact pressure is rho g (H - y).
"""

import numpy as np

from ..cells import bin_particles

from .common import CaseResult, Row, fmt, markdown_table, observed_order, pyplot, run_example, save

RHO, G = 1000.0, 9.81
FILL = 0.1975  # m, the box top asked for
SPACINGS = (0.02, 0.01, 0.005)
END, END_QUICK = 2.0, 0.5  # s
SOLVER_FLOOR = 1e-6  # relative errors below this are the pressure solve's tolerance (1e-8) at work

# tolerances, fixed before the results were looked at
TOL_L2 = 0.01
WHY_L2 = ("1% of rho g H is a 1% error in the wall force rho g H^2/2, the quantity an "
          "engineer takes from a column at rest")
TOL_MAX = 0.02
WHY_MAX = "2% of rho g H: half a particle layer (spacing/8) of head at the 0.02 m grid is 1.3%"
TOL_ORDER = 1.0
WHY_ORDER = "bilinear elements: the pressure error must fall at least linearly with the spacing"
TOL_SPEED = 1e-3
WHY_SPEED = ("0.07% of the wave speed sqrt(g H) = 1.4 m/s; a particle this slow moves 2 mm in "
             "2 s, invisible in any plot")
TOL_CHECKER = 1e-3
WHY_CHECKER = ("0.1% of rho g H; the (-1)^(i+j) mode is the signature of an unstable "
               "equal-order pair, which would grow to O(1) if present")


def checkerboard(sim, H):
    """Amplitude of the (-1)^(i+j) component of the nodal pressure error, / (rho g H).

    Over the interior nodes whose four cells are all full (theta >= 0.9): the mean of
    (-1)^(i+j) (p_i - rho g (H - y_i)). A smooth error averages out; a checkerboard does not."""
    g = sim.grid
    nx, ny = g.cells
    theta = bin_particles(g, sim.particles).theta.reshape(ny, nx)  # [cy, cx]
    p = sim.scheme.projection.p_node.reshape(ny + 1, nx + 1)  # [iy, ix]
    full = theta >= 0.9
    inner = np.zeros((ny + 1, nx + 1), dtype=bool)
    inner[1:-1, 1:-1] = full[:-1, :-1] & full[1:, :-1] & full[:-1, 1:] & full[1:, 1:]
    iy, ix = np.nonzero(inner)
    if iy.size == 0:
        return float("nan")
    err = p[iy, ix] - RHO * G * (H - iy * g.spacing)
    sign = np.where((ix + iy) % 2 == 0, 1.0, -1.0)
    return float(abs(np.mean(sign * err)) / (RHO * G * H))


def run(out, quick=False, context=None):
    end = END_QUICK if quick else END
    res = CaseResult("hydrostatic", "Hydrostatic column")
    runs = []
    for h in SPACINGS:
        sim = run_example("hydrostatic.toml", [f"grid.spacing={h}", f"bodies.0.max=[0.1, {FILL}]",
                                               f"time.end={end}"])
        P = sim.particles
        dp = h / sim.case.bodies[0].particles_per_cell
        H = np.floor(FILL / dp + 1e-9) * dp
        exact = RHO * G * (H - P.x[:, 1])
        err = P.pressure - exact
        runs.append({"h": h, "H": H, "particles": P.count,
                     "l2": float(np.sqrt(np.sum(err**2) / np.sum(exact**2))),
                     "max": float(np.abs(err).max() / (RHO * G * H)),
                     "speed": float(np.nanmax(sim.series("max_speed"))),
                     "speed_end": float(sim.series("max_speed")[-1]),
                     "checker": checkerboard(sim, H), "y": P.x[:, 1].copy(),
                     "p": P.pressure.copy(), "t": sim.series("time"),
                     "vt": sim.series("max_speed"), "wall": sim.summary["wall_seconds"]})
    name = "hydrostatic"
    for r in runs:
        res.rows.append(Row(name, f"pressure (L2), h = {r['h']} m", "relative L2 over particles at "
                            f"t = {end:g} s", r["l2"], TOL_L2, WHY_L2))
        res.rows.append(Row(name, f"pressure (max), h = {r['h']} m", "max |p - rho g (H - y)| / "
                            "(rho g H)", r["max"], TOL_MAX, WHY_MAX))
    l2 = [r["l2"] for r in runs]
    at_floor = all(e < SOLVER_FLOOR for e in l2)
    order = observed_order(SPACINGS, l2)
    res.rows.append(Row(
        name, "pressure, convergence", "observed order of the L2 error (fit over 3 spacings)",
        float("nan") if at_floor else order, TOL_ORDER, WHY_ORDER, sense=">=",
        not_measurable=at_floor,
        miss=("the error is at the pressure solve's tolerance at every spacing (L2 "
              + ", ".join(f"{e:.1e}" for e in l2) + "): there is no discretisation error left "
              "to converge, so no order can be observed; the column is exact, not "
              "first-order" if at_floor else
              "the pressure error does not fall with the spacing (see the section)")))
    res.rows.append(Row(name, "spurious velocity", f"largest particle speed over 0-{end:g} s, "
                        "all spacings", max(r["speed"] for r in runs), TOL_SPEED, WHY_SPEED,
                        unit="m/s"))
    res.rows.append(Row(name, "checkerboard", "|mean of (-1)^(i+j) nodal pressure error| / "
                        "(rho g H), full interior nodes, all spacings",
                        max(r["checker"] for r in runs), TOL_CHECKER, WHY_CHECKER))

    plt = pyplot()
    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    for r in runs:
        o = np.argsort(r["y"])
        ax[0].plot(np.abs(r["p"] - RHO * G * (r["H"] - r["y"]))[o] / (RHO * G * r["H"]),
                   r["y"][o], ".", ms=2, label=f"h = {r['h']} m")
        ax[1].semilogy(r["t"], np.maximum(r["vt"], 1e-16), label=f"h = {r['h']} m")
    ax[0].set_xscale("symlog", linthresh=1e-12)
    ax[0].set_xlabel("|p - rho g (H - y)| / (rho g H) [-]")
    ax[0].set_ylabel("y [m]")
    ax[0].legend()
    ax[1].set_xlabel("t [s]")
    ax[1].set_ylabel("largest particle speed [m/s]")
    ax[1].legend()
    fig.tight_layout()
    save(fig, out / "hydrostatic.png")
    res.figures.append(("hydrostatic.png", "Left: particle pressure error at the end; right: "
                        "the largest particle speed against time."))
    table = markdown_table(
        ["grid spacing h (m)", "surface H (m)", "particles", "L2 error (rel.)",
         "max error / (rho g H)", "max speed (m/s)", f"speed at {end:g} s (m/s)",
         "checkerboard / (rho g H)", "wall (s)"],
        [[r["h"], fmt(r["H"], 4), r["particles"], fmt(r["l2"]), fmt(r["max"]), fmt(r["speed"]),
          fmt(r["speed_end"]), fmt(r["checker"]), fmt(r["wall"])] for r in runs])
    res.text = (
        f"Water at rest in a tank 0.1 m x 0.3 m (`examples/hydrostatic.toml`), filled to "
        f"{FILL} m, 16 particles per cell, dt = 1 ms, default solver settings, {end:g} s. The "
        "particles fill whole layers of h/4, so the surface H is the top of the last layer "
        "below the fill height: it lies a quarter or half a cell off the grid lines. The exact "
        "pressure is rho g (H - y); the error is taken on the particle pressures at the end. "
        "**Checkerboard**: the nodal pressure error e_i at the interior nodes whose four "
        "cells are full (theta >= 0.9), projected on the (-1)^(i+j) mode: |mean((-1)^(i+j) "
        "e_i)| / (rho g H). A smooth error averages out; an odd-even mode of the equal-order "
        "velocity-pressure pair would not.\n\n" + table + "\n\n"
        + ("The error is at the level of the pressure solve's tolerance (relative residual "
           "1e-8) at every spacing: the discretisation reproduces the linear hydrostatic field "
           "exactly (linear fields lie in the bilinear space, the sub-cell free surface places "
           "p = 0 where the material ends, and the wall term balances gravity), so there is "
           "no discretisation error whose order could be observed. The order row reports n/a: "
           "the issue's 'order >= 1' cannot be shown on this case; the mesh convergence of "
           "the method is measured on the sloshing period and the dam break instead."
           if at_floor else f"Observed order of the L2 error: {order:.2f}."))
    return res
