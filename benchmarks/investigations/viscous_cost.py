"""The cost of the viscous step: the paper's dam break inviscid and with a viscous material,
per step, at two meshes (issue 26 item 6).

Each case runs in-process (one short warm-up first), --repeat times, the materials taking
turns; the table gives the
median milliseconds per step of the whole step and of its viscous phase (the core's own
phase clock, ``State.phase_seconds``), and the viscous step's share. Materials: water
(inviscid), Newtonian water (1e-3 Pa s: the viscous solve with a viscosity too small to
matter to the flow) and a Bingham fluid (the viscosity from the strain rate each step).

    python benchmarks/investigations/viscous_cost.py [--repeat 3] [--end 0.2]
"""

import argparse
import statistics
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
MESHES = (0.008, 0.004)  # m: 6.5k and 26k particles
MATERIALS = {
    "water (inviscid)": [],
    "newtonian, 1e-3 Pa s": ["material.model=newtonian", "material.viscosity=1e-3"],
    "herschel_bulkley, 5 Pa / 0.1 Pa s": [
        "material.model=herschel_bulkley",
        "material.yield_stress=5.0",
        "material.consistency=0.1",
    ],
}


def run(overrides):
    from mpmflow import Simulation, load_case, state

    sim = Simulation(
        load_case(ROOT / "examples" / "dam_break.toml", [*overrides, "output.snapshots=false"])
    )
    t0 = time.perf_counter()
    sim.run()
    wall = time.perf_counter() - t0
    phases = dict(zip(state.PHASES, sim.scheme.core.phase_seconds))
    viscous = next(t for name, t in phases.items() if "viscous" in name)
    return sim.steps, sim.particles.count, wall, viscous


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--end", type=float, default=0.2)
    args = ap.parse_args()
    from mpmflow import state

    print(f"{state.max_threads()} threads, dam break to t = {args.end} s, median of {args.repeat}")
    print()
    print(
        "| h (m) | particles | material | ms per step | viscous phase (ms per step) | "
        "viscous share | step vs inviscid |"
    )
    print("|---|---|---|---|---|---|---|")
    for h in MESHES:
        runs = {name: [] for name in MATERIALS}
        for more in MATERIALS.values():  # warm-up
            run([f"grid.spacing={h}", "time.end=0.003", *more])
        for _ in range(args.repeat):  # the materials alternate: the machine's drift hits all
            for name, more in MATERIALS.items():
                runs[name].append(run([f"grid.spacing={h}", f"time.end={args.end}", *more]))
        base = None
        for name, got in runs.items():
            steps, count = got[0][0], got[0][1]
            step = statistics.median(r[2] for r in got) / steps * 1e3
            visc = statistics.median(r[3] for r in got) / steps * 1e3
            base = base or step
            print(
                f"| {h} | {count} | {name} | {step:.2f} | {visc:.2f} | "
                f"{100 * visc / step:.0f}% | {step / base:.2f}x |",
                flush=True,
            )


if __name__ == "__main__":
    main()
