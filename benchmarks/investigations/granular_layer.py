"""A layer of the granular collapse's material on a periodic no-slip floor (issue 26, item 4:
does the pressure the friction sees, and the friction of the floor, hold in thin layers?).

    python benchmarks/investigations/granular_layer.py [--cells 0.5 1 2 4] [--transfer apic flip]
        [--u0 0] [--model mu_i] [--end 0.3] [--set key=value ...]

The material of examples/granular_collapse.toml (4 mm cells, 2 particles per cell axis), a
layer CELLS cells thick filling a periodic strip 16 cells long, started uniformly at u0 m/s
along the floor. Per thickness and transfer it prints:

- at rest (--u0 0): the floor nodes' pressure and the first row of nodes' over rho g H at the
  end, and the largest particle speed (a layer at rest must stay at rest);
- sliding (--u0 > 0): the deceleration of the particles' mean velocity (fitted while it is above
  0.3 u0, after 20 ms), and the distance the mean and the top row of particles slide (the
  integral of their mean velocity) over Coulomb's u0^2 / (2 mu_s g). With friction_limit =
  friction_static (--set material.friction_limit=0.380001) mu(I) is a constant friction: a
  plug on a thin basal shear layer decelerates at mu_s g and slides 1.0 of that distance.
"""

import argparse
import json

import numpy as np

from mpmflow.validation import common

G = 9.81
TRANSFERS = {
    "apic": ["solver.transfer=apic"],
    "flip": ["solver.flip=0.99"],
    "pic": ["solver.flip=0"],
}

ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
ap.add_argument("--cells", type=float, nargs="+", default=[0.5, 1.0, 2.0, 4.0])
ap.add_argument("--transfer", nargs="+", choices=list(TRANSFERS), default=["apic", "flip"])
ap.add_argument("--h", type=float, default=0.004, help="grid spacing (m)")
ap.add_argument("--u0", type=float, default=0.0, help="initial speed along the floor (m/s)")
ap.add_argument("--model", default="mu_i", help="material.model (mu_i or water)")
ap.add_argument("--dt", type=float, default=2.5e-4)
ap.add_argument("--end", type=float, default=0.3)
ap.add_argument("--set", action="append", default=[], help="more overrides key=value")
cli = ap.parse_args()


def layer(cells, transfer):
    h = cli.h
    H, W = cells * h, 16 * h
    ov = [
        f"domain.size=[{W:.6g}, {H + 4 * h:.6g}]",
        "domain.periodic=[true, false]",
        f"grid.spacing={h}",
        "bodies.0.min=[0.0, 0.0]",
        f"bodies.0.max=[{W:.6g}, {H:.6g}]",
        f"bodies.0.velocity=[{cli.u0}, 0.0]",
        f"time.dt={cli.dt}",
        f"time.end={cli.end}",
        "output.interval=0.002",
        *TRANSFERS[transfer],
        *cli.set,
    ]
    if cli.model != "mu_i":
        ov.append(f"material.model='{cli.model}'")
    rows, y0 = [], {}

    def record(sim):
        x, v = sim.particles.x, sim.particles.v
        if not y0:
            y0["y"] = x[:, 1].copy()
        top = y0["y"] > y0["y"].max() - 1e-9
        p = np.asarray(sim.scheme.core.p_node)
        nx = int(sim.grid.cells[0])
        rho_g_H = sim.case.material.density * G * H
        rows.append(
            {
                "t": sim.time,
                "u": float(v[:, 0].mean()),
                "utop": float(v[top, 0].mean()),
                "speed": float(np.abs(v).max()),
                "p_floor": float(p[:nx].mean()) / rho_g_H,
                "p_row1": float(p[nx + 1 : 2 * nx + 1].mean()) / rho_g_H,
            }
        )

    sim = common.run_example("granular_collapse.toml", ov, on_output=record)
    t = np.array([r["t"] for r in rows])
    u = np.array([r["u"] for r in rows])
    out = {"cells": cells, "transfer": transfer, "particles": sim.particles.count, **rows[-1]}
    if cli.u0 > 0:
        mu_s = sim.case.material.friction_static
        fit = (u > 0.3 * cli.u0) & (t > 0.02)
        out["decel_g"] = float(-np.polyfit(t[fit], u[fit], 1)[0] / G) if fit.sum() > 2 else None
        coulomb = cli.u0**2 / (2 * mu_s * G)
        out["mean_slide"] = float(np.trapezoid(u, t) / coulomb)
        out["top_slide"] = float(np.trapezoid([r["utop"] for r in rows], t) / coulomb)
    return out


res = []
for transfer in cli.transfer:
    for cells in cli.cells:
        res.append(layer(cells, transfer))
        print(json.dumps(res[-1]), flush=True)

if cli.u0 > 0:
    print(
        "| transfer | layer (cells) | deceleration of the mean / g | slide of the mean / "
        "Coulomb's | slide of the top row / Coulomb's |"
    )
    print("|---|---|---|---|---|")
    for r in res:
        print(
            f"| {r['transfer']} | {r['cells']:g} | {r['decel_g'] or float('nan'):.3f} | "
            f"{r['mean_slide']:.3f} | {r['top_slide']:.3f} |"
        )
else:
    print(
        "| transfer | layer (cells) | floor pressure / rho g H | first node row / rho g H | "
        "largest speed at the end (m/s) |"
    )
    print("|---|---|---|---|---|")
    for r in res:
        print(
            f"| {r['transfer']} | {r['cells']:g} | {r['p_floor']:.3f} | {r['p_row1']:.3f} | "
            f"{r['speed']:.2g} |"
        )
