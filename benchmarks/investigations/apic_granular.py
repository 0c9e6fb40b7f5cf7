"""Granular column collapse (mu(I)) with each transfer: the run-out against Lube et al.'s law
and whether the deposit stops (issue 26, item 3: does APIC earn the default for materials?).

    python benchmarks/investigations/apic_granular.py [--aspect 2 ...] [--quick]

Runs the validation's collapse (``mpmflow.validation.materials._collapse``: the column of
examples/granular_collapse.toml at aspect ratio a, 12.5 cells across the half-width, to
0.6 s + 6 sqrt(H0 / g)) with PIC (the example's solver.flip = 0), the FLIP blend (0.99)
and APIC, and prints per run: the run-out (L_inf - L0) / L0, Lube's law, their relative
difference, the deposit's height H_inf / H0, the largest particle speed at the end, the
share of particles faster than 1 mm/s then, and the front's creep over the last 0.5 s.
"""

import argparse
import json

import numpy as np

from mpmflow.validation import common, materials

TRANSFERS = {
    "PIC (flip = 0)": [],
    "FLIP 0.99": ["solver.flip=0.99"],
    "APIC": ["solver.transfer=apic"],
}

ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
ap.add_argument("--aspect", type=float, action="append", default=[])
ap.add_argument("--quick", action="store_true", help="6.25 cells across L0 (the quick set)")
ap.add_argument("--transfer", action="append", choices=list(TRANSFERS), default=[])
ap.add_argument(
    "--width",
    type=float,
    default=1.6,
    help="tank half-width L0 + WIDTH x Lube's run-out + 0.02 m (the validation's: "
    "1.6; APIC and FLIP reach its side walls at a >= 2: use 3)",
)
cli = ap.parse_args()

_load, _run = common.load_case, materials.run_example


def collapse(a, extra):
    """materials._collapse(a) with ``extra`` overrides: (its result, the Simulation, the
    spread x_max - x_min at every output)."""
    fronts, holder = [], {}

    def load(path, overrides=()):
        return _load(path, [*overrides, *extra])

    def run_example(example, overrides=(), on_output=None):
        def front(sim):
            x = sim.particles.x[:, 0]
            fronts.append((sim.time, x.max() - x.min()))

        holder["sim"] = _run(example, overrides, on_output=front)
        return holder["sim"]

    common.load_case, materials.run_example = load, run_example
    try:
        r = materials._collapse(a, cli.quick, cli.width)
    finally:
        common.load_case, materials.run_example = _load, _run
    return r, holder["sim"], np.array(fronts)


rows = []
for a in cli.aspect or [2.0]:
    for name in cli.transfer or list(TRANSFERS):
        r, sim, f = collapse(a, TRANSFERS[name])
        speed = np.linalg.norm(sim.particles.v, axis=1)
        late = f[f[:, 0] >= f[-1, 0] - 0.5 - 1e-9]
        rows.append(
            {
                "a": a,
                "transfer": name,
                "runout": r["runout"],
                "law": r["law"],
                "off": (r["runout"] - r["law"]) / r["law"],
                "height": r["height"],
                "speed_max": float(speed.max()),
                "moving": float(np.mean(speed > 1e-3)),
                "creep_mm": float(0.5 * (late[-1, 1] - late[0, 1]) * 1e3),
                "end": float(f[-1, 0]),
                "wall": r["wall"],
                "particles": r["particles"],
                "walled": r["walled"],
            }
        )
        print(json.dumps(rows[-1]), flush=True)

print(
    "| a | transfer | run-out | Lube | off the law | H_inf/H0 | max speed at end (m/s) | "
    "share > 1 mm/s | toe creep, last 0.5 s (mm) | reached a side wall |"
)
print("|---|---|---|---|---|---|---|---|---|---|")
for r in rows:
    print(
        f"| {r['a']:g} | {r['transfer']} | {r['runout']:.3f} | {r['law']:.3f} | "
        f"{100 * r['off']:+.0f}% | {r['height']:.3f} | {r['speed_max']:.3g} | "
        f"{100 * r['moving']:.0f}% | {r['creep_mm']:.1f} | {'yes' if r['walled'] else 'no'} |"
    )
