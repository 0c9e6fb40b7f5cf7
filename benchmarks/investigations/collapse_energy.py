"""Energy budget, front speed and viscosity of the granular column collapse (issue 26, item 4:
why the mu(I) column runs out too far).

    python benchmarks/investigations/collapse_energy.py [--aspect 2] [--transfer apic] [--model water]
        [--cells 6.25] [--dt-factor 1] [--width 3] [--interval 0.01] [--csv out.csv]

The validation's column (``mpmflow.validation.materials._collapse``: examples/
granular_collapse.toml at aspect ratio a, L0 = 0.05 m the half-width, dt = min(5e-4,
0.35 h / sqrt(2 g H0)), to 0.6 s + 6 sqrt(H0 / g)) in a tank of half-width
L0 + WIDTH x Lube's run-out + 0.02 m. Every output (INTERVAL s) it records:

- the energies per metre (J/m): kinetic of the particles' v_p, APIC's affine part
  0.5 m_p sum_kj C_kj^2 h^2 f_j (1 - f_j) (what the particle-to-grid transfer adds to the
  grid's kinetic energy, f_j the particle's place in its cell), potential m g y less its
  start, and the total: its rise between outputs is energy the scheme made;
- the front: the furthest particle on each side (mean of both) less L0, its speed (the
  difference between outputs), and the largest horizontal particle speed within one cell
  of the front; against the free-fall speed sqrt(2 g H0) and Ritter's 2 sqrt(g H0);
- with a viscous material, the cells holding particles: the share whose viscosity (the
  step's, from the last step's pressure) is at the cap, is 0 (no pressure: no friction),
  and in between; and in the yielding cells the shear stress the solved velocity carries,
  eta |2 D(v_new)|, over mu(I) p of that velocity and the new pressure (1: the friction
  is consistent; < 1: the lagged linearisation applied less than mu(I) p).

Prints a table row per output and a summary (JSON) at the end.
"""

import argparse
import json
import math
import os

import numpy as np

from mpmflow.validation import common, materials

G = 9.81
TRANSFERS = materials.TRANSFERS

ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
ap.add_argument("--aspect", type=float, default=2.0)
ap.add_argument("--transfer", choices=list(TRANSFERS), default="apic")
ap.add_argument("--model", default="mu_i", help="material.model (mu_i or water)")
ap.add_argument("--cells", type=float, default=6.25, help="cells across L0")
ap.add_argument("--dt-factor", type=float, default=1.0, help="the validation's dt times this")
ap.add_argument("--width", type=float, default=3.0)
ap.add_argument("--interval", type=float, default=0.01)
ap.add_argument("--end", type=float, default=None)
ap.add_argument("--set", action="append", default=[], help="more overrides key=value")
ap.add_argument("--csv", default=None)
ap.add_argument("--npz", default=None, help="the particles (x, v) at these --snap times")
ap.add_argument("--snap", type=float, action="append", default=[])
ap.add_argument("--quiet", action="store_true")
cli = ap.parse_args()

a, L0 = cli.aspect, materials.L0
case = materials.Collapse(a, cli.cells, cli.width, cli.dt_factor, cli.end, cli.interval)
H0, half, h = case.H0, case.half, case.h
overrides = [*case.overrides(), *TRANSFERS[cli.transfer], *cli.set]
if cli.model != "mu_i":
    overrides.append(f"material.model='{cli.model}'")

rows = []
snaps = {}
state = {"pe0": None, "prev": None}


def mu_of(rate, p, par):
    """mu(I) of the example's material (par: mu_s, mu_2, I0, d, rho_s)."""
    mu_s, mu_2, I0, d, rho_s = par
    inertial = rate * d / np.sqrt(np.maximum(p, 1e-30) / rho_s)
    return mu_s + (mu_2 - mu_s) * inertial / (I0 + inertial)


def viscosity_measures(sim):
    core = sim.scheme.core
    eta = np.asarray(core.eta)
    if eta.size == 0:
        return {}
    m = sim.case.material
    par = (
        m.friction_static,
        m.friction_limit,
        m.inertial_number_ref,
        m.grain_diameter,
        m.grain_density,
    )
    cap = m.max_viscosity
    nx, ny = (int(c) for c in sim.grid.cells)
    NX = nx + 1
    x = sim.particles.x
    cx = np.clip((x[:, 0] / h).astype(int), 0, nx - 1)
    cy = np.clip((x[:, 1] / h).astype(int), 0, ny - 1)
    held = np.zeros(nx * ny, bool)
    held[cx + nx * cy] = True
    c = np.flatnonzero(held)
    e = eta[c]
    ccx, ccy = c % nx, c // nx
    n00 = ccx + NX * ccy
    v = np.asarray(core.v_new)
    p = np.asarray(core.p_node)
    u00, u10, u01, u11 = v[n00], v[n00 + 1], v[n00 + NX], v[n00 + NX + 1]
    dudx = ((u10 + u11) - (u00 + u01)) / (2 * h)  # d(u, v)/dx at the centre
    dudy = ((u01 + u11) - (u00 + u10)) / (2 * h)
    dxx, dyy, dxy = dudx[:, 0], dudy[:, 1], 0.5 * (dudy[:, 0] + dudx[:, 1])
    rate = np.sqrt(2 * (dxx**2 + dyy**2 + 2 * dxy**2))
    pc = 0.25 * (
        np.maximum(p[n00], 0)
        + np.maximum(p[n00 + 1], 0)
        + np.maximum(p[n00 + NX], 0)
        + np.maximum(p[n00 + NX + 1], 0)
    )
    yielding = (e > 0) & (e < cap) & (pc > 0) & (rate > 0)
    ratio = e[yielding] * rate[yielding] / (mu_of(rate[yielding], pc[yielding], par) * pc[yielding])
    out = {
        "cells": int(c.size),
        "capped": float(np.mean(e >= cap)),
        "zero": float(np.mean(e == 0)),
        "zero_but_p": float(np.mean((e == 0) & (pc > 0))),
        "yielding": float(np.mean((e > 0) & (e < cap))),
    }
    if ratio.size:
        out.update(
            {
                "stress_ratio_median": float(np.median(ratio)),
                "stress_ratio_mean": float(np.mean(ratio)),
                "stress_ratio_lt_half": float(np.mean(ratio < 0.5)),
            }
        )
    return out


def floor_measures(sim):
    """The floor nodes under material (a particle within a cell of them): the share the
    last step's wall contact did not hold (no-slip then acts only on the normal), and
    that share among those beyond the 2-layer deposit's edge (the thin tail)."""
    contact = np.asarray(sim.scheme.core.contact)
    nx = int(sim.grid.cells[0])
    x = sim.particles.x
    low = x[:, 1] < h
    near = np.zeros(nx + 1, bool)
    ci = np.clip((x[low, 0] / h).astype(int), 0, nx - 1)
    near[ci] = True
    near[ci + 1] = True
    nodes = np.flatnonzero(near)
    free = ~contact[nodes, 1]
    return {
        "floor_nodes": int(nodes.size),
        "floor_free": float(np.mean(free)) if nodes.size else 0.0,
    }


def record(sim):
    P = sim.particles
    m, x, v = P.mass, P.x, P.v
    ke = float(0.5 * np.sum(m * np.sum(v**2, axis=1)))
    ke_aff = 0.0
    C = getattr(sim.scheme, "affine", None)
    if C is not None:
        f = x / h - np.floor(x / h)
        Dp = h * h * f * (1 - f)  # (n, D)
        ke_aff = float(0.5 * np.sum(m[:, None, None] * C**2 * Dp[:, None, :]))
    pe = float(G * np.sum(m * x[:, 1]))
    if state["pe0"] is None:
        state["pe0"] = pe
    right, left = x[:, 0].max() - half, half - x[:, 0].min()
    front = 0.5 * (right + left) - L0
    near_r, near_l = x[:, 0] > half + right - h, x[:, 0] < half - left + h
    ufront = 0.5 * (v[near_r, 0].max() - v[near_l, 0].min())
    row = {
        "t": sim.time,
        "ke": ke,
        "ke_aff": ke_aff,
        "pe": pe - state["pe0"],
        "total": ke + ke_aff + pe - state["pe0"],
        "front": front,
        "ufront": ufront,
        "vmax": float(np.sqrt((v**2).sum(1)).max()),
    }
    prev = state["prev"]
    row["front_speed"] = (front - prev["front"]) / (sim.time - prev["t"]) if prev else 0.0
    row.update(viscosity_measures(sim))
    row.update(floor_measures(sim))
    rows.append(row)
    state["prev"] = row
    for ts in cli.snap:
        if abs(sim.time - ts) < 1e-6:
            snaps[f"x_{ts:g}"], snaps[f"v_{ts:g}"] = x.copy(), v.copy()
    if not cli.quiet:
        print(
            " ".join(
                f"{k}={val:.5g}" if isinstance(val, float) else f"{k}={val}"
                for k, val in row.items()
            ),
            flush=True,
        )


sim = common.run_example("granular_collapse.toml", overrides, on_output=record)
x = sim.particles.x
reach = 0.5 * ((x[:, 0].max() - half) + (half - x[:, 0].min()))
tot = np.array([r["total"] for r in rows])
rise = np.diff(tot)
summary = {
    "aspect": a,
    "transfer": cli.transfer,
    "model": cli.model,
    "h": h,
    "dt": case.dt,
    "picard": os.environ.get("MPMFLOW_PICARD", "0"),
    "set": cli.set,
    "runout": (reach - L0) / L0,
    "law": materials.lube(a),
    "pe_start": float(-G * np.sum(sim.particles.mass) * H0 / 2),
    "total_end": float(tot[-1]),
    "total_max": float(tot.max()),
    "rise_sum": float(rise[rise > 0].sum()),
    "largest_rise": float(rise.max()) if rise.size else 0.0,
    "t_largest_rise": float(rows[int(np.argmax(rise)) + 1]["t"]) if rise.size else 0.0,
    "front_speed_max": float(max(r["front_speed"] for r in rows)),
    "t_front_speed_max": float(max(rows, key=lambda r: r["front_speed"])["t"]),
    "ufront_max": float(max(r["ufront"] for r in rows)),
    "vmax_max": float(max(r["vmax"] for r in rows)),
    "free_fall": math.sqrt(2 * G * H0),
    "ritter": 2 * math.sqrt(G * H0),
    "capped_cell_steps": sum(r["count"] for r in sim.fallbacks.rows() if "viscosity" in r["what"]),
    "wall": sim.summary["wall_seconds"],
}
print(json.dumps(summary))
if cli.npz:
    snaps["x_end"], snaps["v_end"] = sim.particles.x, sim.particles.v
    np.savez(cli.npz, half=half, h=h, L0=L0, H0=H0, **snaps)
if cli.csv:
    keys = sorted(
        {k for r in rows for k in r}, key=lambda k: list(rows[-1]).index(k) if k in rows[-1] else 99
    )
    with open(cli.csv, "w") as fh:
        fh.write(",".join(keys) + "\n")
        for r in rows:
            fh.write(",".join(f"{r.get(k, float('nan')):.6g}" for k in keys) + "\n")
